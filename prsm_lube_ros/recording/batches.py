# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Samples of the contract's input topics as numpy batches, no ROS types.

Recordings (:mod:`prsm_lube_ros.recording.reader`) and live subscriptions
(:mod:`prsm_lube_ros.nodes`) both turn messages into these batches, so the
windowing, calibration and assessment code never sees a ROS message.  A live
node makes batches of one message; the bag reader makes one batch per topic
and time slice so that an hour of 4 kHz data costs a few numpy calls, not a
Python call per sample.  Stamps are ``header.stamp`` in seconds since the
epoch; SI units throughout.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, overload, Union

import numpy as np
import numpy.typing as npt


__all__ = ['AxialLoadBatch', 'InputBatch', 'ScrewStateBatch', 'TemperatureBatch', 'VibrationBatch', 'stamp_seconds']


@dataclass(frozen=True)
class VibrationBatch:
    """Consecutive ``VibrationBlock`` messages of one topic.

    Block ``k`` holds ``samples[offsets[k]:offsets[k + 1]]``, acquired at
    ``stamps[k] + i / sample_rates[k]``.
    """

    stamps: np.ndarray        # (n,) s, acquisition time of each block's first sample
    sample_rates: np.ndarray  # (n,) Hz
    offsets: np.ndarray       # (n + 1,) int64 indices into samples
    samples: np.ndarray       # (offsets[-1],) m/s^2, float32 or float64

    @classmethod
    def single(cls, stamp: float, sample_rate: float, samples: npt.ArrayLike) -> VibrationBatch:
        """Batch of one block (what a live subscription gets)."""
        samples = np.asarray(samples)
        return cls(np.array([stamp], float), np.array([sample_rate], float),
                   np.array([0, samples.size], np.int64), samples.reshape(-1))

    def __len__(self) -> int:
        return int(self.stamps.size)


@dataclass(frozen=True)
class ScrewStateBatch:
    """The ``screw`` entry of consecutive ``JointState`` messages."""

    stamps: np.ndarray   # (n,) s
    angles: np.ndarray   # (n,) rad, multi-turn absolute screw angle (NaN if absent)
    speeds: np.ndarray   # (n,) rad/s, screw angular speed (NaN if absent)

    def __len__(self) -> int:
        return int(self.stamps.size)


@dataclass(frozen=True)
class AxialLoadBatch:
    """Consecutive ``WrenchStamped`` messages: ``forces`` is ``wrench.force.z`` (sign kept)."""

    stamps: np.ndarray   # (n,) s
    forces: np.ndarray   # (n,) N

    def __len__(self) -> int:
        return int(self.stamps.size)


@dataclass(frozen=True)
class TemperatureBatch:
    """Consecutive ``Temperature`` readings of the nut or oil."""

    stamps: np.ndarray        # (n,) s
    temperatures: np.ndarray  # (n,) degC

    def __len__(self) -> int:
        return int(self.stamps.size)


InputBatch = Union[VibrationBatch, ScrewStateBatch, AxialLoadBatch, TemperatureBatch]


@overload
def stamp_seconds(sec: float, nanosec: float) -> float: ...


@overload
def stamp_seconds(sec: np.ndarray, nanosec: np.ndarray) -> np.ndarray: ...


def stamp_seconds(sec: Any, nanosec: Any) -> Any:
    """``builtin_interfaces/Time`` as float seconds (scalars or arrays)."""
    return sec + np.asarray(nanosec, dtype=float) * 1e-9 if np.ndim(nanosec) else sec + nanosec * 1e-9
