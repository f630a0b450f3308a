# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The condition report: what a vibration analyst looks at before trusting theta_Oil (issue 34, item 5).

``prsm-lube assess --report DIR`` writes it as a page of its own
(:meth:`ConditionReport.write`); ``prsm-lube diagnose --report DIR`` adds it
as a section of the diagnosis page (:meth:`ConditionReport.markdown`).  From
assessed recordings (:class:`~..estimation.pipeline.RecordingAssessment`) it
keeps, per run, a compact summary (:class:`RunSummary`: the indicators, the
screen's finding, theta_Oil, the run-averaged envelope spectrum and order
spectrum on fixed grids) and draws with :mod:`..condition_figures`:

* per recording (a section; at most :data:`MAX_SECTIONS`, recordings with a
  suspected run first): the **order spectrum** (each window's Welch PSD with
  its frequency divided by the window's shaft frequency, averaged over the
  runs of one speed; the analysis band's edges marked where they fall in
  range), two **waterfalls** (the envelope spectra of every run over run
  time; the order spectra over speed), the **indicator trends** and the
  **envelope spectra** of at most :data:`MAX_RUN_FIGURES_PER_SECTION` runs
  (suspected runs first, then the strongest defect-order line; at most
  :data:`MAX_RUN_FIGURES` in all), each with every defect order of the
  actuator marked and the suspected line highlighted;
* over all runs: the trends and a table (at most :data:`MAX_TABLE_ROWS` rows).

