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

The fleet's view (:func:`planner_rows`): each actuator's next crossing of
either level (the error level once the warn level is overdue) with its
probability by the planning date, ranked by it (:func:`planner_rank`); the
last recording and the data's age on the as-of date, flagged stale beyond
``stale_days``; and the forecast band of theta_Oil at the as-of date, not
the last measurement.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
import math
from collections.abc import Sequence

import numpy as np

from .forecast import ActuatorForecast, Crossing, DAY


__all__ = ['CrossingStatus', 'PlannedCrossing', 'PlannerRow', 'STALE_DAYS', 'next_crossing', 'plan', 'plan_crossing',
           'planner_rank', 'planner_rows', 'planner_text', 'probability_crossed_by']

#: data older than this on the as-of date (days since the last recording) is flagged stale
STALE_DAYS = 7.0


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


def next_crossing(planned: Sequence[PlannedCrossing]) -> PlannedCrossing | None:
    """The crossing a planner acts on: the lowest level once it is overdue, else the first level not overdue.

    A warn level overdue while the error level is not makes the error
    crossing the next one.  None without levels.
    """
    if not planned:
        return None
    lowest = min(planned, key=lambda item: item.level)
    if lowest.status is CrossingStatus.OVERDUE:
        return lowest
    return next(item for item in sorted(planned, key=lambda item: -item.level)
                if item.status is not CrossingStatus.OVERDUE)


def planner_rank(forecast: ActuatorForecast, planned: Sequence[PlannedCrossing]) -> tuple[int, float, float, str]:
    """Sort key of the planner's table: the earliest next crossing of either level first.

    A suspected surface defect first (it needs an inspection), then the
    lowest level overdue (longest overdue first), then by the days to go of
    the next crossing (ties: the higher probability by the planning date
    first), then the actuators whose levels lie beyond reach, then those
    without a forecast.
    """
    if forecast.defect is not None:
        return (0, forecast.defect.since, 0.0, forecast.actuator)
    item = next_crossing(planned)
    if forecast.reason or item is None:
        return (5, math.inf, 0.0, forecast.actuator)
    probability = -(item.probability_by or 0.0)
    if item.status is CrossingStatus.OVERDUE:
        return (1, item.days_to_go if item.days_to_go is not None else -math.inf, probability, forecast.actuator)
    if item.days_to_go is None:
        return (3, math.inf, probability, forecast.actuator)
    return (2, item.days_to_go, probability, forecast.actuator)


@dataclass
class PlannerRow:
    """One actuator as the planner's table shows it on the as-of date (rank 1: most urgent)."""

    rank: int
    forecast: ActuatorForecast
    planned: list[PlannedCrossing] = field(default_factory=list)
    next: PlannedCrossing | None = None
    last_seen: float = math.nan                # s since the epoch of the last recording
    data_age_days: float = math.nan            # from the last recording to the as-of date
    stale: bool = False
    #: forecast theta_Oil at the as-of date: centre and the band at the forecast's confidence (NaN without one)
    theta_as_of: tuple[float, float, float] = (math.nan, math.nan, math.nan)

    @property
    def actuator(self) -> str:
        """The actuator's id."""
        return self.forecast.actuator

    def as_json(self) -> dict:
        """Plain mapping (without the forecast itself)."""
        centre, low, high = (v if math.isfinite(v) else None for v in self.theta_as_of)
        return {'rank': self.rank, 'next': None if self.next is None else self.next.as_json(),
                'last_seen': self.last_seen if math.isfinite(self.last_seen) else None,
                'data_age_days': self.data_age_days if math.isfinite(self.data_age_days) else None,
                'stale': self.stale, 'theta_as_of': centre, 'theta_as_of_low': low, 'theta_as_of_high': high}


def planner_rows(forecasts: Sequence[ActuatorForecast], as_of: float, by: float,
                 stale_days: float = STALE_DAYS) -> list[PlannerRow]:
    """Every forecast as a row of the planner's table, ranked by :func:`planner_rank`.

    ``as_of`` and ``by`` in s since the epoch; a row is ``stale`` when its
    last recording is more than ``stale_days`` before ``as_of``.
    """
    rows = []
    for forecast in forecasts:
        planned = plan(forecast, as_of, by)
        last = forecast.last_recording
        age = (as_of - last) / DAY if math.isfinite(last) else math.nan
        theta = (math.nan, math.nan, math.nan)
        if not forecast.reason and forecast.state is not None:
            theta = tuple(float(v[0]) for v in forecast.band(np.array([as_of])))    # type: ignore[assignment]
        rows.append(PlannerRow(0, forecast, planned, next_crossing(planned), last, age,
                               bool(age > stale_days), theta))
    rows.sort(key=lambda row: planner_rank(row.forecast, row.planned))
    for rank, row in enumerate(rows, start=1):
        row.rank = rank
    return rows
