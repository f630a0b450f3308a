# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Input rate and stamp statuses with ``diagnostic_updater``'s semantics, in plain Python (no ROS import).

``diagnostic_updater`` is not on PyPI; this module gives its ``TopicDiagnostic``
(``FrequencyStatus`` and ``TimeStampStatus`` merged into one status per topic)
to the estimator, per actuator and input stream:

- :class:`FrequencyStatus`: the rate of the messages over the last ``window``
  diagnostic periods (a ring of the message counts at each of the last
  ``window`` status reads, as diagnostic_updater keeps it), against an expected
  rate in messages per s with a relative ``tolerance``: no message in the
  window is ERROR "No events recorded.", a rate below ``expected * (1 -
  tolerance)`` WARN "Frequency too low.", above ``expected * (1 + tolerance)``
  WARN "Frequency too high." (only when ``max_rate`` is given), else OK
  "Desired frequency met".  ``expected`` 0: an optional input with no target: no
  message is OK "No events expected.", and its stamp status is OK without data.
- :class:`TimeStampStatus`: the age of the header stamps (node clock at
  arrival minus stamp, s) over the same last ``window`` reads (diagnostic_updater
  judges one period only, so an input slower than the diagnostic period, a 1 Hz
  temperature, would flap between OK and "No data"): older than ``max_age`` is ERROR
  "Timestamps too far in past seen.", newer than ``-max_future`` (stamps from
  the future) ERROR "Timestamps too far in future seen.", a zero stamp ERROR
  "Zero timestamp seen.", no message WARN "No data since last update.", else OK
  "Timestamps are reasonable.".

The messages are fixed texts, one per state (aggregators and loggers that
de-duplicate on the message see a change only when the state changes); every
number is a KeyValue.  :class:`TopicStatus` merges the two as diagnostic_updater's
``CompositeDiagnosticTask`` does: the highest level, the messages of that level
joined by ``'; '``.  Not thread-safe: the caller holds its own lock.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
import math

from ..estimation.health import ERROR, OK, WARN

__all__ = ['FrequencyStatus', 'RateSettings', 'StampSettings', 'TaskStatus', 'TimeStampStatus', 'TopicStatus',
           'merge']


@dataclass(frozen=True)
class RateSettings:
    """What rate an input must keep (``FrequencyStatusParam``)."""

    expected: float = 0.0       # messages per s (lowest acceptable before tolerance); 0: not judged
    tolerance: float = 0.1      # relative
    window: int = 5             # diagnostic periods the rate is measured over
    max_rate: float = math.inf  # messages per s above which (before tolerance) it is too high


@dataclass(frozen=True)
class StampSettings:
    """Acceptable stamp ages (``TimeStampStatusParam``: min_acceptable = -max_future, max_acceptable = max_age)."""

    max_age: float = 5.0        # s
    max_future: float = 1.0     # s a stamp may lie ahead of the node clock


@dataclass(frozen=True)
class TaskStatus:
    """Level (diagnostic_msgs levels), fixed message of the state and (key, value) pairs."""

    level: int
    message: str
    values: list


def merge(statuses: list[TaskStatus]) -> TaskStatus:
    """diagnostic_updater's merged summary: the highest level, the messages of that level joined by '; '."""
    level = max(s.level for s in statuses)
    message = '; '.join(s.message for s in statuses if s.level == level and s.message)
    return TaskStatus(level, message, [kv for s in statuses for kv in s.values])


class FrequencyStatus:
    """Counts messages; :meth:`status` judges the rate over the last ``settings.window`` reads."""

    def __init__(self, settings: RateSettings, now: float):
        self.settings = settings
        self.count = 0
        window = max(1, int(settings.window))
        self._times = [now] * window
        self._counts = [0] * window
        self._index = 0

    def tick(self, count: int = 1) -> None:
        """``count`` messages arrived."""
        self.count += count

    def status(self, now: float) -> TaskStatus:
        """The rate since the read ``window`` reads ago, judged; the ring moves on by one."""
        s = self.settings
        events = self.count - self._counts[self._index]
        span = now - self._times[self._index]
        rate = events / span if span > 0 else math.nan
        self._counts[self._index], self._times[self._index] = self.count, now
        self._index = (self._index + 1) % len(self._times)
        low, high = s.expected * (1.0 - s.tolerance), s.max_rate * (1.0 + s.tolerance)
        if events == 0:
            level, message = (ERROR, 'No events recorded.') if s.expected > 0 else (OK, 'No events expected.')
        elif s.expected > 0 and rate < low:
            level, message = WARN, 'Frequency too low.'
        elif rate > high:
            level, message = WARN, 'Frequency too high.'
        else:
            level, message = OK, 'Desired frequency met'
        values = [('Events in window', events), ('Events since startup', self.count),
                  ('Duration of window (s)', span), ('Actual frequency (Hz)', rate),
                  ('Target frequency (Hz)', s.expected if s.expected > 0 else 'none'),
                  ('Minimum acceptable frequency (Hz)', low if s.expected > 0 else 'none')]
        if math.isfinite(high):
            values.append(('Maximum acceptable frequency (Hz)', high))
        return TaskStatus(level, message, values)