What was left out to keep the page usable for 100+ runs is said on it, and so
are the resolutions (Hz and orders per bin, the demodulation bands).
Windows' spectra are dropped from the assessment once summarised
(:meth:`ConditionReport.add`), so memory stays flat over many recordings.
"""
from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field, replace
import datetime
import html
import math
from pathlib import Path
import re
from typing import TYPE_CHECKING

import numpy as np

from ..atomic_file import write_atomically
from ..errors import InputError
from ..estimation.condition_indicators import FLOOR_LOWEST_ORDER, MAX_ORDER, ORDER_GRID, ORDER_STEP, order_spectrum_db
from ..estimation.defect_screen import DEFAULT_RULES, screen_limits, strike_orders
from ..physics.defect_orders import label_order

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ..estimation.assessment import RunAssessment, WindowAssessment
    from ..estimation.defect_screen import ConditionBaseline, DefectRules
    from ..estimation.pipeline import RecordingAssessment
    from ..physics.defect_orders import DefectOrder

__all__ = ['MAX_RUN_FIGURES', 'MAX_RUN_FIGURES_PER_SECTION', 'MAX_SECTIONS', 'MAX_SPEED_CURVES', 'MAX_TABLE_ROWS',
           'ORDER_SPECTRUM_GRID', 'ORDER_SPECTRUM_MAX', 'ConditionReport', 'RunSummary', 'defect_marks',
           'markdown_html']

#: Highest screw order of the order spectrum (3 harmonics of every default and FEMTO bearing defect order, the
#: low orders of the drive); the band's upper edge usually lies beyond it and is then stated, not drawn.
ORDER_SPECTRUM_MAX = 50.0
#: The fixed grid the runs' order spectra are kept on, orders (finer than any Welch bin in orders here).
ORDER_SPECTRUM_GRID = np.arange(0.0, ORDER_SPECTRUM_MAX + ORDER_STEP / 2, ORDER_STEP)
#: Recordings that get a section of figures (those with a suspected run first).
MAX_SECTIONS = 12
#: Per-run envelope spectra drawn in all, and per section.
MAX_RUN_FIGURES = 24
MAX_RUN_FIGURES_PER_SECTION = 6
#: Rows of the table of runs.
MAX_TABLE_ROWS = 400
#: Speeds drawn as separate curves of the order spectrum.
MAX_SPEED_CURVES = 6


@dataclass(frozen=True)
class RunSummary:
    """One run as the report draws it: indicators, finding, theta_Oil and its spectra on fixed grids."""

    recording: str
    run_index: int
    start: float                  # s since the epoch
    speed: float                  # rad/s
    load: float                   # N
    windows: int
    kurtosis: float
    crest: float
    line_order: float             # strike order whose envelope line is strongest (NaN: none measured)
    line_db: float                # its level, dB over the floor
    line_component: str
    theta: float
    theta_std: float
    theta_flag: str               # theta out of its physical range, in words ('' when in it)
    reason: str                   # why theta is NaN ('' when assessed)
    suspected: bool
    evidence: str
    finding_order: float          # the suspected line's order (NaN: impulsive only, or not suspected)
    finding_component: str
    envelope_resolution: float    # orders per envelope bin
    spectrum_resolution: float    # Hz per Welch bin
    demodulation_bands: tuple[tuple[float, float], ...] = ()
    envelope_db: np.ndarray | None = field(default=None, compare=False, repr=False)   # on ORDER_GRID
    order_psd: np.ndarray | None = field(default=None, compare=False, repr=False)     # on ORDER_SPECTRUM_GRID

    @property
    def rpm(self) -> float:
        """Screw speed in r/min."""
        return self.speed * 30.0 / math.pi

    @property
    def name(self) -> str:
        """``recording run N`` (the recording's file or folder name)."""
        return f'{Path(self.recording).name} run {self.run_index}'


def defect_marks(orders: Sequence[DefectOrder]) -> list[tuple[float, str]]:
    """Each defect order once, labelled with every component at it ("nut raceway or roller")."""
    marks: list[tuple[float, str]] = []
    for item in sorted(orders, key=lambda o: o.order):
        label = label_order(item.order, orders, harmonics=1)
        if not any(text == label and abs(order - item.order) <= 0.01 * item.order for order, text in marks):
            marks.append((item.order, label or item.component))
    return marks


def _run_order_psd(windows: Sequence[WindowAssessment]) -> tuple[np.ndarray | None, float]:
    """Mean of the windows' PSDs with frequency over the window's shaft frequency, on :data:`ORDER_SPECTRUM_GRID`."""
    rows, resolutions = [], []
    for item in windows:
        w = item.window
        shaft_hz = abs(w.screw_speed) / (2.0 * math.pi)
        if w.spectrum is None or not (shaft_hz > 0 and math.isfinite(w.spectrum_resolution)):
            continue
        axis = np.arange(w.spectrum.size) * w.spectrum_resolution / shaft_hz
        rows.append(np.interp(ORDER_SPECTRUM_GRID, axis, w.spectrum, right=math.nan))
        resolutions.append(w.spectrum_resolution)
    if not rows:
        return None, math.nan
    return _nanmean(rows), float(np.median(resolutions))


def _nanmean(rows: Sequence[np.ndarray]) -> np.ndarray:
    """Mean of ``rows`` over their finite values, column by column (NaN where none is finite)."""
    stack = np.vstack(rows).astype(float)
    finite = np.isfinite(stack)
    count = finite.sum(axis=0)
    total = np.where(finite, stack, 0.0).sum(axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), math.nan)


def _strongest_line(run: RunAssessment, orders: Sequence[DefectOrder]) -> tuple[float, float, str]:
    """(order, dB over floor, component) of the run's strongest envelope level at a strike order's fundamental."""
    condition = run.condition
    strikes = strike_orders(orders) or list(orders)
    best = (math.nan, math.nan, '')
    if condition is None:
        return best
    for item in strikes:
        level = condition.level_at(item.order)
        if math.isfinite(level) and not level <= best[1]:
            best = (item.order, level, label_order(item.order, strikes, harmonics=1) or item.component)
    return best


