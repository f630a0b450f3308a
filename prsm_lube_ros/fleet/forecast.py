# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""theta_Oil over service time per actuator: depletion fit and when it will cross the warn and error levels.

Law.  Oil is flung out as the screw turns (``physics.effects.lubricant_depletion``,
theta = theta_r exp(-N_rev / N_d)); at a usage of r revolutions a day,
N_rev grows by r dt, so between relubrications

    ln theta_Oil(t) = ln a_c - k t          (k = r / N_d per day, tau = 1/k)

with one level ``a_c`` per lubrication cycle ``c`` (it absorbs the unknown
moment of the relubrication and the oil put in) and one drift ``k`` shared by
the cycles of an actuator.  Day-to-day scatter of the usage makes ln theta a
random walk with that drift and a diffusion ``q = s k^2`` per day, ``s`` the
relative variance of a day's revolutions: a property of how the fleet is
operated, estimated over all actuators and over spans of one to eight
recordings, the largest kept
(:func:`~.depletion_walk.usage_scatter_over_strides`).

Data.  One point per recording: its runs' theta_Oil averaged with
inverse-variance weights.  Each run's one-sigma has a part of its own (the
vibration scatter) and a part from the calibration's covariance, common to all
recordings assessed with it (``theta_oil_std_calibration`` in the history):
the fit weighs by the own part and adds the common part once, to the level.

Relubrications are given, or found as a jump up in theta_Oil between two
consecutive recordings larger than ``min_jump`` and than ``jump_sigmas`` times
their combined own uncertainty (placed half-way between them).

Fit.  Weighted least squares of ``ln a_c`` and ``k`` for the time constant
and crossings already seen in the data; a Kalman
filter of (ln theta, k), the level reset at each relubrication, for the state
at the last recording (:func:`depletion_state`).

Forecast.  From that state the first passage of the walk to ln L is inverse
Gaussian (mean D/k, shape D^2/q, D the distance to ln L); drawn over the
state's uncertainty it gives the estimate and a 95 % interval (a draw with
k <= 0 never crosses: the interval is open upwards, ``None``).  A level
already crossed in the recordings is placed between the bracketing
recordings, its interval widened to the fitted law's.  The default levels are
the estimator's ``warn_below`` and ``error_below``
(:class:`~prsm_lube_ros.estimation.health.HealthThresholds`).  With an
odometer the same filter runs against revolutions (:func:`fit_revolutions`).

Surface defects.  An actuator whose history holds a run the defect screen
flagged gets no forecast from the onset on (:mod:`.defects`: theta_Oil then
reads damage, not oil); its ``defect`` says since when and where, it ranks
first (:func:`urgency_key`: it needs an inspection, not oil), and its
recordings from the onset on stay out of the fleet's usage scatter.

The diagnostics' and the trend table's words for a forecast are in
:mod:`.forecast_summary`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from statistics import NormalDist
from pathlib import Path
from typing import Any, TYPE_CHECKING
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from ..errors import InputError
from ..estimation.health import HealthThresholds
from ..validation import finite_or_none as _finite, utc_or_none
from .defects import before_onsets, defect_marks, defect_onsets, DefectMark, DefectOnset
from .depletion_walk import (depletion_state, drift_and_diffusion, Increments, increments, STRIDES,
                             strided_increments, usage_scatter_over_strides)

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ['ActuatorForecast', 'Crossing', 'DAY', 'DRAWS', 'FleetRecords', 'INTERVAL', 'KILO', 'MODEL_FORM_RATE',
           'ODOMETER_REACH',
           'RecordingPoint', 'detect_relubrications', 'fit_depletion', 'fit_one', 'fit_revolutions', 'fleet_walk',
           'forecast_history', 'forecast_points', 'history_points', 'history_readers', 'history_records',
           'recording_points', 'two_sided_quantile', 'urgency_key', 'utc_minutes']

DAY = 86400.0            # s
#: probability inside the stated forecast interval (the default of ``trend --level``)
INTERVAL = 0.95
#: parameter draws for the interval (seeded: a forecast is reproducible)
DRAWS = 4000
#: model-form uncertainty: relative one-sigma of the depletion rate k ahead beyond what the recordings say of it
#: (usage that changes, a law not exactly exponential in time), added in quadrature to var(k): it widens the
#: forecast in proportion to the horizon, as an error of the rate does
MODEL_FORM_RATE = 0.10


def two_sided_quantile(confidence: float) -> float:
    """Normal quantile z with P(|Z| < z) = ``confidence`` (1.96 for 0.95)."""
    return NormalDist().inv_cdf(0.5 + confidence / 2.0)


