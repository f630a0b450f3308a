# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Is the vibration that of a surface defect rather than of the lubrication?  The decision, apart from the measures.

:mod:`.condition_indicators` measures each window; this module pools them
into a run (or the last windows of a live stream), keeps the healthy
distribution of the calibration recordings as a :class:`ConditionBaseline`,
and decides (:func:`screen`) whether a defect is suspected.  While one is,
theta_Oil is no lubrication measure: a spall raises the band RMS as oil loss
does, so Eq. 23 would read the damage as a loss of oil.

The rule, in the terms of envelope analysis ("impulsive *and* periodic at a
defect order"); thresholds are the fields of :class:`DefectRules`:

* **impulsive**: the run's median kurtosis beyond what healthy rolling contact
  gives anywhere (``healthy_kurtosis``, Gaussian vibration is 3) and beyond the
  calibration's typical healthy run by ``kurtosis_ratio``;
  **strongly impulsive**: also beyond every calibration run by
  ``kurtosis_margin`` (the baseline's upper end plus a stated margin), or the
  crest factor beyond every calibration run by ``crest_ratio`` and above
  ``healthy_crest``;
* **periodic at a defect order**: the run's envelope spectrum (the windows'
  order spectra averaged, so the noise floor is tight) holds a line at a
  strike order (a raceway pass or a rolling element, :data:`STRIKE_COMPONENTS`;
  carrier and cage orders modulate rather than strike) at least
  ``envelope_db`` over its floor; **strongly periodic**: also
  ``envelope_margin_db`` above the largest level the calibration runs show at
  that order, and at least ``unexplained_margin_db`` above every line of the
  run at an order no component explains (a machine modulates its vibration
  wherever no defect is: a line at a defect order below those is not
  specific to a defect);
* suspected when strongly impulsive, or strongly periodic, or impulsive and
  periodic together.

Without a baseline (calibration files written before it) the baseline terms
fall away and only the absolute ones hold; the assessment says so.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import numbers
from typing import Any, TYPE_CHECKING
import warnings

import numpy as np

from ..errors import InputError
from ..physics.defect_orders import label_order, ORDER_TOLERANCE
from .condition_indicators import (ConditionIndicators, envelope_peaks, EnvelopePeak, ORDER_GRID,
                                   order_spectrum_db, REPORT_DB, RUN_REPORT_DB)

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import numpy.typing as npt

    from ..physics.defect_orders import DefectOrder

__all__ = ['ConditionBaseline', 'DEFAULT_RULES', 'DefectFinding', 'DefectRules', 'NOT_SUSPECTED', 'RunCondition',
           'STRIKE_COMPONENTS', 'run_condition', 'screen', 'screen_limits', 'strike_line', 'strike_orders',
           'unexplained_level', 'below_unexplained']

#: Components whose defect is struck by passing contacts (their order is a strike rate).
STRIKE_COMPONENTS = ('screw raceway', 'nut raceway', 'roller', 'support bearing outer race',
                     'support bearing inner race', 'support bearing rolling element')


@dataclass(frozen=True)
class DefectRules:
    """Thresholds of :func:`screen`, each with where it comes from."""

    #: Kurtosis healthy rolling contact stays below anywhere: Gaussian is 3; healthy bearings read 2.9-4.1
    #: (FEMTO-ST PRONOSTIA early runs 2.9-3.8 per run median outside the calibration set, ISO 13373-3 practice).
    healthy_kurtosis: float = 4.0
    #: Impulsive: run kurtosis at least this times the calibration runs' median (a 25 % rise).
    kurtosis_ratio: float = 1.25
    #: Strongly impulsive: run kurtosis beyond the highest calibration run by this (kurtosis units).
    kurtosis_margin: float = 0.5
    #: Crest factor of Gaussian vibration over 1 s at 1-50 kHz is 3.7-4.4; strongly impulsive above this ...
    healthy_crest: float = 6.0
    #: ... and beyond the highest calibration run times this.
    crest_ratio: float = 1.25
    #: A line of the run's envelope spectrum at a strike order at least this far over the floor (dB); the run
    #: average of Gaussian noise stays within 3 dB of its floor, healthy machines' own lines reach 9 dB.
    envelope_db: float = 10.0
    #: Strongly periodic: also this far above the calibration runs' largest level at that order (dB).
    envelope_margin_db: float = 3.0
    #: Strongly periodic: also at least this far above every line of the run at an order no component explains
    #: (dB; None: not required). A machine makes lines wherever no defect is (a mode's ring beating with the
    #: orders, modulation): one that sits at a strike order is no more specific than they are. Healthy runs
    #: flagged by a line alone, 30 simulated seeds: 11 of 3,150 without it, 5 with it; defect runs 492 and 487
    #: of 1,080 (``benchmarks/defect_false_alarms.py``). Shaft-order lines (runout at 1x, 2x) and a defect's own
    #: sidebands are unlabelled too, and count here (docs/surface-defects.md).
    unexplained_margin_db: float | None = 0.0

    def __post_init__(self) -> None:
        """Reject thresholds that cannot separate anything."""
        for name in ('healthy_kurtosis', 'kurtosis_ratio', 'healthy_crest', 'crest_ratio'):
            value = getattr(self, name)
            if not (_real(value) and math.isfinite(value) and value > 0):
                raise InputError(f'defect rule {name}={value!r} must be a positive number')
        for name in ('kurtosis_margin', 'envelope_db', 'envelope_margin_db', 'unexplained_margin_db'):
            value = getattr(self, name)
            if name == 'unexplained_margin_db' and value is None:
                continue
            if not (_real(value) and math.isfinite(value) and value >= 0):
                raise InputError(f'defect rule {name}={value!r} must be a number >= 0')


def _real(value: object) -> bool:
    """A real number (numpy's too), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


DEFAULT_RULES = DefectRules()


@dataclass(frozen=True)
class RunCondition:
    """The condition indicators of a run (or of the last windows of a stream), pooled."""

    kurtosis: float                  # median over the windows
    crest_factor: float              # median over the windows
    envelope_peaks: tuple[EnvelopePeak, ...]   # of the averaged order spectrum
    windows: int
    order_resolution: float
    envelope: np.ndarray | None = field(default=None, compare=False, repr=False)   # averaged, on ORDER_GRID

    def level_at(self, order: float) -> float:
        """dB over the floor of the averaged envelope spectrum near ``order`` (within its tolerance), NaN if none."""
        if self.envelope is None:
            return math.nan
        db = order_spectrum_db(self.envelope)
        near = (np.abs(ORDER_GRID - order) <= max(ORDER_TOLERANCE * order, self.order_resolution / 2)) & np.isfinite(db)
        return float(db[near].max()) if near.any() else math.nan

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the contract's ``condition_indicators`` of a run."""
        return {'kurtosis': _rounded(self.kurtosis), 'crest_factor': _rounded(self.crest_factor),
                'envelope_peaks': [p.as_dict() for p in self.envelope_peaks], 'windows': self.windows,
                'order_resolution': _rounded(self.order_resolution)}


def _rounded(value: float) -> float | None:
    return round(float(value), 4) if math.isfinite(value) else None


def strike_orders(orders: Sequence[DefectOrder]) -> list[DefectOrder]:
    """The defect orders at which a defect is struck (:data:`STRIKE_COMPONENTS`)."""
    return [o for o in orders if o.component in STRIKE_COMPONENTS]


def run_condition(indicators: Sequence[ConditionIndicators], orders: Sequence[DefectOrder]) -> RunCondition:
    """Pool windows' indicators: medians of kurtosis and crest, the order spectra averaged and their peaks."""
    usable = [c for c in indicators if math.isfinite(c.kurtosis)]
    if not usable:
        return RunCondition(math.nan, math.nan, (), 0, math.nan)
    kurt = float(np.median([c.kurtosis for c in usable]))
    crest = float(np.median([c.crest_factor for c in usable]))
    spectra = [c.envelope for c in usable if c.envelope is not None]
    if not spectra:
        return RunCondition(kurt, crest, (), len(usable), math.nan)
    with np.errstate(invalid='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)    # orders no window reaches: NaN, said by none
        average = np.nanmean(np.vstack(spectra).astype(float), axis=0) if len(spectra) > 1 else spectra[0].astype(float)
    resolution = float(np.nanmedian([c.order_resolution for c in usable]))
    peaks = envelope_peaks(average, resolution, orders, RUN_REPORT_DB if len(spectra) > 1 else REPORT_DB)
    return RunCondition(kurt, crest, peaks, len(usable), resolution, average)


@dataclass(frozen=True)
class ConditionBaseline:
    """The healthy distribution of the indicators over the calibration runs (stored in the calibration file).

    Kurtosis and crest factor: median and largest run median.  Envelope: per
    strike order of the actuator, the largest level (dB over floor) a
    calibration run shows there.
    """

    runs: int
    kurtosis_median: float
    kurtosis_max: float
    crest_median: float
    crest_max: float
    envelope_levels: tuple[tuple[float, float], ...] = ()   # (order, largest dB of a calibration run)

    @classmethod
    def from_runs(cls, runs: Sequence[RunCondition], orders: Sequence[DefectOrder]) -> ConditionBaseline | None:
        """The baseline of healthy runs; None when no run has indicators."""
        usable = [r for r in runs if math.isfinite(r.kurtosis)]
        if not usable:
            return None
        kurt = np.array([r.kurtosis for r in usable])
        crest = np.array([r.crest_factor for r in usable])
        levels: list[tuple[float, float]] = []
        for item in strike_orders(orders):
            if any(abs(known - item.order) <= ORDER_TOLERANCE * known for known, _ in levels):
                continue   # an order two components share is one line
            values = [r.level_at(item.order) for r in usable]
            finite = [v for v in values if math.isfinite(v)]
            if finite:
                levels.append((round(item.order, 6), round(max(finite), 3)))
        return cls(len(usable), float(np.median(kurt)), float(kurt.max()), float(np.nanmedian(crest)),
                   float(np.nanmax(crest)), tuple(levels))

    def level_at(self, order: float) -> float:
        """The calibration runs' largest level at ``order`` (NaN if that order was not measured)."""
        for known, level in self.envelope_levels:
            if abs(known - order) <= ORDER_TOLERANCE * known:
                return level
        return math.nan

    def as_dict(self) -> dict[str, Any]:
        """As written under ``condition_baseline:`` in a calibration file."""
        return {'runs': self.runs, 'kurtosis_median': round(self.kurtosis_median, 6),
                'kurtosis_max': round(self.kurtosis_max, 6), 'crest_median': round(self.crest_median, 6),
                'crest_max': round(self.crest_max, 6),
                'envelope_levels': [{'order': o, 'db': d} for o, d in self.envelope_levels]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = 'calibration') -> ConditionBaseline:
        """Read it back; :class:`InputError` naming the field when a value is missing or not plausible."""
        if not isinstance(data, dict):
            raise InputError(f'{source}: condition_baseline must be a mapping')
        values: dict[str, Any] = {}
        for name, low in (('runs', 1), ('kurtosis_median', 1.0), ('kurtosis_max', 1.0), ('crest_median', 1.0),
                          ('crest_max', 1.0)):
            value = data.get(name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value) \
                    or value < low or value > 1e6:
                raise InputError(f'{source}: condition_baseline.{name} = {value!r} is not a number in [{low}, 1e6]')
            values[name] = int(value) if name == 'runs' else float(value)
        levels = data.get('envelope_levels', [])
        if not isinstance(levels, list):
            raise InputError(f'{source}: condition_baseline.envelope_levels must be a list')
        pairs = []
        for item in levels:
            pair = (item.get('order'), item.get('db')) if isinstance(item, dict) else (None, None)
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in pair):
                raise InputError(f'{source}: condition_baseline.envelope_levels entry {item!r} needs a finite '
                                 'order and db')
            order, db = float(pair[0]), float(pair[1])   # type: ignore[arg-type]
            if not (0 < order <= 1e3 and -100 <= db <= 200):
                raise InputError(f'{source}: condition_baseline.envelope_levels entry {item!r}: order must lie in '
                                 '(0, 1000], db in [-100, 200]')
            pairs.append((order, db))
        return cls(values['runs'], values['kurtosis_median'], values['kurtosis_max'], values['crest_median'],
                   values['crest_max'], tuple(pairs))


@dataclass(frozen=True)
class DefectFinding:
    """The decision on one run or window: suspected or not, and why (in words)."""

    suspected: bool
    evidence: str            # why suspected, or '' (or why it could not be judged)
    component: str = ''      # the component the envelope line points at ('' when none)
    order: float = math.nan  # that line's order

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {'defect_suspected': self.suspected, 'defect_evidence': self.evidence,
                'defect_component': self.component, 'defect_order': _rounded(self.order)}


NOT_SUSPECTED = DefectFinding(False, '')


def screen_limits(baseline: ConditionBaseline | None,
                  rules: DefectRules = DEFAULT_RULES) -> tuple[float, float, float]:
    """The screen's limits: (impulsive kurtosis, strongly impulsive kurtosis, strongly impulsive crest factor).

    Without a baseline only the absolute term holds: the strong limits are infinite.
    """
    if baseline is None:
        return rules.healthy_kurtosis, math.inf, math.inf
    impulsive = max(rules.healthy_kurtosis, rules.kurtosis_ratio * baseline.kurtosis_median)
    return (impulsive, max(impulsive, baseline.kurtosis_max + rules.kurtosis_margin),
            max(rules.healthy_crest, rules.crest_ratio * baseline.crest_max))


def screen(condition: RunCondition, orders: Sequence[DefectOrder], baseline: ConditionBaseline | None,
           rules: DefectRules = DEFAULT_RULES) -> DefectFinding:
    """Whether ``condition`` shows a surface defect (see module doc for the rule)."""
    if not math.isfinite(condition.kurtosis):
        return NOT_SUSPECTED
    kurt, crest = condition.kurtosis, condition.crest_factor
    kurt_limit, strong_kurt_limit, strong_crest_limit = screen_limits(baseline, rules)
    impulsive = kurt >= kurt_limit
    strongly_impulsive = kurt >= strong_kurt_limit or (math.isfinite(crest) and crest >= strong_crest_limit)
    line = strike_line(condition.envelope_peaks, orders, condition.order_resolution)
    periodic = line is not None and line.db >= rules.envelope_db
    strongly_periodic = False
    if periodic and baseline is not None and line is not None:
        known = baseline.level_at(_nearest_order(line.order, orders))
        strongly_periodic = (math.isfinite(known) and line.db >= known + rules.envelope_margin_db
                             and not below_unexplained(line.db, unexplained_level(condition.envelope_peaks), rules))
    if not (strongly_impulsive or strongly_periodic or (impulsive and periodic)):
        return NOT_SUSPECTED
    parts = []
    if impulsive or strongly_impulsive:
        parts.append(f'impulsive (kurtosis {kurt:.1f}, crest factor {crest:.1f}; healthy up to {kurt_limit:.1f})')
    if periodic and line is not None:
        parts.append(f'envelope line at {line.order:.2f}x screw speed, {line.db:.0f} dB over the floor: '
                     f'{line.component} defect suspected')
    component = line.component if periodic and line is not None else ''
    return DefectFinding(True, '; '.join(parts), component, line.order if periodic and line is not None else math.nan)


def strike_line(peaks: Sequence[EnvelopePeak], orders: Sequence[DefectOrder],
                resolution: float) -> EnvelopePeak | None:
    """The strongest of ``peaks`` at a strike order's fundamental, labelled with its component(s); None if none."""
    strikes = strike_orders(orders)
    best: EnvelopePeak | None = None
    for peak in peaks:
        label = label_order(peak.order, strikes, resolution / 2 if math.isfinite(resolution) else 0.0, harmonics=1)
        if label and (best is None or peak.db > best.db):
            best = EnvelopePeak(peak.order, peak.db, label)
    return best


def unexplained_level(peaks: Sequence[EnvelopePeak]) -> float:
    """dB over the floor of the largest of ``peaks`` at an order no component explains (unlabelled); 0 if none."""
    return max((p.db for p in peaks if not p.component), default=0.0)


def below_unexplained(line_db: npt.ArrayLike, unexplained_db: npt.ArrayLike,
                      rules: DefectRules = DEFAULT_RULES) -> np.ndarray:
    """Whether a strike-order line (dB) is below the run's unexplained line plus ``rules.unexplained_margin_db``.

    Element by element; False where either is NaN (not known: nothing to judge
    the line against) or the rule is off (margin None).
    """
    line = np.asarray(line_db, dtype=float)
    if rules.unexplained_margin_db is None:
        return np.zeros(line.shape, dtype=bool)
    with np.errstate(invalid='ignore'):
        return np.less(line, np.asarray(unexplained_db, dtype=float) + rules.unexplained_margin_db)


def _nearest_order(order: float, orders: Sequence[DefectOrder]) -> float:
    """The strike order nearest ``order``."""
    return min((o.order for o in strike_orders(orders)), key=lambda o: abs(o - order))
