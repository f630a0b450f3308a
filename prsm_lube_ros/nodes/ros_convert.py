# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""ROS messages to input batches and back: the only place nodes touch message fields.

Incoming contract messages become one-message batches of
:mod:`prsm_lube_ros.recording.batches` (what :class:`~prsm_lube_ros.estimation.windowing.WindowBuilder`
takes); results become ``LubricationState``, ``DiagnosticStatus`` and
``Calibrate`` responses.  The ``*_msg`` builders for the input topics serve
the sensor bridge and the tests.  A message that cannot be read raises
:class:`~prsm_lube_ros.errors.InputError` naming the topic.
"""
from __future__ import annotations

import array
import math
from typing import Any, TYPE_CHECKING, Union
from collections.abc import Iterable

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
import numpy as np
import numpy.typing as npt
from sensor_msgs.msg import JointState, Temperature

from ..contract import SCREW_JOINT
from ..errors import InputError
from ..estimation.health import format_value
from ..msg import LubricationState, VibrationBlock
from ..recording.batches import AxialLoadBatch, InputBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch

if TYPE_CHECKING:
    from ..estimation.windowing import Window

#: Name of the screw's entry in ``JointState`` (CONTRACT.md).


__all__ = ['Stamp', 'batch_messages', 'diagnostic_status', 'header_seconds', 'joint_state_msg', 'load_batch',
           'lubrication_state_msg', 'screw_batch', 'stamp_seconds', 'status_level', 'temperature_batch',
           'temperature_msg', 'time_from_ns', 'time_msg', 'vibration_batch', 'vibration_block_msg', 'wrench_msg']


def stamp_seconds(stamp: Time) -> float:
    """``builtin_interfaces/Time`` as float seconds since the epoch."""
    return stamp.sec + stamp.nanosec * 1e-9


def header_seconds(msg: Any, topic: str) -> float:
    """``msg.header.stamp`` in s; InputError for an unset (zero) stamp.

    A zero stamp is a publisher that never filled the header; taken as a time
    it would look like a clock reset and close every open window.
    """
    stamp = msg.header.stamp
    if stamp.sec == 0 and stamp.nanosec == 0:
        raise InputError(f'{topic}: header.stamp is zero (not set by the publisher); message left out')
    return stamp_seconds(stamp)


def time_msg(seconds: float) -> Time:
    """Float seconds as ``builtin_interfaces/Time`` (rounded to the nanosecond; NaN/negative give 0)."""
    if not (math.isfinite(seconds) and seconds >= 0):
        return Time()
    total = int(round(seconds * 1e9))
    return Time(sec=total // 1_000_000_000, nanosec=total % 1_000_000_000)


def time_from_ns(stamp_ns: int) -> Time:
    """Integer ns since the epoch as ``builtin_interfaces/Time`` (exact, for stamps replayed bit for bit)."""
    sec, nanosec = divmod(int(stamp_ns), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


#: A header stamp given as float seconds or as a ready ``Time``.
Stamp = Union[float, Time]


def _header_time(stamp: Stamp) -> Time:
    return stamp if isinstance(stamp, Time) else time_msg(float(stamp))


# -- inputs -> batches ------------------------------------------------------------------------------
def vibration_batch(msg: VibrationBlock, topic: str = 'vibration') -> VibrationBatch:
    """One ``VibrationBlock`` as a batch (bad rates or samples are judged by the window builder)."""
    samples = np.asarray(msg.samples, dtype=np.float32)
    return VibrationBatch.single(header_seconds(msg, topic), float(msg.sample_rate), samples)


def screw_batch(msg: JointState, topic: str = 'joint_states', joint: str = SCREW_JOINT) -> ScrewStateBatch:
    """The ``joint`` entry of one ``JointState``; InputError when the message has no such entry.

    A missing position or velocity (arrays shorter than ``name``) becomes NaN.
    """
    try:
        index = list(msg.name).index(joint)
    except ValueError:
        names = ', '.join(repr(n) for n in msg.name[:5]) or 'none'
        raise InputError(f'{topic}: JointState without the {joint!r} entry (names: {names}); '
                         'message left out') from None
    angle = float(msg.position[index]) if index < len(msg.position) else math.nan
    speed = float(msg.velocity[index]) if index < len(msg.velocity) else math.nan
    return ScrewStateBatch(np.array([header_seconds(msg, topic)]), np.array([angle]), np.array([speed]))


def load_batch(msg: WrenchStamped, topic: str = 'axial_load') -> AxialLoadBatch:
    """``wrench.force.z`` of one ``WrenchStamped`` (N, sign kept)."""
    return AxialLoadBatch(np.array([header_seconds(msg, topic)]), np.array([float(msg.wrench.force.z)]))


def temperature_batch(msg: Temperature, topic: str = 'temperature') -> TemperatureBatch:
    """One ``Temperature`` reading (degC)."""
    return TemperatureBatch(np.array([header_seconds(msg, topic)]), np.array([float(msg.temperature)]))


# -- batches -> inputs (sensor bridge, tests) --------------------------------------------------------
def vibration_block_msg(stamp: Stamp, sample_rate: float, samples: npt.ArrayLike, frame_id: str = '') -> VibrationBlock:
    """A ``VibrationBlock`` with samples (m/s^2) acquired from ``stamp`` at ``sample_rate`` (Hz).

    The samples go in as one float32 copy (``array.array``, rclpy's fast path).
    """
    msg = VibrationBlock()
    msg.header.stamp = _header_time(stamp)
    msg.header.frame_id = frame_id
    msg.sample_rate = float(sample_rate)
    values = array.array('f')
    values.frombytes(np.ascontiguousarray(samples, dtype=np.float32).tobytes())
    msg.samples = values
    return msg


def joint_state_msg(stamp: Stamp, angle: float, speed: float, joint: str = SCREW_JOINT) -> JointState:
    """A ``JointState`` with one entry: screw angle (rad) and speed (rad/s)."""
    msg = JointState()
    msg.header.stamp = _header_time(stamp)
    msg.name = [joint]
    msg.position = [float(angle)]
    msg.velocity = [float(speed)]
    return msg


def wrench_msg(stamp: Stamp, force: float, frame_id: str = '') -> WrenchStamped:
    """A ``WrenchStamped`` carrying the axial load (N) in ``wrench.force.z``."""
    msg = WrenchStamped()
    msg.header.stamp = _header_time(stamp)
    msg.header.frame_id = frame_id
    msg.wrench.force.z = float(force)
    return msg


def temperature_msg(stamp: Stamp, temperature: float, frame_id: str = '') -> Temperature:
    """A ``Temperature`` reading in degC."""
    msg = Temperature()
    msg.header.stamp = _header_time(stamp)
    msg.header.frame_id = frame_id
    msg.temperature = float(temperature)
    return msg


def batch_messages(batch: InputBatch) -> list[Any]:
    """Messages of one input batch, one per entry (for publishing a synthetic or recorded slice)."""
    if isinstance(batch, VibrationBatch):
        return [vibration_block_msg(float(batch.stamps[k]), float(batch.sample_rates[k]),
                                    batch.samples[batch.offsets[k]:batch.offsets[k + 1]])
                for k in range(len(batch))]
    if isinstance(batch, ScrewStateBatch):
        return [joint_state_msg(t, a, s) for t, a, s in zip(batch.stamps, batch.angles, batch.speeds)]
    if isinstance(batch, AxialLoadBatch):
        return [wrench_msg(t, f) for t, f in zip(batch.stamps, batch.forces)]
    if isinstance(batch, TemperatureBatch):
        return [temperature_msg(t, v) for t, v in zip(batch.stamps, batch.temperatures)]
    raise TypeError(f'not an input batch: {type(batch).__name__}')


# -- results -> outputs ------------------------------------------------------------------------------
def lubrication_state_msg(actuator: str, window: Window, theta: float, theta_std: float, level: int,
                          message: str, frame_id: str = '', theta_oil_flag: str = '') -> LubricationState:
    """``LubricationState`` of one closed window (see :class:`~prsm_lube_ros.estimation.windowing.Window`).

    ``frame_id``: the frame of the vibration the window was measured in;
    ``theta_oil_flag``: why theta lies outside its physical range ('' inside).
    """
    msg = LubricationState()
    msg.header.stamp = time_msg(window.end)
    msg.header.frame_id = frame_id
    msg.theta_oil = float(theta)
    msg.theta_oil_std = float(theta_std)
    msg.vibration_rms = float(window.vibration_rms)
    msg.screw_speed = float(window.screw_speed)
    msg.axial_load = float(window.axial_load)
    msg.level = int(level)
    msg.message = message
    msg.actuator = actuator
    msg.window_start = float(window.start)
    msg.nut_position = float(window.nut_position)
    msg.temperature = float(window.temperature)
    msg.run_index = max(int(window.run_index), 0)
    msg.theta_oil_flag = theta_oil_flag
    return msg


def diagnostic_status(name: str, hardware_id: str, level: int, message: str,
                      values: Iterable[tuple[str, object]]) -> DiagnosticStatus:
    """A ``DiagnosticStatus`` with KeyValue strings (numbers via :func:`format_value`)."""
    status = DiagnosticStatus()
    status.level = bytes([int(level)])
    status.name = name
    status.hardware_id = hardware_id
    status.message = message
    status.values = [KeyValue(key=str(k), value=format_value(v)) for k, v in values]
    return status


def status_level(status: DiagnosticStatus) -> int:
    """The level of a ``DiagnosticStatus`` as an int (rclpy holds the byte as ``bytes``)."""
    level = status.level
    return level[0] if isinstance(level, (bytes, bytearray)) else int(level)