@dataclass(frozen=True)
class RecordingPoint:
    """One recording's theta_Oil: time of its first run (s since the epoch), value and one-sigma.

    ``theta_oil_std`` is the whole one-sigma; ``calibration_std`` its part
    from the calibration constants, common to every recording assessed with
    the same calibration (it shifts them all alike and does not average out).
    """

    time: float
    theta_oil: float
    theta_oil_std: float
    recording_path: str = ''
    calibration_std: float = 0.0

    @property
    def independent_std(self) -> float:
        """The one-sigma of this recording alone (its own vibration scatter), at least a fifth of the whole."""
        return math.sqrt(max(self.theta_oil_std ** 2 - self.calibration_std ** 2, (0.2 * self.theta_oil_std) ** 2))


@dataclass(frozen=True)
class Crossing:
    """When theta_Oil crosses ``level``: estimate and interval in s since the epoch (None: not within reach)."""

    level: float
    time: float | None
    low: float | None
    high: float | None

    def as_json(self) -> dict:
        """Mapping with UTC strings beside the epoch seconds."""
        result: dict[str, Any] = {'level': self.level}
        for name in ('time', 'low', 'high'):
            value = getattr(self, name)
            result[name] = value
            result[f'{name}_utc'] = utc_minutes(value)
        return result


