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

import numpy as np

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


def plausible_rates(rates) -> np.ndarray:
    """Mask of sample rates (Hz) in [MIN_SAMPLE_RATE, MAX_SAMPLE_RATE] (NaN and infinities fail)."""
    rates = np.asarray(rates, float)
    with np.errstate(invalid='ignore'):
        return (rates >= MIN_SAMPLE_RATE) & (rates <= MAX_SAMPLE_RATE)


def rate_problem(rate: float) -> str:
    """Why one sample rate (Hz) is refused, in words."""
    return f'sample_rate {float(rate):g} Hz (outside {MIN_SAMPLE_RATE:g} Hz to {MAX_SAMPLE_RATE:g} Hz)'


def plausible_durations(counts, rates) -> np.ndarray:
    """Mask of blocks of ``counts`` samples at ``rates`` Hz lasting at most MAX_BLOCK_SECONDS (rates checked)."""
    counts, rates = np.asarray(counts, float), np.asarray(rates, float)
    with np.errstate(invalid='ignore', divide='ignore', over='ignore'):
        return counts <= MAX_BLOCK_SECONDS * rates


def duration_problem(count: int, rate: float) -> str:
    """Why one block is refused for its length, in words."""
    return (f'{int(count)} samples at {float(rate):g} Hz ({count / rate:.3g} s, longer than '
            f'{MAX_BLOCK_SECONDS:g} s)')


def plausible_magnitudes(values, limit: float) -> np.ndarray:
    """Mask of finite ``values`` with magnitude at most ``limit`` (NaN and infinities fail)."""
    values = np.asarray(values)
    with np.errstate(invalid='ignore'):
        return np.abs(values) <= limit


def plausible_temperatures(values) -> np.ndarray:
    """Mask of finite temperatures (degC) within :data:`TEMPERATURE_RANGE`."""
    values = np.asarray(values, float)
    low, high = TEMPERATURE_RANGE
    with np.errstate(invalid='ignore'):
        return (values >= low) & (values <= high)