class TimeStampStatus:
    """Stamp ages since the last :meth:`status`; see the module docstring."""

    def __init__(self, settings: StampSettings, required: bool = True, window: int = 1):
        self.settings = settings
        self.required = required        # False: no data is OK (an optional input)
        self._reset()
        self.late_count = self.early_count = self.zero_count = 0
        self._periods: deque = deque(maxlen=max(1, int(window)))   # (seen, earliest, latest, early, late, zero)

    def _reset(self) -> None:
        self.seen = False
        self.earliest = math.inf        # smallest age (s) since the last read: the newest stamp
        self.latest = -math.inf         # largest age (s): the oldest stamp
        self.late = self.early = self.zero = False

    def tick(self, oldest_stamp: float, newest_stamp: float, now: float) -> None:
        """Messages stamped from ``oldest_stamp`` to ``newest_stamp`` (s) arrived at node time ``now``."""
        self.seen = True
        if oldest_stamp == 0.0:
            self.zero = True
            return
        oldest_age, newest_age = now - oldest_stamp, now - newest_stamp
        self.earliest = min(self.earliest, newest_age)
        self.latest = max(self.latest, oldest_age)
        if oldest_age > self.settings.max_age:
            self.late = True
        if newest_age < -self.settings.max_future:
            self.early = True

    def status(self) -> TaskStatus:
        """The judgement over the last ``window`` reads, this one's period included; the period starts over."""
        s = self.settings
        self.late_count += self.late
        self.early_count += self.early
        self.zero_count += self.zero
        self._periods.append((self.seen, self.earliest, self.latest, self.early, self.late, self.zero))
        seen = any(p[0] for p in self._periods)
        earliest = min(p[1] for p in self._periods)
        latest = max(p[2] for p in self._periods)
        found = [(any(p[3] for p in self._periods), 'Timestamps too far in future seen.'),
                 (any(p[4] for p in self._periods), 'Timestamps too far in past seen.'),
                 (any(p[5] for p in self._periods), 'Zero timestamp seen.')]
        errors = [text for flag, text in found if flag]
        if not seen:
            level, message = (WARN if self.required else OK), 'No data since last update.'
        elif errors:
            level, message = ERROR, ' '.join(errors)
        else:
            level, message = OK, 'Timestamps are reasonable.'
        stamped = math.isfinite(earliest)
        values = [('Earliest timestamp delay (s)', earliest if stamped else math.nan),
                  ('Latest timestamp delay (s)', latest if stamped else math.nan),
                  ('Earliest acceptable timestamp delay (s)', -s.max_future),
                  ('Latest acceptable timestamp delay (s)', s.max_age),
                  ('Late diagnostic update count', self.late_count),
                  ('Early diagnostic update count', self.early_count),
                  ('Zero seen diagnostic update count', self.zero_count)]
        self._reset()
        return TaskStatus(level, message, values)


class TopicStatus:
    """``TopicDiagnostic``: the frequency and stamp statuses of one input stream, merged."""

    def __init__(self, topic: str, rate: RateSettings, stamps: StampSettings, now: float):
        self.topic = topic
        self.frequency = FrequencyStatus(rate, now)
        self.stamps = TimeStampStatus(stamps, required=rate.expected > 0, window=rate.window)

    def tick(self, count: int, oldest_stamp: float, newest_stamp: float, now: float) -> None:
        """``count`` messages stamped ``oldest_stamp`` .. ``newest_stamp`` arrived at node time ``now``."""
        self.frequency.tick(count)
        self.stamps.tick(oldest_stamp, newest_stamp, now)

    def status(self, now: float) -> TaskStatus:
        """Both judgements merged, with the topic as the first KeyValue."""
        merged = merge([self.frequency.status(now), self.stamps.status()])
        return TaskStatus(merged.level, merged.message, [('topic', self.topic)] + merged.values)