@dataclass
class ActuatorForecast:
    """Depletion fit of one actuator and its threshold crossings."""

    actuator: str
    points: list[RecordingPoint]
    relubrications: list[float]                    # s since the epoch
    tau_days: float = math.nan                     # depletion time constant
    tau_days_std: float = math.nan
    theta_now: float = math.nan                    # the law at the last recording
    last_recording: float = math.nan
    crossings: list[Crossing] = field(default_factory=list)
    reason: str = ''                               # why there is no forecast
    fit_rmse: float = math.nan                     # RMS of ln theta residuals
    #: state of ln theta at the last recording: mean (ln theta, k 1/day), covariance, Student-t degrees of
    #: freedom (0: normal) and the diffusion q (1/day) of the usage scatter
    state: np.ndarray | None = None
    state_covariance: np.ndarray | None = None
    state_dof: int = 0
    diffusion: float = 0.0
    #: against revolutions (with an odometer): N_d (rev) and its one-sigma, the odometer at the last recording
    #: and the odometer readings at which the levels are crossed (``Crossing`` in rev instead of s; None
    #: where theta_Oil is already below the level)
    depletion_revolutions: float = math.nan
    depletion_revolutions_std: float = math.nan
    odometer_last: float = math.nan
    revolution_crossings: list[Crossing] = field(default_factory=list)
    #: probability inside the stated intervals and the band
    confidence: float = INTERVAL
    #: per level, draws of the days from the last recording to the first passage (< 0: already below; inf: never)
    passage_days: dict = field(default_factory=dict)
    #: why there is no fit against revolutions although an odometer was given
    revolutions_reason: str = ''
    #: the suspected surface defect that stops the forecast (:mod:`.defects`), None when none is
    defect: DefectOnset | None = None

    def crossing(self, level: float) -> Crossing | None:
        """The crossing of ``level``, if forecast."""
        return next((c for c in self.crossings if math.isclose(c.level, level)), None)

    def band(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """theta_Oil expected after the last recording at ``times`` (s since the epoch), with the interval.

        ln theta = x - k dt, variance var(x) - 2 cov(x, k) dt + var(k) dt^2 + q dt
        (dt in days from the last recording); the interval covers
        ``confidence`` (normal).
        """
        if self.state is None:
            nan = np.full(np.shape(times), math.nan)
            return nan, nan, nan
        (x, k), cov = self.state, self.state_covariance
        assert cov is not None  # set with the state
        dt = np.maximum((np.asarray(times, float) - self.last_recording) / DAY, 0.0)
        centre = x - k * dt
        variance = cov[0, 0] - 2.0 * cov[0, 1] * dt + cov[1, 1] * dt ** 2 + self.diffusion * dt
        spread = two_sided_quantile(self.confidence) * np.sqrt(np.maximum(variance, 0.0))
        return np.exp(centre), np.exp(centre - spread), np.exp(centre + spread)

    def as_json(self) -> dict:
        """Plain mapping for the trend JSON."""
        return {'actuator': self.actuator, 'reason': self.reason, 'tau_days': _finite(self.tau_days),
                'tau_days_std': _finite(self.tau_days_std), 'theta_now': _finite(self.theta_now),
                'last_recording': _finite(self.last_recording), 'last_recording_utc': utc_minutes(self.last_recording),
                'fit_rmse_ln': _finite(self.fit_rmse), 'recordings': len(self.points),
                'relubrications': [{'time': t, 'time_utc': utc_minutes(t)} for t in self.relubrications],
                'crossings': [c.as_json() for c in self.crossings],
                'revolutions': {'depletion_revolutions': _finite(self.depletion_revolutions),
                                'depletion_revolutions_std': _finite(self.depletion_revolutions_std),
                                'odometer_last': _finite(self.odometer_last),
                                'crossings': [{'level': c.level, 'odometer': c.time, 'low': c.low, 'high': c.high}
                                              for c in self.revolution_crossings]},
                'points': [{'time': p.time, 'theta_oil': p.theta_oil, 'theta_oil_std': p.theta_oil_std,
                            'recording_path': p.recording_path} for p in self.points],
                **(self.defect.as_json() if self.defect is not None else _NO_DEFECT)}


#: the defect fields of an actuator without a suspected defect in trend.json
_NO_DEFECT = {'defect_suspected': False, 'defect_since': None, 'defect_since_utc': None, 'defect_component': '',
              'defect_order': None, 'defect_evidence': '', 'defect_recording': '', 'defect_recordings': 0}


def utc_minutes(seconds: float | None) -> str | None:
    """ISO 8601 UTC to the minute of ``seconds`` since the epoch, None when not finite."""
    stamp = utc_or_none(seconds)
    return None if stamp is None else stamp.isoformat(timespec='minutes')


def recording_points(runs: pa.Table) -> dict[str, list[RecordingPoint]]:
    """One point per recording and actuator from a history ``runs`` table, in time order.

    A recording's value is the inverse-variance mean of its assessed runs,
    weighted by their own (independent) one-sigma; that mean's one-sigma is
    the larger of the propagated one and the runs' scatter about it over
    sqrt(n), and the calibration's share (``theta_oil_std_calibration``,
    0 where the history has none) is added back in quadrature.
    """
    names = ('actuator', 'recording_path', 'start', 'theta_oil', 'theta_oil_std', 'theta_oil_std_calibration')
    columns = {name: runs.column(name).to_pylist() if name in runs.column_names else [None] * runs.num_rows
               for name in names}
    grouped: dict[tuple[str, str], list[tuple[float, float, float, float]]] = {}
    for actuator, path, start, theta, std, shared in zip(*columns.values()):
        if theta is None or std is None or not theta > 0 or not std > 0 or start is None:
            continue
        shared = min(shared or 0.0, std)
        own = RecordingPoint(0.0, theta, std, calibration_std=shared).independent_std
        grouped.setdefault((actuator, path), []).append((start.timestamp(), theta, own, shared))
    points: dict[str, list[RecordingPoint]] = {}
    for (actuator, path), rows in grouped.items():
        times, thetas, stds, shared = (np.array(v, float) for v in zip(*rows))
        weights = 1.0 / stds ** 2
        mean = float(np.sum(weights * thetas) / np.sum(weights))
        std = math.sqrt(1.0 / np.sum(weights))
        if thetas.size > 1:
            std = max(std, float(np.std(thetas, ddof=1)) / math.sqrt(thetas.size))
        calibration = float(np.mean(shared))
        points.setdefault(actuator, []).append(RecordingPoint(float(times.min()), mean, math.hypot(std, calibration),
                                                              path, calibration))
    return {actuator: sorted(items, key=lambda p: p.time) for actuator, items in sorted(points.items())}


def detect_relubrications(points: Sequence[RecordingPoint], *, min_jump: float = 0.05,
                          jump_sigmas: float = 4.0) -> list[float]:
    """Times (s since the epoch) of jumps up in theta_Oil between consecutive recordings."""
    found = []
    for before, after in zip(points, points[1:]):
        rise = after.theta_oil - before.theta_oil
        if rise > min_jump and rise > jump_sigmas * math.hypot(before.independent_std, after.independent_std):
            found.append(0.5 * (before.time + after.time))
    return found


def fit_depletion(actuator: str, points: Sequence[RecordingPoint], *, relubrications: Sequence[float] | None = None,
                  levels: Sequence[float] = (HealthThresholds.warn_below, HealthThresholds.error_below),
                  usage_scatter: float | None = None, odometer: Sequence[float] | np.ndarray | None = None,
                  seed: int = 0, confidence: float = INTERVAL) -> ActuatorForecast:
    """Fit ``theta = a_c exp(-t / tau)`` to an actuator's recordings and forecast the crossings of ``levels``.

    ``relubrications`` (s since the epoch) are detected from jumps when None.
    ``usage_scatter`` is the fleet's (:func:`fleet_walk`); None fits
    this actuator's alone.  ``odometer`` (cumulative screw revolutions at each
    point, in time order) adds the fit against revolutions:
    :func:`fit_revolutions`.  ``confidence`` is the probability inside the
    stated intervals.  A forecast that cannot be made has ``reason`` set and
    no crossings.
    """
    order = sorted(range(len(points)), key=lambda j: points[j].time)
    points = [points[j] for j in order]
    odometer = None if odometer is None else np.array([odometer[j] for j in order], float)
    relubrications = sorted(detect_relubrications(points) if relubrications is None else relubrications)
    result = ActuatorForecast(actuator, list(points), list(relubrications), confidence=confidence)
    if not points:
        result.reason = 'no assessed recording'
        return result
    times = np.array([p.time for p in points])
    cycles = np.searchsorted(np.array(relubrications, float), times, side='right')
    used = np.unique(cycles)
    index = np.searchsorted(used, cycles)
    result.last_recording = float(times[-1])
    distinct = np.unique(times).size
    if distinct < used.size + 2:
        result.reason = (f'{len(points)} recordings ({distinct} start times) in {used.size} lubrication cycles: '
                         f'need at least {used.size + 2} start times to fit the depletion')
        return result
    y = np.log([p.theta_oil for p in points])
    sigma = np.array([p.independent_std / p.theta_oil for p in points])
    shared = points[-1].calibration_std / points[-1].theta_oil     # common to all recordings, relative
    origin = times[0]
    solution, covariance, residual, dof, scaled = _fit_cycles(times - origin, y, sigma, index, used.size)
    rate = solution[-1]                                  # 1/day
    result.fit_rmse = float(np.sqrt(np.mean(residual ** 2)))
    rate_std = math.sqrt(covariance[-1, -1])
    result.tau_days = 1.0 / rate if rate > 0 else math.inf
    result.tau_days_std = rate_std / rate ** 2 if rate > 0 else math.inf
    last = index[-1]
    last_level = solution[last]                          # ln a_last at t = origin
    result.theta_now = float(math.exp(last_level - rate * (times[-1] - origin) / DAY))
    rng = np.random.default_rng(seed)
    pair = np.array([last, used.size])
    # the calibration moves the level; the law's form and changing usage the rate (MODEL_FORM_RATE)
    block = covariance[np.ix_(pair, pair)] + np.diag([shared ** 2, (MODEL_FORM_RATE * rate) ** 2])
    draws = _posterior_draws(np.array([last_level, rate]), block, dof if scaled else 0, rng)
    _walk_state(result, (times, y, sigma, cycles), usage_scatter, shared)
    _level_crossings(result, levels, (times, y, sigma, cycles), draws, (origin, last_level, rate), rng, seed)
    if odometer is not None:
        fit_revolutions(result, odometer, y, sigma, cycles, shared, levels, rng)
    return result


def _walk_state(result: ActuatorForecast, series: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                usage_scatter: float | None, shared: float) -> None:
    """The random walk's state at the last recording and its diffusion, when the recordings give the walk.

    ``series``: (times s, ln theta, its sigma, lubrication cycle) of the
    recordings; ``shared``: the calibration's relative one-sigma, added to
    the level's variance.
    """
    times, y, sigma, cycles = series
    walk = drift_and_diffusion(increments(times / DAY, y, sigma, cycles), usage_scatter)
    if walk is not None:
        result.diffusion = walk[2]
        result.state, result.state_covariance, result.state_dof = depletion_state(times / DAY, y, sigma, cycles,
                                                                                  walk[2])
        result.state_covariance[0, 0] += shared ** 2
        result.state_covariance[1, 1] += (MODEL_FORM_RATE * result.state[1]) ** 2


def _level_crossings(result: ActuatorForecast, levels: Sequence[float],
                     series: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray], draws: np.ndarray,
                     law: tuple[float, float, float], rng: np.random.Generator, seed: int) -> None:
    """Each level's crossing: the walk's first passage from the last recording, else seen or where the law puts it.

    ``series`` as for :func:`_walk_state`; ``draws``: posterior draws of (ln
    a, rate) of the last cycle; ``law``: (origin s, ln a of the last cycle
    at the origin, rate 1/day) of the least-squares fit.
    """
    times, y, sigma, cycles = series
    origin, last_level, rate = law
    tail = (1.0 - result.confidence) / 2.0
    for level in levels:
        if y[-1] > math.log(level) and result.state is not None:
            estimate, low, high, result.passage_days[level] = _first_passage(result, math.log(level), rng, tail)
            result.crossings.append(Crossing(float(level), *(float(times[-1] + v * DAY) if math.isfinite(v)
                                                             else None for v in (estimate, low, high))))
            continue
        if result.state is not None:     # its own generator: the crossings above draw what they always drew
            result.passage_days[level] = _passage_draws(result, math.log(level), np.random.default_rng(seed + 1))
        result.crossings.append(_crossing_seen_or_fitted(level, draws, tail, origin, last_level, rate,
                                                         (times, y, sigma, cycles)))


