# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Fit Eq. 22 alone and extended by each candidate effect; score on held-out runs.

Every model is fitted by least squares on ``ln A`` (window RMS), so residuals
are relative errors.  The baseline is the paper's model (ordinary least squares
in ``(ln C_sys, C_F, C_lambda)``, as :mod:`prsm_lube_ros.estimation.calibration`); an
extended model adds the effect's parameters and is fitted jointly with the
constants (bounded trust-region least squares, multi-start).

Scores:

* ``rmse``: relative RMS error ``A_model / A - 1`` over the windows fitted;
* ``cv_rmse``: the same on runs held out of the fit (leave one run out; folds
  that would leave fewer than two speeds or two loads to fit are skipped for
  every model alike); ``cv_run_rmse`` the same for run amplitudes (windows
  pooled per run), where the window scatter averages out;
* ``bic``: BIC on window log residuals with an effective sample size
  ``n / (1 + (m - 1) ICC)`` (``m`` windows per run, ICC of the residuals
  between runs), because windows of one run are not independent.
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
import math
import warnings
from typing import Any, TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares, lsq_linear

from ..estimation.calibration import operating_levels, run_level_covariance
from ..physics.vibration_model import FREQUENCY_EXPONENT, ModelConstants, STIFFNESS_EXPONENT
from .table import WindowTable

if TYPE_CHECKING:
    from .effects import Effect
    from .table import Columns

__all__ = ['BASELINE', 'BASE_PARAMETERS', 'MAX_STARTS', 'ModelFit', 'PHYSICAL_START', 'UNPHYSICAL_SIGMAS', 'bic',
           'constants_jacobian', 'cv_folds', 'effective_sample_size', 'fit_model', 'fit_vector',
           'held_out_log_residuals', 'identifiable', 'intraclass_correlation', 'ln_eq22', 'predict_log',
           'relative_errors', 'relative_rmse', 'run_deviations', 'run_level_rmse', 'score_held_out',
           'within_run_delta_bic', 'within_run_correlation', 'within_run_gain', 'within_run_residual',
           'within_run_sample_size', 'within_run_share']

BASELINE = 'baseline'
#: Starts of an effect's own grid that are optimised (those with the lowest initial cost).
MAX_STARTS = 4
#: Parameters of the paper's model.
BASE_PARAMETERS = 3
#: Where a fit with C_lambda held physical starts C_lambda when the free start lies below 0.
PHYSICAL_START = 1e-3
#: A fit's C_lambda is unphysical when it lies below 0 by more than this many standard errors.
UNPHYSICAL_SIGMAS = 2.0


def ln_eq22(table: Columns, vector: np.ndarray, film_factor: float | np.ndarray = 1.0) -> np.ndarray:
    """ln A_0 of Eq. 22 with theta_Oil scaled by ``film_factor``; vector = (ln C_sys, C_F, C_lambda)."""
    speed = np.abs(np.asarray(table.speed, dtype=float))
    load = np.abs(np.asarray(table.load, dtype=float))
    return (vector[0] + FREQUENCY_EXPONENT * np.log(speed) - STIFFNESS_EXPONENT * np.log(load)
            + vector[1] * load - vector[2] * table.theta * film_factor * table.film_term)


def predict_log(table: Columns, vector: np.ndarray, effect: Effect | None = None,
                scales: dict[str, Any] | None = None) -> np.ndarray:
    """ln A of the model: Eq. 22 (``effect`` None) or Eq. 22 extended by ``effect``.

    ``vector`` holds (ln C_sys, C_F, C_lambda) followed by the effect's internal parameters.
    """
    if effect is None:
        return ln_eq22(table, vector)
    params = effect.to_params(np.asarray(vector[3:]), scales or {})
    base = ln_eq22(table, vector, effect.film_factor(params, table))
    return base + effect.log_gain(params, table, base)