def _summary(path: str, run: RunAssessment, windows: Sequence[WindowAssessment],
             orders: Sequence[DefectOrder]) -> RunSummary:
    """The :class:`RunSummary` of one assessed run and its steady windows."""
    condition = run.condition
    line_order, line_db, component = _strongest_line(run, orders)
    psd, spectrum_resolution = _run_order_psd(windows)
    bands = tuple((round(c.demodulation_band[0], 1), round(c.demodulation_band[1], 1))
                  for c in (item.window.condition for item in windows)
                  if c is not None and all(math.isfinite(v) for v in c.demodulation_band))
    envelope = (order_spectrum_db(condition.envelope).astype(np.float32)
                if condition is not None and condition.envelope is not None else None)
    return RunSummary(
        recording=path, run_index=run.run_index, start=run.start, speed=run.screw_speed, load=run.axial_load,
        windows=run.windows, kurtosis=condition.kurtosis if condition else math.nan,
        crest=condition.crest_factor if condition else math.nan, line_order=line_order, line_db=line_db,
        line_component=component, theta=run.theta_oil, theta_std=run.theta_oil_std, theta_flag=run.flag,
        reason=run.reason, suspected=run.defect.suspected, evidence=run.defect.evidence,
        finding_order=run.defect.order, finding_component=run.defect.component,
        envelope_resolution=condition.order_resolution if condition else math.nan,
        spectrum_resolution=spectrum_resolution, demodulation_bands=bands, envelope_db=envelope,
        order_psd=None if psd is None else psd.astype(np.float32))


def _time_axis(starts: np.ndarray) -> tuple[np.ndarray, str, str]:
    """Run starts as (values, unit, label) since the first, in s, min, h or days by the span."""
    first = float(np.nanmin(starts)) if starts.size else 0.0
    span = float(np.nanmax(starts)) - first if starts.size else 0.0
    unit, scale = next(((u, s) for u, s, limit in (('s', 1.0, 120.0), ('min', 60.0, 7200.0),
                                                   ('h', 3600.0, 172800.0)) if span < limit), ('days', 86400.0))
    when = datetime.datetime.fromtimestamp(first, datetime.UTC).strftime('%Y-%m-%d %H:%M:%S UTC')
    return (starts - first) / scale, unit, f'run start, {unit} after {when}'


def _speed_groups(runs: Sequence[RunSummary]) -> list[list[RunSummary]]:
    """Runs with an order spectrum grouped by speed (within 2 %), at most :data:`MAX_SPEED_CURVES` groups spread."""
    groups: list[list[RunSummary]] = []
    for run in sorted((r for r in runs if r.order_psd is not None), key=lambda r: r.speed):
        if groups and abs(run.speed - groups[-1][0].speed) <= 0.02 * groups[-1][0].speed:
            groups[-1].append(run)
        else:
            groups.append([run])
    if len(groups) > MAX_SPEED_CURVES:
        keep = sorted({int(round(v)) for v in np.linspace(0, len(groups) - 1, MAX_SPEED_CURVES)})
        groups = [groups[k] for k in keep]
    return groups


def _db(power: np.ndarray) -> np.ndarray:
    with np.errstate(divide='ignore', invalid='ignore'):
        return 10.0 * np.log10(power)


def _fmt(value: float, digits: int = 2) -> str:
    return f'{value:.{digits}f}' if math.isfinite(value) else '—'


def _band_words(bands: Sequence[tuple[float, float]]) -> str:
    """The demodulation bands chosen, most common first, with how many windows chose each."""
    counts = Counter(bands)
    if not counts:
        return 'none (no window had an envelope)'
    parts = [f'{lo:.0f}-{hi:.0f} Hz ({n} window{"s" if n > 1 else ""})' for (lo, hi), n in counts.most_common(4)]
    more = len(counts) - 4
    return ', '.join(parts) + (f' and {more} other band{"s" if more > 1 else ""}' if more > 0 else '')


