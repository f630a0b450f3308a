# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Backtest: forecast from the history cut DAYS earlier and score it against what was measured afterwards.

The cut lies ``days`` before the newest recording of the history.  Each
actuator is forecast from its recordings up to the cut (the fleet's usage
scatter from everyone's), then scored on its later recordings, up to its
first relubrication after the cut (which the forecast cannot know of):

* band: a later recording counts as inside when its ln theta_Oil lies within
  the forecast band widened by its own one-sigma (both at the forecast's
  confidence);
* crossings: where the later recordings cross a level (interpolated between
  the last one above and the first one below), whether that time lies inside
  the forecast interval widened by the time measurement noise moves it (the
  recordings' own one-sigma over the forecast's fall rate, at the same
  confidence, as the band is widened), and the error of the estimate in days.

Coverage near the stated confidence says the intervals mean what they say.
Each crossing is scored with its horizon, the days from the cut to the
crossing seen; :func:`horizon_coverage` gives the coverage per level and
horizon class (up to 3, 7, 14 and 30 days: :data:`HORIZONS`), and
:func:`rolling_backtest` cuts the history at several origins (every
``step_days`` up to the longest horizon before the newest recording) so every
horizon class gets crossings to score.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from collections.abc import Mapping, Sequence

import numpy as np

from .defects import defect_onsets, DefectMark
from .forecast import (ActuatorForecast, DAY, detect_relubrications, forecast_points, INTERVAL, RecordingPoint,
                       two_sided_quantile)
from ..validation import finite_or_none


__all__ = ['ActuatorBacktest', 'Backtest', 'CrossingScore', 'HORIZONS', 'HorizonCoverage', 'backtest',
           'horizon_class', 'horizon_coverage', 'rolling_backtest']

#: horizon classes (days from the cut to the crossing seen): up to 3, over 3 up to 7, ...
HORIZONS = (3.0, 7.0, 14.0, 30.0)


@dataclass(frozen=True)
class CrossingScore:
    """A level's crossing seen after the cut: when, whether inside the interval, estimate error (days)."""

    level: float
    observed: float                   # s since the epoch
    inside: bool
    error_days: float | None          # estimate minus observed; None without an estimate
    horizon_days: float = math.nan    # from the cut to the crossing seen
    estimate_inside: bool = True      # the forecast's own estimate lies inside its own interval


@dataclass
class ActuatorBacktest:
    """One actuator's forecast at the cut, scored on its later recordings."""

    actuator: str
    later: int = 0                    # recordings scored (after the cut, before a relubrication)
    inside_band: int = 0
    crossings: list[CrossingScore] = field(default_factory=list)
    reason: str = ''


@dataclass
class Backtest:
    """All actuators' scores and the fleet's coverage figures."""

    days: float
    cut: float                        # s since the epoch
    confidence: float
    actuators: list[ActuatorBacktest]

    @property
    def band_coverage(self) -> float:
        """Share of later recordings inside the forecast band (NaN without any)."""
        total = sum(a.later for a in self.actuators)
        return sum(a.inside_band for a in self.actuators) / total if total else math.nan

    @property
    def crossing_coverage(self) -> float:
        """Share of crossings seen after the cut that lie inside their forecast interval (NaN without any)."""
        scores = [c for a in self.actuators for c in a.crossings]
        return sum(c.inside for c in scores) / len(scores) if scores else math.nan

    def as_json(self) -> dict:
        """Plain mapping for the backtest JSON."""
        errors = [abs(c.error_days) for a in self.actuators for c in a.crossings if c.error_days is not None]
        return {'days': self.days, 'cut': self.cut, 'confidence': self.confidence,
                'band_coverage': finite_or_none(self.band_coverage),
                'crossing_coverage': finite_or_none(self.crossing_coverage),
                'recordings_scored': sum(a.later for a in self.actuators),
                'crossings_scored': sum(len(a.crossings) for a in self.actuators),
                'by_horizon': [c.as_json() for c in horizon_coverage([self])],
                'median_abs_crossing_error_days': float(np.median(errors)) if errors else None,
                'actuators': [{'actuator': a.actuator, 'reason': a.reason, 'later': a.later,
                               'inside_band': a.inside_band,
                               'crossings': [vars(c) for c in a.crossings]} for a in self.actuators]}


@dataclass(frozen=True)
class HorizonCoverage:
    """Crossings of one level seen within one horizon class: how many, how many inside their interval."""

    level: float
    horizon_days: float               # the class's upper end; the lower is the previous class's
    scored: int
    inside: int
    estimates_outside: int            # forecast estimates outside their own interval

    @property
    def coverage(self) -> float:
        """Share inside (NaN without any crossing)."""
        return self.inside / self.scored if self.scored else math.nan

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'level': self.level, 'horizon_days': self.horizon_days, 'scored': self.scored, 'inside': self.inside,
                'coverage': finite_or_none(self.coverage), 'estimates_outside': self.estimates_outside}