#: revolutions per unit of the filter's axis against revolutions (keeps its numbers near those in days)
KILO = 1000.0


def _fit_cycles(since: np.ndarray, y: np.ndarray, sigma: np.ndarray, cycle_index: np.ndarray,
                cycle_count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, bool]:
    """Weighted least squares of ln theta = ln a_c - rate t: one level per lubrication cycle, one rate.

    ``since``: time since the first recording, s.
    Returns ``(solution, covariance, residual, dof, scaled)``: levels then the
    rate (1/day), their covariance (scaled by chi^2/dof when above 1, ``scaled``).
    """
    design = np.zeros((len(y), cycle_count + 1))
    design[np.arange(len(y)), cycle_index] = 1.0
    design[:, -1] = -since / DAY
    weights = 1.0 / sigma
    solution, *_ = np.linalg.lstsq(design * weights[:, None], y * weights, rcond=None)
    residual = y - design @ solution
    dof = len(y) - design.shape[1]
    chi2 = float(np.sum((residual * weights) ** 2))
    covariance = np.linalg.pinv((design * weights[:, None]).T @ (design * weights[:, None]))
    scaled = chi2 / dof > 1.0
    if scaled:
        covariance = covariance * (chi2 / dof)
    return solution, covariance, residual, dof, scaled


