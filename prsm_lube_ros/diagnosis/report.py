# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A one-minute report of a diagnosis: its figures, the condition figures, and a page (Markdown and HTML).

* ``residual.png`` — model error against the covariate that carries the
  mismatch, the paper's model beside the chosen one;
* ``runs.png`` — measured RMS against both models, run by run;
* ``candidates.png`` — held-out error of every candidate against the paper's;
* ``spectrum.png`` — median spectrum per screw speed with fixed lines marked
  (when spectra were kept);
* ``empirical.png`` — for physics outside the catalogue: run amplitudes against
  the paper's model over the located covariate, with the empirical term;
* ``condition_*.png`` — given the recordings, the condition report of
  :mod:`.condition_report` (order and envelope spectra with the defect orders,
  waterfalls, indicator trends per run) in a section of its own.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, cast, TYPE_CHECKING

import numpy as np

from ..atomic_file import write_atomically
from ..errors import InputError
from .condition_report import ConditionReport, markdown_html
from .empirical import causes
from .engine import Diagnosis, Status
from .fitting import ModelFit, predict_log

if TYPE_CHECKING:
    from collections.abc import Sequence
    from types import ModuleType

    from ..estimation.pipeline import RecordingWindows
    from .table import WindowTable

__all__ = ['LABELS', 'write_report']

LABELS = {'position': 'nut position along the stroke, mm', 'revolutions': 'revolutions since start of recording',
          'time': 'time since start of recording, s', 'temperature': 'temperature, degC',
          'speed': 'screw speed, rad/s', 'load': 'axial load, N',
          'direction': 'direction of travel (+1 out, -1 back)'}


def _finish(fig: Any, ax: Any, path: Path, plt: ModuleType, legend_size: int) -> None:
    """Legend, grid, layout; the figure written to ``path`` and closed."""
    ax.legend(fontsize=legend_size)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _pyplot() -> ModuleType:
    """matplotlib's pyplot, drawing without a display."""
    import matplotlib
    matplotlib.use('Agg', force=False)
    import matplotlib.pyplot as plt
    return plt


def _covariate(diagnosis: Diagnosis) -> str:
    """The covariate the residual figure is drawn against: the located one, else the chosen effect's."""
    located = diagnosis.location.located
    if located in LABELS:
        return located
    chosen = diagnosis.chosen or diagnosis.best
    return chosen.effect.covariate if chosen is not None and chosen.effect.covariate in LABELS else 'speed'


def _values(table: WindowTable, name: str) -> np.ndarray:
    """A column of ``table`` in the units of :data:`LABELS` (positions in mm)."""
    values = np.asarray(getattr(table, name), dtype=float)
    return values * 1e3 if name == 'position' else values


def _residual_figure(diagnosis: Diagnosis, path: Path, plt: ModuleType) -> None:
    """Model error against the covariate of the mismatch: the paper's model beside the chosen one(s)."""
    table = diagnosis.table
    assert table is not None  # diagnose_table always sets it
    name = _covariate(diagnosis)
    x = _values(table, name)
    panels = [('paper\'s model (Eq. 22)', diagnosis.baseline)]
    if diagnosis.chosen is not None:
        panels.append((f'with {diagnosis.chosen.effect.id}', cast(ModelFit, diagnosis.chosen.fit)))
        if diagnosis.second is not None and not diagnosis.second.unresolved:
            panels.append((f'and {diagnosis.second.effect.id}', diagnosis.second.fit))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 3.6), dpi=110, sharey=True,
                             squeeze=False)
    for ax, (title, fit) in zip(axes[0], panels):
        error = 100 * np.expm1(fit.log_residual)
        ax.scatter(x, error, c=table.run, cmap='tab20', s=10)
        ax.axhline(0, color='k', linewidth=0.8)
        ax.set_title(f'{title}: RMS error {100 * fit.rmse:.1f} %', fontsize=9)
        ax.set_xlabel(LABELS[name])
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel('model / measured - 1, %  (colour: run)')
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _empirical_figure(diagnosis: Diagnosis, path: Path, plt: ModuleType) -> bool:
    """Run amplitudes over the paper's model against the located covariate, with the empirical term."""
    empirical = diagnosis.empirical
    if empirical is None:
        return False
    table, term = diagnosis.table, empirical.term
    assert table is not None  # diagnose_table always sets it
    measured = 100 * np.expm1(-table.run_means(diagnosis.baseline.log_residual))
    term_only = 100 * np.expm1(table.run_means(empirical.fit.log_residual - diagnosis.baseline.log_residual))
    if term.form in ('step', 'stretch'):
        order = np.lexsort((table.run_means('time'), table.run_means(table.recording.astype(float))))
        x, label = np.arange(1, order.size + 1), 'run in recording order'
        measured, term_only = measured[order], term_only[order]
    elif term.form == 'direction':
        x, label = table.run_means('direction'), LABELS['direction']
    else:
        x, label = _values(table, term.covariate), LABELS.get(term.covariate, term.covariate)
        x = table.run_means(x)
    fig, ax = plt.subplots(figsize=(6.5, 3.8), dpi=110)
    ax.scatter(x, measured, s=14, label='measured / paper\'s model - 1 (run means)')
    shown = np.argsort(x, kind='stable')
    ax.plot(x[shown], term_only[shown], 'r.-' if term.form != 'direction' else 'r_', markersize=12,
            label=f'empirical {term.form}: {term.describe(empirical.fit.params)}')
    ax.axhline(0, color='k', linewidth=0.8)
    ax.set_xlabel(label)
    ax.set_ylabel('%')
    ax.set_title(f'outside the catalogue: {term.form} in {term.covariate}, held-out error '
                 f'{100 * empirical.gain:.0f} % lower', fontsize=9)
    _finish(fig, ax, path, plt, legend_size=7)
    return True


