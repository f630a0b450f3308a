# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The contract's four input messages: layout checks and bulk CDR decoding.

A topic is accepted when the message definition embedded in the recording has
the contract's field layout, whatever the package part of its type name
(``acme_msgs/msg/VibrationBlock`` is a VibrationBlock if its fields are).

Decoding is vectorised: the messages of one channel in one chunk are grouped by
size; the first message of a group is parsed in Python to find where its
values sit, every other message of the group is checked to carry the same
structure bytes (CDR header, string lengths and contents, sequence lengths),
and the values of the whole group are then read as numpy columns at those
offsets.  Anything that is not plain little-endian CDR of that shape goes
through the rosbags deserializer one message at a time, which is also the
reference path (``vectorised=False``).  No ROS import.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import re
import struct
from typing import Any, TYPE_CHECKING

import numpy as np
from rosbags.typesys import get_types_from_idl, get_types_from_msg
from rosbags.interfaces import Nodetype

from ..contract import (AXIAL_LOAD_TOPIC as AXIAL_LOAD, JOINT_STATE, JOINT_STATES_TOPIC as JOINT_STATES, SCREW_JOINT,
                        TEMPERATURE, TEMPERATURE_TOPIC as TEMPERATURE_KIND, VIBRATION_BLOCK,
                        VIBRATION_TOPIC as VIBRATION, WRENCH_STAMPED)
from .batches import stamp_seconds
from .typestore import contract_fielddef, contract_typestore

if TYPE_CHECKING:
    from typing import TypeAlias

    from rosbags.interfaces.typing import Typesdict
    #: Messages decoded together: ``(message indices, columns, samples)``; samples one array for a group
    #: decoded in bulk, one array per message for messages decoded one at a time, None for no samples.
    _Part: TypeAlias = tuple[np.ndarray, dict[str, np.ndarray], np.ndarray | list[np.ndarray] | None]

__all__ = ['COLUMNS', 'Decoded', 'KINDS', 'MAX_TEMPLATES', 'NotPlain', 'check_layout', 'decode_messages',
           'embedded_types', 'layout_signature', 'ragged_take', 'rows_at']

#: topic leaf name -> contract message type
KINDS = {VIBRATION: VIBRATION_BLOCK, JOINT_STATES: JOINT_STATE, AXIAL_LOAD: WRENCH_STAMPED,
         TEMPERATURE_KIND: TEMPERATURE}
#: how many different structures one size group may show before the rest goes per message
MAX_TEMPLATES = 4
#: layouts found so far, by (kind, message size): most chunks reuse the previous chunk's
_LAYOUTS: dict[tuple[str, int], _Layout] = {}

_U32 = struct.Struct('<I')
_F8 = struct.Struct('<d')


# -- layouts ----------------------------------------------------------------------------------------

def _describe(desc: tuple[Nodetype, Any], typs: Typesdict | None, depth: int = 0) -> object:
    nodetype, payload = desc
    if nodetype == Nodetype.BASE:
        return payload[0]
    if nodetype == Nodetype.NAME:
        return layout_signature(payload, typs, depth + 1)
    inner, size = payload
    if nodetype == Nodetype.ARRAY:
        return ('array', size, _describe(inner, typs, depth))
    return ('sequence', _describe(inner, typs, depth))


def layout_signature(typename: str, typs: Typesdict | None = None, depth: int = 0) -> tuple:
    """Field names and types of ``typename``, nested types expanded, type names left out.

    ``typs`` are the definitions embedded in a recording; types they do not
    define (``builtin_interfaces/msg/Time``...) come from the contract typestore.
    """
    if depth > 16:
        raise ValueError(f'{typename} nests too deep')
    definition = (typs or {}).get(typename) or contract_fielddef(typename)
    if definition is None:
        raise ValueError(f'no definition of {typename}')
    return tuple((name, _describe(desc, typs, depth)) for name, desc in definition[1])


#: the line before each dependency's definition in a ``ros2idl`` schema (and maybe before the root's)
_IDL_SEPARATOR = re.compile(r'^={80}[ \t]*\r?\n', re.MULTILINE)
#: the ``IDL: pkg/msg/Type`` line that follows a separator
_IDL_NAME = re.compile(r'\A[ \t\r\n]*IDL: [^\n]*\n')
#: ``#include "std_msgs/msg/Header.idl"`` and other preprocessor lines, which rosbags' IDL parser refuses
_PREPROCESSOR = re.compile(r'^[ \t]*#[^\n]*$', re.MULTILINE)


