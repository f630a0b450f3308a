# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Input messages straight from their CDR bytes into window-builder batches: no Python message built.

The estimator subscribes to vibration with ``raw=True``: rclpy hands over the
serialized message and builds no Python ``VibrationBlock`` (whose ``samples``
field alone is an ``array.array`` copied from C, then converted again to
numpy).  The contract fixes the layout (``msg/VibrationBlock.msg``,
CONTRACT.md): after the 4-byte encapsulation header, in CDR alignment
relative to the first byte after it::

    int32 header.stamp.sec, uint32 header.stamp.nanosec,
    uint32 length + bytes of header.frame_id (NUL included),
    float64 sample_rate (aligned to 8), uint32 count, float32 samples[count]

so the samples are read in place as a numpy view.  Little- and big-endian
plain CDR (encapsulation 0x0001, 0x0000) are read; anything else, or a
buffer shorter than its lengths say, is an :class:`~prsm_lube_ros.errors.InputError`
naming the topic (the node counts it and goes on).

The joint states and the axial load, drained raw a hundred and fifty times a
second per actuator, are read the same way (:func:`raw_screw_converter`,
:func:`raw_load_converter`): the fields the window builder takes are read at
their CDR offsets, and a message whose bytes do not end where its layout says
(an encoding this reader does not take) goes through rclpy's deserializer and
:mod:`.ros_convert` instead, so the result is always the message's.

A publisher sends the same bytes every time but for the stamp and the values
(the same joint names, array lengths and frame).  The first message read
field by field teaches its converter that :class:`FixedLayout`, and
``convert.many(messages)`` then reads a whole drained queue at once as numpy
records over the joined bytes: the same values as one message at a time, or
None (the caller goes one at a time) when any message differs from the
layout, has a zero stamp, or its stamps do not rise.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import struct
from typing import Any
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import InputError
from ..recording.batches import AxialLoadBatch, ScrewStateBatch, stamp_seconds, VibrationBatch

__all__ = ['FixedLayout', 'RAW_INPUTS', 'RawBlock', 'decode_block', 'join_blocks', 'raw_load_converter',
           'raw_screw_converter', 'raw_vibration_converter']

#: encapsulation id (second byte of the header) -> byte order
_ENDIAN = {1: '<', 0: '>'}
_HEAD = {order: struct.Struct(order + 'iII') for order in _ENDIAN.values()}     # sec, nanosec, frame_id length
_RATE_COUNT = {order: struct.Struct(order + 'dI') for order in _ENDIAN.values()}  # sample_rate, sample count
_ORIGIN = 4         # CDR alignment counts from the first byte after the encapsulation header
#: The estimator's inputs it subscribes to raw (the temperature, once a second, stays a typed message).
RAW_INPUTS = ('vibration', 'joint_states', 'axial_load')
#: Bytes a serialized message may carry after its last field: Fast CDR sizes the buffer by its estimate, which
#: keeps room for the alignment of sequences left empty (up to 7 bytes each; 4 to 12 seen for a JointState)
_END_PADDING = 32


@dataclass(frozen=True)
class RawBlock:
    """One decoded block: stamp (s since the epoch), frame id, sample rate (Hz) and samples (float32, m/s^2)."""

    stamp: float
    frame_id: str
    sample_rate: float
    samples: np.ndarray