def _crossing_seen_or_fitted(level: float, draws: np.ndarray, tail: float, origin: float, last_level: float,
                             rate: float, series: tuple) -> Crossing:
    """A crossing of ``level`` the recordings already show (bracketed), or where the fitted law and its draws put it.

    ``series``: (times s, ln theta, its sigma, lubrication cycle) of the recordings.
    """
    with np.errstate(divide='ignore', invalid='ignore'):
        days = np.where(draws[:, 1] > 0, (draws[:, 0] - math.log(level)) / draws[:, 1], math.inf)
        quantiles = np.quantile(days, [tail, 0.5, 1.0 - tail])
    low, estimate, high = (float(origin + v * DAY) if math.isfinite(v) else None for v in quantiles)
    times, y, sigma, cycles = series
    bracket = _crossed_between(times, y, sigma, cycles, math.log(level))
    if bracket is not None:     # seen in the recordings: there, or where the fitted law puts it
        estimate = bracket[0]
        low = bracket[1] if low is None else min(low, bracket[1])
        high = None if high is None else max(high, bracket[2])
    return _holding_estimate(Crossing(float(level), estimate, low, high))


def _holding_estimate(crossing: Crossing) -> Crossing:
    """The crossing with its interval widened to hold its estimate (an open end holds every later time)."""
    if crossing.time is None:
        return crossing
    low = crossing.time if crossing.low is None else min(crossing.low, crossing.time)
    high = None if crossing.high is None else max(crossing.high, crossing.time)
    return Crossing(crossing.level, crossing.time, low, high)


def fit_revolutions(result: ActuatorForecast, odometer: np.ndarray, y: np.ndarray, sigma: np.ndarray,
                    cycles: np.ndarray, shared: float, levels: Sequence[float], rng: np.random.Generator) -> None:
    """The law against revolutions: ln theta = ln a_c - N / N_d (``lubricant_depletion``), N from an odometer.

    The Kalman filter of :func:`depletion_state` on the odometer axis, without
    usage diffusion (the law is deterministic in revolutions); gives N_d and
    the odometer readings where the levels are crossed, with the 95 % interval
    of the remaining revolutions.  Nothing when the odometer does not cover
    every recording or does not increase.
    """
    if not (np.all(np.isfinite(odometer)) and np.all(np.diff(odometer) >= 0)) or len(odometer) < 3:
        return
    state, cov, dof = depletion_state(odometer / KILO, y, sigma, cycles, 0.0)
    cov = cov + np.diag([shared ** 2, 0.0])
    k = state[1]
    result.odometer_last = float(odometer[-1])
    result.depletion_revolutions = KILO / k if k > 0 else math.inf
    result.depletion_revolutions_std = KILO * math.sqrt(cov[1, 1]) / k ** 2 if k > 0 else math.inf
    draws = _posterior_draws(state, cov, dof, rng)
    tail = (1.0 - result.confidence) / 2.0
    for level in levels:
        if not state[0] > math.log(level):
            result.revolution_crossings.append(Crossing(float(level), None, None, None))   # already below
            continue
        with np.errstate(divide='ignore', invalid='ignore'):
            remaining = np.where(draws[:, 1] > 0, np.maximum(draws[:, 0] - math.log(level), 0.0) / draws[:, 1],
                                 math.inf)
            low, estimate, high = np.quantile(remaining, [tail, 0.5, 1.0 - tail])   # the median: inside
        result.revolution_crossings.append(Crossing(float(level), *(
            float(odometer[-1] + v * KILO) if math.isfinite(v) else None for v in (estimate, low, high))))


