# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Single stamped accelerometer samples (one ``sensor_msgs/Imu`` axis) grouped into VibrationBlocks, no ROS types.

An IMU driver publishes one message per sample, each with its own stamp; a
VibrationBlock (CONTRACT.md) holds consecutive samples *uniformly spaced at
1/sample_rate* and is stamped with its first sample.  :class:`ImuBlockAssembler`
therefore checks every stamp against the sample period before it joins a block:

- ``backwards``: a stamp not after the previous one (clock reset, repeated
  message);
- ``gap``: an interval of 1.5 periods or more; ``round(interval / period) - 1``
  samples were lost (counted in :attr:`ImuBlockAssembler.lost_samples`);
- ``jitter``: an interval off the period by more than ``jitter_tolerance``
  (a fraction of the period) that is not a gap;
- ``rate``: the median of the last :data:`RATE_WINDOW` intervals departs from
  the period in use by more than ``rate_tolerance`` (a fraction); the measured
  rate is used from then on.  The first :data:`RATE_WINDOW` intervals measure
  the rate before gaps and jitter are judged; with ``sample_rate`` 0 that
  measured rate is the one blocks carry (no problem reported).

Each of these closes the current block early (its samples are still uniform)
and starts a new one at the sample that broke the pattern (a rate found wrong
at the end of the warm-up keeps the block: its samples came at that rate); the first
occurrence of each kind is reported through ``on_problem(kind, line)``, later
ones only counted (:attr:`ImuBlockAssembler.problems`).  A full block has
``round(block_length * sample_rate)`` samples (at least 1).

Gravity: every ``sensor_msgs/Imu`` includes it (9.81 m/s^2 on the vertical
axis), and the window RMS must not.  With ``highpass`` (Hz, > 0) each block
leaves through a streaming high-pass at the lower edge of the windows' band
(:class:`prsm_lube_ros.estimation.conditioning.HighPassFilter`, Butterworth
order 2): its state carries from one block to
the next and starts afresh, at the steady state of the block's mean (no
transient from the gravity step), after a gap, stamps going back, a rate
change or a pause.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
import math
from collections.abc import Callable

import numpy as np

from ..errors import InputError
from ..estimation.conditioning import HighPassFilter

__all__ = ['AXES', 'AssembledBlock', 'GAP_PERIODS', 'ImuBlockAssembler', 'PROBLEM_KINDS', 'RATE_WINDOW', 'check_axis']

#: Intervals whose median is the measured sample period.
RATE_WINDOW = 16
#: An interval of this many periods or more is a gap (at least one sample lost).
GAP_PERIODS = 1.5
#: Kinds of stamp problem, in the order they are checked.
PROBLEM_KINDS = ('backwards', 'gap', 'jitter', 'rate')
#: Accelerometer axes of ``sensor_msgs/Imu.linear_acceleration``.
AXES = ('x', 'y', 'z')


@dataclass(frozen=True)
class AssembledBlock:
    """One VibrationBlock's content: stamp of ``samples[0]`` (int ns), rate (Hz), samples (m/s^2, float32)."""

    stamp_ns: int
    sample_rate: float
    samples: np.ndarray


def check_axis(axis: str) -> str:
    """``axis`` lower-cased if it is x, y or z; InputError (one line) otherwise."""
    name = str(axis).strip().lower()
    if name not in AXES:
        raise InputError(f'parameter imu_axis: {axis!r} is not one of x, y, z')
    return name