def decode_block(data: bytes | bytearray | memoryview, topic: str = 'vibration') -> RawBlock:
    """A serialized ``VibrationBlock`` as a :class:`RawBlock`; InputError naming ``topic`` when it is not one.

    The stamp is ``sec + nanosec * 1e-9`` as for a deserialized message; a zero
    stamp (a publisher that never set the header) is refused as there.
    """
    size = len(data)
    if size < _ORIGIN + 12 or data[0] != 0 or data[1] not in _ENDIAN:
        raise InputError(f'{topic}: {size} bytes are not a plain CDR VibrationBlock; message left out')
    order = _ENDIAN[data[1]]
    sec, nanosec, length = _HEAD[order].unpack_from(data, _ORIGIN)
    text_end = _ORIGIN + 12 + length
    rate_at = _ORIGIN + ((text_end - _ORIGIN + 7) & ~7)
    if length == 0 or rate_at + 12 > size:
        raise InputError(f'{topic}: VibrationBlock of {size} bytes cut short in its header; message left out')
    if sec == 0 and nanosec == 0:
        raise InputError(f'{topic}: header.stamp is zero (not set by the publisher); message left out')
    rate, count = _RATE_COUNT[order].unpack_from(data, rate_at)
    first = rate_at + 12
    if first + 4 * count > size:
        raise InputError(f'{topic}: VibrationBlock says {count} samples, its {size} bytes hold '
                         f'{max(size - first, 0) // 4}; message left out')
    samples = np.frombuffer(data, dtype=order + 'f4', count=count, offset=first)
    frame_id = bytes(data[_ORIGIN + 12:text_end - 1]).decode('utf-8', 'replace')
    return RawBlock(sec + nanosec * 1e-9, frame_id, rate,
                    samples if samples.dtype.isnative else samples.astype(np.float32))


def raw_vibration_converter(topic: str, on_frame_id: Callable[[str], None]) -> Callable[[bytes], VibrationBatch]:
    """``convert(data)`` for a raw vibration subscription: the block as a one-block batch.

    ``on_frame_id`` receives each block's frame id (the node keeps the last one
    for its outputs).  The node joins the blocks taken at one wake-up into one
    batch while their stamps rise (``join_batches``).
    """
    def convert(data: bytes) -> VibrationBatch:
        block = decode_block(data, topic)
        on_frame_id(block.frame_id)
        return VibrationBatch.single(block.stamp, block.sample_rate, block.samples)
    return convert


def join_blocks(batches: Sequence[VibrationBatch]) -> VibrationBatch:
    """Vibration batches (of one or more blocks each), in order, as one batch: samples joined once."""
    if len(batches) == 1:
        return batches[0]
    shifts = np.cumsum([0] + [int(batch.offsets[-1]) for batch in batches[:-1]])
    offsets = np.concatenate([batches[0].offsets[:1]] + [batch.offsets[1:] + shift
                                                         for batch, shift in zip(batches, shifts)])
    return VibrationBatch(np.concatenate([batch.stamps for batch in batches]),
                          np.concatenate([batch.sample_rates for batch in batches]), offsets,
                          np.concatenate([batch.samples for batch in batches]))


class _Cursor:
    """Reads plain CDR fields in order (alignment from the first byte after the encapsulation header).

    ``gaps`` lists the alignment padding skipped, as (start, stop) byte ranges:
    a serializer may leave anything there.
    """

    __slots__ = ('data', 'order', 'at', 'gaps')

    def __init__(self, data: bytes, order: str) -> None:
        self.data, self.order, self.at = data, order, _ORIGIN
        self.gaps: list[tuple[int, int]] = []

    def _align(self, size: int) -> None:
        aligned = _ORIGIN + ((self.at - _ORIGIN + size - 1) & -size)
        if aligned != self.at:
            self.gaps.append((self.at, aligned))
            self.at = aligned

    def read(self, code: str, size: int) -> Any:
        """One value of struct ``code`` (``size`` bytes, aligned to it)."""
        self._align(size)
        value = struct.unpack_from(self.order + code, self.data, self.at)[0]
        self.at += size
        return value

    def string(self) -> bytes:
        """The next CDR text: its length (NUL included), then its bytes, returned without the NUL."""
        length = self.read('I', 4)
        text = self.data[self.at:self.at + length - 1]
        self.at += length
        return text

    def doubles(self) -> tuple[float, ...]:
        """A sequence of float64 (aligned to 8 only when not empty, as Fast CDR writes it)."""
        count = self.read('I', 4)
        if not count:
            return ()
        self._align(8)
        values = struct.unpack_from(f'{self.order}{count}d', self.data, self.at)
        self.at += 8 * count
        return values


def _cursor(data: bytes) -> tuple[_Cursor, float] | None:
    """A cursor past the header of a plain-CDR stamped message, and its stamp (s); None for anything else."""
    if len(data) < _ORIGIN + 12 or data[0] != 0 or data[1] not in _ENDIAN:
        return None
    cursor = _Cursor(data, _ENDIAN[data[1]])
    sec, nanosec = cursor.read('i', 4), cursor.read('I', 4)
    cursor.string()
    return (cursor, sec + nanosec * 1e-9) if cursor.at <= len(data) else None


