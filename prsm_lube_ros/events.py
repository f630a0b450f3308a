"""Samples of the contract's input topics as plain Python values.

Recordings (:mod:`prsm_lube_ros.bag_reader`) and live subscriptions
(:mod:`prsm_lube_ros.nodes`) both turn messages into these, so the windowing,
calibration and assessment code never sees a ROS message.  Stamps are seconds
since the epoch (``header.stamp``), SI units throughout.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Union

import numpy as np


@dataclass(frozen=True)
class VibrationSamples:
    """One ``VibrationBlock``: ``samples[i]`` was acquired at ``stamp + i / sample_rate``."""

    stamp: float            # s, acquisition time of samples[0]
    sample_rate: float      # Hz
    samples: np.ndarray     # m/s^2, float32 or float64, 1-D


@dataclass(frozen=True)
class ScrewState:
    """The ``screw`` entry of a ``JointState``."""

    stamp: float            # s
    angle: float            # rad, multi-turn absolute screw angle (NaN if absent)
    speed: float            # rad/s, screw angular speed (NaN if absent)


@dataclass(frozen=True)
class AxialLoad:
    """A ``WrenchStamped``: ``force`` is ``wrench.force.z`` as recorded (sign kept)."""

    stamp: float            # s
    force: float            # N


@dataclass(frozen=True)
class NutTemperature:
    """A ``Temperature`` reading of the nut or oil."""

    stamp: float            # s
    temperature: float      # degC


InputEvent = Union[VibrationSamples, ScrewState, AxialLoad, NutTemperature]


def stamp_seconds(sec: int, nanosec: int) -> float:
    """``builtin_interfaces/Time`` as float seconds."""
    return sec + nanosec * 1e-9