def embedded_types(msgtype: str, encoding: str, text: str) -> Typesdict:
    """Type definitions from a schema embedded in a recording (``ros2msg`` or ``ros2idl``).

    A ``ros2idl`` schema is the root type's IDL followed by each dependency's,
    every one after a line of 80 ``=`` and ``IDL: <type>`` (rosbag2 writes
    these when no ``.msg`` exists); ``#include`` lines are dropped, the
    definitions they name being appended or standard types.
    """
    if encoding == 'ros2msg':
        return get_types_from_msg(text, msgtype)
    if encoding == 'ros2idl':
        types: Typesdict = {}
        for part in _IDL_SEPARATOR.split(text):
            body = _PREPROCESSOR.sub('', _IDL_NAME.sub('', part, count=1))
            if body.strip():
                types.update(get_types_from_idl(body))
        return types
    raise ValueError(f'unknown schema encoding {encoding!r}')


def _fields_text(typename: str, typs: Typesdict | None) -> str:
    definition = (typs or {}).get(typename) or contract_fielddef(typename)
    if definition is None:
        return '?'

    def name_of(desc: tuple[Nodetype, Any]) -> str:
        nodetype, payload = desc
        if nodetype == Nodetype.BASE:
            return payload[0]
        if nodetype == Nodetype.NAME:
            return payload
        suffix = f'[{payload[1]}]' if nodetype == Nodetype.ARRAY else '[]'
        return name_of(payload[0]) + suffix
    return ', '.join(f'{name} {name_of(desc)}' for name, desc in definition[1])


def check_layout(kind: str, msgtype: str, encoding: str, text: str) -> str | None:
    """None if ``msgtype`` (defined by the embedded ``text``) has the contract layout of ``kind``.

    Otherwise the reason, in words.  Without an embedded definition the type
    name must be the contract's (any package for VibrationBlock).
    """
    expected = KINDS[kind]
    msgtype, encoding, text = msgtype or '(no type name)', encoding or '', text or ''
    if not text.strip():
        if msgtype == expected or (kind == VIBRATION and msgtype.endswith('/VibrationBlock')):
            return None
        return f'has type {msgtype} without a stored definition; expected {expected}'
    try:
        typs = embedded_types(msgtype, encoding, text)
        found = layout_signature(msgtype, typs)
    except Exception as err:  # the msg/idl parsers raise their own error types
        return f'has type {msgtype} whose stored definition does not parse ({type(err).__name__})'
    if found == layout_signature(expected):
        return None
    return (f'has type {msgtype} with fields ({_fields_text(msgtype, typs)}); expected the '
            f'{expected.rsplit("/", 1)[-1]} layout ({_fields_text(expected, None)})')


# -- decoded data -----------------------------------------------------------------------------------

@dataclass
class Decoded:
    """Values of one topic from one chunk, in file order.

    ``columns`` per kind: vibration ``stamps, sample_rates`` plus the ragged
    ``offsets``/``samples``; joint_states ``stamps, angles, speeds``;
    axial_load ``stamps, forces``; temperature ``stamps, temperatures``.
    """

    log_times: np.ndarray
    columns: dict[str, np.ndarray]
    offsets: np.ndarray | None = None
    samples: np.ndarray | None = None
    undecodable: int = 0
    without_screw: int = 0


COLUMNS = {VIBRATION: ('stamps', 'sample_rates'), JOINT_STATES: ('stamps', 'angles', 'speeds'),
           AXIAL_LOAD: ('stamps', 'forces'), TEMPERATURE_KIND: ('stamps', 'temperatures')}


class NotPlain(Exception):
    """The message is not plain little-endian CDR of the expected shape."""


