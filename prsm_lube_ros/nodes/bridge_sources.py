# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What the sensor bridge publishes, as plain events: recordings and the rig simulator, no ROS types.

An *event* is one message to publish, a tuple ``(due, kind, stamp_ns, values)``:

- ``due``: s of header-stamp time at which a live sensor would have delivered
  it (a vibration block after its last sample, other messages at their
  stamp); the bridge paces publishing on it;
- ``kind``: ``vibration``, ``joint_states``, ``axial_load`` or ``temperature``;
- ``stamp_ns``: the header stamp as int ns since the epoch;
- ``values``: ``(sample_rate, samples)`` for vibration, ``(angle, speed)`` for
  joint states, ``(force,)`` for the load, ``(temperature,)``.

Recorded stamps are published unchanged: :func:`stamps_ns` picks for each
float stamp the ``(sec, nanosec)`` whose ``sec + nanosec * 1e-9`` is that very
float, so the estimator computes bit for bit the stamps ``prsm-lube assess``
reads from the bag, and both cut the same windows.
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ..recording.batches import AxialLoadBatch, InputBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch
from ..recording.plausibility import plausible_durations, plausible_rates

if TYPE_CHECKING:
    from ..recording.reader import Recording
    from ..simulation.rig_acceleration import RigBlock

__all__ = ['Event', 'KINDS', 'Pacer', 'batch_events', 'recording_events', 'rig_block_events', 'stamps_ns']

Event = tuple[float, str, int, tuple]
KINDS = ('vibration', 'joint_states', 'axial_load', 'temperature')
_NS = 1_000_000_000


def stamps_ns(seconds: npt.ArrayLike) -> np.ndarray:
    """Int64 ns stamps whose ``sec + nanosec * 1e-9`` (as ROS readers compute it) equals ``seconds`` exactly.

    Float seconds since the epoch resolve about 0.24 us, so several ns values
    map onto one float; the one closest to the float's value is taken among
    those that give the float back (``seconds`` must be finite and >= 0).
    """
    seconds = np.atleast_1d(np.asarray(seconds, dtype=float))
    sec = np.floor(seconds)
    nanosec = np.rint((seconds - sec) * 1e9)
    result = sec.astype(np.int64) * _NS + nanosec.astype(np.int64)
    for i in np.flatnonzero(_seconds_of(result) != seconds):
        result[i] = _search_ns(float(seconds[i]), int(result[i]))
    return result


def _seconds_of(ns: np.ndarray) -> np.ndarray:
    """``sec + nanosec * 1e-9`` as ``builtin_interfaces/Time`` readers compute it."""
    return (ns // _NS).astype(float) + (ns % _NS).astype(float) * 1e-9


def _search_ns(seconds: float, guess: int) -> int:
    for step in range(1, 2000):
        for candidate in (guess - step, guess + step):
            sec, nanosec = divmod(candidate, _NS)
            if sec + nanosec * 1e-9 == seconds:
                return candidate
    return guess


def batch_events(batches: Iterable[InputBatch]) -> list[Event]:
    """Events of one slice of recorded batches (any mix of kinds), in due order (stable by stamp)."""
    events: list[Event] = []
    for batch in batches:
        if len(batch) == 0:
            continue
        good = np.isfinite(batch.stamps) & (batch.stamps >= 0)
        ns = np.zeros(len(batch), np.int64)
        ns[good] = stamps_ns(batch.stamps[good])
        if isinstance(batch, VibrationBatch):
            offsets, rates = batch.offsets, batch.sample_rates
            for k in np.flatnonzero(good):
                samples = batch.samples[offsets[k]:offsets[k + 1]]
                rate = float(rates[k])
                # A rate no sensor gives (a corrupt header) must not pace the replay for days: no span.
                plausible = plausible_rates(rate) and plausible_durations(samples.size, rate)
                span = samples.size / rate if plausible else 0.0
                events.append((float(batch.stamps[k]) + span, 'vibration', int(ns[k]), (rate, samples)))
        elif isinstance(batch, ScrewStateBatch):
            events.extend((float(t), 'joint_states', int(n), (float(a), float(s)))
                          for t, n, a, s in zip(batch.stamps[good], ns[good], batch.angles[good],
                                                batch.speeds[good]))
        elif isinstance(batch, AxialLoadBatch):
            events.extend((float(t), 'axial_load', int(n), (float(f),))
                          for t, n, f in zip(batch.stamps[good], ns[good], batch.forces[good]))
        elif isinstance(batch, TemperatureBatch):
            events.extend((float(t), 'temperature', int(n), (float(v),))
                          for t, n, v in zip(batch.stamps[good], ns[good], batch.temperatures[good]))
    events.sort(key=lambda e: e[0])
    return events


def recording_events(recording: Recording, on_problem: Callable[[str], None] | None = None) -> Iterator[list[Event]]:
    """Events of a :class:`~prsm_lube_ros.recording.reader.Recording`, one sorted list per time slice."""
    for batches in recording.slices(on_problem=on_problem):
        yield batch_events(batches)


def rig_block_events(block: RigBlock) -> list[Event]:
    """Events of one :class:`~prsm_lube_ros.simulation.rig_acceleration.RigBlock`: the block and its sensor data."""
    chunk = block.topics
    events: list[Event] = []
    rate = float(chunk.sample_rate)
    for stamp, samples in zip(chunk.block_stamps, chunk.samples):
        stamp = int(stamp)
        events.append((stamp * 1e-9 + samples.size / rate, 'vibration', stamp, (rate, samples)))
    events.extend((int(t) * 1e-9, 'joint_states', int(t), (float(a), float(s)))
                  for t, a, s in zip(chunk.joint_stamps, chunk.joint_angles, chunk.joint_speeds))
    events.extend((int(t) * 1e-9, 'axial_load', int(t), (float(f),)) for t, f in zip(chunk.load_stamps, chunk.loads))
    events.extend((int(t) * 1e-9, 'temperature', int(t), (float(v),))
                  for t, v in zip(chunk.temperature_stamps, chunk.temperatures))
    events.sort(key=lambda e: e[0])
    return events


class Pacer:
    """Waits on a monotonic clock so that ``due`` times (s) pass ``rate`` times faster than real time.

    Due times that go back (jitter, stamps repeated) do not wait: the pace
    follows the latest due time seen.  :meth:`restart` begins a new timeline
    (loop, clock reset).  ``rate`` <= 0 or infinite publishes as fast as possible.
    """

    def __init__(self, rate: float, stop: threading.Event | None = None):
        self.rate = float(rate)
        self.stop = stop or threading.Event()
        self._origin: tuple[float, float] | None = None          # (monotonic start, first due)
        self._latest = -math.inf

    def restart(self) -> None:
        """Forget the timeline: the next due time is published at once and anchors the new one."""
        self._origin = None
        self._latest = -math.inf

    def wait(self, due: float) -> bool:
        """Sleep until ``due`` is reached; False when stopped meanwhile."""
        if self._origin is None:
            self._origin = (time.monotonic(), due)
        self._latest = max(self._latest, due)
        if not (self.rate > 0 and math.isfinite(self.rate)):
            return not self.stop.is_set()
        start, first = self._origin
        delay = start + (self._latest - first) / self.rate - time.monotonic()
        if delay > 0:
            return not self.stop.wait(delay)
        return not self.stop.is_set()