def _ends(cursor: _Cursor, data: bytes) -> bool:
    """Whether the fields read end within :data:`_END_PADDING` bytes of the end of the bytes."""
    return 0 <= len(data) - cursor.at <= _END_PADDING


#: Where a message's values sit: (byte order, {value name: offset of its float64}, byte ranges that vary from
#: message to message besides the stamp, end of the last field)
_Where = tuple[str, dict[str, int], list[tuple[int, int]], int]


@dataclass(frozen=True)
class FixedLayout:
    """One publisher's message layout: numpy records over whole messages and the bytes every message shares.

    Learnt from one message read field by field: ``records`` has the stamp's
    ``sec`` and ``nanosec`` and one float64 per value at their offsets (byte
    order kept), over the message's whole size; ``shared_at`` are the offsets
    of every byte but the stamp, the value arrays, the alignment padding (a
    serializer may leave anything there) and the slack after the last field,
    ``shared`` their values.  A message of the same size sharing those bytes
    has its fields exactly there.
    """

    size: int
    records: np.dtype
    shared_at: np.ndarray
    shared: np.ndarray

    @classmethod
    def learn(cls, data: bytes, where: _Where) -> FixedLayout:
        """The layout of ``data`` given :data:`_Where` its values are."""
        order, values, varying, end = where
        records = np.dtype({'names': ['sec', 'nanosec', *values],
                            'formats': [order + 'i4', order + 'u4'] + [order + 'f8'] * len(values),
                            'offsets': [_ORIGIN, _ORIGIN + 4, *values.values()], 'itemsize': len(data)})
        keep = np.ones(len(data), dtype=bool)
        keep[_ORIGIN:_ORIGIN + 8] = False
        for start, stop in varying:
            keep[start:stop] = False
        keep[end:] = False
        shared_at = np.flatnonzero(keep)
        return cls(len(data), records, shared_at, np.frombuffer(data, dtype=np.uint8)[shared_at].copy())

    def read(self, messages: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray] | None:
        """(stamps s, records) of ``messages``; None unless all have this layout, set stamps, rising stamps."""
        if any(len(data) != self.size for data in messages):
            return None
        joined = b''.join(messages)
        rows = np.frombuffer(joined, dtype=np.uint8).reshape(len(messages), self.size)
        if not (rows[:, self.shared_at] == self.shared).all():
            return None
        records = np.frombuffer(joined, dtype=self.records)
        stamps = stamp_seconds(records['sec'], records['nanosec'])      # as for one message
        if not ((stamps[1:] > stamps[:-1]).all() and stamps.all()):     # rising, none zero (one may pass 0)
            return None
        return stamps, records


def _screw(data: bytes, joint: bytes) -> tuple[float, float, float, _Where | None] | None:
    """(stamp s, angle rad, speed rad/s, where) of the ``joint`` entry of a serialized JointState.

    None: not read here.  ``where`` (:data:`_Where` of ``angle`` and ``speed``)
    is None when the entry has no position or no velocity.
    """
    start = _cursor(data)
    if start is None:
        return None
    cursor, stamp = start
    try:
        count = cursor.read('I', 4)
        if count > len(data) // 4:
            return None
        names = [cursor.string() for _ in range(count)]
        arrays = []
        for _ in range(3):              # position, velocity, effort: (values, offset of the first)
            values = cursor.doubles()
            arrays.append((values, cursor.at - 8 * len(values)))
    except struct.error:        # lengths beyond the bytes
        return None
    if not _ends(cursor, data) or stamp == 0 or joint not in names:
        return None          # the typed path says what is wrong (or reads what this cannot)
    index = names.index(joint)
    (position, position_at), (velocity, velocity_at), (effort, effort_at) = arrays
    where: _Where | None = None
    if index < len(position) and index < len(velocity):
        where = (cursor.order, {'angle': position_at + 8 * index, 'speed': velocity_at + 8 * index},
                 [(at, at + 8 * len(values)) for values, at in arrays] + cursor.gaps, cursor.at)
    return (stamp, position[index] if index < len(position) else math.nan,
            velocity[index] if index < len(velocity) else math.nan, where)


