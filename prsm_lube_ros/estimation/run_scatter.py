# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Run-to-run scatter: a random effect per run (traverse) beside the window scatter inside runs.

Every traverse of a real rig has its own amplitude factor (sensor coupling,
preload, temperature: 1-4 % on one unit, more between units) on top of the
window-to-window scatter inside it.  In ln amplitude, for window ``i`` of run
``g``::

    y_gi = x_gi^T b + u_g + e_gi,   u_g ~ N(0, tau^2),   e_gi ~ N(0, sigma_w^2)

with ``x b`` the fixed part (Eq. 22 in its linear form, or the Jacobian of an
extended model), ``tau`` the *run scatter* and ``sigma_w`` the *window
scatter* (both dimensionless, relative).  The variance components are
estimated by restricted maximum likelihood (REML, Patterson & Thompson 1971),
which holds for few runs: per run the covariance is
``V_g = sigma_w^2 (I + lambda J)`` with ``lambda = tau^2 / sigma_w^2``, whose
inverse and determinant are closed-form, so the restricted likelihood is
profiled in ``sigma_w^2`` and maximised over ``lambda`` alone (the same
estimate as statsmodels' MixedLM with a random intercept, tested in
``test/estimation/test_run_scatter.py``).

A slow wander inside runs makes window residuals correlated; what it adds to a
run's mean is then estimated as part of ``tau^2``, which is what a new run
will also carry.

The fixed-part estimates stay ordinary least squares (the calibration's
constants do not depend on the variance model); their covariance is that of
OLS under the fitted ``V``::

    Cov(b) = (X^T X)^-1 X^T V X (X^T X)^-1.

``tau^2`` rests on ``dof = runs - fixed parameters`` degrees of freedom.  A
new run's ln amplitude then follows a Student t with ``dof`` degrees of
freedom rather than a normal, so a one-sigma uncertainty stated is the
half-width of that t's central 68.3 % interval, the interval one sigma spans
of a normal: variances are multiplied by :attr:`RunScatter.predictive_factor`
``t_dof(0.8413)^2`` (1.43 at 3 degrees of freedom, 1.12 at 9, at most
:data:`MAX_PREDICTIVE_FACTOR`).  With no run beyond the fixed parameters
``tau`` cannot be estimated; :data:`ASSUMED_RUN_STD` is used and said.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
import math

import numpy as np
import numpy.typing as npt

__all__ = ['ASSUMED_RUN_STD', 'MAX_PREDICTIVE_FACTOR', 'MAX_VARIANCE_RATIO', 'ONE_SIGMA_QUANTILE', 'RunScatter',
           'estimate_run_scatter', 'ols_covariance', 'student_t_quantile']

#: Run scatter (relative, ln units) assumed when the runs cannot estimate it: the middle of the 1-4 % seen on rigs.
ASSUMED_RUN_STD = 0.03
#: Largest variance factor for the t of few degrees of freedom (that of one degree of freedom, rounded down).
MAX_PREDICTIVE_FACTOR = 3.0
#: Probability below one sigma above the mean of a normal: the one-sigma interval holds 68.27 % of it.
ONE_SIGMA_QUANTILE = 0.8413447460685429
#: Upper end of the search for lambda = tau^2 / sigma_w^2.
MAX_VARIANCE_RATIO = 1e8


@dataclass(frozen=True)
class RunScatter:
    """Variance components of ln amplitude: between runs (``run_std``) and inside runs (``window_std``)."""

    run_std: float          # tau, relative (ln units), std of a run's own amplitude factor
    window_std: float       # sigma_w, relative, std of windows around their run's level
    runs: int               # runs behind the estimate
    dof: int                # runs - fixed parameters: degrees of freedom of tau^2
    estimated: bool = True  # False: tau could not be estimated and ASSUMED_RUN_STD stands for it
    note: str = ''          # where the figures come from when not from REML (an old calibration file)

    @cached_property
    def predictive_factor(self) -> float:
        """Variance factor that makes one sigma span the central 68.3 % of a Student t with :attr:`dof` dof."""
        if self.dof < 1:
            return MAX_PREDICTIVE_FACTOR
        return min(student_t_quantile(self.dof, ONE_SIGMA_QUANTILE) ** 2, MAX_PREDICTIVE_FACTOR)

    def new_run_variance(self, windows: float, window_variance: float | None = None) -> float:
        """Variance of ln(RMS) of a new run pooled over ``windows`` windows, predictive factor included.

        ``window_variance``: the run's own window scatter (ln units^2); default
        the calibration's.  One window: ``tau^2 + sigma_w^2``.
        """
        within = self.window_std ** 2 if window_variance is None else window_variance
        return (self.run_std ** 2 + within / max(windows, 1.0)) * self.predictive_factor

    @property
    def summary(self) -> str:
        """In words, for messages and the calibration file."""
        if self.note:
            source = self.note
        elif self.estimated:
            source = f'REML over {self.runs} runs, {self.dof} degrees of freedom'
        else:
            source = f'assumed: {self.runs} runs leave none beyond the fixed parameters'
        return (f'run-to-run scatter {100 * self.run_std:.2f} % ({source}), '
                f'window scatter {100 * self.window_std:.2f} %')