def _crossed_between(times: np.ndarray, y: np.ndarray, sigma: np.ndarray, cycles: np.ndarray, level: float,
                     sigmas: float = 2.0) -> tuple[float, float, float] | None:
    """A crossing of ``level`` already seen in the last cycle: interpolated time and bracketing interval.

    The interval runs from the last recording clearly above the level
    (``sigmas`` one-sigmas) to the first one clearly below it after that.
    None when the last cycle has no recording above the level.
    """
    last = np.flatnonzero(cycles == cycles[-1])
    above = [j for j in last if y[j] > level]
    if not above:
        return None
    first_below = next((j for j in last if j > above[0] and y[j] <= level), None)
    if first_below is None:
        return None
    before = first_below - 1
    share = (y[before] - level) / (y[before] - y[first_below])
    estimate = times[before] + (times[first_below] - times[before]) * share
    sure_above = [j for j in last if y[j] - sigmas * sigma[j] > level and j <= before]
    sure_below = [j for j in last if y[j] + sigmas * sigma[j] < level and j >= first_below]
    if not sure_above:
        return None
    low = times[sure_above[-1]]
    high = times[sure_below[0]] if sure_below else times[last[-1]]
    return float(estimate), float(min(low, estimate)), float(max(high, estimate))


def _posterior_draws(mean: np.ndarray, covariance: np.ndarray, dof: int, rng: np.random.Generator) -> np.ndarray:
    """:data:`DRAWS` draws of a 2-vector: normal around ``mean``, Student-t with ``dof`` degrees of freedom if > 0."""
    normal = rng.standard_normal((DRAWS, 2)) @ np.linalg.cholesky(covariance + 1e-18 * np.eye(2)).T
    if dof:
        normal /= np.sqrt(rng.chisquare(dof, (DRAWS, 1)) / dof)
    return mean + normal


def _passage_draws(forecast: ActuatorForecast, level: float, rng: np.random.Generator) -> np.ndarray:
    """:data:`DRAWS` draws of the days from the last recording until ln theta first falls to ``level``.

    From a state (x, k) the first passage of the walk to ``level`` is inverse
    Gaussian (mean D/k with D = x - level, shape D^2/q); (x, k) are drawn from
    the filter's posterior (Student-t when its covariance was scaled).  A
    draw with k <= 0 never crosses (``inf``); a draw already below ``level``
    crossed before the last recording, as long ago as its drift puts it (a
    negative number of days; 0 without a drift).
    """
    assert forecast.state is not None and forecast.state_covariance is not None  # only forecasts with a state
    draws = _posterior_draws(forecast.state, forecast.state_covariance, forecast.state_dof, rng)
    distance = np.maximum(draws[:, 0] - level, 1e-12)
    days = np.full(DRAWS, math.inf)
    falling = draws[:, 1] > 0
    mean = distance[falling] / draws[falling, 1]
    q = forecast.diffusion
    days[falling] = rng.wald(mean, distance[falling] ** 2 / q) if q > 0 else mean
    below = draws[:, 0] <= level            # crossed before the last recording: when the draw's own drift says
    days[below] = np.where(draws[below, 1] > 0, (draws[below, 0] - level) / np.maximum(draws[below, 1], 1e-12), 0.0)
    return days


def _first_passage(forecast: ActuatorForecast, level: float, rng: np.random.Generator,
                   tail: float) -> tuple[float, float, float, np.ndarray]:
    """Days from the last recording until ln theta first falls to ``level``: estimate, interval and the draws.

    The estimate is the draws' median, so it lies inside the central interval by construction (inf when
    more than half the draws never cross).
    """
    days = _passage_draws(forecast, level, rng)
    with np.errstate(invalid='ignore'):               # inf - inf between never-crossing draws: still inf
        low, estimate, high = np.quantile(days, [tail, 0.5, 1.0 - tail])
    return float(estimate), float(low), float(high), days