def horizon_class(days: float, horizons: Sequence[float] = HORIZONS) -> float | None:
    """The horizon class (its upper end, days) of a crossing ``days`` after the cut; None beyond the last."""
    return next((h for h in horizons if days <= h), None)


def horizon_coverage(results: Sequence[Backtest], horizons: Sequence[float] = HORIZONS,
                     levels: Sequence[float] | None = None) -> list[HorizonCoverage]:
    """Coverage of the crossing intervals per level and horizon class over one or more backtests."""
    scores = [c for result in results for a in result.actuators for c in a.crossings]
    levels = sorted({c.level for c in scores} if levels is None else set(levels), reverse=True)
    table = []
    for level in levels:
        for horizon in horizons:
            chosen = [c for c in scores if math.isclose(c.level, level)
                      and horizon_class(c.horizon_days, horizons) == horizon]
            table.append(HorizonCoverage(float(level), float(horizon), len(chosen), int(sum(c.inside for c in chosen)),
                                         int(sum(not c.estimate_inside for c in chosen))))
    return table


def rolling_backtest(points: Mapping[str, Sequence[RecordingPoint]], *, horizons: Sequence[float] = HORIZONS,
                     step_days: float = 2.0, relubrications: dict | None = None, levels: Sequence[float],
                     confidence: float = INTERVAL, defects: Mapping[str, Sequence[DefectMark]] | None = None,
                     truth: Mapping[str, Sequence[RecordingPoint]] | None = None) -> list[Backtest]:
    """:func:`backtest` cut ``step_days``, 2 ``step_days``, ... up to the longest horizon before the newest recording.

    Cuts that leave no recording before them are skipped.  Score them
    together with :func:`horizon_coverage`.
    """
    oldest = min(p.time for items in points.values() for p in items)
    newest = max(p.time for items in points.values() for p in items)
    results = []
    for days in np.arange(step_days, max(horizons) + step_days / 2.0, step_days):
        if newest - days * DAY > oldest:
            results.append(backtest(points, float(days), relubrications=relubrications, levels=levels,
                                    confidence=confidence, defects=defects, truth=truth))
    return results


def backtest(points: Mapping[str, Sequence[RecordingPoint]], days: float, *, relubrications: dict | None = None,
             levels: Sequence[float], confidence: float = INTERVAL,
             defects: Mapping[str, Sequence[DefectMark]] | None = None,
             truth: Mapping[str, Sequence[RecordingPoint]] | None = None) -> Backtest:
    """Forecast every actuator from ``points`` up to ``days`` before the newest one; score on the rest.

    ``truth`` (a simulation's true theta_Oil at the same recordings, zero
    one-sigma) scores the forecast made from ``points`` against the process
    itself instead of its measurements.

    ``defects`` (:func:`~.forecast.history_records`): an actuator with a
    suspected surface defect by the cut has no forecast to score; one whose
    defect is first seen after the cut is scored up to the recording it is
    first seen in (theta_Oil reads damage from there on).
    """
    newest = max(p.time for items in points.values() for p in items)
    cut = newest - days * DAY
    forecasts = forecast_points(points, relubrications=relubrications, levels=levels, confidence=confidence,
                                as_of=cut, defects=defects)
    onsets = defect_onsets(defects or {})
    scoring = points if truth is None else truth
    scored = {f.actuator: _score(f, scoring.get(f.actuator, []), cut, (relubrications or {}).get(f.actuator),
                                 onsets[f.actuator].since_recording if f.actuator in onsets else math.inf)
              for f in forecasts}
    missing = [ActuatorBacktest(name, reason='no recording before the cut') for name in points if name not in scored]
    return Backtest(days, cut, confidence, sorted(scored.values(), key=lambda a: a.actuator) + missing)