def student_t_quantile(dof: int, probability: float) -> float:
    """Quantile of Student's t with ``dof`` (a positive integer) degrees of freedom at ``probability`` (0.5 to 1).

    Pure Python, so ``assess`` pays no scipy import for it (``scipy.special.stdtrit``
    gives the same to 1e-12, tested).  Up to :data:`_SERIES_DOF` degrees of freedom
    the closed-form CDF of an integer ``dof`` (Abramowitz & Stegun 26.7.3-4,
    in ``theta = atan(t / sqrt(dof))``) is inverted by bisection in ``theta``
    to machine precision; beyond, the expansion of A&S 26.7.5 around the
    normal quantile (terms to ``dof^-4``: 1e-13 relative there at the one-sigma quantile).
    """
    from statistics import NormalDist
    if not (isinstance(dof, int) and dof >= 1 and 0.5 <= probability < 1.0):
        raise ValueError(f'Student t quantile: dof {dof!r} must be an integer >= 1, probability {probability!r} '
                         'in [0.5, 1)')
    if dof > _SERIES_DOF:
        x = NormalDist().inv_cdf(probability)
        terms = ((x ** 3 + x) / 4, (5 * x ** 5 + 16 * x ** 3 + 3 * x) / 96,
                 (3 * x ** 7 + 19 * x ** 5 + 17 * x ** 3 - 15 * x) / 384,
                 (79 * x ** 9 + 776 * x ** 7 + 1482 * x ** 5 - 1920 * x ** 3 - 945 * x) / 92160)
        return x + sum(term / dof ** (k + 1) for k, term in enumerate(terms))
    target = 2.0 * probability - 1.0          # P(|T| < t)
    low, high = 0.0, math.pi / 2
    for _ in range(200):
        middle = 0.5 * (low + high)
        if middle in (low, high):
            break
        if _central_probability(middle, dof) < target:
            low = middle
        else:
            high = middle
    return math.sqrt(dof) * math.tan(0.5 * (low + high))


#: Degrees of freedom up to which :func:`student_t_quantile` inverts the closed-form CDF.
_SERIES_DOF = 300


