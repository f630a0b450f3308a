# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What the contract's sensors can give: bounds checked before any header field sizes anything.

A file or a topic is untrusted input.  A VibrationBlock's ``sample_rate`` and
sample count decide how many windows one block spans (so how many rows the
windowing opens), and a corrupt payload can hold any float.  The bounds below
are physical, with a wide margin over ``CONTRACT.md`` ("vibration at 1-20 kHz
in blocks of 5-200 ms"; real accelerometer data up to 51.2 kHz):

* sample rate: :data:`MIN_SAMPLE_RATE` to :data:`MAX_SAMPLE_RATE` Hz;
* block duration (samples / rate): at most :data:`MAX_BLOCK_SECONDS`, so one
  block spans at most ``MAX_BLOCK_SECONDS / window_length + 1`` windows;
* acceleration magnitude: at most :data:`MAX_ACCELERATION` m/s^2 (10^4 g; the
  paper's IEPE sensor, 100 mV/g on a +-5 V input, saturates at 50 g; shock
  accelerometers reach a few thousand g);
* screw speed magnitude: at most :data:`MAX_SCREW_SPEED` rad/s (95,000 r/min;
  roller screws turn below 6,000 r/min);
* axial load magnitude: at most :data:`MAX_AXIAL_LOAD` N (10 MN; the largest
  roller screws carry about 1 MN);
* temperature: :data:`TEMPERATURE_RANGE` degC.

Each check returns a boolean mask of the entries that pass (vectorised,
numpy only) and the words for the first entry that does not, so the caller
reports one named problem and leaves the entries out.  No ROS import.
"""
from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

__all__ = ['MAX_ACCELERATION', 'MAX_AXIAL_LOAD', 'MAX_BLOCK_SECONDS', 'MAX_SAMPLE_RATE', 'MAX_SCREW_SPEED',
           'MIN_SAMPLE_RATE', 'RATE_SPIKE_FRACTION', 'STAMP_SPIKE_SECONDS', 'SpikeCount', 'TEMPERATURE_RANGE',
           'duration_problem', 'plausible_durations', 'plausible_magnitudes', 'plausible_rates',
           'plausible_temperatures', 'rate_problem']

#: Vibration sample rates accepted, Hz.
MIN_SAMPLE_RATE = 1.0
MAX_SAMPLE_RATE = 1e6
#: Longest vibration block accepted, s (samples / sample_rate).
MAX_BLOCK_SECONDS = 60.0
#: Largest acceleration magnitude accepted, m/s^2.
MAX_ACCELERATION = 1e5
#: Largest screw angular speed magnitude accepted, rad/s.
MAX_SCREW_SPEED = 1e4
#: Largest axial load magnitude accepted, N.
MAX_AXIAL_LOAD = 1e7
#: Temperatures accepted, degC.
TEMPERATURE_RANGE = (-100.0, 500.0)


def plausible_rates(rates: npt.ArrayLike) -> np.ndarray:
    """Mask of sample rates (Hz) in [MIN_SAMPLE_RATE, MAX_SAMPLE_RATE] (NaN and infinities fail)."""
    rates = np.asarray(rates, float)
    with np.errstate(invalid='ignore'):
        return (rates >= MIN_SAMPLE_RATE) & (rates <= MAX_SAMPLE_RATE)


def rate_problem(rate: float) -> str:
    """Why one sample rate (Hz) is refused, in words."""
    return f'sample_rate {float(rate):g} Hz (outside {MIN_SAMPLE_RATE:g} Hz to {MAX_SAMPLE_RATE:g} Hz)'


def plausible_durations(counts: npt.ArrayLike, rates: npt.ArrayLike) -> np.ndarray:
    """Mask of blocks of ``counts`` samples at ``rates`` Hz lasting at most MAX_BLOCK_SECONDS (rates checked)."""
    counts, rates = np.asarray(counts, float), np.asarray(rates, float)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        return counts <= MAX_BLOCK_SECONDS * rates


def duration_problem(count: int, rate: float) -> str:
    """Why one block is refused for its length, in words."""
    return (f'{int(count)} samples at {float(rate):g} Hz ({count / rate:.3g} s, longer than '
            f'{MAX_BLOCK_SECONDS:g} s)')


def plausible_magnitudes(values: npt.ArrayLike, limit: float) -> np.ndarray:
    """Mask of finite ``values`` with magnitude at most ``limit`` (NaN and infinities fail)."""
    values = np.asarray(values)
    with np.errstate(invalid='ignore'):
        return np.abs(values) <= limit


def plausible_temperatures(values: npt.ArrayLike) -> np.ndarray:
    """Mask of finite temperatures (degC) within :data:`TEMPERATURE_RANGE`."""
    values = np.asarray(values, float)
    low, high = TEMPERATURE_RANGE
    with np.errstate(invalid='ignore'):
        return (values >= low) & (values <= high)


#: A header stamp that jumps away from both neighbours of its topic by more than this (s) while they agree
#: with each other is damage, not jitter: no clock goes forward and back by a second for one message.
STAMP_SPIKE_SECONDS = 1.0
#: Likewise a block's sample rate that differs from both neighbours' by more than this fraction while
#: they agree: an acquisition changes its rate for good (the IMU bridge's measured rate), not for one block.
RATE_SPIKE_FRACTION = 0.05


def _spikes(values: np.ndarray, jump: float) -> np.ndarray:
    """Mask of values jumping more than ``jump`` from both neighbours (same side) whose neighbours agree.

    The first and last values are not judged (False): see :func:`_edge`.
    """
    spikes = np.zeros(values.size, bool)
    if values.size < 3:
        return spikes
    with np.errstate(invalid='ignore'):
        before, after = values[1:-1] - values[:-2], values[1:-1] - values[2:]
        spikes[1:-1] = ((np.abs(before) > jump) & (np.abs(after) > jump) & (np.sign(before) == np.sign(after))
                        & (np.abs(values[2:] - values[:-2]) < jump))
    return spikes


class SpikeCount:
    """Counts isolated jumps (damage, not jitter or resets) in one stream of values fed piece by piece.

    ``jump``: the threshold, in the values' unit, or as a fraction when
    ``relative`` (compared in log space).  A gap (lost messages) or a clock
    reset jumps without coming back and is not a spike.  The last values of
    a piece are kept, so pieces join without blind spots; the stream's first
    value is judged against the two after it, its last one by :meth:`finish`.
    """

    def __init__(self, jump: float, relative: bool = False) -> None:
        self.jump = math.log1p(jump) if relative else jump
        self.relative = relative
        self.count = 0
        self._tail = np.zeros(0)      # the last (up to 3) values; the last one not judged yet
        self._started = False

    def add(self, values: npt.ArrayLike) -> None:
        """Judge ``values``, the next piece of the stream."""
        values = np.asarray(values, float).reshape(-1)
        if self.relative:
            with np.errstate(divide='ignore', invalid='ignore'):
                values = np.log(values)
        joined = np.concatenate((self._tail, values))
        if joined.size < 3:
            self._tail = joined
            return
        spikes = _spikes(joined, self.jump)
        if self._started:
            start = self._tail.size - 1
        else:
            spikes[0], start, self._started = _edge(joined[0], joined[1], joined[2], self.jump), 0, True
        self.count += int(np.count_nonzero(spikes[start:joined.size - 1]))
        self._tail = joined[-3:]

    def finish(self) -> int:
        """Judge the stream's last value against the two before it; return the spikes counted."""
        tail = self._tail
        if self._started and tail.size == 3 and _edge(tail[2], tail[1], tail[0], self.jump):
            self.count += 1
        self._tail = np.zeros(0)
        self._started = False
        return self.count


def _edge(value: float, first: float, second: float, jump: float) -> bool:
    """An end value that jumps more than ``jump`` from its two neighbours, which agree."""
    with np.errstate(invalid='ignore'):
        return bool(abs(value - first) > jump and abs(value - second) > jump and abs(first - second) < jump
                    and np.sign(value - first) == np.sign(value - second))