def urgency_key(forecast: ActuatorForecast) -> tuple[int, float, float, str]:
    """Sort key: a suspected surface defect first, then the earliest warn crossing, then error; no forecast last.

    A defect ranks above every crossing (earliest onset first): it needs an
    inspection, not oil, and its theta_Oil is no lubrication measure.
    """
    if forecast.defect is not None:
        return (0, forecast.defect.since, forecast.defect.since, forecast.actuator)
    times = [c.time if c.time is not None else math.inf for c in forecast.crossings] or [math.inf]
    return (2 if forecast.reason else 1, times[0], times[-1], forecast.actuator)


def forecast_history(history: str | Path, *, actuator: str | None = None, relubrications: dict | None = None,
                     levels: Sequence[float] = (HealthThresholds.warn_below, HealthThresholds.error_below),
                     odometers: dict | None = None, confidence: float = INTERVAL, as_of: float | None = None,
                     on_problem: Callable[[str], None] | None = None) -> list[ActuatorForecast]:
    """Forecasts of every actuator (or one) in a history folder, most urgent first.

    ``relubrications`` maps an actuator id to its relubrication times (s since
    the epoch); actuators not in it have theirs detected.  ``odometers`` maps
    an actuator id to ``(times, cumulative revolutions)`` for the fit against
    revolutions.  ``as_of`` (s since the epoch) forecasts from the recordings
    made by then only.  ``on_problem(line)`` hears of history files skipped
    (without it they raise).  An actuator with a suspected surface defect
    has none (:mod:`.defects`).
    """
    records = history_records(history, on_problem=on_problem, actuator=actuator)
    return forecast_points(records.points, relubrications=relubrications, levels=levels, confidence=confidence,
                           as_of=as_of, only=actuator, odometers=odometers, defects=records.defects)


@dataclass(frozen=True)
class FleetRecords:
    """What a forecast reads from a history: recording points and defect marks per actuator, and notes.

    ``notes`` are lines worth one mention in a report (recordings assessed
    before the defect screen).
    """

    points: dict[str, list[RecordingPoint]]
    defects: dict[str, list[DefectMark]]
    notes: list[str]


def history_records(history: str | Path, *, on_problem: Callable[[str], None] | None = None,
                    actuator: str | None = None) -> FleetRecords:
    """Each actuator's recording points and defect marks from one read of a history's runs.

    :class:`InputError` when the history (or ``actuator``) has no assessed
    run; a run the defect screen flagged counts as assessed even without a
    theta_Oil.
    """
    actuator_key, read_table = history_readers()
    notes: list[str] = []
    runs = read_table(history, 'runs', on_problem=on_problem, on_note=notes.append)
    points, marks = recording_points(runs), defect_marks(runs)
    if not points and not marks:
        raise InputError(f'{history}: no assessed run in the history')
    if actuator is not None and actuator_key(actuator) not in points.keys() | marks.keys():
        raise InputError(f'{history}: no assessed run of actuator {actuator!r}')
    return FleetRecords(points, marks, notes)


def history_points(history: str | Path, *, on_problem: Callable[[str], None] | None = None,
                   actuator: str | None = None) -> dict[str, list[RecordingPoint]]:
    """Each actuator's recording points from a history folder; :class:`InputError` when it has none."""
    return history_records(history, on_problem=on_problem, actuator=actuator).points


def forecast_points(points: Mapping[str, Sequence[RecordingPoint]], *, relubrications: dict | None = None,
                    levels: Sequence[float] = (HealthThresholds.warn_below, HealthThresholds.error_below),
                    only: str | None = None, odometers: dict | None = None, confidence: float = INTERVAL,
                    as_of: float | None = None,
                    defects: Mapping[str, Sequence[DefectMark]] | None = None) -> list[ActuatorForecast]:
    """Forecasts from each actuator's recording points (the fleet's usage scatter pooled), most urgent first.

    ``only`` forecasts that actuator alone (the others still inform the
    usage scatter).  ``relubrications`` and ``odometers`` (``(times,
    readings)``: s since the epoch, cumulative revolutions, interpolated at
    the recordings for the fit against revolutions) are keyed by actuator id
    or partition key.  ``as_of`` keeps the points, relubrications and defect
    marks up to that time (s since the epoch) only.  ``defects`` (partition
    key to :class:`~.defects.DefectMark`, as :func:`history_records` gives
    them): an actuator with one by then has no forecast, only its
    ``defect``, and its recordings from the onset on stay out of the usage
    scatter.
    """
    actuator_key, _ = history_readers()
    given = {actuator_key(k): v for k, v in (relubrications or {}).items()}
    odometers = {actuator_key(k): v for k, v in (odometers or {}).items()}
    if as_of is not None:
        points = {name: kept for name, items in points.items() if (kept := [p for p in items if p.time <= as_of])}
        given = {name: [t for t in times if t <= as_of] for name, times in given.items()}
    onsets = defect_onsets(defects or {}, as_of)
    found, scatter = fleet_walk(before_onsets(points, onsets), given)
    names = [actuator_key(only)] if only is not None else list(dict.fromkeys([*points, *onsets]))
    forecasts = [fit_one(name, points.get(name, []), found.get(name, sorted(given.get(name, []))), levels, scatter,
                         odometers.get(name), confidence, defect=onsets.get(name)) for name in names]
    return sorted(forecasts, key=urgency_key)