class _Walker:
    """Walks a little-endian CDR message, noting which bytes are structure (not values)."""

    def __init__(self, data: bytes) -> None:
        if len(data) < 16 or data[0:2] != b'\x00\x01':
            raise NotPlain
        self.data = data
        self.pos = 4
        self.structure: list[tuple[int, int]] = [(0, 2)]

    def align(self, size: int) -> None:
        self.pos = 4 + -(-(self.pos - 4) // size) * size

    def count(self) -> int:
        self.align(4)
        if self.pos + 4 > len(self.data):
            raise NotPlain
        value = _U32.unpack_from(self.data, self.pos)[0]
        self.structure.append((self.pos, self.pos + 4))
        self.pos += 4
        return value

    def string(self) -> bytes:
        length = self.count()
        if length < 1 or self.pos + length > len(self.data):
            raise NotPlain
        text = self.data[self.pos:self.pos + length - 1]
        self.structure.append((self.pos, self.pos + length))
        self.pos += length
        return text

    def take(self, size: int, count: int = 1) -> int:
        """Offset of ``count`` values of ``size`` bytes (aligned), and step over them."""
        self.align(size)
        start = self.pos
        self.pos += size * count
        if self.pos > len(self.data):
            raise NotPlain
        return start

    def header(self) -> None:
        self.pos = 12
        self.string()


@dataclass
class _Layout:
    """Where the values sit in messages of one structure."""

    structure: list[tuple[int, int]]
    values: dict[str, tuple[int | None, str]] = field(default_factory=dict)
    samples: tuple[int, int] = (0, 0)   # offset, count (vibration)
    has_screw: bool = True
    head: int = 0                       # bytes of each message gathered as a row (all but samples)
    check: _StructureCheck | None = None


def _probe(kind: str, data: bytes) -> _Layout:
    walker = _Walker(data)
    walker.header()
    values: dict[str, tuple[int | None, str]] = {'sec': (4, '<i4'), 'nanosec': (8, '<u4')}
    layout = _Layout(walker.structure, values)
    if kind == VIBRATION:
        values['sample_rates'] = (walker.take(8), '<f8')
        count = walker.count()
        layout.samples = (walker.take(4, count), count)
    elif kind == JOINT_STATES:
        names = [walker.string() for _ in range(walker.count())]
        arrays = []
        for _ in range(3):
            count = walker.count()
            arrays.append((walker.take(8, count) if count else walker.pos, count))
        if SCREW_JOINT.encode() not in names:
            layout.has_screw = False
        else:
            index = names.index(SCREW_JOINT.encode())
            for name, (start, count) in zip(('angles', 'speeds'), arrays[:2]):
                values[name] = (start + 8 * index if index < count else None, '<f8')
    elif kind == AXIAL_LOAD:
        values['forces'] = (walker.take(8, 6) + 16, '<f8')
    else:
        values['temperatures'] = (walker.take(8), '<f8')
        walker.take(8)
    if walker.pos != len(data):
        raise NotPlain
    layout.head = layout.samples[0] if kind == VIBRATION else len(data)
    layout.check = _StructureCheck(np.frombuffer(data, np.uint8)[:layout.head], layout.structure)
    return layout


def _column(rows: np.ndarray, offset: int | None, dtype: str) -> np.ndarray:
    """One value per row, read at ``offset`` of each row (NaN column for None)."""
    if offset is None:
        return np.full(rows.shape[0], np.nan)
    return np.ndarray((rows.shape[0],), dtype, rows, offset, (rows.strides[0],))


def rows_at(buffer: np.ndarray, offsets: np.ndarray, width: int) -> np.ndarray:
    """``buffer[o:o + width]`` for every ``o`` in ``offsets``, as one (n, width) uint8 array (one copy).

    Gathers whole rows as ``width``-byte void items, which numpy copies with one
    memcpy each (several times faster than a byte-strided 2-D gather).
    """
    if width == 0:
        return np.zeros((offsets.size, 0), np.uint8)
    windows = np.ndarray((buffer.size - width + 1,), np.dtype((np.void, width)), buffer, 0, (1,))
    return windows[offsets].view(np.uint8).reshape(offsets.size, width)


class _StructureCheck:
    """Which rows carry the same structure bytes as a template message.

    Compares 8 bytes at a time: the masked XOR of each 64-bit word that holds
    structure bytes, OR-ed over those words; the last ``width % 8`` bytes one by one.
    """

    def __init__(self, template: np.ndarray, structure: list[tuple[int, int]]) -> None:
        width = template.size
        mask = np.zeros(width, np.uint8)
        for begin, end in structure:
            mask[begin:end] = 0xFF
        self.words = width // 8 * 8
        mask_words = mask[:self.words].view('<u8')
        template_words = template[:self.words].copy().view('<u8') & mask_words
        self.word_checks = [(int(k), mask_words[k], template_words[k]) for k in np.nonzero(mask_words)[0]]
        self.byte_checks = [(int(k), template[k]) for k in np.nonzero(mask[self.words:])[0] + self.words]

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        differs = np.zeros(rows.shape[0], np.uint64)
        if self.word_checks:
            row_words = rows[:, :self.words].view('<u8')
            for k, mask, template in self.word_checks:
                differs |= (row_words[:, k] & mask) ^ template
        for k, template in self.byte_checks:
            differs |= rows[:, k] != template
        return differs == 0


def _decode_rows(kind: str, rows: np.ndarray, layout: _Layout, buffer: np.ndarray,
                 offsets: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray | None]:
    values = layout.values
    columns = {'stamps': stamp_seconds(_column(rows, *values['sec']).astype(np.float64),
                                       _column(rows, *values['nanosec']))}
    for name in COLUMNS[kind][1:]:
        columns[name] = _column(rows, *values[name]).astype(np.float64)
    samples = None
    if kind == VIBRATION:
        start, count = layout.samples
        samples = (rows_at(buffer, offsets + start, 4 * count).view('<f4').reshape(-1) if count
                   else np.empty(0, np.float32))
    return columns, samples


def _decode_one(kind: str, data: bytes) -> tuple[Any, ...] | None:
    """Values of one message through the rosbags deserializer; None if it has no screw entry.

    One value per :data:`COLUMNS` entry of the kind (floats) and, for vibration, the samples last (an array).
    """
    message = contract_typestore().deserialize_cdr(data, KINDS[kind])
    stamp = message.header.stamp.sec + message.header.stamp.nanosec * 1e-9
    if kind == VIBRATION:
        return stamp, float(message.sample_rate), np.asarray(message.samples, np.float32)
    if kind == JOINT_STATES:
        if SCREW_JOINT not in message.name:
            return None
        index = list(message.name).index(SCREW_JOINT)

        def pick(array: np.ndarray) -> float:
            return float(array[index]) if index < len(array) else np.nan
        return stamp, pick(message.position), pick(message.velocity)
    if kind == AXIAL_LOAD:
        return stamp, float(message.wrench.force.z)
    return stamp, float(message.temperature)


def decode_messages(kind: str, buffer: np.ndarray, data_offsets: np.ndarray, data_lengths: np.ndarray,
                    log_times: np.ndarray, vectorised: bool = True) -> Decoded:
    """Decode the messages of one topic from one chunk's buffer (see module docstring)."""
    n = data_offsets.size
    parts: list[_Part] = []
    slow: list[int] = []
    without_screw = 0
    if vectorised and n:
        sizes = [int(data_lengths[0])] if data_lengths.min() == data_lengths.max() else np.unique(data_lengths)
        for size in sizes:
            todo = np.arange(n) if len(sizes) == 1 else np.nonzero(data_lengths == size)[0]
            without_screw += _decode_size_group(kind, int(size), todo, buffer, data_offsets, parts, slow)
    else:
        slow = list(range(n))
    undecodable = 0
    if slow:
        undecodable, slow_without_screw = _decode_slowly(kind, sorted(slow), buffer, data_offsets, data_lengths,
                                                         parts)
        without_screw += slow_without_screw
    return _assemble(kind, parts, log_times, undecodable, without_screw)


def _decode_size_group(kind: str, size: int, todo: np.ndarray, buffer: np.ndarray, data_offsets: np.ndarray,
                       parts: list[_Part], slow: list[int]) -> int:
    """Decode the messages ``todo`` (all of ``size`` bytes) in bulk, by up to :data:`MAX_TEMPLATES` + 1 structures.

    Appends each structure's decoded messages to ``parts``, and to ``slow``
    those left for the rosbags deserializer; returns how many have no screw
    entry.
    """
    layout = _LAYOUTS.get((kind, size))
    without_screw = 0
    for _ in range(MAX_TEMPLATES + 1):
        if not todo.size:
            break
        if layout is None:
            start = int(data_offsets[todo[0]])
            try:
                layout = _probe(kind, buffer[start:start + size].tobytes())
            except NotPlain:
                slow.append(int(todo[0]))
                todo = todo[1:]
                continue
            if len(_LAYOUTS) > 256:
                _LAYOUTS.clear()
            _LAYOUTS[kind, size] = layout
        offsets = data_offsets[todo]
        rows = rows_at(buffer, offsets, layout.head)
        assert layout.check is not None  # _probe sets it
        same = layout.check(rows)
        if not same.all():
            rows, offsets = rows[same], offsets[same]
        if layout.has_screw:
            if rows.shape[0]:
                columns, samples = _decode_rows(kind, rows, layout, buffer, offsets)
                parts.append((todo[same], columns, samples))
        else:
            without_screw += int(same.sum())
        todo = todo[~same]
        layout = None
    slow.extend(todo.tolist())
    return without_screw


def _decode_slowly(kind: str, slow: list[int], buffer: np.ndarray, data_offsets: np.ndarray,
                   data_lengths: np.ndarray, parts: list[_Part]) -> tuple[int, int]:
    """Decode the messages ``slow`` (in order) one at a time with rosbags; append them to ``parts`` as one part.

    Returns how many do not decode and how many have no screw entry.
    """
    undecodable = without_screw = 0
    rows_slow, kept = [], []
    for index in slow:
        start = int(data_offsets[index])
        try:
            values = _decode_one(kind, buffer[start:start + int(data_lengths[index])].tobytes())
        except Exception:  # rosbags raises assorted errors on malformed CDR
            undecodable += 1
            continue
        if values is None:
            without_screw += 1
            continue
        rows_slow.append(values)
        kept.append(index)
    if kept:
        names = COLUMNS[kind]
        if kind == VIBRATION:
            columns = {'stamps': np.array([r[0] for r in rows_slow], np.float64),
                       'sample_rates': np.array([r[1] for r in rows_slow], np.float64)}
            parts.append((np.array(kept), columns, [r[2] for r in rows_slow]))
        else:
            table = np.array(rows_slow, np.float64).reshape(len(kept), len(names))
            parts.append((np.array(kept), {name: table[:, i] for i, name in enumerate(names)}, None))
    return undecodable, without_screw


def _assemble(kind: str, parts: list[_Part], log_times: np.ndarray, undecodable: int, without_screw: int) -> Decoded:
    """Join decoded groups back into file order."""
    names = COLUMNS[kind]
    if not parts:
        columns = {name: np.empty(0) for name in names}
        decoded = Decoded(np.empty(0, np.int64), columns, undecodable=undecodable,
                          without_screw=without_screw)
        if kind == VIBRATION:
            decoded.offsets, decoded.samples = np.zeros(1, np.int64), np.empty(0, np.float32)
        return decoded
    indices, columns, samples = parts[0]
    if len(parts) == 1 and not isinstance(samples, list):      # the usual case: one structure
        offsets = None
        if kind == VIBRATION:
            assert samples is not None  # vibration parts carry their samples
            offsets = np.arange(indices.size + 1, dtype=np.int64) * (samples.size // max(indices.size, 1))
        return Decoded(log_times if indices.size == log_times.size else log_times[indices], columns, offsets,
                       samples, undecodable, without_screw)
    indices = np.concatenate([p[0] for p in parts])
    columns = {name: np.concatenate([p[1][name] for p in parts]) for name in names}
    order = np.argsort(indices, kind='stable') if len(parts) > 1 else None
    offsets = samples = None
    if kind == VIBRATION:
        pieces: list = []
        counts: list[int] = []
        for _, part_columns, part_samples in parts:
            if isinstance(part_samples, list):
                pieces.extend(part_samples)
                counts.extend(s.size for s in part_samples)
            else:
                assert part_samples is not None  # vibration parts carry their samples
                rows = part_columns['stamps'].size
                pieces.append(part_samples)
                counts.extend([part_samples.size // rows if rows else 0] * rows)
        samples = pieces[0] if len(pieces) == 1 else np.concatenate(pieces)
        offsets = np.concatenate([[0], np.cumsum(counts, dtype=np.int64)])
        if order is not None:
            samples, offsets = ragged_take(samples, offsets, order)
    if order is not None:
        columns = {name: values[order] for name, values in columns.items()}
        indices = indices[order]
    return Decoded(log_times[indices], columns, offsets, samples, undecodable, without_screw)


def ragged_take(samples: np.ndarray, offsets: np.ndarray, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Blocks ``order`` of a ragged array (``samples`` split at ``offsets``), as (samples, offsets)."""
    counts = np.diff(offsets)[order]
    new_offsets = np.concatenate([[0], np.cumsum(counts, dtype=np.int64)])
    index = np.repeat(offsets[:-1][order] - new_offsets[:-1], counts) + np.arange(new_offsets[-1])
    return samples[index], new_offsets