def _load(data: bytes) -> tuple[float, float, _Where] | None:
    """(stamp s, wrench.force.z N, where) of a serialized WrenchStamped; None: not read here."""
    start = _cursor(data)
    if start is None:
        return None
    cursor, stamp = start
    try:
        force = [cursor.read('d', 8) for _ in range(6)]
    except struct.error:
        return None
    if not _ends(cursor, data) or stamp == 0:
        return None
    first = cursor.at - 48
    return stamp, force[2], (cursor.order, {'force': first + 16}, [(first, cursor.at)] + cursor.gaps, cursor.at)


class _LayoutConverter:
    """``convert(data)`` of one raw input, plus ``convert.many(messages)`` once a message taught the layout."""

    def __init__(self) -> None:
        self.layout: FixedLayout | None = None

    def _learn(self, data: bytes, where: _Where | None) -> None:
        if self.layout is None and where is not None:
            self.layout = FixedLayout.learn(data, where)

    def _records(self, messages: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray] | None:
        """The layout's read of ``messages``; a mismatch forgets the layout (the next message teaches one)."""
        if self.layout is None:
            return None
        read = self.layout.read(messages)
        if read is None:
            self.layout = None
        return read


class _RawScrewConverter(_LayoutConverter):
    def __init__(self, topic: str, joint: str) -> None:
        from rclpy.serialization import deserialize_message
        from sensor_msgs.msg import JointState
        from .ros_convert import screw_batch
        super().__init__()
        self._typed: Callable[[bytes], ScrewStateBatch] = \
            lambda data: screw_batch(deserialize_message(data, JointState), topic, joint)
        self._name = joint.encode()

    def __call__(self, data: bytes) -> ScrewStateBatch:
        name = self._name
        found = _screw(data, name) if name and b'\0' not in name else None
        if found is None:
            return self._typed(data)
        stamp, angle, speed, where = found
        self._learn(data, where)
        return ScrewStateBatch(np.array([stamp]), np.array([angle]), np.array([speed]))

    def many(self, messages: Sequence[bytes]) -> ScrewStateBatch | None:
        """The messages as one batch, equal to one at a time joined; None: take them one at a time."""
        read = self._records(messages)
        if read is None:
            return None
        stamps, records = read
        return ScrewStateBatch(stamps, records['angle'].astype(np.float64), records['speed'].astype(np.float64))


class _RawLoadConverter(_LayoutConverter):
    def __init__(self, topic: str) -> None:
        from geometry_msgs.msg import WrenchStamped
        from rclpy.serialization import deserialize_message
        from .ros_convert import load_batch
        super().__init__()
        self._typed: Callable[[bytes], AxialLoadBatch] = \
            lambda data: load_batch(deserialize_message(data, WrenchStamped), topic)

    def __call__(self, data: bytes) -> AxialLoadBatch:
        found = _load(data)
        if found is None:
            return self._typed(data)
        stamp, force, where = found
        self._learn(data, where)
        return AxialLoadBatch(np.array([stamp]), np.array([force]))

    def many(self, messages: Sequence[bytes]) -> AxialLoadBatch | None:
        """The messages as one batch, equal to one at a time joined; None: take them one at a time."""
        read = self._records(messages)
        if read is None:
            return None
        stamps, records = read
        return AxialLoadBatch(stamps, records['force'].astype(np.float64))


def raw_screw_converter(topic: str, joint: str) -> Callable[[bytes], ScrewStateBatch]:
    """``convert(data)`` for a raw joint-state subscription: the ``joint`` entry as a one-entry batch.

    Bytes this reader does not take (another encoding, a missing entry, a zero
    stamp) go through ``deserialize_message`` and :func:`.ros_convert.screw_batch`,
    which read them or raise the InputError naming ``topic``.  ``convert.many``:
    module doc.
    """
    return _RawScrewConverter(topic, joint)


def raw_load_converter(topic: str) -> Callable[[bytes], AxialLoadBatch]:
    """``convert(data)`` for a raw axial-load subscription: ``wrench.force.z`` as a one-entry batch (else as above)."""
    return _RawLoadConverter(topic)