def fleet_walk(points: Mapping[str, Sequence[RecordingPoint]], given: dict) -> tuple[dict[str, list[float]], float]:
    """Each actuator's relubrications (given, else detected) and the fleet's usage scatter."""
    found = {name: sorted(given[name]) if name in given else detect_relubrications(items)
             for name, items in points.items()}
    by_stride = [[_increments_of(items, found[name], stride) for name, items in points.items()] for stride in STRIDES]
    return found, usage_scatter_over_strides(by_stride)


def fit_one(name: str, points: Sequence[RecordingPoint], relubrications: Sequence[float], levels: Sequence[float],
            scatter: float | None, odometer: tuple[Sequence[float], Sequence[float]] | None,
            confidence: float = INTERVAL, *, defect: DefectOnset | None = None) -> ActuatorForecast:
    """:func:`fit_depletion` of one actuator; a numerical failure is its ``reason``, never the fleet's.

    With a suspected surface ``defect`` no fit at all: the forecast holds the
    points, relubrications and the defect, its ``reason`` says why.
    """
    if defect is not None:
        result = ActuatorForecast(name, sorted(points, key=lambda p: p.time), list(relubrications),
                                  confidence=confidence, defect=defect, reason=defect.reason)
        result.last_recording = max((p.time for p in points), default=math.nan)
        return result
    try:
        return fit_depletion(name, points, relubrications=relubrications, levels=levels, usage_scatter=scatter,
                             odometer=_odometer_at(points, odometer), confidence=confidence)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:   # one bad actuator, not a broken trend
        result = ActuatorForecast(name, list(points), list(relubrications))
        result.reason = f'no fit ({exc.__class__.__name__}: {exc})'.replace('\n', ' ')
        return result


#: how far (s) before the first or after the last odometer reading a recording may lie (extrapolated linearly)
ODOMETER_REACH = 3600.0


def _odometer_at(points: Sequence[RecordingPoint],
                 odometer: tuple[Sequence[float], Sequence[float]] | None) -> list[float] | None:
    """Odometer readings interpolated at the points' times, NaN beyond :data:`ODOMETER_REACH`, or None."""
    if odometer is None:
        return None
    times, readings = (np.asarray(v, float) for v in odometer)
    order = np.argsort(times)
    times, readings = times[order], readings[order]
    at = np.array([p.time for p in points])
    values = np.interp(at, times, readings)
    if times.size > 1:
        rates = np.diff(readings) / np.maximum(np.diff(times), 1e-9)
        values = np.where(at < times[0], readings[0] + rates[0] * (at - times[0]), values)
        values = np.where(at > times[-1], readings[-1] + rates[-1] * (at - times[-1]), values)
    values[(at < times[0] - ODOMETER_REACH) | (at > times[-1] + ODOMETER_REACH)] = math.nan
    return values.tolist()


def _increments_of(points: Sequence[RecordingPoint], relubrications: Sequence[float],
                   stride: int = 1) -> Increments | None:
    """The increments of ln theta_Oil between every ``stride``-th recording of each lubrication cycle of an actuator."""
    times = np.array([p.time for p in points])
    cycles = np.searchsorted(np.array(relubrications, float), times, side='right')
    return strided_increments(times / DAY, np.log([p.theta_oil for p in points]),
                              np.array([p.independent_std / p.theta_oil for p in points]), cycles, stride)


def history_readers() -> tuple[Callable[[str], str], Callable[..., pa.Table]]:
    """``actuator_key`` and ``read_table`` of :mod:`.history`; an :class:`InputError` line without pyarrow."""
    try:
        from .history import actuator_key, read_table
    except ImportError as exc:
        raise InputError(f'reading the fleet history needs pyarrow ({exc}): pip install "pyarrow>=14"') from None
    return actuator_key, read_table
