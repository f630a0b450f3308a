# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnostic level of one actuator's lubrication: thresholds, hysteresis, staleness.

Pure logic, no ROS import: the estimator node feeds it each window's theta_Oil
and the node-clock time of each vibration message, and turns
:meth:`HealthMonitor.status` into a ``diagnostic_msgs/DiagnosticStatus``.

Levels follow ``diagnostic_msgs/DiagnosticStatus``: OK=0, WARN=1, ERROR=2,
STALE=3.  The rules:

* the level is judged on the mean theta_Oil of the last ``level_smoothing``
  assessed windows (8 by default; 1 judges each window alone): the scatter of
  single windows (about 0.02 in theta) is close to a useful hysteresis, and
  judged window by window a theta at a threshold flipped WARN/ERROR every half
  minute.  The mean of 8 scatters by 0.007, a quarter of the default
  hysteresis (a median of 5 or a mean of 5 still flapped in simulation), and
  follows a step from 0.95 to 0.6 after 6 windows;
* that theta below ``warn_below`` is WARN, below ``error_below`` is ERROR; a
  worse level is taken at once, a better one only when theta_Oil rises above
  the threshold plus ``hysteresis`` (so a theta hovering at a threshold does
  not make the level flicker);
* a window that cannot be assessed (NaN theta: screw at rest, no load, blocks
  lost) does not change the theta level; the message says "not assessable:
  <reason>".  Only when ``max_unassessed_windows`` consecutive windows in a
  row cannot be assessed *while the screw moves* (an input problem, not a
  pause) is the status raised to at least WARN; a screw at rest never is;
* STALE when no vibration arrived for ``stale_timeout`` s of node clock (and
  before the first one); the theta level is kept and comes back with the
  inputs.