def _central_probability(theta: float, dof: int) -> float:
    """``P(|T| < sqrt(dof) tan(theta))`` for Student's t with integer ``dof`` (A&S 26.7.3 odd, 26.7.4 even)."""
    sin, cos2 = math.sin(theta), math.cos(theta) ** 2
    if dof % 2 == 0:
        term = total = 1.0
        for k in range(1, dof // 2):
            term *= cos2 * (2 * k - 1) / (2 * k)
            total += term
        return sin * total
    if dof == 1:
        return 2.0 * theta / math.pi
    term = total = math.cos(theta)
    for k in range(1, (dof - 1) // 2):
        term *= cos2 * (2 * k) / (2 * k + 1)
        total += term
    return 2.0 / math.pi * (theta + sin * total)


def _group_sums(x: np.ndarray, y: np.ndarray, index: np.ndarray,
                groups: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-run sizes, column sums X_g^T 1 and sums of y."""
    sizes = np.bincount(index, minlength=groups).astype(float)
    column_sums = np.zeros((groups, x.shape[1]))
    np.add.at(column_sums, index, x)
    y_sums = np.bincount(index, weights=y, minlength=groups)
    return sizes, column_sums, y_sums


def _restricted_fit(ratio: float, xtx: np.ndarray, xty: np.ndarray, yty: float, sizes: np.ndarray,
                    column_sums: np.ndarray, y_sums: np.ndarray, n: int, p: int) -> tuple[float, float]:
    """-2 restricted log likelihood (profiled in sigma_w^2, constants dropped) and sigma_w^2 at ``ratio``."""
    shrink = ratio / (1.0 + sizes * ratio)
    a = xtx - (column_sums * shrink[:, None]).T @ column_sums
    b = xty - column_sums.T @ (shrink * y_sums)
    c = yty - float(np.sum(shrink * y_sums ** 2))
    try:
        solution = np.linalg.solve(a, b)
        sign, logdet = np.linalg.slogdet(a)
    except np.linalg.LinAlgError:
        return math.inf, math.nan
    rss = max(c - float(b @ solution), 1e-300)
    sigma2 = rss / (n - p)
    if sign <= 0:
        return math.inf, sigma2
    return (n - p) * math.log(sigma2) + float(np.sum(np.log1p(sizes * ratio))) + logdet, sigma2


def estimate_run_scatter(x: npt.ArrayLike, residual: npt.ArrayLike, runs: npt.ArrayLike) -> RunScatter:
    """REML run and window scatter of ``residual`` (ln units) with fixed design ``x`` (n x p), runs ``runs``.

    ``residual`` may be the OLS residual or ln A itself: REML sees only what
    ``x`` does not explain.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(residual, dtype=float)
    n, p = x.shape
    _, index = np.unique(np.asarray(runs), return_inverse=True)
    groups = int(index.max()) + 1 if n else 0
    dof = groups - p
    sizes, column_sums, y_sums = _group_sums(x, y, index, groups)
    xtx, xty, yty = x.T @ x, x.T @ y, float(y @ y)
    if n - p <= 0:
        return RunScatter(ASSUMED_RUN_STD, 0.0, groups, dof, estimated=False)
    if n == groups and dof > 0:     # one window a run: all scatter is between runs
        _, sigma2 = _restricted_fit(0.0, xtx, xty, yty, sizes, column_sums, y_sums, n, p)
        return RunScatter(math.sqrt(sigma2), 0.0, groups, dof)
    if dof <= 0 or n <= groups:
        _, sigma2 = _restricted_fit(0.0, xtx, xty, yty, sizes, column_sums, y_sums, n, p)
        window_var = _within_run_variance(y, index, groups) if n > groups else sigma2
        return RunScatter(ASSUMED_RUN_STD, math.sqrt(max(window_var, 0.0)), groups, dof, estimated=False)

    from scipy.optimize import minimize_scalar    # here: assess never fits, and must start without scipy.optimize

    def objective(log_ratio: float) -> float:
        return _restricted_fit(math.exp(log_ratio), xtx, xty, yty, sizes, column_sums, y_sums, n, p)[0]

    result = minimize_scalar(objective, bounds=(math.log(1e-8), math.log(MAX_VARIANCE_RATIO)), method='bounded',
                             options={'xatol': 1e-6})
    at_zero, sigma2_zero = _restricted_fit(0.0, xtx, xty, yty, sizes, column_sums, y_sums, n, p)
    ratio = math.exp(result.x) if result.fun < at_zero else 0.0
    _, sigma2 = _restricted_fit(ratio, xtx, xty, yty, sizes, column_sums, y_sums, n, p) if ratio else (0, sigma2_zero)
    return RunScatter(math.sqrt(ratio * sigma2), math.sqrt(sigma2), groups, dof)


def _within_run_variance(y: np.ndarray, index: np.ndarray, groups: int) -> float:
    """Pooled variance of ``y`` around its run means."""
    sizes = np.bincount(index, minlength=groups)
    means = np.bincount(index, weights=y, minlength=groups) / np.maximum(sizes, 1)
    return float(np.sum((y - means[index]) ** 2) / max(y.size - groups, 1))


def ols_covariance(x: npt.ArrayLike, runs: npt.ArrayLike, scatter: RunScatter) -> np.ndarray:
    """Covariance of the OLS estimates of ``x``'s parameters under the run-effect model, predictive factor in.

    ``(X^T X)^-1 X^T V X (X^T X)^-1`` with ``V`` block-diagonal per run:
    ``sigma_w^2 I + tau^2 J``.
    """
    x = np.asarray(x, dtype=float)
    _, index = np.unique(np.asarray(runs), return_inverse=True)
    column_sums = np.zeros((int(index.max()) + 1, x.shape[1]))
    np.add.at(column_sums, index, x)
    bread = np.linalg.inv(x.T @ x)
    meat = scatter.window_std ** 2 * (x.T @ x) + scatter.run_std ** 2 * (column_sums.T @ column_sums)
    return scatter.predictive_factor * bread @ meat @ bread
