# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``VibrationBlock`` messages straight from their CDR bytes into one window-builder batch.

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
"""
from __future__ import annotations

from dataclasses import dataclass
import struct
from collections.abc import Callable, Sequence

import numpy as np

from ..errors import InputError
from ..recording.batches import VibrationBatch

__all__ = ['RawBlock', 'decode_block', 'join_blocks', 'raw_vibration_converter']

#: encapsulation id (second byte of the header) -> byte order
_ENDIAN = {1: '<', 0: '>'}
_HEAD = {order: struct.Struct(order + 'iII') for order in _ENDIAN.values()}     # sec, nanosec, frame_id length
_RATE_COUNT = {order: struct.Struct(order + 'dI') for order in _ENDIAN.values()}  # sample_rate, sample count
_ORIGIN = 4         # CDR alignment counts from the first byte after the encapsulation header


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