Messages stay the same while the state does (diagnostic aggregators and
loggers de-duplicate on them): they name the level's cause and the
thresholds, never a number that changes window by window.  The numbers
(theta_Oil, its mean, windows not assessed, seconds without vibration, the
window's reason in full) are in :class:`HealthStatus` for the KeyValues.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace
import math
import statistics
from typing import Any

from ..errors import InputError

__all__ = ['ERROR', 'HealthMonitor', 'HealthStatus', 'HealthThresholds', 'LEVEL_NAMES', 'OK', 'REASON_WORDS',
           'STALE', 'WARN', 'format_value', 'out_of_range', 'outside_domain', 'theta_level', 'uncalibrated']

OK = 0
WARN = 1
ERROR = 2
STALE = 3

LEVEL_NAMES = {OK: 'OK', WARN: 'WARN', ERROR: 'ERROR', STALE: 'STALE'}

#: Why a window was not assessed, in words without numbers, by ``Window.reason_kind`` (and ``low_load``).
REASON_WORDS = {
    'no_vibration': 'no vibration samples in the window',
    'blocks_lost': 'vibration blocks lost (coverage below min_coverage)',
    'no_speed': 'no screw speed in the window',
    'at_rest': 'screw at rest or crawling (below min_speed)',
    'speed_changing': 'screw speed not steady (acceleration or deceleration)',
    'spans_runs': 'window spans the end of one run and the start of the next',
    'no_load': 'no axial load in the window',
    'low_load': 'axial load below min_axial_load',
}


@dataclass(frozen=True)
class HealthThresholds:
    """Where the levels change, theta_Oil dimensionless, times in s of node clock."""

    warn_below: float = 0.85
    error_below: float = 0.70
    hysteresis: float = 0.03
    stale_timeout: float = 5.0
    max_unassessed_windows: int = 30   # 0: never raise for windows that cannot be assessed
    level_smoothing: int = 8           # assessed windows whose mean theta_Oil sets the level

    def __post_init__(self) -> None:
        """Reject thresholds that cannot order the levels."""
        numbers = {'warn_below': self.warn_below, 'error_below': self.error_below,
                   'hysteresis': self.hysteresis, 'stale_timeout': self.stale_timeout}
        for name, value in numbers.items():
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise InputError(f'health threshold {name}={value!r} must be a finite number')
        if not self.error_below < self.warn_below:
            raise InputError(f'health thresholds: error_below ({self.error_below}) must be below '
                             f'warn_below ({self.warn_below})')
        if not 0 <= self.hysteresis < self.warn_below - self.error_below:
            raise InputError(f'health threshold hysteresis={self.hysteresis} must be >= 0 and smaller than '
                             f'warn_below - error_below ({self.warn_below - self.error_below:.3g})')
        if not self.stale_timeout > 0:
            raise InputError(f'health threshold stale_timeout={self.stale_timeout} s must be > 0')
        if not (isinstance(self.max_unassessed_windows, int) and self.max_unassessed_windows >= 0):
            raise InputError(f'health threshold max_unassessed_windows={self.max_unassessed_windows!r} '
                             'must be an integer >= 0')
        if not (isinstance(self.level_smoothing, int) and self.level_smoothing >= 1):
            raise InputError(f'health threshold level_smoothing={self.level_smoothing!r} must be an integer >= 1')


def theta_level(theta: float, previous: int | None, thresholds: HealthThresholds) -> int:
    """Level for a finite theta_Oil given the previous theta level (None: no previous), with hysteresis.

    Worsening is immediate (theta < threshold); improving needs theta above
    threshold + hysteresis.
    """
    t = thresholds
    if theta < t.error_below:
        return ERROR
    if theta < t.warn_below:
        if previous == ERROR and not theta > t.error_below + t.hysteresis:
            return ERROR
        return WARN
    # theta >= warn_below
    if previous in (WARN, ERROR) and not theta > t.warn_below + t.hysteresis:
        return WARN
    return OK


@dataclass(frozen=True)
class HealthStatus:
    """What the diagnostic status says right now."""

    level: int
    message: str
    theta_level: int | None        # level from the last assessed theta (None before the first)
    unassessed_windows: int        # consecutive windows without a theta
    theta_mean: float = math.nan   # mean theta_Oil of the windows that set the level
    unassessed_moving: int = 0     # consecutive windows without a theta while the screw moves
    reason: str = ''               # the last unassessed window's reason, in full (with its numbers)


class HealthMonitor:
    """Level and message of one actuator, updated window by window."""

    def __init__(self, thresholds: HealthThresholds | None = None):
        self.thresholds = thresholds or HealthThresholds()
        self._theta_level: int | None = None
        self._recent: deque[float] = deque()
        self._theta = math.nan
        self._theta_std = math.nan
        self._unassessed = 0
        self._unassessed_moving = 0
        self._reason = ''
        self._reason_words = ''
        self._judged = math.nan
        self._last_input: float | None = None
        self._message = 'no window evaluated yet'

    def restart_smoothing(self) -> None:
        """Forget the windows averaged for the level (new calibration: old thetas are on another scale).

        The theta level itself is kept until the next assessed window judges it anew.
        """
        self._recent.clear()

    def set_thresholds(self, thresholds: HealthThresholds) -> None:
        """New thresholds; the theta level is re-judged at the next assessed window."""
        self.thresholds = thresholds

    def note_input(self, now: float) -> None:
        """A vibration message arrived at node-clock time ``now`` (s)."""
        self._last_input = now

    def observe(self, theta: float, theta_std: float = math.nan, reason: str = '',
                moving: bool = True, kind: str = '') -> int:
        """Take one window's theta_Oil (NaN with ``reason`` when not assessable); return the theta level.

        ``moving`` says whether the screw turned in that window (a NaN window at
        rest is a pause, not a problem); ``kind`` is the reason's code
        (:data:`REASON_WORDS`), whose words go into the message instead of
        ``reason`` (which may carry the window's numbers).
        """
        if math.isfinite(theta):
            t = self.thresholds
            self._recent.append(theta)
            while len(self._recent) > t.level_smoothing:
                self._recent.popleft()
            judged = statistics.fmean(self._recent)
            self._theta_level = theta_level(judged, self._theta_level, t)
            self._theta, self._theta_std, self._judged = theta, theta_std, judged
            self._unassessed = self._unassessed_moving = 0
            self._reason = self._reason_words = ''
            if self._theta_level == ERROR:
                why = (f'below the error threshold {t.error_below:g}' if judged < t.error_below else
                       f'not yet above {t.error_below + t.hysteresis:g} (error threshold + hysteresis)')
                self._message = f'lubrication insufficient: mean theta_oil {why}'
            elif self._theta_level == WARN:
                why = (f'below the warning threshold {t.warn_below:g}' if judged < t.warn_below else
                       f'not yet above {t.warn_below + t.hysteresis:g} (warning threshold + hysteresis)')
                self._message = f'lubrication degraded: mean theta_oil {why}'
            else:
                self._message = 'lubrication good'
        else:
            self._unassessed += 1
            self._unassessed_moving = self._unassessed_moving + 1 if moving else 0
            self._reason = reason or 'theta_oil is not a number'
            self._reason_words = REASON_WORDS.get(kind, self._reason)
            self._message = f'not assessable: {self._reason_words}' + self._last_level()
        return self._theta_level if self._theta_level is not None else OK

    def _last_level(self) -> str:
        """'; last level WARN' once a theta was assessed ('' before)."""
        return '' if self._theta_level is None else f'; last level {LEVEL_NAMES[self._theta_level]}'

    def stale_for(self, now: float) -> float:
        """Seconds since the last vibration message (inf before the first)."""
        return math.inf if self._last_input is None else now - self._last_input

    def status(self, now: float) -> HealthStatus:
        """Level and message at node-clock time ``now`` (s)."""
        t = self.thresholds
        silent = self.stale_for(now)
        numbers: dict[str, Any] = dict(theta_mean=self._judged, unassessed_moving=self._unassessed_moving,
                                       reason=self._reason)
        if silent > t.stale_timeout:
            if self._last_input is None:
                message = 'no vibration received yet'
            else:
                message = f'inputs stopped: no vibration for more than stale_timeout ({t.stale_timeout:g} s)'
            return HealthStatus(STALE, message + self._last_level(), self._theta_level, self._unassessed, **numbers)
        level = self._theta_level if self._theta_level is not None else OK
        message = self._message
        if t.max_unassessed_windows and self._unassessed_moving >= t.max_unassessed_windows:
            level = max(level, WARN)
            message = (f'not assessable while the screw moves (max_unassessed_windows {t.max_unassessed_windows} '
                       f'reached): {self._reason_words}' + self._last_level())
        return HealthStatus(level, message, self._theta_level, self._unassessed, **numbers)


def uncalibrated(status: HealthStatus, note: str) -> HealthStatus:
    """``status`` of an actuator without calibration: never OK (WARN 'not calibrated: <note>')."""
    if status.level != OK:
        return status
    return replace(status, level=WARN, message=f'not calibrated: {note}' if note else 'not calibrated')


def out_of_range(status: HealthStatus, flag: str) -> HealthStatus:
    """``status`` when the last theta_Oil lies outside its physical range (``flag`` says why): at least WARN.

    A theta_Oil far above 1 would otherwise read "lubrication good"; the
    calibration does not describe what is measured, and the status says so.
    """
    if not flag or status.level != OK:
        return status
    return replace(status, level=WARN, message=f'theta_oil outside its physical range: {flag}')


def outside_domain(status: HealthStatus, flag: str) -> HealthStatus:
    """``status`` when the last window lies outside the calibration's domain (``flag``, :mod:`.domain`): at least WARN.

    theta_Oil there is an extrapolation of the fitted form; the value is still
    published, and the status says how far outside.
    """
    if not flag or status.level != OK:
        return status
    return replace(status, level=WARN, message=f'theta_oil {flag}')


def format_value(value: object) -> str:
    """A diagnostic KeyValue string: numbers with 6 significant digits, NaN as 'nan'."""
    if isinstance(value, float):
        return f'{value:.6g}'
    return str(value)