class ImuBlockAssembler:
    """Groups stamped samples into uniformly spaced blocks; see the module docstring.

    ``block_length``: s per full block; ``sample_rate``: expected Hz (0: take
    the measured one); ``rate_tolerance`` and ``jitter_tolerance``: fractions
    of the sample period; ``on_problem(kind, line)``: called once per kind;
    ``highpass``: corner in Hz of the gravity (DC) high-pass, 0 for none.
    """

    def __init__(self, block_length: float, sample_rate: float = 0.0, rate_tolerance: float = 0.05,
                 jitter_tolerance: float = 0.25, on_problem: Callable[[str, str], None] | None = None,
                 highpass: float = 0.0):
        checks = {'block_length': block_length > 0 and math.isfinite(block_length),
                  'sample_rate': sample_rate >= 0 and math.isfinite(sample_rate),
                  'rate_tolerance': 0 < rate_tolerance < 1,
                  'jitter_tolerance': 0 < jitter_tolerance < GAP_PERIODS - 1,
                  'highpass': highpass >= 0 and math.isfinite(highpass)}
        for name, ok in checks.items():
            if not ok:
                raise InputError(f'parameter {name}: {locals()[name]!r} is out of range')
        self.block_length = float(block_length)
        self.rate_tolerance = float(rate_tolerance)
        self.jitter_tolerance = float(jitter_tolerance)
        self.on_problem = on_problem
        self.period_ns: float | None = 1e9 / sample_rate if sample_rate > 0 else None
        self.problems = {kind: 0 for kind in PROBLEM_KINDS}
        self.lost_samples = 0
        self.dropped_samples = 0
        self.last_problem = ''
        self._rate_checked = False
        self._last_stamp: int | None = None
        self._intervals: deque = deque(maxlen=RATE_WINDOW)
        self._first_stamp = 0             # ns, stamp of the current block's first sample
        self._values: list[float] = []
        self._gravity_filter = HighPassFilter(highpass) if highpass > 0 else None

    @property
    def sample_rate(self) -> float:
        """The rate blocks are published with (Hz); NaN while it is still being measured."""
        return 1e9 / self.period_ns if self.period_ns else math.nan

    @property
    def block_size(self) -> int | None:
        """Samples in a full block; None while the rate is not known."""
        return max(1, int(round(self.block_length * self.sample_rate))) if self.period_ns else None

    def push(self, stamp_ns: int, value: float) -> list[AssembledBlock]:
        """Add one sample; return the blocks it completed or closed (none, one, or two)."""
        stamp_ns = int(stamp_ns)
        done: list[AssembledBlock] = []
        if self._last_stamp is not None:
            interval = stamp_ns - self._last_stamp
            kind = self._problem_of(interval)
            if kind is not None:
                done += self._close()
            if interval > 0:
                self._intervals.append(interval)
                done += self._follow_rate()
        if not self._values:
            self._first_stamp = stamp_ns
        self._values.append(float(value))
        self._last_stamp = stamp_ns
        size = self.block_size
        if size is not None and len(self._values) >= size:
            done += self._close()
        return done

    def flush(self) -> list[AssembledBlock]:
        """The current (partial) block, if it has samples and a known rate."""
        return self._close()

    def pause(self) -> list[AssembledBlock]:
        """End of a stretch of samples (the source deactivated): :meth:`flush`, and the next sample starts afresh.

        The time until that sample is a pause of the bridge, not samples the
        IMU lost: it is neither a gap nor counted in :attr:`lost_samples`.
        The rate measured so far is kept.
        """
        blocks = self._close()
        self._last_stamp = None
        if self._gravity_filter is not None:
            self._gravity_filter.reset()
        return blocks

    # -- checks -------------------------------------------------------------------------------------
    def _problem_of(self, interval: int) -> str | None:
        """The kind of problem of one interval, reported and counted; None when it fits the period.

        Gaps and jitter are judged once the rate is checked (after :data:`RATE_WINDOW` intervals).
        """
        previous = self._last_stamp
        assert previous is not None          # an interval ends on a stamp after a previous one
        if interval <= 0:
            return self._report('backwards', f'stamp {(previous + interval) * 1e-9:.6f} s is not after the '
                                f'previous one ({previous * 1e-9:.6f} s)')
        if not self._rate_checked or self.period_ns is None:
            return None
        periods = interval / self.period_ns
        if periods >= GAP_PERIODS:
            lost = int(round(periods)) - 1
            self.lost_samples += lost
            return self._report('gap', f'{interval * 1e-9:.6f} s without a sample after {previous * 1e-9:.6f} s '
                                f'(about {lost} lost at {self.sample_rate:g} Hz)')
        if abs(periods - 1.0) > self.jitter_tolerance:
            return self._report('jitter', f'interval {interval * 1e-9:.6f} s at {previous * 1e-9:.6f} s is '
                                f'{periods:.2f} sample periods (tolerance {self.jitter_tolerance:g})')
        return None

    def _follow_rate(self) -> list[AssembledBlock]:
        """Compare the measured period with the one in use; adopt it when they differ beyond the tolerance.

        The first comparison (end of the warm-up) keeps the block open: its
        samples came at the measured rate.  A later change closes the block.
        """
        if len(self._intervals) < RATE_WINDOW:
            return []
        measured = float(np.median(self._intervals))
        reference, first = self.period_ns, not self._rate_checked
        self._rate_checked = True
        if reference is None:                  # sample_rate 0: the measured rate, no problem
            self.period_ns = measured
            return []
        if abs(measured / reference - 1.0) <= self.rate_tolerance:
            return []
        expected = 'the sample_rate parameter says' if first else 'blocks so far used'
        self._report('rate', f'stamps give {1e9 / measured:.6g} Hz, {expected} {1e9 / reference:.6g} Hz '
                     f'(tolerance {self.rate_tolerance:g}); using the measured rate')
        done = [] if first else self._close()
        self.period_ns = measured
        return done

    def _report(self, kind: str, line: str) -> str:
        self.problems[kind] += 1
        self.last_problem = f'{kind}: {line}'
        if self.problems[kind] == 1 and self.on_problem is not None:
            self.on_problem(kind, line)
        return kind

    def _close(self) -> list[AssembledBlock]:
        """The current samples as a block, and a new block begun.

        Before the rate is known (``sample_rate`` 0, first :data:`RATE_WINDOW`
        intervals) a block closed by a stamp problem cannot be stamped with a
        rate: its samples are dropped and counted in :attr:`dropped_samples`.
        """
        first_stamp, values = self._first_stamp, self._values
        self._values = []
        if not values:
            return []
        if self.period_ns is None:
            self.dropped_samples += len(values)
            return []
        samples = np.asarray(values, dtype=np.float64)
        if self._gravity_filter is not None:
            samples = self._gravity_filter.apply(samples, np.array([first_stamp * 1e-9]), np.array([self.sample_rate]),
                                                 np.zeros(1, np.int64), np.array([samples.size]))
        return [AssembledBlock(first_stamp, self.sample_rate, samples.astype(np.float32))]
