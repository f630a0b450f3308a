# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The nut accelerometer through an NI-DAQmx card (the paper's acquisition), no ROS types.

::

    settings = DaqSettings(channel='Dev1/ai0', sample_rate=4000.0, block_size=400)
    with NiDaqAccelerometer(settings) as card:      # InputError (one line) without card, driver or package
        stamp_ns, samples = card.read_block()       # m/s^2, float32; stamp = acquisition time of samples[0]

The channel is an IEPE accelerometer channel (constant-current excitation,
AC coupled) read in g with the sensor's sensitivity (the paper's: 100 mV/g) and
converted here to m/s^2 (x 9.80665).  Acquisition is continuous into a
finite ring buffer of ``buffer_seconds``; each read takes one block.  Stamps
count samples from the wall-clock time at which the task started, so they are
as regular as the card's sample clock (no read-time jitter); the start time is
when ``task.start()`` returned (a few ms after the first sample on USB cards).

``nidaqmx`` is imported only when an accelerometer is opened, so this module
imports on any machine.
"""
from __future__ import annotations

from dataclasses import dataclass
import importlib
import math
import time
from typing import Any
from collections.abc import Callable

import numpy as np

from ..errors import InputError

__all__ = ['DaqSettings', 'NiDaqAccelerometer', 'STANDARD_GRAVITY', 'import_nidaqmx']

#: Standard gravity, m/s^2 per g.
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class DaqSettings:
    """One accelerometer channel: names, rates and scaling in the units NI-DAQmx takes."""

    channel: str = 'Dev1/ai0'          # physical channel
    sample_rate: float = 4000.0        # Hz (paper: 4 kHz)
    block_size: int = 400              # samples per VibrationBlock
    sensitivity: float = 100.0         # mV/g (paper: 100 mV/g)
    iepe_current: float = 0.004        # A of IEPE excitation; 0: none (external conditioning)
    range_g: float = 50.0              # measurement range +/- g
    buffer_seconds: float = 10.0       # ring buffer of the continuous acquisition, s

    def __post_init__(self) -> None:
        """Reject settings the card cannot be set to."""
        checks = {'channel': bool(str(self.channel).strip()),
                  'sample_rate': self.sample_rate > 0 and math.isfinite(self.sample_rate),
                  'block_size': int(self.block_size) >= 1,
                  'sensitivity': self.sensitivity > 0 and math.isfinite(self.sensitivity),
                  'iepe_current': 0 <= self.iepe_current <= 0.1,
                  'range_g': self.range_g > 0 and math.isfinite(self.range_g),
                  'buffer_seconds': self.buffer_seconds * self.sample_rate >= 2 * self.block_size}
        for name, ok in checks.items():
            if not ok:
                raise InputError(f'hardware setting {name}={getattr(self, name)!r} is out of range')

    @property
    def buffer_size(self) -> int:
        """Samples in the acquisition's ring buffer."""
        return int(math.ceil(self.buffer_seconds * self.sample_rate))


def import_nidaqmx() -> Any:
    """The ``nidaqmx`` package; InputError (one line) when it is not installed."""
    try:
        return importlib.import_module('nidaqmx')
    except ImportError:
        raise InputError('source hardware: the Python package nidaqmx is not installed (pip install nidaqmx; '
                         'it also needs the NI-DAQmx driver from ni.com)') from None


def _one_line(exc: BaseException) -> str:
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    return (lines[0] if lines else type(exc).__name__)[:300]


def _member(enum: Any, *names: str) -> Any:
    """The first of ``names`` the enum has (member names differ between nidaqmx versions)."""
    for name in names:
        if hasattr(enum, name):
            return getattr(enum, name)
    raise AttributeError(f'{enum.__name__} has none of {names}')