def _ols_constants(table: Columns, film_factor: float | np.ndarray = 1.0,
                   offset: float | np.ndarray = 0.0, physical: bool = False) -> np.ndarray:
    """(ln C_sys, C_F, C_lambda) by OLS with the film column scaled and ``offset`` removed from ln A.

    ``physical``: C_lambda held at 0 or above (bounded least squares; Eq. 22: a thicker film never raises the
    vibration).
    """
    load = np.abs(table.load)
    x = np.column_stack([np.ones(len(table)), load, -table.theta * film_factor * table.film_term])
    y = table.reduced - offset
    scale = np.linalg.norm(x, axis=0)
    scale[scale == 0] = 1.0
    solution, *_ = np.linalg.lstsq(x / scale, y, rcond=None)
    if physical and solution[2] < 0:
        solution = lsq_linear(x / scale, y, bounds=([-np.inf, -np.inf, 0.0], np.inf)).x
    return solution / scale


class _CachedColumns:
    """The table's columns and derived arrays (film term, log RMS), each computed once for a fit's many calls."""

    def __init__(self, table: WindowTable) -> None:
        self._table = table

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._table, name)
        setattr(self, name, value)
        return value

    def __len__(self) -> int:
        return len(self._table)


def fit_vector(table: WindowTable, effect: Effect | None = None, scales: dict[str, Any] | None = None,
               starts: Sequence[npt.ArrayLike] | None = None, physical: bool = False,
               excitation: bool = False) -> np.ndarray:
    """Least-squares parameter vector of the baseline or of Eq. 22 extended by ``effect``.

    ``starts``: internal effect parameter vectors (or full vectors) to start from;
    default the effect's own multi-start grid.  ``physical``: C_lambda held at
    0 or above (a thicker film never raises the vibration, Eq. 22), for an
    effect whose free fit trades C_lambda against its own parameters.
    ``excitation``: C_F held at 0 or above too (Eq. 18: the load excites the
    contacts through friction and sliding, it does not silence them), for an
    effect whose free fit traded C_F against its own law of load until a
    measurement contradicted it (:meth:`.effects.Effect.measured_against`).
    """
    if effect is None:
        return _ols_constants(table, physical=physical)
    baseline = _ols_constants(table)
    scales = scales if scales is not None else effect.scales(table)
    lo, hi = effect.bounds()
    lower = np.r_[-np.inf, 0.0 if excitation else -np.inf, 0.0 if physical else -np.inf, lo]
    upper = np.r_[np.inf, np.inf, np.inf, hi]
    floor = np.r_[-np.inf, lower[1], PHYSICAL_START if physical else -np.inf]    # where a start's constants begin
    y = table.log_rms
    columns = _CachedColumns(table)

    def residual(vector: np.ndarray) -> np.ndarray:
        return predict_log(columns, vector, effect, scales) - y

    candidates: list[tuple[float, int, np.ndarray]] = []
    for start in (starts if starts is not None else effect.starts()):
        start = np.asarray(start, dtype=float)
        if start.size == 3 + lo.size:
            x0 = start.copy()
        else:
            params = effect.to_params(start, scales)
            film = effect.film_factor(params, columns)
            gain = effect.log_gain(params, columns, ln_eq22(columns, baseline))
            x0 = np.r_[_ols_constants(columns, film, gain), start]
        x0[3:] = np.clip(x0[3:], lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        x0[:3] = np.maximum(x0[:3], floor)
        r0 = residual(x0)
        if np.all(np.isfinite(r0)):
            candidates.append((float(r0 @ r0), len(candidates), x0))
    best, best_cost = None, math.inf
    # Starts given explicitly are all tried; of a grid, the MAX_STARTS that fit best to begin with.
    for initial, _, x0 in sorted(candidates)[:None if starts is not None else MAX_STARTS]:
        try:
            with warnings.catch_warnings():     # the NaN below, met inside the solver first
                warnings.simplefilter('ignore', RuntimeWarning)
                result = least_squares(residual, x0, bounds=(lower, upper), x_scale='jac', max_nfev=300)
            x, cost = (result.x, result.cost) if np.all(np.isfinite(result.fun)) else (x0, math.inf)
        except ValueError:
            # A step met a point where the law is not finite (NaN in the Jacobian): the start itself stands.
            x, cost = x0, 0.5 * initial
        if cost < best_cost:
            best, best_cost = x, cost
    if best is None:
        best = np.r_[baseline, np.clip(np.asarray(effect.starts()[0], float), lo, hi)]
    return best


def relative_errors(log_residual: npt.ArrayLike) -> np.ndarray:
    """Relative amplitude errors ``A_model / A - 1`` from log residuals ``ln A_model - ln A``."""
    return np.expm1(np.asarray(log_residual, dtype=float))


def relative_rmse(log_residual: npt.ArrayLike) -> float:
    """RMS of the relative errors over the finite entries."""
    errors = relative_errors(log_residual)
    errors = errors[np.isfinite(errors)]
    return float(np.sqrt(np.mean(errors ** 2))) if errors.size else math.nan


def run_level_rmse(table: WindowTable, log_residual: np.ndarray) -> float:
    """Relative RMS error of run amplitudes (windows pooled in power per run) over runs with finite residuals.

    Window-to-window scatter averages out, so this measures the model's error, not the noise.
    """
    errors = []
    for run in table.runs:
        sel = (table.run == run) & np.isfinite(log_residual)
        if sel.any():
            power = table.rms[sel] ** 2
            errors.append(math.sqrt(np.mean(power * np.exp(2 * log_residual[sel])) / np.mean(power)) - 1.0)
    return float(np.sqrt(np.mean(np.square(errors)))) if errors else math.nan


def identifiable(table: WindowTable) -> bool:
    """True when the windows span two speed levels and two load levels (the constants are identifiable)."""
    return len(table) >= 4 and len(operating_levels(table.speed)) >= 2 and len(operating_levels(table.load)) >= 2


def cv_folds(table: WindowTable) -> list[int]:
    """Runs that can be held out: the rest still identifies the constants."""
    return [int(r) for r in table.runs if identifiable(table.subset(table.run != r))]


def held_out_log_residuals(table: WindowTable, effect: Effect | None, scales: dict[str, Any] | None,
                           full_vector: np.ndarray, folds: Iterable[int], physical: bool = False,
                           excitation: bool = False) -> np.ndarray:
    """Leave-one-run-out log residuals (prediction minus measurement); NaN for runs not held out.

    ``physical``, ``excitation``: each fold fitted with C_lambda (and C_F) held at 0 or above, as the fit it scores.
    """
    out = np.full(len(table), np.nan)
    for run in folds:
        held = table.run == run
        train = table.subset(~held)
        starts = None if effect is None else [full_vector]
        vector = fit_vector(train, effect, scales, starts=starts, physical=physical, excitation=excitation)
        # Predicted on the whole table: effects with a history (recovery at rest) see the windows before.
        out[held] = (predict_log(table, vector, effect, scales) - table.log_rms)[held]
    return out


def intraclass_correlation(residual: npt.ArrayLike, groups: npt.ArrayLike) -> tuple[float, float]:
    """One-way ANOVA ICC of ``residual`` between ``groups`` and the mean group size m0."""
    residual = np.asarray(residual, dtype=float)
    means, inverse, sizes = _group_means(residual, np.asarray(groups))
    n, k = residual.size, sizes.size
    if k < 2 or n <= k:
        return 0.0, float(n / max(k, 1))
    grand = residual.mean()
    msb = float(np.sum(sizes * (means - grand) ** 2) / (k - 1))
    msw = float(np.sum((residual - means[inverse]) ** 2) / (n - k))
    m0 = float((n - np.sum(sizes ** 2) / n) / (k - 1))
    denominator = msb + (m0 - 1) * msw
    icc = (msb - msw) / denominator if denominator > 0 else 0.0
    return float(np.clip(icc, 0.0, 1.0)), m0


def effective_sample_size(residual: np.ndarray, groups: npt.ArrayLike) -> float:
    """``n / (1 + (m0 - 1) ICC)``: windows counted as independent observations."""
    icc, m0 = intraclass_correlation(residual, groups)
    return float(len(residual) / (1.0 + max(m0 - 1.0, 0.0) * icc))


def bic(log_residual: npt.ArrayLike, n_params: int, n_eff: float) -> float:
    """Gaussian BIC with ``n_eff`` observations: ``n_eff ln(SSR/n) + k ln(n_eff)``."""
    r = np.asarray(log_residual, dtype=float)
    ssr = float(np.mean(r ** 2))
    return float(n_eff * math.log(max(ssr, 1e-300)) + n_params * math.log(max(n_eff, 2.0)))


def within_run_residual(table: WindowTable, residual: npt.ArrayLike) -> tuple[np.ndarray, float]:
    """``residual`` less its run means, and how many windows it counts as independent.

    With n windows in R runs the deviations have n_w = n - R degrees of
    freedom, counted as n_w (1 - rho) / (1 + rho) (at least 2), rho the lag-1
    autocorrelation between consecutive windows of a run in time, in
    [0, 0.95]: a slow wander within runs is not taken for independent windows.
    Taking out run means biases the raw estimate r by -(1 + 3 rho) / m on runs
    of m windows (m the mean, at least 4), so rho = (r + 1/m) / (1 - 3/m).
    """
    return _deviations(np.asarray(residual, dtype=float), table.run, table.time)


def _group_means(values: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mean of ``values`` in each group, each value's group (index into the means) and the group sizes."""
    _, inverse, sizes = np.unique(groups, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    return np.bincount(inverse, values, minlength=sizes.size) / sizes, inverse, sizes


def run_deviations(values: np.ndarray, run: np.ndarray) -> np.ndarray:
    """``values`` less the mean of their run."""
    means, inverse, _ = _group_means(values, run)
    return values - means[inverse]


def _deviations(residual: np.ndarray, run: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`within_run_residual` on the windows' ``run`` and ``time`` columns."""
    means, inverse, sizes = _group_means(residual, run)
    within = residual - means[inverse]
    order = np.lexsort((time, run))
    ordered, runs = within[order], run[order]
    same = runs[1:] == runs[:-1]
    power = float(ordered @ ordered)
    raw = float(ordered[1:][same] @ ordered[:-1][same]) / power if same.any() and power > 0 else 0.0
    m = max(float(sizes.mean()), 4.0)
    rho = min(max((raw + 1.0 / m) / (1.0 - 3.0 / m), 0.0), 0.95)
    return within, max((residual.size - sizes.size) * (1.0 - rho) / (1.0 + rho), 2.0)


def within_run_delta_bic(table: WindowTable, candidate: npt.ArrayLike, reference: npt.ArrayLike,
                         added_params: int) -> float:
    """BIC(candidate) - BIC(reference) on the windows' deviations from their run means (log residuals).

    Windows of one run share its set-up scatter (sensor coupling, preload,
    temperature: 1-4 % of amplitude), which :func:`effective_sample_size`
    counts once a run; a law that changes the amplitude along each run
    (position along the stroke) is instead seen against the scatter between
    windows of a run, which the run means leave out.  Both are scored on the
    sample size of :func:`within_run_residual` of the one that fits better
    there (:func:`within_run_sample_size`); the candidate's ``added_params``
    are charged ln n_eff each.  A law that moves run means only gains nothing
    here and pays its parameters.
    """
    residuals = [within_run_residual(table, r) for r in (candidate, reference)]
    n_eff = within_run_sample_size(residuals)
    return bic(residuals[0][0], added_params, n_eff) - bic(residuals[1][0], 0, n_eff)


def within_run_sample_size(residuals: Sequence[tuple[np.ndarray, float]]) -> float:
    """The sample size to compare fits on within runs: that of the one fitting best (:func:`within_run_residual`).

    A misfit along the run leaves consecutive windows correlated, which says
    nothing of the scatter between windows itself: the best fit's residual
    is the closest to that scatter (its lag-1 autocorrelation the least
    inflated), and all are counted with its sample size.
    """
    return min(residuals, key=lambda pair: float(pair[0] @ pair[0]))[1]


def within_run_gain(table: WindowTable, candidate: npt.ArrayLike, reference: npt.ArrayLike) -> float:
    """1 - RMS / reference RMS of held-out log residuals' deviations from their run means (NaN: not held out).

    How much better a law predicts the shape of held-out runs along the run
    (:func:`held_out_log_residuals`), whatever their set-up offsets.
    """
    cand, ref = np.asarray(candidate, dtype=float), np.asarray(reference, dtype=float)
    held = np.isfinite(cand) & np.isfinite(ref)
    if not held.any():
        return math.nan
    own, other = (run_deviations(r[held], table.run[held]) for r in (cand, ref))
    power = float(other @ other)
    return 1.0 - math.sqrt(float(own @ own) / power) if power > 0 else math.nan


def within_run_correlation(table: WindowTable, first: str, second: str = 'time') -> float:
    """Pearson r of two columns' deviations from their run means (NaN when either does not vary within runs).

    Position and time within runs: +-1 when every traverse runs one way
    (a drift during each traverse has the shape of a law of position), near 0
    with traverses out and back.
    """
    columns = [np.asarray(getattr(table, name), dtype=float) for name in (first, second)]
    keep = np.isfinite(columns[0]) & np.isfinite(columns[1])
    a, b = (run_deviations(c[keep], table.run[keep]) for c in columns)
    scale = math.sqrt(float(a @ a) * float(b @ b))
    return float(a @ b) / scale if scale > 0 else math.nan


def within_run_share(table: WindowTable, covariate: str) -> float:
    """Share of ``covariate``'s variance over windows that lies within runs (1: every run sweeps it alike)."""
    column = getattr(table, covariate, None) if covariate else None
    if column is None:      # not a column of the table ('speed' is one; a pair's or no covariate)
        return 0.0
    values = np.asarray(column, dtype=float)
    keep = np.isfinite(values)
    if keep.sum() < 2 or not np.var(values[keep]) > 0:
        return 0.0
    within = run_deviations(values[keep], table.run[keep])
    return float(np.var(within) / np.var(values[keep]))


@dataclass
class ModelFit:
    """One fitted model: the baseline or Eq. 22 extended by one effect."""

    effect: str                     # effect ID or 'baseline'
    vector: np.ndarray              # (ln C_sys, C_F, C_lambda, internal effect parameters)
    params: dict                    # effect parameters, physical (SI)
    log_residual: np.ndarray        # ln A_model - ln A, per window
    cv_log_residual: np.ndarray     # the same for held-out runs (NaN where not held out)
    n_params: int
    rmse: float = math.nan
    cv_rmse: float = math.nan
    n_eff: float = math.nan
    cv_run_rmse: float = math.nan   # relative RMS error of held-out run amplitudes
    notes: list = field(default_factory=list)
    c_lambda_std: float = math.nan  # standard error of C_lambda under the run-effect model (effect held)
    physical: bool = False          # fitted with C_lambda held at 0 or above (fit_vector's ``physical``)
    excitation: bool = False        # fitted with C_F held at 0 or above too (fit_vector's ``excitation``)

    @property
    def constants(self) -> ModelConstants:
        """C_sys, C_F, C_lambda of this fit."""
        return ModelConstants.from_vector(self.vector[:3])

    def unphysical(self) -> list[str]:
        """What about the constants no real actuator gives (empty when none)."""
        problems = []
        c = self.constants
        std = self.c_lambda_std if math.isfinite(self.c_lambda_std) else 0.0
        if not c.c_lambda > -UNPHYSICAL_SIGMAS * std:
            below = f' by {-c.c_lambda / std:.1f} standard errors' if std > 0 else ''
            problems.append(f'C_lambda = {c.c_lambda:.3g} <= 0{below} (the film would raise vibration)')
        return problems


def fit_model(table: WindowTable, effect: Effect | None = None, folds: Sequence[int] | None = None,
              starts: Sequence[npt.ArrayLike] | None = None, physical: bool = False,
              excitation: bool = False) -> ModelFit:
    """Fit a model on all windows and score it on held-out runs (``folds``; default :func:`cv_folds`).

    ``starts``, ``physical``, ``excitation``: as :func:`fit_vector`; ``folds=[]`` skips the held-out scores (NaN).
    """
    scales = effect.scales(table) if effect is not None else {}
    vector = fit_vector(table, effect, scales, starts=starts, physical=physical, excitation=excitation)
    residual = predict_log(table, vector, effect, scales) - table.log_rms
    folds = cv_folds(table) if folds is None else folds
    params = effect.to_params(vector[3:], scales) if effect is not None else {}
    n_params = BASE_PARAMETERS + (len(effect.parameter_names) if effect is not None else 0)
    jacobian = constants_jacobian(table, vector, effect, scales)
    c_lambda_std = math.nan     # no standard error where a forward step leaves the law's domain (a mode at r = 1)
    if np.all(np.isfinite(jacobian)):
        try:
            covariance = run_level_covariance(jacobian, residual, table.run)[0]
            c_lambda_std = math.sqrt(covariance[2, 2]) if covariance[2, 2] >= 0 else math.nan
        except np.linalg.LinAlgError:
            pass
    return ModelFit(effect=effect.id if effect is not None else BASELINE, vector=vector, params=params,
                    log_residual=residual, n_params=n_params, rmse=relative_rmse(residual),
                    n_eff=effective_sample_size(residual, table.run), c_lambda_std=c_lambda_std,
                    physical=physical, excitation=excitation,
                    **_held_out(table, effect, scales, vector, folds, physical, excitation))


def constants_jacobian(table: Columns, vector: np.ndarray, effect: Effect | None,
                       scales: dict[str, Any]) -> np.ndarray:
    """d ln A / d (ln C_sys, C_F, C_lambda) per window (n x 3), the effect's parameters held (forward steps)."""
    base = predict_log(table, vector, effect, scales)
    jacobian = np.empty((len(table), BASE_PARAMETERS))
    for i in range(BASE_PARAMETERS):
        step = 1e-6 * max(abs(vector[i]), 1e-3)
        shifted = np.array(vector, dtype=float)
        shifted[i] += step
        jacobian[:, i] = (predict_log(table, shifted, effect, scales) - base) / step
    return jacobian


def score_held_out(table: WindowTable, fit: ModelFit, effect: Effect | None, folds: Iterable[int]) -> ModelFit:
    """``fit`` (made with ``folds=[]``) with its held-out scores on ``folds``, without fitting all windows again."""
    scales = effect.scales(table) if effect is not None else {}
    return replace(fit, **_held_out(table, effect, scales, fit.vector, folds, fit.physical, fit.excitation))


def _held_out(table: WindowTable, effect: Effect | None, scales: dict[str, Any], vector: np.ndarray,
              folds: Iterable[int], physical: bool = False, excitation: bool = False) -> dict[str, Any]:
    """ModelFit's held-out fields: each fold refitted from ``vector`` and scored on its runs."""
    cv = held_out_log_residuals(table, effect, scales, vector, folds, physical, excitation)
    return {'cv_log_residual': cv, 'cv_rmse': relative_rmse(cv), 'cv_run_rmse': run_level_rmse(table, cv)}
