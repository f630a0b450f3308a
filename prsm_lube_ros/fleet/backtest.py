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
  the forecast interval, and the error of the estimate in days.

Coverage near the stated confidence says the intervals mean what they say.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from collections.abc import Mapping, Sequence

import numpy as np

from .defects import defect_onsets, DefectMark
from .forecast import (ActuatorForecast, DAY, detect_relubrications, forecast_points, INTERVAL, RecordingPoint,
                       two_sided_quantile)


__all__ = ['ActuatorBacktest', 'Backtest', 'CrossingScore', 'backtest']


@dataclass(frozen=True)
class CrossingScore:
    """A level's crossing seen after the cut: when, whether inside the interval, estimate error (days)."""

    level: float
    observed: float                   # s since the epoch
    inside: bool
    error_days: float | None          # estimate minus observed; None without an estimate


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
                'band_coverage': _finite(self.band_coverage), 'crossing_coverage': _finite(self.crossing_coverage),
                'recordings_scored': sum(a.later for a in self.actuators),
                'crossings_scored': sum(len(a.crossings) for a in self.actuators),
                'median_abs_crossing_error_days': float(np.median(errors)) if errors else None,
                'actuators': [{'actuator': a.actuator, 'reason': a.reason, 'later': a.later,
                               'inside_band': a.inside_band,
                               'crossings': [vars(c) for c in a.crossings]} for a in self.actuators]}


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def backtest(points: Mapping[str, Sequence[RecordingPoint]], days: float, *, relubrications: dict | None = None,
             levels: Sequence[float], confidence: float = INTERVAL,
             defects: Mapping[str, Sequence[DefectMark]] | None = None) -> Backtest:
    """Forecast every actuator from ``points`` up to ``days`` before the newest one; score on the rest.

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
    scored = {f.actuator: _score(f, points.get(f.actuator, []), cut, (relubrications or {}).get(f.actuator),
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
    relubricated = [t for t in (given if given is not None else detect_relubrications(points)) if t > cut]
    end = min(relubricated + [defect_from])
    later = [p for p in points if cut < p.time < end]
    result.later = len(later)
    result.inside_band = sum(_inside_band(forecast, p) for p in later)
    before = [p for p in points if p.time <= cut]
    for crossing in forecast.crossings:
        observed = _observed_crossing(before[-1:] + later, crossing.level)
        if observed is not None:
            high = math.inf if crossing.high is None else crossing.high
            inside = crossing.low is not None and crossing.low <= observed <= high
            error = None if crossing.time is None else (crossing.time - observed) / DAY
            result.crossings.append(CrossingScore(crossing.level, observed, inside, error))
    return result


def _inside_band(forecast: ActuatorForecast, point: RecordingPoint) -> bool:
    """True when the point's ln theta lies in the band widened by its own one-sigma (same confidence)."""
    centre, low, high = (float(v[0]) for v in forecast.band(np.array([point.time])))
    z = two_sided_quantile(forecast.confidence)
    spread = math.hypot((math.log(high) - math.log(low)) / 2.0, z * point.theta_oil_std / point.theta_oil)
    return abs(math.log(point.theta_oil) - math.log(centre)) <= spread


def _observed_crossing(points: Sequence[RecordingPoint], level: float) -> float | None:
    """Time the measured theta_Oil first falls below ``level`` (interpolated), None when it does not."""
    for before, after in zip(points, points[1:]):
        if before.theta_oil > level >= after.theta_oil:
            share = (before.theta_oil - level) / (before.theta_oil - after.theta_oil)
            return before.time + share * (after.time - before.time)
    return None