class NiDaqAccelerometer:
    """A started continuous acquisition on one IEPE accelerometer channel; see the module docstring."""

    def __init__(self, settings: DaqSettings, clock_ns: Callable[[], int] = time.time_ns, start: bool = True):
        """Set the channel up and (``start``) start acquiring; InputError (one line) when it cannot."""
        self.settings = settings
        self._clock_ns = clock_ns
        nidaqmx = import_nidaqmx()
        self._task: Any = None
        try:
            constants = importlib.import_module('nidaqmx.constants')
            task = nidaqmx.Task()
            self._task = task
            iepe = settings.iepe_current > 0
            channel = task.ai_channels.add_ai_accel_chan(
                settings.channel, min_val=-settings.range_g, max_val=settings.range_g,
                units=constants.AccelUnits.G, sensitivity=settings.sensitivity,
                sensitivity_units=_member(constants.AccelSensitivityUnits, 'MILLIVOLTS_PER_G', 'M_VOLTS_PER_G'),
                current_excit_source=(constants.ExcitationSource.INTERNAL if iepe
                                      else constants.ExcitationSource.NONE),
                current_excit_val=settings.iepe_current)
            if iepe:
                channel.ai_coupling = constants.Coupling.AC
            task.timing.cfg_samp_clk_timing(settings.sample_rate, sample_mode=constants.AcquisitionType.CONTINUOUS,
                                            samps_per_chan=settings.buffer_size)
        except Exception as exc:     # driver missing, no such device, unsupported setting: one line
            raise self._cannot_acquire(exc) from None
        self.start_ns, self.samples_read, self.running = 0, 0, False
        self._timeout = max(2.0, 4.0 * settings.block_size / settings.sample_rate)
        if start:
            self.start()

    def start(self) -> None:
        """Start (or restart) the acquisition; stamps count samples from now.  InputError when it cannot."""
        if self._task is None:
            raise InputError(f'source hardware: the acquisition from {self.settings.channel} was closed')
        try:
            self._task.start()
        except Exception as exc:
            raise self._cannot_acquire(exc) from None
        self.start_ns, self.samples_read, self.running = int(self._clock_ns()), 0, True

    def _cannot_acquire(self, exc: Exception) -> InputError:
        """Close the task; the one-line error to raise for ``exc`` from the driver."""
        self.close()
        return InputError(f'source hardware: NI-DAQmx cannot acquire from {self.settings.channel}: '
                          f'{_one_line(exc)}')

    def stop(self) -> None:
        """Stop acquiring (the task stays set up; :meth:`start` again to resume)."""
        if self._task is not None and self.running:
            try:
                self._task.stop()
            except Exception:        # stopping a task that failed: nothing more to do
                pass
        self.running = False

    def read_block(self) -> tuple[int, np.ndarray]:
        """The next block: ``(stamp_ns of its first sample, samples in m/s^2 as float32)``.

        Raises InputError (one line) when the acquisition fails (buffer overrun,
        card unplugged): the stream has a gap then and the caller must stop.
        """
        size = self.settings.block_size
        try:
            data = self._task.read(number_of_samples_per_channel=size, timeout=self._timeout)
        except Exception as exc:
            raise InputError(f'source hardware: reading {self.settings.channel} failed: {_one_line(exc)}') from None
        samples = (np.asarray(data, dtype=float).reshape(-1) * STANDARD_GRAVITY).astype(np.float32)
        if samples.size != size:
            raise InputError(f'source hardware: {self.settings.channel} gave {samples.size} samples, '
                             f'expected {size}')
        stamp = self.start_ns + int(round(self.samples_read * 1e9 / self.settings.sample_rate))
        self.samples_read += size
        return stamp, samples

    def close(self) -> None:
        """Stop and release the task (safe to call twice)."""
        task, self._task = self._task, None
        self.running = False
        if task is None:
            return
        for step in ('stop', 'close'):
            try:
                getattr(task, step)()
            except Exception:        # closing a task that failed half-way: nothing more to do
                pass

    def __enter__(self) -> NiDaqAccelerometer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
