# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What a maintenance planner reads off a forecast: days to go, overdue, probability of crossing by a date.

Everything is stated "as of" a date (default: now): the days to go until
theta_Oil crosses a level (estimate and interval at the forecast's
confidence), and the probability that it has crossed by then or will have by
a chosen date.  The probabilities come from the same draws as the interval
(the first passage of the depletion walk over the state's uncertainty,
:func:`~prsm_lube_ros.fleet.forecast.fit_depletion`): a draw whose level is
already below at the last recording counts as crossed, so a theta_Oil that
truly fell below the level before the last recording but was measured just
above it shows as "may have crossed" with its probability, instead of a
crossing that can only lie ahead.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
import math

import numpy as np

from .forecast import ActuatorForecast, Crossing, DAY


__all__ = ['CrossingStatus', 'PlannedCrossing', 'plan', 'plan_crossing', 'planner_text', 'probability_crossed_by']


class CrossingStatus(Enum):
    """Where a level's crossing stands on the as-of date."""

    AHEAD = 'ahead'                          # crossed by the as-of date with at most the interval's tail
    MAY_HAVE_CROSSED = 'may have crossed'    # the as-of date lies inside the interval
    OVERDUE = 'overdue'                      # crossed by then but for the interval's tail
    NO_FORECAST = 'no forecast'


@dataclass(frozen=True)
class PlannedCrossing:
    """One level's crossing as a planner reads it on ``as_of`` (days from ``as_of``; None: not within reach)."""

    level: float
    status: CrossingStatus
    days_to_go: float | None
    days_low: float | None
    days_high: float | None
    probability_crossed: float | None        # by the as-of date
    probability_by: float | None             # by the chosen date

    def as_json(self) -> dict:
        """Plain mapping (the status as its text)."""
        return {'level': self.level, 'status': self.status.value, 'days_to_go': self.days_to_go,
                'days_low': self.days_low, 'days_high': self.days_high,
                'probability_crossed': self.probability_crossed, 'probability_by': self.probability_by}


def probability_crossed_by(forecast: ActuatorForecast, level: float, when: float) -> float | None:
    """Probability that theta_Oil has fallen to ``level`` by ``when`` (s since the epoch); None without draws."""
    draws = forecast.passage_days.get(level)
    if draws is None:
        return None
    return float(np.mean(draws <= (when - forecast.last_recording) / DAY))


def _days_from(as_of: float, seconds: float | None) -> float | None:
    return None if seconds is None else (seconds - as_of) / DAY


def plan_crossing(forecast: ActuatorForecast, crossing: Crossing, as_of: float, by: float) -> PlannedCrossing:
    """Status, days to go and probabilities of one crossing on ``as_of``, and the probability by ``by``."""
    crossed = probability_crossed_by(forecast, crossing.level, as_of)
    by_date = probability_crossed_by(forecast, crossing.level, by)
    days = _days_from(as_of, crossing.time)
    low, high = _days_from(as_of, crossing.low), _days_from(as_of, crossing.high)
    return PlannedCrossing(crossing.level, _status(crossed, low, high, (1.0 - forecast.confidence) / 2.0), days,
                           low, high, crossed, by_date)


def _status(crossed: float | None, low: float | None, high: float | None, tail: float) -> CrossingStatus:
    """OVERDUE when crossed beyond the interval's doubt, MAY_HAVE_CROSSED inside it, else AHEAD.

    From the probability of having crossed by the as-of date when the
    forecast has draws, else from where the interval (days from the as-of
    date) lies.
    """
    if crossed is not None:
        if crossed >= 1.0 - tail:
            return CrossingStatus.OVERDUE
        return CrossingStatus.MAY_HAVE_CROSSED if crossed > tail else CrossingStatus.AHEAD
    if high is not None and high < 0:
        return CrossingStatus.OVERDUE
    return CrossingStatus.MAY_HAVE_CROSSED if low is not None and low <= 0 else CrossingStatus.AHEAD


def plan(forecast: ActuatorForecast, as_of: float, by: float) -> list[PlannedCrossing]:
    """Every level of ``forecast`` as the planner reads it; none without a forecast.

    An actuator with a suspected surface defect has none either: it needs an
    inspection, and :func:`~.forecast.urgency_key` puts it first.
    """
    if forecast.reason:
        return []
    return [plan_crossing(forecast, crossing, as_of, by) for crossing in forecast.crossings]


def planner_text(item: PlannedCrossing) -> str:
    """Short text: ``in 12.3 d (8.1 .. 20.0)``, ``overdue by 2.0 d``, ``may have crossed (p 0.31)``."""
    if item.status is CrossingStatus.OVERDUE:
        return 'overdue' if item.days_to_go is None or item.days_to_go > 0 else f'overdue by {-item.days_to_go:.1f} d'
    interval = f'{_fmt(item.days_low)} .. {_fmt(item.days_high)}'
    ahead = 'never' if item.days_to_go is None else f'in {item.days_to_go:.1f} d'
    if item.status is CrossingStatus.MAY_HAVE_CROSSED:
        probability = '' if item.probability_crossed is None else f', p {item.probability_crossed:.2f}'
        return f'may have crossed{probability}; {ahead} ({interval})'
    return f'{ahead} ({interval})'


def _fmt(days: float | None) -> str:
    return 'never' if days is None or not math.isfinite(days) else f'{days:.1f}'