class ConditionReport:
    """Collects assessed recordings and writes the condition figures and words (see module doc).

    ``orders`` are the actuator's defect orders; ``band`` (Hz) the analysis
    band; ``baseline`` and ``rules`` the screen's; ``notes`` lines said on
    the page before the figures (what theta_Oil and the screen were judged
    against); ``paths`` the recordings in the order the page shows them
    (recordings may be added as they finish, in any order; others follow).
    """

    def __init__(self, orders: Sequence[DefectOrder], *, band: tuple[float, float] | None = None,
                 baseline: ConditionBaseline | None = None, rules: DefectRules = DEFAULT_RULES,
                 notes: Sequence[str] = (), title: str = 'prsm-lube assess: condition report',
                 paths: Sequence[str] = ()):
        self.paths = [str(p) for p in paths]
        self.orders = tuple(orders)
        self.band = band
        self.baseline = baseline
        self.rules = rules
        self.notes = list(notes)
        self.title = title
        self.recordings: dict[str, list[RunSummary]] = {}

    def add(self, assessment: RecordingAssessment, *, release: bool = True) -> None:
        """Summarise every run of ``assessment``; with ``release`` drop its windows' spectra afterwards."""
        by_run: dict[int, list[WindowAssessment]] = {}
        for item in assessment.windows:
            if item.window.steady:
                by_run.setdefault(item.window.run_index, []).append(item)
        self.recordings[assessment.path] = [_summary(assessment.path, run, by_run.get(run.run_index, []), self.orders)
                                            for run in assessment.runs]
        if release:
            assessment.windows[:] = [replace(item, window=replace(item.window, spectrum=None))
                                     if item.window.spectrum is not None else item for item in assessment.windows]

    def _order(self) -> list[str]:
        """The recordings summarised, in the order of ``paths`` (the others after them, as added)."""
        rank = {path: i for i, path in enumerate(self.paths)}
        return sorted(self.recordings, key=lambda path: rank.get(path, len(rank)))

    @property
    def runs(self) -> list[RunSummary]:
        """Every run summarised, recordings in the page's order."""
        return [run for path in self._order() for run in self.recordings[path]]

    # -- words ----------------------------------------------------------------------------------
    def _orders_words(self) -> str:
        marks = defect_marks(self.orders)
        if not marks:
            return 'none configured (the actuator file sets no defect order)'
        strikes = {o.order for o in strike_orders(self.orders)}
        return '; '.join(f'{order:.4g}x {label}'
                         + ('' if any(abs(order - s) <= 0.01 * s for s in strikes) else ' (modulates, not screened)')
                         for order, label in marks)

    def _screen_words(self) -> str:
        r = self.rules
        words = (f'defect suspected when strongly impulsive, strongly periodic, or impulsive and periodic together: '
                 f'impulsive = run median kurtosis >= {r.healthy_kurtosis:g}')
        if self.baseline is not None:
            b = self.baseline
            words += (f' and >= {r.kurtosis_ratio:g} x the calibration runs\' median {b.kurtosis_median:.2f}; '
                      f'strongly impulsive = kurtosis >= {b.kurtosis_max + r.kurtosis_margin:.2f} or crest factor >= '
                      f'{max(r.healthy_crest, r.crest_ratio * b.crest_max):.2f} (healthy baseline of {b.runs} runs)')
        else:
            words += ' (no healthy baseline: the absolute limits only)'
        words += f'; periodic = an envelope line at a strike order >= {r.envelope_db:g} dB over the floor'
        if self.baseline is None:
            return words
        words += f', strongly periodic also {r.envelope_margin_db:g} dB above the calibration runs\' level there'
        if r.unexplained_margin_db is not None:
            words += (f' and at least {r.unexplained_margin_db:g} dB above every line of the run at an order no '
                      'component explains')
        return words

    def _resolution_words(self, runs: Sequence[RunSummary]) -> list[str]:
        """The resolutions of the section's spectra, in words (Hz and orders per bin, the demodulation bands)."""
        lines = []
        with_psd = [r for r in runs if r.order_psd is not None and math.isfinite(r.spectrum_resolution)]
        if with_psd:
            hz = float(np.median([r.spectrum_resolution for r in with_psd]))
            slow, fast = min(with_psd, key=lambda r: r.speed), max(with_psd, key=lambda r: r.speed)
            per_bin = (f'{hz / (fast.speed / (2 * math.pi)):.3g} orders per bin at {fast.rpm:.0f} r/min'
                       + (f' to {hz / (slow.speed / (2 * math.pi)):.3g} at {slow.rpm:.0f} r/min'
                          if slow.rpm < 0.98 * fast.rpm else ''))
            text = (f'**Order spectrum resolution:** Welch PSD of each steady window, {hz:.3g} Hz per bin = '
                    f'{per_bin}; kept on a {ORDER_STEP:g}-order grid up to {ORDER_SPECTRUM_MAX:g} orders.')
            if self.band is not None:
                low, high = self.band
                text += (f' Analysis band {low:g}-{high:.0f} Hz = {low / (fast.speed / (2 * math.pi)):.3g}-'
                         f'{high / (fast.speed / (2 * math.pi)):.4g} orders at {fast.rpm:.0f} r/min'
                         + (f', {low / (slow.speed / (2 * math.pi)):.3g}-{high / (slow.speed / (2 * math.pi)):.4g}'
                            f' at {slow.rpm:.0f} r/min' if slow.rpm < 0.98 * fast.rpm else '')
                         + f'; edges beyond {ORDER_SPECTRUM_MAX:g} orders are not drawn.')
            lines.append(text)
        else:
            lines.append('**Order spectrum:** none (the windows kept no spectrum).')
        resolutions = [r.envelope_resolution for r in runs if math.isfinite(r.envelope_resolution)]
        bands = [b for r in runs for b in r.demodulation_bands]
        if resolutions:
            lines.append(f'**Envelope spectrum resolution:** {min(resolutions):.3g}-{max(resolutions):.3g} orders per '
                         f'bin (one over the screw revolutions in a window), kept on a {ORDER_STEP:g}-order grid up '
                         f'to {MAX_ORDER:g} orders and averaged over each run\'s windows; dB over the floor (median '
                         f'of the spectrum above order {FLOOR_LOWEST_ORDER:g}). **Demodulation band** (chosen per '
                         f'window by spectral kurtosis): {_band_words(bands)}.')
        return lines

    # -- figures --------------------------------------------------------------------------------
    def _section(self, folder: Path, prefix: str, runs: Sequence[RunSummary], budget: int,
                 heading: str) -> list[str]:
        """Figures and words of one recording's runs, with at most ``budget`` per-run envelope spectra."""
        lines = [heading, '', f'{len(runs)} run{"s" if len(runs) != 1 else ""}, '
                 f'{sum(r.suspected for r in runs)} with a defect suspected.', '']
        lines += [line for text in self._resolution_words(runs) for line in (text, '')]
        for name, alt in ((self._order_spectrum(folder / f'{prefix}order_spectrum.png', runs), 'order spectrum'),
                          *self._waterfalls(folder, prefix, runs),
                          (self._trends(folder / f'{prefix}trends.png', sorted(runs, key=lambda r: r.start)),
                           'indicator trends')):
            if name:
                lines += [f'![{alt}]({name})', '']
        return lines + self._run_figures(folder, prefix, runs, budget)

    def _order_spectrum(self, path: Path, runs: Sequence[RunSummary]) -> str:
        """The order spectrum, the runs of each speed averaged, band edges marked where in range; '' if none."""
        from .. import condition_figures as figures
        groups = _speed_groups(runs)
        if not groups:
            return ''
        curves, edges = [], []
        for group in groups:
            mean = _nanmean([r.order_psd for r in group if r.order_psd is not None])
            shaft = group[0].speed / (2 * math.pi)
            band = f'; band {self.band[0] / shaft:.3g}-{self.band[1] / shaft:.4g}x' if self.band is not None else ''
            curves.append((f'{group[0].rpm:.0f} r/min ({len(group)} run{"s" if len(group) > 1 else ""}{band})',
                           _db(mean)))
            edges.append([(edge / shaft, f'{edge:g} Hz') for edge in (self.band or ())])
        figures.order_spectrum(path, ORDER_SPECTRUM_GRID, curves, edges,
                               'order spectrum, runs averaged per speed (dashed: analysis band edges)',
                               order_max=_covered(ORDER_SPECTRUM_GRID, [c for _, c in curves], ORDER_SPECTRUM_MAX))
        return path.name

    def _waterfalls(self, folder: Path, prefix: str, runs: Sequence[RunSummary]) -> list[tuple[str, str]]:
        """Envelope spectra of every run over run time, order spectra over speed: (file, alt text) of each drawn."""
        from .. import condition_figures as figures
        marks = defect_marks(self.orders)
        drawn = []
        enveloped = [(r, r.envelope_db) for r in sorted(runs, key=lambda r: r.start) if r.envelope_db is not None]
        if enveloped:
            times, unit, label = _time_axis(np.array([r.start for r, _ in enveloped]))
            rows = np.vstack([row for _, row in enveloped])
            name = f'{prefix}waterfall_envelope.png'
            figures.waterfall(folder / name, ORDER_GRID, rows,
                              [f'{t:.3g} {unit} (run {r.run_index})' for t, (r, _) in zip(times, enveloped)], label,
                              'envelope spectra of every run over run time (dB over floor; red: defect suspected)',
                              order_max=_covered(ORDER_GRID, list(rows), MAX_ORDER), marks=marks,
                              suspected=[r.suspected for r, _ in enveloped])
            drawn.append((name, 'envelope waterfall'))
        spectral = [(r, r.order_psd) for r in sorted(runs, key=lambda r: (r.speed, r.start)) if r.order_psd is not None]
        if spectral:
            rows = np.vstack([_db(psd) for _, psd in spectral])
            name = f'{prefix}waterfall_order.png'
            figures.waterfall(folder / name, ORDER_SPECTRUM_GRID, rows,
                              [f'{r.rpm:.0f} r/min (run {r.run_index})' for r, _ in spectral], 'screw speed',
                              'order spectra of every run over speed (dB re 1 (m/s^2)^2/Hz): a line at a fixed order '
                              'stays vertical, one at a fixed frequency slants',
                              order_max=_covered(ORDER_SPECTRUM_GRID, list(rows), ORDER_SPECTRUM_MAX), marks=marks,
                              suspected=[r.suspected for r, _ in spectral])
            drawn.append((name, 'order waterfall'))
        return drawn

    def _run_figures(self, folder: Path, prefix: str, runs: Sequence[RunSummary], budget: int) -> list[str]:
        """Envelope spectra of the most telling runs (suspected first, then the strongest line), at most ``budget``."""
        from .. import condition_figures as figures
        marks = defect_marks(self.orders)
        candidates = [(r, r.envelope_db) for r in runs if r.envelope_db is not None]
        if not candidates:
            return []
        candidates.sort(key=lambda item: (not item[0].suspected,
                                          -(item[0].line_db if math.isfinite(item[0].line_db) else -math.inf)))
        chosen = candidates[:max(0, budget)]
        lines = [f'Envelope spectra of {len(chosen)} of {len(candidates)} runs drawn (defect suspected first, then '
                 'the strongest line at a strike order); every run is in the waterfalls, the trends and the table.', '']
        for run, db in sorted(chosen, key=lambda item: item[0].start):
            name = f'{prefix}envelope_run{run.run_index}.png'
            highlight = None
            if run.suspected and math.isfinite(run.finding_order):
                level = _level_near(db, run.finding_order, run.envelope_resolution)
                highlight = (run.finding_order, level, f'{run.finding_order:.2f}x, {level:.0f} dB: '
                             f'{run.finding_component}')
            title = (f'{run.name}: {run.rpm:.0f} r/min, {run.load:.0f} N, kurtosis {_fmt(run.kurtosis)}, '
                     f'crest {_fmt(run.crest, 1)}' + ('  DEFECT SUSPECTED' if run.suspected else ''))
            figures.envelope_spectrum(folder / name, ORDER_GRID, db, marks, title,
                                      order_max=_covered(ORDER_GRID, [db], MAX_ORDER),
                                      threshold_db=self.rules.envelope_db, highlight=highlight)
            words = (f'**{run.name}:** defect suspected: {run.evidence}' if run.suspected else
                     f'**{run.name}:** no defect suspected; strongest line at a strike order '
                     f'{_fmt(run.line_db, 1)} dB ({run.line_component or "—"}, {_fmt(run.line_order)}x).')
            lines += [words, '', f'![envelope spectrum, run {run.run_index}]({name})', '']
        return lines

    def _trends(self, path: Path, runs: Sequence[RunSummary]) -> str:
        """Indicator trends of ``runs`` (in time order) with the screen's limits; the file's name."""
        from .. import condition_figures as figures
        x, _, label = _time_axis(np.array([r.start for r in runs]))
        rules, baseline = self.rules, self.baseline
        impulsive, strong, crest = screen_limits(baseline, rules)
        limits = [(2, rules.envelope_db, f'periodic from {rules.envelope_db:g} dB'), (3, 1.0, 'reference state 1')]
        if baseline is not None:
            limits.append((1, crest, f'strongly impulsive from {crest:.2f}'))
            if strong > impulsive + 0.005:
                limits.append((0, strong, f'strongly impulsive from {strong:.2f}'))
        else:
            limits.append((1, rules.healthy_crest, f'healthy crest factor up to {rules.healthy_crest:g}'))
        limits.append((0, impulsive, f'impulsive from {impulsive:.2f}'
                       + (' (strongly too)' if baseline is not None and strong <= impulsive + 0.005 else '')))
        figures.indicator_trends(path, x, label, [r.kurtosis for r in runs], [r.crest for r in runs],
                                 [r.line_db for r in runs], [r.theta for r in runs], [r.theta_std for r in runs],
                                 [r.suspected for r in runs],
                                 'condition indicators and theta_Oil per run (red x: defect suspected)',
                                 limits=limits, theta_flagged=[bool(r.theta_flag) for r in runs])
        return path.name

    def _table(self, runs: Sequence[RunSummary]) -> list[str]:
        lines = ['| run | start (UTC) | r/min | load N | kurtosis | crest | strongest strike-order line | '
                 'theta_Oil | flag | evidence |', '|---|---|---|---|---|---|---|---|---|---|']
        for r in runs[:MAX_TABLE_ROWS]:
            when = datetime.datetime.fromtimestamp(r.start, datetime.UTC).strftime('%Y-%m-%d %H:%M:%S')
            line = (f'{_fmt(r.line_db, 1)} dB at {_fmt(r.line_order)}x ({r.line_component})'
                    if math.isfinite(r.line_db) else '—')
            theta = f'{r.theta:.3f} ± {r.theta_std:.3f}' if math.isfinite(r.theta) else f'— ({r.reason})'
            flag = ('D' if r.suspected else '') + (' !' if r.theta_flag else '')
            lines.append(f'| {r.name} | {when} | {r.rpm:.0f} | {r.load:.0f} | {_fmt(r.kurtosis)} | {_fmt(r.crest)} | '
                         f'{line} | {theta} | {flag.strip() or "—"} | {_cell(r.evidence or r.theta_flag)} |')
        if len(runs) > MAX_TABLE_ROWS:
            lines += ['', f'Table cut at {MAX_TABLE_ROWS} of {len(runs)} runs; the JSON (--json) holds every run.']
        return lines

    def markdown(self, folder: str | Path, prefix: str = '', level: int = 2) -> list[str]:
        """Draw the figures into ``folder`` (names start with ``prefix``) and return the report's Markdown lines."""
        folder = Path(folder)
        runs = self.runs
        h = '#' * level
        lines = [f'{h} Condition indicators: is it lubrication or a surface defect?', '']
        lines += [f'**Defect orders of the actuator** (marked on every envelope spectrum; orders in multiples of the '
                  f'screw speed): {self._orders_words()}.', '']
        lines += [f'**Screen:** {self._screen_words()}.', '']
        lines += [line for note in self.notes for line in (note, '')]
        if not runs:
            return lines + ['No run was assessed: nothing to draw.', '']
        suspected = sum(r.suspected for r in runs)
        lines += [f'{len(runs)} runs in {len(self.recordings)} recording{"s" if len(self.recordings) > 1 else ""}; '
                  f'defect suspected in {suspected}: their theta_Oil is no lubrication measure.', '']
        if len(self.recordings) > 1:
            name = f'{prefix}trends_all.png'
            self._trends(folder / name, sorted(runs, key=lambda r: r.start))
            lines += [f'![indicator trends of every run]({name})', '']
        lines += self._table(runs) + ['']
        order = self._order()
        ranked = sorted(order, key=lambda p: (not any(r.suspected for r in self.recordings[p]), order.index(p)))
        sectioned = set(ranked[:MAX_SECTIONS])
        if len(order) > MAX_SECTIONS:
            left = [Path(p).name for p in order if p not in sectioned]
            lines += [f'Figures drawn for {MAX_SECTIONS} of {len(order)} recordings (those with a defect suspected '
                      f'first); not drawn: {", ".join(left[:20])}{", ..." if len(left) > 20 else ""} (their runs are '
                      'in the table' + (' and the trends above' if len(order) > 1 else '') + ').', '']
        allotted, budget = {}, MAX_RUN_FIGURES     # per-run figures, handed out in the order of priority
        for path in ranked[:MAX_SECTIONS]:
            allotted[path] = min(MAX_RUN_FIGURES_PER_SECTION, budget,
                                 sum(r.envelope_db is not None for r in self.recordings[path]))
            budget -= allotted[path]
        for number, path in enumerate(order):
            if path in sectioned:
                lines += self._section(folder, f'{prefix}rec{number}_', self.recordings[path], allotted[path],
                                       f'{h}# {path}')
        return lines

    def write(self, folder: str | Path) -> Path:
        """Figures, ``index.md`` and ``index.html`` in ``folder`` (each written atomically); the page's path."""
        folder = Path(folder)
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f'{folder}: cannot create report folder ({exc.strerror or exc})') from None
        try:
            text = '\n'.join([f'# {self.title}', ''] + self.markdown(folder))
            write_atomically(folder / 'index.md', lambda stream: stream.write(text), binary=False)
            page = markdown_html(text, self.title)
            write_atomically(folder / 'index.html', lambda stream: stream.write(page), binary=False)
        except OSError as exc:
            raise InputError(f'{folder}: cannot write the report ({exc.strerror or exc})') from None
        return folder / 'index.html'