def _runs_figure(diagnosis: Diagnosis, path: Path, plt: ModuleType) -> None:
    """Measured RMS against the paper's and the chosen model, run by run."""
    table = diagnosis.table
    assert table is not None  # diagnose_table always sets it
    measured = table.run_means(table.rms)
    base = table.run_means(np.exp(predict_log(table, diagnosis.baseline.vector)))
    speeds, loads = table.run_means('speed'), table.run_means('load')
    order = np.arange(table.runs.size)
    fig, ax = plt.subplots(figsize=(max(6.0, 0.35 * order.size + 2), 3.6), dpi=110)
    ax.plot(order, measured, 'ko', label='measured')
    ax.plot(order, base, 'x', color='tab:red', label='paper\'s model', markersize=8)
    if diagnosis.chosen is not None:
        fit, effect = diagnosis.chosen.fit, diagnosis.chosen.effect
        assert fit is not None  # the chosen candidate was fitted
        chosen = table.run_means(np.exp(predict_log(table, fit.vector, effect, effect.scales(table))))
        ax.plot(order, chosen, '+', color='tab:green', label=f'with {effect.id}', markersize=10)
    ax.set_xticks(order, [f'{s * 30 / math.pi:.0f}/{f:.0f}' for s, f in zip(speeds, loads)], rotation=90,
                  fontsize=7)
    ax.set_xlabel('run in recorded order (r/min / N)')
    ax.set_ylabel('mean RMS, m/s$^2$')
    _finish(fig, ax, path, plt, legend_size=8)


def _candidates_figure(diagnosis: Diagnosis, path: Path, plt: ModuleType) -> None:
    """Held-out error of every fitted candidate against the paper's model."""
    fitted = sorted([c for c in diagnosis.candidates if c.fit is not None],
                    key=lambda c: -cast(ModelFit, c.fit).cv_rmse)
    fig, ax = plt.subplots(figsize=(7.0, 0.5 * len(fitted) + 1.4), dpi=110)
    colours = {Status.EARNS: 'tab:green', Status.REJECTED: 'tab:gray', Status.DROPPED: 'tab:orange'}
    for i, cand in enumerate(fitted):
        assert cand.fit is not None  # only fitted candidates are drawn
        ax.barh(i, 100 * cand.fit.cv_rmse, color=colours.get(cand.status, 'tab:gray'))
        ax.text(100 * cand.fit.cv_rmse, i, f' {100 * cand.gain:+.0f} %  ({cand.status})', va='center', fontsize=8)
    ax.axvline(100 * diagnosis.baseline.cv_rmse, color='tab:red', linestyle='--', label='paper\'s model')
    ax.set_yticks(range(len(fitted)), [c.effect.id for c in fitted], fontsize=8)
    ax.set_xlabel('relative RMS error on held-out runs, %  (label: gain over the paper\'s model)')
    ax.legend(fontsize=8, loc='lower right')
    ax.set_xlim(0, 100 * max([diagnosis.baseline.cv_rmse] + [cast(ModelFit, c.fit).cv_rmse for c in fitted]) * 1.5)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _spectrum_figure(diagnosis: Diagnosis, path: Path, plt: ModuleType) -> bool:
    """Median spectrum per screw speed with the fixed lines and modes marked; False without spectra."""
    table = diagnosis.table
    assert table is not None  # diagnose_table always sets it
    if table.spectra is None or not math.isfinite(table.spectrum_resolution):
        return False
    from ..estimation.calibration import operating_levels
    levels: np.ndarray = np.array(operating_levels(table.speed))
    index = np.argmin(np.abs(np.abs(table.speed)[:, None] - levels[None, :]), axis=1)
    freqs = np.arange(table.spectra.shape[1]) * table.spectrum_resolution
    fig, ax = plt.subplots(figsize=(7.0, 3.4), dpi=110)
    for i, level in enumerate(levels):
        ax.semilogy(freqs, np.nanmedian(table.spectra[index == i], axis=0), linewidth=0.9,
                    label=f'{level * 30 / math.pi:.0f} r/min')
    for f in diagnosis.location.spectrum.frequencies:
        ax.axvline(f, color='k', linestyle=':', linewidth=0.8)
    for f in diagnosis.location.spectrum.mode_frequencies:
        ax.axvline(f, color='tab:red', linestyle='--', linewidth=0.8)
    ax.set_xlabel('frequency, Hz (dotted: fixed lines with constant power; dashed: a band fixed in Hz whose power '
                  'follows the speed)', fontsize=8)
    ax.set_ylabel('PSD, (m/s$^2$)$^2$/Hz')
    _finish(fig, ax, path, plt, legend_size=8)
    return True


