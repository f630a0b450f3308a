# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Least-squares fit of C_sys, C_F and C_lambda on windows at a known theta_Oil.

With theta_Oil known, Eq. 22 is linear in ``p = (ln C_sys, C_F, C_lambda)``::

    ln(A_0 omega_S^-2 F_a^(1/3)) = ln C_sys + C_F F_a - C_lambda theta_Oil omega_S^0.68 F_a^-0.073

so the constants follow from ordinary least squares on the steady windows of
reference recordings.  The three columns are only independent when the windows
span at least two axial loads and two screw speeds; anything less gets an
:class:`InputError` that says what to record, never a fit.

Standard errors come from a run-level variance model.  Windows of one run
share its set-up (mounting, sensor coupling, temperature, the oil film of that
traverse), so they are not independent: every run carries its own amplitude
factor.  :mod:`.run_scatter` estimates the run-to-run scatter ``tau`` and the
window scatter ``sigma_w`` by REML, and the constants' covariance is that of
the least-squares estimates under that model, as the standard deviation of a
Student t with ``runs - 3`` degrees of freedom (:class:`.run_scatter.RunScatter`).
The run scatter is kept in the calibration: a new run's theta_Oil carries it
(:mod:`.assessment`).  Without run labels every window counts as its own run.

The model's *form* is only tested by operating conditions beyond the three
constants: with three (speed, load) conditions the fit is exact whatever the
truth.  :class:`Calibration.flags` says so ("form untested: record N more
conditions") when fewer than :data:`MIN_SPARE_CONDITIONS` conditions are spare.
Levels closer than :data:`LEVEL_TOLERANCE` merge into one; set-points that
differ but merge (loads of 4000 and 4200 N) are named in
:attr:`Calibration.merged`, so a message can say what it counted.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, TYPE_CHECKING
from collections.abc import Iterable, Sequence

import numpy as np
import numpy.typing as npt

from ..errors import InputError
from ..physics.vibration_model import acceleration_amplitude, design_matrix, ModelConstants, reduced_log_amplitude
from .conditioning import AnalysisBand
from .defect_screen import ConditionBaseline
from .domain import CalibrationDomain
from .run_scatter import estimate_run_scatter, ols_covariance, RunScatter
from .windowing import MIN_AXIAL_LOAD, usable_windows

if TYPE_CHECKING:
    from .windowing import Window

__all__ = ['CONSTANTS', 'C_LAMBDA_IDENTIFIED', 'Calibration', 'LEVEL_TOLERANCE', 'MIN_SPARE_CONDITIONS',
           'MIN_WINDOWS', 'SETPOINT_TOLERANCE', 'calibration_flags', 'check_identifiable', 'condition_labels',
           'fit_constants', 'fit_windows', 'form_advice', 'form_flag', 'form_testable', 'merged_setpoints',
           'operating_conditions', 'operating_levels', 'replicated_conditions', 'run_level_covariance', 'scale_flag',
           'scatter_flags', 'sign_flags']

#: Relative tolerance within which two speeds or loads count as one operating level.
LEVEL_TOLERANCE = 0.05
#: Fewest windows for a fit with standard errors (three constants and one degree of freedom).
MIN_WINDOWS = 4
#: Constants of Eq. 22 fitted (ln C_sys, C_F, C_lambda).
CONSTANTS = 3
#: Operating conditions beyond the constants needed before the fit tests the model's form.
MIN_SPARE_CONDITIONS = 2
#: Relative tolerance within which run set-points count as the same set-point (finer than a level).
SETPOINT_TOLERANCE = 0.015


@dataclass(frozen=True)
class Calibration:
    """Fitted constants with their uncertainty and what they were fitted on."""

    constants: ModelConstants
    covariance: np.ndarray          # 3x3 covariance of (ln C_sys, C_F, C_lambda)
    fit_rmse: float                 # relative RMS error of the fitted amplitudes
    residual_std: float             # std of ln(A) residuals (window-to-window scatter), dimensionless
    windows_used: int
    reference_theta: float
    speed_levels: tuple = ()        # rad/s, distinct screw speeds in the data
    load_levels: tuple = ()         # N, distinct axial loads in the data
    sources: tuple = ()             # recordings the fit used
    extension: dict = field(default_factory=dict)  # model extension (effect id and parameters), if any
    conditions: int = 0             # distinct (speed level, load level) pairs in the data
    runs: int = 0                   # runs (clusters of the standard errors)
    standard_errors: str = ''       # how the covariance was computed
    merged: tuple = ()              # set-points merged into one level, in words ("loads 4000 and 4200 N")
    flags: tuple = ()               # what the fit cannot vouch for, in words ("form untested: ...")
    scatter: RunScatter | None = None   # run-to-run and window scatter (None: a file from before they were kept)
    band: AnalysisBand | None = None      # band of the window RMS fitted (conditioning); None: raw RMS (old files)
    domain: CalibrationDomain | None = None  # speed, load, temperature and sample-rate ranges fitted in
    #: Healthy distribution of the condition indicators over the calibration runs (None: an older file)
    condition_baseline: ConditionBaseline | None = None

    @property
    def run_scatter(self) -> RunScatter:
        """The run-level variance model; for a calibration file without one, its window scatter as run scatter."""
        if self.scatter is not None:
            return self.scatter
        return RunScatter(self.residual_std if math.isfinite(self.residual_std) else 0.0, 0.0, self.runs, 10 ** 6,
                          estimated=False, note='a calibration file without run-level scatter: its window '
                          'scatter taken as run scatter')

    @property
    def c_sys_factor(self) -> float:
        """One-sigma factor of C_sys: it is fitted in log space, so C_sys is known within x/ this factor."""
        return math.exp(math.sqrt(self.covariance[0, 0]))

    @property
    def c_sys_std(self) -> float:
        """One-sigma standard error of C_sys (delta method from ln C_sys)."""
        return self.constants.c_sys * math.sqrt(self.covariance[0, 0])

    @property
    def c_sys_text(self) -> str:
        """``C_sys = 0.0073 (x/ 1.04, 1 sigma)``: a factor, since C_sys is fitted as ln C_sys."""
        return f'{self.constants.c_sys:.6g} (x/ {self.c_sys_factor:.3g}, one sigma)'

    @property
    def c_f_std(self) -> float:
        """One-sigma standard error of C_F, 1/N."""
        return math.sqrt(self.covariance[1, 1])

    @property
    def c_lambda_std(self) -> float:
        """One-sigma standard error of C_lambda."""
        return math.sqrt(self.covariance[2, 2])

    @property
    def plan_summary(self) -> str:
        """What the fit counted: ``3 speeds x 2 loads (loads 4000 and 4200 N merged), 3 conditions``."""
        text = f'{len(self.speed_levels)} speeds x {len(self.load_levels)} loads'
        if self.merged:
            text += f' ({"; ".join(self.merged)} merged)'
        if self.conditions:
            text += f', {self.conditions} conditions'
        return text

    @property
    def summary(self) -> str:
        """One line on the fit for messages: plan, runs, standard errors and flags."""
        text = (f'fitted on {self.windows_used} windows, {self.plan_summary}'
                + (f', {self.runs} runs' if self.runs else '')
                + f'; relative RMS error {100 * self.fit_rmse:.2f} %')
        return text + ''.join(f'; {flag}' for flag in self.flags)


def operating_levels(values: Sequence[float] | np.ndarray, tolerance: float = LEVEL_TOLERANCE) -> list[float]:
    """Distinct levels in ``values``: sorted values closer than ``tolerance`` (relative) merge."""
    ordered = np.sort(np.abs(np.asarray(values, dtype=float)))
    levels: list[list[float]] = []
    for value in ordered:
        if levels and value <= levels[-1][0] * (1 + tolerance):
            levels[-1].append(value)
        else:
            levels.append([value])
    return [float(np.mean(group)) for group in levels]


def check_identifiable(speeds: Sequence[float] | np.ndarray,
                       loads: Sequence[float] | np.ndarray) -> tuple[list[float], list[float]]:
    """Raise :class:`InputError` saying what to record unless the data can identify all three constants.

    Returns the speed and load levels found.
    """
    n = len(speeds)
    speed_levels = operating_levels(speeds)
    load_levels = operating_levels(loads)
    if n == 0:
        raise InputError('calibration: no steady window with a screw speed and an axial load in the '
                         'recordings; record runs at constant speed under load (3 speeds x 2 loads as in the paper)')
    missing = []
    if len(load_levels) < 2:
        missing.append(_second_level('axial load', 'loads', loads, load_levels, 'N')
                       + '; C_sys and C_F cannot be told apart at one load')
    if len(speed_levels) < 2:
        missing.append(_second_level('screw speed', 'speeds', speeds, speed_levels, 'rad/s')
                       + '; C_lambda cannot be told from C_F with one speed')
    if not missing and operating_conditions(speeds, loads) < CONSTANTS:
        missing.append(_more_conditions(speeds, loads, speed_levels, load_levels))
    if n < MIN_WINDOWS:
        missing.append(f'more windows ({n} steady, need at least {MIN_WINDOWS}): longer runs or shorter windows')
    if missing:
        raise InputError('calibration cannot identify C_sys, C_F and C_lambda: record ' + '; and '.join(missing))
    return speed_levels, load_levels


def _second_level(what: str, plural: str, values: npt.ArrayLike, levels: Sequence[float], unit: str) -> str:
    """What to record when all windows sit at one level: a second one, naming set-points that merged."""
    merged = merged_setpoints(values, unit=unit, name=plural)
    if merged:
        return (f'a second {what} more than {100 * LEVEL_TOLERANCE:g} % from the others ({merged[0]} were '
                f'recorded, but lie within {100 * LEVEL_TOLERANCE:g} % of each other and count as one level)')
    return f'a second {what} (all windows at {_levels(levels, unit)})'


def _more_conditions(speeds: npt.ArrayLike, loads: npt.ArrayLike, speed_levels: Sequence[float],
                     load_levels: Sequence[float]) -> str:
    """What to record when there are two speeds and two loads but fewer (speed, load) pairs than constants."""
    speed, load = np.abs(np.asarray(speeds, float)), np.abs(np.asarray(loads, float))
    pairs = sorted(set(zip(_nearest_level(speed, speed_levels).tolist(), _nearest_level(load, load_levels).tolist())))
    named = ', '.join(f'{speed_levels[i]:.4g} rad/s at {load_levels[j]:.4g} N' for i, j in pairs)
    return (f'a third operating condition: the windows hold {len(pairs)} distinct (speed, load) pairs ({named}) '
            f'for {CONSTANTS} constants, each speed at one load only; a speed at a second load would do '
            '(3 speeds x 2 loads as in the paper)')


def _levels(levels: Iterable[float], unit: str) -> str:
    return ', '.join(f'{v:.4g} {unit}' for v in levels) or 'none'


def _nearest_level(values: np.ndarray, levels: Sequence[float] | np.ndarray) -> np.ndarray:
    levels = np.asarray(levels, dtype=float)
    return np.argmin(np.abs(np.abs(values)[:, None] - levels[None, :]), axis=1)


def _cluster_means(values: np.ndarray, clusters: npt.ArrayLike | None) -> np.ndarray:
    if clusters is None:
        return values
    _, index = np.unique(clusters, return_inverse=True)
    return np.bincount(index, weights=values) / np.bincount(index)


def merged_setpoints(values: npt.ArrayLike, clusters: npt.ArrayLike | None = None, unit: str = '',
                     name: str = 'values') -> list[str]:
    """Set-points (run means, or values without ``clusters``) that differ yet merge into one level, in words."""
    magnitudes = np.abs(np.asarray(values, dtype=float))
    setpoints = operating_levels(_cluster_means(magnitudes, clusters), SETPOINT_TOLERANCE)
    levels = operating_levels(setpoints)
    nearest = _nearest_level(np.asarray(setpoints), levels)
    words = []
    for level_index in np.unique(nearest):
        group = [p for p, k in zip(setpoints, nearest) if k == level_index]
        if len(group) > 1:
            words.append(f'{name} ' + ' and '.join(f'{v:.4g}' for v in group) + (f' {unit}' if unit else ''))
    return words


def condition_labels(speeds: npt.ArrayLike, loads: npt.ArrayLike) -> np.ndarray:
    """Index of each (speed, load)'s condition: its pair of operating levels (:func:`operating_levels`)."""
    speed, load = np.abs(np.asarray(speeds, float)), np.abs(np.asarray(loads, float))
    if speed.size == 0:
        return np.zeros(0, dtype=int)
    pairs = np.column_stack([_nearest_level(speed, operating_levels(speed)),
                             _nearest_level(load, operating_levels(load))])
    _, labels = np.unique(pairs, axis=0, return_inverse=True)
    return np.asarray(labels).reshape(-1)


def operating_conditions(speeds: npt.ArrayLike, loads: npt.ArrayLike) -> int:
    """Distinct (speed level, load level) pairs among the windows."""
    return int(np.unique(condition_labels(speeds, loads)).size)


def form_testable(conditions: int) -> bool:
    """Whether ``conditions`` (speed, load) pairs leave any beyond the constants to test the model's form."""
    return conditions > CONSTANTS


def form_advice(conditions: int) -> str:
    """What to record so that a plan of ``conditions`` tests the model's form ('' if it does)."""
    more = MIN_SPARE_CONDITIONS - (conditions - CONSTANTS)
    if more <= 0:
        return ''
    return f'record {more} more condition (speed and load pair)' if more == 1 else \
        f'record {more} more conditions (speed and load pairs)'


def form_flag(conditions: int) -> str:
    """Flag for a plan with too few conditions beyond the constants to test the model's form ('' if enough)."""
    spare = conditions - CONSTANTS
    advice = form_advice(conditions)
    if not advice:
        return ''
    if spare <= 0:
        return (f'form untested: {advice}; {conditions} conditions '
                f'for {CONSTANTS} constants fit exactly whatever the truth')
    return f'form weakly tested: {advice}; {conditions} conditions leave one beyond the {CONSTANTS} constants'


def run_level_covariance(x: np.ndarray, residual: np.ndarray,
                         clusters: npt.ArrayLike | None = None) -> tuple[np.ndarray, RunScatter, str]:
    """Covariance of least-squares parameters under the run-effect model (see module doc).

    ``x`` the design (or an extended model's Jacobian), ``residual`` its ln
    residuals, ``clusters`` one run label per window (None: each window a run).
    Returns the covariance, the run scatter and how it was computed, in words.
    """
    runs = np.arange(len(residual)) if clusters is None else np.asarray(clusters)
    scatter = estimate_run_scatter(x, residual, runs)
    covariance = ols_covariance(x, runs, scatter)
    labels = '' if clusters is not None else '; no run labels: each window taken as its own run'
    return covariance, scatter, f'least squares under a random run effect ({scatter.summary}{labels})'


def scatter_flags(scatter: RunScatter, replicated: bool) -> list[str]:
    """What the run-level variance model cannot vouch for, in words."""
    if not scatter.estimated and scatter.note:
        return []
    if not scatter.estimated:
        return [f'run scatter not estimable: {scatter.runs} runs for {CONSTANTS} constants; theta\'s sigma '
                f'assumes {100 * scatter.run_std:.0f} % run-to-run scatter (record each condition in two runs '
                'or more)']
    if not replicated:
        return ['no condition repeated: the run-to-run scatter is estimated from the model\'s residuals and '
                'includes whatever the model misses (record each condition in two runs or more)']
    return []


def sign_flags(constants: ModelConstants) -> list[str]:
    """Constants with a sign Eq. 18-22 do not allow, in words (flagged like an unphysical theta_Oil)."""
    flags = []
    if constants.c_f < 0:
        flags.append(f'C_F = {constants.c_f:.3g} 1/N < 0 is unphysical: the load excitation factor '
                     'exp(C_F F_a) (Eq. 18) would fall as the load rises; the fit absorbs something the model '
                     'leaves out (check the load signal and the speed and load range)')
    if not constants.c_lambda > 0:
        flags.append(f'C_lambda = {constants.c_lambda:.3g} <= 0 is unphysical: the oil film would raise the '
                     'vibration (Eq. 19)')
    return flags


#: Relative one-sigma of C_lambda above which theta_Oil's scale counts as not identified.
C_LAMBDA_IDENTIFIED = 0.3


def scale_flag(constants: ModelConstants, covariance: np.ndarray) -> str:
    """When C_lambda, the scale of theta_Oil - 1 (Eq. 23), is not identified by the fit ('' when it is)."""
    spread = math.sqrt(max(float(covariance[2, 2]), 0.0))
    relative = spread / abs(constants.c_lambda) if constants.c_lambda else math.inf
    if relative <= C_LAMBDA_IDENTIFIED:
        return ''
    return (f'C_lambda not identified (one sigma {100 * relative:.0f} % of its value): a change of theta_oil is '
            'detected against its sigma, but how large it is is uncertain by that factor; record speeds and loads '
            'that vary independently (3 speeds x 2 loads)')


def replicated_conditions(speeds: Sequence[float] | np.ndarray, loads: Sequence[float] | np.ndarray,
                          clusters: npt.ArrayLike | None) -> bool:
    """Whether some (speed, load) condition was recorded in two runs or more."""
    if clusters is None or len(speeds) == 0:
        return False
    runs_of: dict[Any, set] = {}
    for condition, run in zip(condition_labels(speeds, loads).tolist(), np.asarray(clusters).tolist()):
        runs_of.setdefault(condition, set()).add(run)
    return any(len(runs) > 1 for runs in runs_of.values())


def fit_constants(speeds: npt.ArrayLike, loads: npt.ArrayLike, amplitudes: npt.ArrayLike, theta: float = 1.0, *,
                  sources: Sequence[str] = (), clusters: npt.ArrayLike | None = None) -> Calibration:
    """Fit Eq. 22 by least squares on windows at lubrication state ``theta``.

    speeds in rad/s, loads in N, amplitudes (window RMS) in m/s^2, theta
    dimensionless (the reference state, 1 = fully lubricated); ``clusters``
    one run label per window (the runs of the run-level variance model).
    """
    speed = np.abs(np.asarray(speeds, dtype=float))
    load = np.abs(np.asarray(loads, dtype=float))
    amplitude = np.asarray(amplitudes, dtype=float)
    if not (math.isfinite(theta) and theta > 0):
        raise InputError(f'calibration: reference theta {theta!r} must be a positive number')
    usable = (np.isfinite(speed) & np.isfinite(load) & np.isfinite(amplitude)
              & (speed > 0) & (load > 0) & (amplitude > 0))
    speed, load, amplitude = speed[usable], load[usable], amplitude[usable]
    if clusters is not None:
        clusters = np.asarray(clusters)[usable]
    speed_levels, load_levels = check_identifiable(speed, load)
    x = design_matrix(speed, load, theta)
    y = reduced_log_amplitude(amplitude, speed, load)
    # Scale columns so the conditioning test means something whatever the units.
    scale = np.linalg.norm(x, axis=0)
    xs = x / scale
    singular = np.linalg.svd(xs, compute_uv=False)
    if singular[-1] < 1e-9 * singular[0]:
        raise InputError('calibration cannot identify C_sys, C_F and C_lambda: the '
                         f'{operating_conditions(speeds, loads)} (speed, load) conditions recorded leave the fit '
                         'degenerate; record each speed at a second load (3 speeds x 2 loads as in the paper)')
    solution, *_ = np.linalg.lstsq(xs, y, rcond=None)
    params = solution / scale
    residual = y - x @ params
    dof = max(len(y) - 3, 1)
    residual_var = float(residual @ residual) / dof
    covariance, scatter, method = run_level_covariance(x, residual, clusters)
    constants = ModelConstants.from_vector(params)
    fitted = acceleration_amplitude(speed, load, theta, constants)
    fit_rmse = float(np.sqrt(np.mean((fitted / amplitude - 1.0) ** 2)))
    conditions = operating_conditions(speed, load)
    merged = (merged_setpoints(speed, clusters, 'rad/s', 'speeds')
              + merged_setpoints(load, clusters, 'N', 'loads'))
    flags = calibration_flags(conditions, scatter, replicated_conditions(speed, load, clusters), constants,
                              covariance)
    return Calibration(constants=constants, covariance=covariance, fit_rmse=fit_rmse,
                       residual_std=math.sqrt(residual_var), windows_used=int(len(y)),
                       reference_theta=float(theta), speed_levels=tuple(speed_levels),
                       load_levels=tuple(load_levels), sources=tuple(str(s) for s in sources),
                       conditions=conditions, runs=int(np.unique(clusters).size) if clusters is not None else 0,
                       standard_errors=method, merged=tuple(merged), flags=flags, scatter=scatter)


def calibration_flags(conditions: int, scatter: RunScatter, replicated: bool, constants: ModelConstants,
                      covariance: np.ndarray) -> tuple[str, ...]:
    """Every flag of a fit: untested form, run scatter it cannot estimate, unphysical signs, theta's scale."""
    flags = [form_flag(conditions)] + scatter_flags(scatter, replicated) + sign_flags(constants)
    return tuple(flag for flag in flags + [scale_flag(constants, covariance)] if flag)


def fit_windows(windows: Iterable[Window], theta: float = 1.0, *, min_axial_load: float = MIN_AXIAL_LOAD,
                sources: Sequence[str] = (), recordings: Iterable[object] | None = None) -> Calibration:
    """Fit on the steady windows (see :mod:`.windowing`) whose load is at least ``min_axial_load``.

    Runs of the variance model are ``(recording, run_index)``, with
    ``recordings`` one recording label per window (all one recording if None).
    """
    windows = list(windows)
    labels = list(recordings) if recordings is not None else [0] * len(windows)
    chosen_ids = {id(w) for w in usable_windows(windows, min_axial_load)}
    chosen = [(w, label) for w, label in zip(windows, labels) if id(w) in chosen_ids]
    runs = [f'{label}#{w.run_index}' for w, label in chosen]
    return fit_constants([w.screw_speed for w, _ in chosen], [w.axial_load for w, _ in chosen],
                         [w.vibration_rms for w, _ in chosen], theta, sources=sources, clusters=runs)