def _cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return text.replace('|', '/') or '—'


def _covered(grid: np.ndarray, rows: Sequence[np.ndarray | None], limit: float) -> float:
    """Highest grid order any row holds a finite value at (at most ``limit``)."""
    highest = 0.0
    for row in rows:
        if row is not None:
            finite = np.flatnonzero(np.isfinite(row))
            if finite.size:
                highest = max(highest, float(grid[finite[-1]]))
    return min(limit, highest) if highest > 0 else limit


def _level_near(db: np.ndarray, order: float, resolution: float) -> float:
    """Largest level of ``db`` (on ORDER_GRID) within half a bin (or 3 %) of ``order``."""
    near = (np.abs(ORDER_GRID - order) <= max(0.03 * order, (resolution if math.isfinite(resolution) else 0) / 2))
    values = db[near & np.isfinite(db)]
    return float(values.max()) if values.size else math.nan


def markdown_html(markdown: str, title: str) -> str:
    """Minimal Markdown to HTML for the report pages: headings (#, ##, ###), bold, code, tables, images, lists."""
    body, in_table = [], False
    for line in markdown.split('\n'):
        text = html.escape(line)
        text = re.sub(r'\*\*(.+?)\*\*', r'<b>\1</b>', text)
        text = re.sub(r'`(.+?)`', r'<code>\1</code>', text)
        if line.startswith('|'):
            cells = [c.strip() for c in text.strip('|').split('|')]
            if set(line.replace('|', '').strip()) <= {'-'}:
                continue
            tag = 'th' if not in_table else 'td'
            if not in_table:
                body.append('<table border="1" cellspacing="0" cellpadding="3">')
                in_table = True
            body.append('<tr>' + ''.join(f'<{tag}>{c}</{tag}>' for c in cells) + '</tr>')
            continue
        if in_table:
            body.append('</table>')
            in_table = False
        image = re.match(r'!\[(.*)\]\((.*)\)', line)
        heading = re.match(r'(#{1,4}) (.*)', line)
        if image:
            body.append(f'<p><img src="{html.escape(image.group(2))}" alt="{html.escape(image.group(1))}" '
                        'style="max-width: 100%"></p>')
        elif heading:
            depth = len(heading.group(1))
            body.append(f'<h{depth}>{text[depth + 1:]}</h{depth}>')
        elif line.startswith('- '):
            body.append(f'<li>{text[2:]}</li>')
        elif line:
            body.append(f'<p>{text}</p>')
    if in_table:
        body.append('</table>')
    return (f'<!DOCTYPE html><html><head><meta charset="utf-8"><title>{html.escape(title)}</title></head>'
            '<body style="font-family: sans-serif; max-width: 1200px">' + '\n'.join(body) + '</body></html>')