def _score(forecast: ActuatorForecast, points: Sequence[RecordingPoint], cut: float,
           given: Sequence[float] | None, defect_from: float = math.inf) -> ActuatorBacktest:
    """One actuator's later recordings against its forecast at the cut, up to a relubrication or a defect."""
    result = ActuatorBacktest(forecast.actuator, reason=forecast.reason)
    if forecast.reason:
        return result
    before = [p for p in points if p.time <= cut]
    # a relubrication after the last recording the forecast saw ends the scoring, even one before the cut: a
    # jump up is placed half-way between two recordings, which may put it before the cut the forecast knew no
    # recording after
    seen_until = before[-1].time if before else cut
    relubricated = [t for t in (given if given is not None else detect_relubrications(points)) if t > seen_until]
    end = min(relubricated + [defect_from])
    later = [p for p in points if cut < p.time < end]
    result.later = len(later)
    result.inside_band = sum(_inside_band(forecast, p) for p in later)
    for crossing in forecast.crossings:
        seen = _observed_crossing(before[-1:] + later, crossing.level)
        if seen is not None:
            observed, noise, local_slope = seen
            slack = _timing_slack(forecast, crossing.level, noise, local_slope)
            high = math.inf if crossing.high is None else crossing.high
            low = -math.inf if crossing.low is None else crossing.low
            inside = bool(crossing.low is not None and crossing.low - slack <= observed <= high + slack)
            error = None if crossing.time is None else (crossing.time - observed) / DAY
            estimate_inside = bool(crossing.time is None or low <= crossing.time <= high)
            result.crossings.append(CrossingScore(crossing.level, observed, inside, error, (observed - cut) / DAY,
                                                  estimate_inside))
    return result


def _inside_band(forecast: ActuatorForecast, point: RecordingPoint) -> bool:
    """True when the point's ln theta lies in the band widened by its own one-sigma (same confidence)."""
    centre, low, high = (float(v[0]) for v in forecast.band(np.array([point.time])))
    z = two_sided_quantile(forecast.confidence)
    spread = math.hypot((math.log(high) - math.log(low)) / 2.0, z * point.theta_oil_std / point.theta_oil)
    return abs(math.log(point.theta_oil) - math.log(centre)) <= spread


def _observed_crossing(points: Sequence[RecordingPoint], level: float) -> tuple[float, float, float] | None:
    """The measured theta_Oil's first fall below ``level``: interpolated time, its theta one-sigma, local slope.

    The one-sigma is that of the interpolated value (the bracketing
    recordings' own), the slope (theta per s, > 0 falling) that between them;
    None when the values never fall below ``level``.
    """
    for before, after in zip(points, points[1:]):
        if before.theta_oil > level >= after.theta_oil:
            share = (before.theta_oil - level) / (before.theta_oil - after.theta_oil)
            gap = after.time - before.time
            noise = math.hypot((1.0 - share) * before.independent_std, share * after.independent_std)
            return before.time + share * gap, noise, (before.theta_oil - after.theta_oil) / max(gap, 1e-9)
    return None


def _timing_slack(forecast: ActuatorForecast, level: float, noise: float, local_slope: float) -> float:
    """How far (s) measurement noise moves a measured crossing: ``z`` one-sigmas of theta over theta's fall rate.

    The fall rate is the forecast's own drift at the level (k theta), the
    bracketing recordings' slope without one: that slope is steepest exactly
    where a recording's noise dips below the level, and would make the slack
    smallest where it is needed most.
    """
    z = two_sided_quantile(forecast.confidence)
    drift = forecast.state[1] / DAY if forecast.state is not None else 0.0
    slope = drift * level if drift > 0 else local_slope
    return z * noise / slope if slope > 0 else math.inf
