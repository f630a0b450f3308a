# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The sensor bridge's own health (its source, not the lubrication), as a diagnostic level and values; no ROS.

:class:`SourceHealth` is told of every published vibration block, every loss
of samples and a failure of the source; :meth:`SourceHealth.status`
gives the level the bridge puts on ``/diagnostics``:

- ERROR: the source failed (acquisition stopped, bag unreadable mid-way);
- STALE: no block for ``stale_timeout`` s (or none yet), or the bridge is
  not active (managed bridge between configure and activate);
- WARN: the block rate over the last :data:`RATE_SPAN` s is below
  ``1 - RATE_SLACK`` of the expected one, or samples were lost within
  the last :data:`RATE_SPAN` s;
- OK otherwise.

Each state has one fixed message (the terminal ERROR adds its reason; aggregators and loggers that de-duplicate
on the message see a change only when the state does); the numbers (rates,
silence, losses) and the last error are KeyValues.

Times are s of a monotonic clock given by the caller.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
import math
import threading

from ..estimation.health import ERROR, OK, STALE, WARN

__all__ = ['RATE_SLACK', 'RATE_SPAN', 'SourceHealth', 'SourceStatus']

#: s over which the block rate is measured and losses count as recent.
RATE_SPAN = 10.0
#: A block rate this fraction below the expected one is WARN.
RATE_SLACK = 0.2


@dataclass(frozen=True)
class SourceStatus:
    """Level (diagnostic_msgs levels), one-line message and (key, value) pairs for ``DiagnosticStatus.values``."""

    level: int
    message: str
    values: list[tuple[str, object]]


class SourceHealth:
    """Counts of one bridge source; thread-safe (the worker records, the diagnostics timer reads)."""

    def __init__(self, source: str, stale_timeout: float, expected_block_rate: float | None = None):
        self.source = source
        self.stale_timeout = float(stale_timeout)
        self.expected_block_rate = expected_block_rate      # blocks/s; None: not known (playback)
        self.blocks = 0
        self.sample_rate = math.nan
        self.lost_samples = 0
        self.last_error = ''
        self.failed = False
        self.active = True                                  # False: publishing halted on purpose
        self._first_block: float | None = None
        self._last_block: float | None = None
        self._block_times: deque = deque()
        self._loss_times: deque = deque()
        self._lock = threading.Lock()

    def block(self, now: float, sample_rate: float) -> None:
        """One vibration block published at ``now``."""
        with self._lock:
            if self._first_block is None:
                self._first_block = now
            self._last_block = now
            self.blocks += 1
            self.sample_rate = float(sample_rate)
            self._block_times.append(now)
            self._forget(now)

    def loss(self, now: float, samples: int, why: str = '') -> None:
        """``samples`` samples lost (never published) at ``now``; ``why`` becomes the last error."""
        if samples <= 0:
            return
        with self._lock:
            self.lost_samples += int(samples)
            self._loss_times.append(now)
            if why:
                self.last_error = why
            self._forget(now)

    def fail(self, why: str) -> None:
        """The source stopped for good (ERROR from now on)."""
        with self._lock:
            self.failed, self.last_error = True, why

    def note(self, why: str) -> None:
        """A problem that loses nothing (kept as the last error, level unchanged)."""
        with self._lock:
            self.last_error = why

    def _forget(self, now: float) -> None:
        for times in (self._block_times, self._loss_times):
            while times and times[0] < now - RATE_SPAN:
                times.popleft()

    def block_rate(self, now: float) -> float:
        """Blocks per second over the last :data:`RATE_SPAN` s (since the first block, if later); NaN before."""
        with self._lock:
            return self._block_rate(now)

    def _block_rate(self, now: float) -> float:
        self._forget(now)
        span = min(RATE_SPAN, now - self._first_block) if self._first_block is not None else 0.0
        return len(self._block_times) / span if span > 0 else math.nan

    def status(self, now: float) -> SourceStatus:
        """The level, message and values at ``now``."""
        with self._lock:
            rate = self._block_rate(now)
            expected = self.expected_block_rate
            values = [('source', self.source), ('blocks published', self.blocks),
                      ('block rate [1/s]', rate), ('expected block rate [1/s]', expected or math.nan),
                      ('sample rate [Hz]', self.sample_rate), ('lost samples', self.lost_samples),
                      ('last error', self.last_error or 'none'),
                      ('silent for [s]', now - self._last_block if self._last_block is not None else math.inf),
                      ('stale timeout [s]', self.stale_timeout), ('rate span [s]', RATE_SPAN)]
            if self.failed:
                # Terminal: the reason cannot flap, so it stays in the message.
                return SourceStatus(ERROR, f'source {self.source} failed: {self.last_error}', values)
            if not self.active:
                return SourceStatus(STALE, 'not active: the source is open, publishing is halted', values)
            if self._last_block is None:
                return SourceStatus(STALE, 'no block published yet', values)
            if now - self._last_block >= self.stale_timeout:
                return SourceStatus(STALE, 'no block for stale_timeout', values)
            if self._loss_times:
                return SourceStatus(WARN, 'data lost recently (last error in the values)', values)
            settled = self._first_block is not None and now - self._first_block >= RATE_SPAN
            if expected and settled and rate < (1.0 - RATE_SLACK) * expected:
                return SourceStatus(WARN, 'block rate below the expected one', values)
            return SourceStatus(OK, 'publishing', values)