def _verdict_lines(diagnosis: Diagnosis) -> list[str]:
    """The page's verdict: the chosen effect(s) with their forms and models, or why none was chosen."""
    base = diagnosis.baseline
    lines = []
    if diagnosis.chosen is not None:
        cand = diagnosis.chosen
        assert cand.fit is not None  # the chosen candidate was fitted
        lines += [f'**Verdict: `{diagnosis.verdict}`** — {cand.effect.title}. Held-out error '
                  f'{100 * base.cv_rmse:.1f} % → {100 * cand.fit.cv_rmse:.1f} % ({100 * cand.gain:.0f} % lower).',
                  '']
        if diagnosis.second is not None and diagnosis.second.unresolved:
            lines += [f'**Two effects at once**: `{diagnosis.second.effect.id}` shown outside the amplitude fit, its '
                      'share of the RMS unresolved (the model is the first effect alone).', '']
        elif diagnosis.second is not None:
            lines += [f'**Two effects at once**: held-out error {100 * diagnosis.second.fit.cv_rmse:.1f} % with both '
                      f'(BIC {diagnosis.second.delta_bic:+.0f} against the first alone).', '']
        for effect, form, text in diagnosis.named_descriptions():
            lines += [f'**`{effect.id}`, form:** {form}', '', text, '',
                      f'Model: `{effect.equations}`', '']
        lines.pop()
    elif diagnosis.verdict == 'adequate':
        lines += ['**Verdict: `adequate`** — no candidate earns its extra parameters; the paper\'s model explains '
                  f'the recording to {100 * base.cv_rmse:.1f} % on held-out runs.']
    elif diagnosis.verdict == 'cannot tell':
        lines += ['**Verdict: `cannot tell`** — the paper\'s model fits, but the recordings hold too few speed and '
                  'load conditions beyond its three constants to test its form: a fit this good would come out '
                  'whatever the truth.']
    else:
        tied = f' — tied: {", ".join(diagnosis.tied)}' if diagnosis.tied else ''
        lines += [f'**Verdict: `{diagnosis.verdict}`**{tied}']
    return lines


