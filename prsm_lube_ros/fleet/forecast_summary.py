# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A forecast in words: the estimator's diagnostics KeyValues and the trend table's crossing intervals.

:func:`forecast_summaries` is the one call for the estimator's diagnostics:
every actuator it names from a history folder, the table read and the fleet's
usage scatter fitted once (:mod:`.forecast`); :func:`forecast_summary` does it
for one.
"""
from __future__ import annotations

from typing import TYPE_CHECKING
from collections.abc import Sequence

from ..errors import InputError
from ..estimation.health import HealthThresholds
from .defects import before_onsets, defect_marks, defect_onsets
from .forecast import ActuatorForecast, Crossing, fit_one, fleet_walk, history_readers, recording_points, utc_minutes

if TYPE_CHECKING:
    from pathlib import Path

__all__ = ['crossing_interval_text', 'forecast_summaries', 'forecast_summary']


def forecast_summaries(history: str | Path, actuator_ids: Sequence[str], *,
                       warn_below: float = HealthThresholds.warn_below,
                       error_below: float = HealthThresholds.error_below) -> dict[str, dict[str, str]]:
    """The forecast of each of ``actuator_ids`` as short key/value strings (diagnostics KeyValue lists).

    One call per period for all of an estimator's actuators: the runs table
    is read and the fleet's usage scatter fitted once.  Keys of each summary:
    ``forecast``, ``tau_days``, ``theta_now``, ``warn_crossing``,
    ``warn_interval``, ``error_crossing``, ``error_interval`` (UTC, minutes);
    ``forecast`` holds ``ok`` or the reason there is none, and is the only key
    (``none: <reason>``) for an id the history has no assessed run of.  An
    actuator with a suspected surface defect (:mod:`.defects`) has the
    defect as its ``forecast`` reason and ``defect_since`` (UTC, minutes),
    ``defect_component`` and ``defect_evidence`` instead of the numbers.
    Raises :class:`InputError` for a history that cannot be read (missing,
    unreadable, pyarrow not installed).
    """
    return {name: {'forecast': f'none: {found}'} if isinstance(found, InputError) else found
            for name, found in _summaries(history, actuator_ids, (warn_below, error_below)).items()}


def forecast_summary(history: str | Path, actuator_id: str, *, warn_below: float = HealthThresholds.warn_below,
                     error_below: float = HealthThresholds.error_below) -> dict[str, str]:
    """The forecast of one actuator as :func:`forecast_summaries` gives it.

    Raises :class:`InputError` for a missing history or an actuator without runs.
    """
    found = _summaries(history, [actuator_id], (warn_below, error_below))[actuator_id]
    if isinstance(found, InputError):
        raise found
    return found


def _summaries(history: str | Path, actuator_ids: Sequence[str],
               levels: tuple[float, float]) -> dict[str, dict[str, str] | InputError]:
    """Summary of each id, or the :class:`InputError` saying why there is none."""
    actuator_key, read_table = history_readers()
    runs = read_table(history, 'runs')
    points, onsets = recording_points(runs), defect_onsets(defect_marks(runs))
    found, scatter = fleet_walk(before_onsets(points, onsets), {})
    result: dict[str, dict[str, str] | InputError] = {}
    for actuator_id in actuator_ids:
        try:
            key = actuator_key(actuator_id)
        except InputError as exc:
            result[actuator_id] = exc
            continue
        if key not in points and key not in onsets:
            result[actuator_id] = InputError(f'{history}: no assessed run of actuator {actuator_id!r}')
            continue
        result[actuator_id] = _summary(fit_one(key, points.get(key, []), found.get(key, []), levels, scatter, None,
                                               defect=onsets.get(key)))
    return result


def _summary(forecast: ActuatorForecast) -> dict[str, str]:
    """Short key/value strings of a forecast."""
    if forecast.defect is not None:
        return {'forecast': forecast.reason, 'defect_since': forecast.defect.since_utc,
                'defect_component': forecast.defect.component, 'defect_evidence': forecast.defect.evidence}
    if forecast.reason:
        return {'forecast': forecast.reason}
    summary = {'forecast': 'ok', 'tau_days': f'{forecast.tau_days:.3g}', 'theta_now': f'{forecast.theta_now:.3f}'}
    for name, crossing in zip(('warn', 'error'), forecast.crossings):
        summary[f'{name}_crossing'] = utc_minutes(crossing.time) or 'never'
        summary[f'{name}_interval'] = crossing_interval_text(crossing)
    return summary


def crossing_interval_text(crossing: Crossing) -> str:
    """``low .. high`` in UTC minutes (``never`` for an open end); ``never`` alone when no crossing is estimated."""
    if crossing.time is None:
        return 'never'
    return f'{utc_minutes(crossing.low) or "never"} .. {utc_minutes(crossing.high) or "never"}'