def _page(diagnosis: Diagnosis, figures: list[str]) -> str:
    """The report page in Markdown: verdict, findings, the candidates' and the covariate tests' tables, figures."""
    base = diagnosis.baseline
    lines = ['# prsm-lube diagnose', '']
    lines += _verdict_lines(diagnosis)
    if diagnosis.empirical is not None:
        empirical = diagnosis.empirical
        lines += ['', f'**Physics outside the catalogue:** an empirical {empirical.term.form} in '
                  f'{empirical.term.covariate}: {empirical.term.describe(empirical.fit.params)}; held-out error '
                  f'{100 * base.cv_rmse:.1f} % → {100 * empirical.fit.cv_rmse:.1f} % ({100 * empirical.gain:.0f} % '
                  f'lower). No catalogue effect has this shape; {causes(empirical.term)}.']
    if diagnosis.what_to_record:
        lines += ['', f'**What to record:** {diagnosis.what_to_record}']
    lines += ['', f'**Where the model misses:** {diagnosis.location.summary}.']
    test: Any   # a lack-of-fit test (or None), then a covariate test
    for label, test in (('paper\'s model', diagnosis.baseline_fit_test), ('chosen model', diagnosis.chosen_fit_test)):
        if test is not None:
            lines += ['', f'**Lack of fit, {label}:** {test.sentence}.']
    for flag in diagnosis.calibration_flags:
        lines += ['', f'**Calibration flag:** {flag}.']
    lines.append('')
    for note in diagnosis.notes:
        lines.append(f'- {note}')
    lines += ['', '| candidate | status | held-out error | gain | ΔBIC | why |', '|---|---|---|---|---|---|',
              f'| paper\'s model | — | {100 * base.cv_rmse:.2f} % | — | — | C_sys {base.constants.c_sys:.4g}, '
              f'C_F {base.constants.c_f:.3g}, C_lambda {base.constants.c_lambda:.3g} |']
    for cand in sorted(diagnosis.candidates, key=lambda c: c.fit.cv_rmse if c.fit else math.inf):
        if cand.fit is None:
            lines.append(f'| {cand.effect.id} | {cand.status} | — | — | — | {cand.reason} |')
        else:
            lines.append(f'| {cand.effect.id} | {cand.status} | {100 * cand.fit.cv_rmse:.2f} % | '
                         f'{100 * cand.gain:+.0f} % | {cand.delta_bic:+.0f} | {cand.reason} |')
    lines += ['', '| covariate | test | share of residual variance | p | shape |', '|---|---|---|---|---|']
    for test in diagnosis.location.tests:
        lines.append(f'| {test.covariate} | {test.kind} | {100 * test.r_squared:.0f} % | {test.p_value:.2g} | '
                     f'{test.shape or "—"} |')
    lines.append('')
    for figure in figures:
        lines += [f'![{figure}]({figure})', '']
    return '\n'.join(lines)


def _html(markdown: str) -> str:
    """The report page as HTML (:func:`.condition_report.markdown_html`)."""
    return markdown_html(markdown, 'prsm-lube diagnose')


def _condition_section(diagnosis: Diagnosis, recordings: Sequence[RecordingWindows], folder: Path) -> list[str]:
    """The condition report of the diagnosed recordings (figures ``condition_*.png``), as Markdown lines.

    theta_Oil per run is what ``calibrate`` then ``assess`` on these same
    recordings reads (the paper's model); the defect screen has no healthy
    reference here (a baseline of the recordings themselves would hide a
    defect they all carry), so only its absolute limits apply.
    """
    from dataclasses import replace
    from ..estimation.pipeline import assess_recording, calibrate_recordings
    table = diagnosis.table
    theta = table.theta if table is not None else 1.0
    calibration = replace(calibrate_recordings(recordings, theta), condition_baseline=None)
    band = recordings[0].band
    report = ConditionReport(
        recordings[0].defect_orders, band=(band.low, band.high) if band is not None and band.chosen else None,
        notes=[f'theta_Oil per run: the paper\'s model calibrated on these recordings at theta_Oil = {theta:g} and '
               'read back (what `calibrate` then `assess` give); the screen has no healthy reference here, so only '
               'its absolute limits apply.'])
    for recording in recordings:
        report.add(assess_recording(recording, calibration), release=False)
    return report.markdown(folder, prefix='condition_')


def write_report(diagnosis: Diagnosis, folder: str | Path,
                 recordings: Sequence[RecordingWindows] | None = None) -> Path:
    """Write the figures, ``index.md`` and ``index.html`` into ``folder``; returns the HTML page's path.

    With the diagnosed ``recordings`` the page also holds their condition
    report (:mod:`.condition_report`: order and envelope spectra, waterfalls,
    indicator trends).  The page is written last, each file atomically.
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f'{folder}: cannot create report folder ({exc.strerror or exc})') from None
    plt = _pyplot()
    figures = []
    _residual_figure(diagnosis, folder / 'residual.png', plt)
    figures.append('residual.png')
    _runs_figure(diagnosis, folder / 'runs.png', plt)
    figures.append('runs.png')
    if any(c.fit is not None for c in diagnosis.candidates):
        _candidates_figure(diagnosis, folder / 'candidates.png', plt)
        figures.append('candidates.png')
    if _spectrum_figure(diagnosis, folder / 'spectrum.png', plt):
        figures.append('spectrum.png')
    if _empirical_figure(diagnosis, folder / 'empirical.png', plt):
        figures.append('empirical.png')
    markdown = _page(diagnosis, figures)
    if recordings:
        markdown += '\n' + '\n'.join(_condition_section(diagnosis, recordings, folder))
    write_atomically(folder / 'index.md', lambda stream: stream.write(markdown), binary=False)
    page = folder / 'index.html'
    text = _html(markdown)
    write_atomically(page, lambda stream: stream.write(text), binary=False)
    return page
