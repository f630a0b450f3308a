# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A small, defensive reader of the MCAP container format, chunk by chunk.

Only what the recordings need: Schema, Channel, Chunk, MessageIndex, Message,
Statistics and the Footer (https://mcap.dev/spec).  Chunks are read one at a
time, decompressed (``''``, ``zstd`` or ``lz4``) and split into their Message
records with numpy: the MessageIndex records that follow a chunk give every
message's offset, so no Python loop runs per message; a chunk without a usable
index is walked record by record instead.  Every length is checked against the
bytes that are really there, every loop advances, and anything malformed ends
as a :class:`McapProblem` with one line -- never an unrelated exception, never
a hang.  No ROS import.
"""
from __future__ import annotations

from array import array
from dataclasses import dataclass, field
from enum import IntEnum
from functools import lru_cache
import struct
from types import ModuleType
from typing import BinaryIO, cast, TYPE_CHECKING
from collections.abc import Iterator

import lz4.frame
import numpy as np

from ..errors import RecordingError
from ..input_file import open_regular

try:  # ISA-L's CRC-32 (same polynomial as zlib's): 3.3x zlib 1.2's here (benchmarks/crc_speed.py)
    from isal.isal_zlib import crc32
except ImportError:  # pragma: no cover - an install without the isal wheel checks with zlib
    from zlib import crc32

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable
    from pathlib import Path
    from typing import TypeAlias

    from ..errors import ProblemSink
    #: Records as read (bytes), or an uncompressed chunk's records as a view into the chunk record.
    _Bytes: TypeAlias = bytes | memoryview
    #: Receives each record that is not a message: ``(opcode, content)``.
    _RecordSink: TypeAlias = Callable[[int, _Bytes], None]
    #: A chunk read and awaiting its MessageIndex records: ``(records, start_time, indexes, file offset)``.
    _PendingChunk: TypeAlias = tuple[_Bytes, int, dict[int, bytes], int]

__all__ = ['Channel', 'DataLayout', 'FIRST_USER_OPCODE', 'GATHER_BYTES', 'MAGIC', 'MAX_CHUNK_BYTES',
           'MESSAGE_HEADER', 'McapFile', 'McapProblem', 'MessageGroup', 'OP_CHANNEL', 'OP_CHUNK', 'OP_CHUNK_INDEX',
           'OP_DATA_END', 'OP_FOOTER', 'OP_HEADER', 'OP_MESSAGE', 'OP_MESSAGE_INDEX', 'OP_SCHEMA', 'OP_STATISTICS',
           'Opcode', 'RECORD_PREFIX', 'RawChunk', 'ReadCheck', 'SMALL_CHUNK_BYTES', 'SMALL_CHUNK_MESSAGES',
           'SUMMARY_OPCODES', 'Schema', 'Summary', 'channel_messages', 'data_layout', 'decompress', 'parse_channel',
           'parse_schema', 'signed', 'split_indexed', 'split_records', 'split_sequential',
           'walk_records', 'zstd_file', 'zstd_frame']

_zstandard: ModuleType | None
try:  # the zstandard package comes with ``mcap``; rosbags brings backports.zstd
    import zstandard as _zstandard
except ImportError:  # pragma: no cover - depends on the installed wheels
    _zstandard = None

MAGIC = b'\x89MCAP0\r\n'


class Opcode(IntEnum):
    """Record opcodes of the MCAP specification (0x01-0x0F); :data:`FIRST_USER_OPCODE` and up are user records."""

    HEADER = 0x01
    FOOTER = 0x02
    SCHEMA = 0x03
    CHANNEL = 0x04
    MESSAGE = 0x05
    CHUNK = 0x06
    MESSAGE_INDEX = 0x07
    CHUNK_INDEX = 0x08
    ATTACHMENT = 0x09
    ATTACHMENT_INDEX = 0x0A
    STATISTICS = 0x0B
    METADATA = 0x0C
    METADATA_INDEX = 0x0D
    SUMMARY_OFFSET = 0x0E
    DATA_END = 0x0F


#: Records from this opcode on are an application's own; readers skip them.
FIRST_USER_OPCODE = 0x80
#: The opcodes this reader acts on, by their short names.
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL = Opcode.HEADER, Opcode.FOOTER, Opcode.SCHEMA, Opcode.CHANNEL
OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX, OP_CHUNK_INDEX = Opcode.MESSAGE, Opcode.CHUNK, Opcode.MESSAGE_INDEX, \
    Opcode.CHUNK_INDEX
OP_STATISTICS, OP_DATA_END = Opcode.STATISTICS, Opcode.DATA_END
#: opcode + uint64 record length
RECORD_PREFIX = 9
#: channel_id uint16, sequence uint32, log_time uint64, publish_time uint64
MESSAGE_HEADER = 22
#: a chunk claiming more than this many uncompressed bytes is treated as corrupt
MAX_CHUNK_BYTES = 1 << 31
#: chunks with at most this many messages (or, unindexed, bytes) are gathered with their neighbours
SMALL_CHUNK_MESSAGES = 16
SMALL_CHUNK_BYTES = 16 << 10
#: bytes of top-level messages and small chunks gathered into one pseudo-chunk
GATHER_BYTES = 1 << 20

_RECORD = struct.Struct('<BQ')
_U16 = struct.Struct('<H')
_U32 = struct.Struct('<I')
_U64 = struct.Struct('<Q')
_MESSAGE = struct.Struct('<HIQQ')
#: Chunk record: message_start_time, message_end_time, uncompressed_size, uncompressed_crc, compression length
_CHUNK_HEAD = struct.Struct('<QQQII')
#: MessageIndex record: channel_id, byte length of the records array
_INDEX_HEAD = struct.Struct('<HI')


class McapProblem(Exception):
    """The file is not (or no longer) valid MCAP at some point; one line, without the file name."""


@dataclass
class Schema:
    """An MCAP Schema record: a message type and its embedded definition."""

    id: int
    name: str
    encoding: str
    data: bytes


@dataclass
class Channel:
    """An MCAP Channel record: a topic with its schema and message encoding."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str


@dataclass
class MessageGroup:
    """The messages of one channel inside one chunk: views into ``RawChunk.buffer``."""

    data_offsets: np.ndarray   # (n,) int64, start of each serialized message
    data_lengths: np.ndarray   # (n,) int64
    log_times: np.ndarray      # (n,) int64 ns


@dataclass
class RawChunk:
    """Decompressed message records of one chunk (or of a run of unchunked records)."""

    start_time: int                     # ns, earliest log time the chunk claims
    buffer: np.ndarray                  # uint8
    groups: dict[int, MessageGroup]     # by channel id
    file_offset: int

    def message_count(self) -> int:
        """Number of messages in the chunk."""
        return sum(g.data_offsets.size for g in self.groups.values())


@dataclass
class Summary:
    """What the summary section (or a scan of the data section) says about a file."""

    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    message_counts: dict[int, int] = field(default_factory=dict)
    start_time: int | None = None
    end_time: int | None = None
    complete: bool = False              # True when read from an intact summary section
    schema_count: int = 0               # as the Statistics record says
    channel_count: int = 0

    def lacks_definitions(self) -> bool:
        """True when the statistics count more schemas/channels than the summary repeats, or one is missing."""
        wanted = {c.schema_id for c in self.channels.values() if c.schema_id} - set(self.schemas)
        return (len(self.channels) < self.channel_count or len(self.schemas) < self.schema_count
                or bool(wanted) or bool(set(self.message_counts) - set(self.channels)))


def signed(time: int) -> int:
    """A uint64 log time as the int64 the arrays hold (a corrupt time past 2**63 becomes negative)."""
    return time - (1 << 64) if time >= 1 << 63 else time


# -- record field parsing ---------------------------------------------------------------------------

class _Fields:
    """Sequential reads of MCAP primitive fields from one record's content."""

    __slots__ = ('data', 'pos')

    def __init__(self, data: bytes | memoryview, pos: int = 0) -> None:
        self.data = data
        self.pos = pos

    def _take(self, size: int) -> int:
        start = self.pos
        if size < 0 or start + size > len(self.data):
            raise McapProblem('record field runs past the end of its record')
        self.pos = start + size
        return start

    def u16(self) -> int:
        return _U16.unpack_from(self.data, self._take(2))[0]

    def u32(self) -> int:
        return _U32.unpack_from(self.data, self._take(4))[0]

    def u64(self) -> int:
        return _U64.unpack_from(self.data, self._take(8))[0]

    def raw(self, size: int) -> bytes:
        start = self._take(size)
        return bytes(self.data[start:start + size])

    def string(self) -> str:
        try:
            return self.raw(self.u32()).decode('utf-8')
        except UnicodeDecodeError:
            raise McapProblem('record string is not UTF-8') from None


def parse_schema(content: bytes | memoryview) -> Schema:
    """Schema record content -> :class:`Schema`."""
    fields = _Fields(content)
    return Schema(fields.u16(), fields.string(), fields.string(), fields.raw(fields.u32()))


def parse_channel(content: bytes | memoryview) -> Channel:
    """Channel record content -> :class:`Channel` (metadata ignored)."""
    fields = _Fields(content)
    return Channel(fields.u16(), fields.u16(), fields.string(), fields.string())


# -- decompression ----------------------------------------------------------------------------------

def decompress(data: bytes | memoryview, compression: str, size: int, partial: bool = False) -> bytes | memoryview:
    """Chunk records from their compressed form.

    With ``partial`` (the chunk was cut off by truncation), return as much of
    the beginning as can be recovered instead of failing.
    """
    if size > MAX_CHUNK_BYTES:
        raise McapProblem(f'chunk claims {size} uncompressed bytes')
    try:
        if compression == '':
            out = data
        elif compression == 'zstd':
            if _zstandard is None:  # pragma: no cover
                from rosbags.rosbag2.storage_mcap import zstd  # type: ignore[attr-defined]  # rosbags' own zstd
                out = zstd.decompress(bytes(data))
            elif partial:
                out = _zstd_prefix(data, size)
            else:
                out = _zstandard.ZstdDecompressor().decompress(bytes(data), max_output_size=size)
        elif compression == 'lz4':
            if partial:
                out = lz4.frame.LZ4FrameDecompressor().decompress(bytes(data), max_length=size)
            else:
                out = lz4.frame.decompress(bytes(data))
        else:
            raise McapProblem(f'unsupported chunk compression {compression!r}')
    except McapProblem:
        raise
    except Exception as err:  # zstd/lz4 raise assorted types on corrupt input
        if partial:
            return b''
        raise McapProblem(f'{compression} chunk does not decompress ({type(err).__name__}: {err})') from None
    if not partial and len(out) != size:
        raise McapProblem(f'chunk decompressed to {len(out)} bytes, its header says {size}')
    return out[:size]


def zstd_frame(data: bytes, limit: int = MAX_CHUNK_BYTES) -> bytes:
    """One zstd frame that states its size (a rosbag2 message- or file-compressed unit), decompressed.

    Raises :class:`McapProblem` when it is not such a frame, claims more than
    ``limit`` bytes, or does not decompress.
    """
    if _zstandard is None:  # pragma: no cover - zstandard comes with mcap
        raise McapProblem('zstd data cannot be read without the zstandard package')
    try:
        size = _zstandard.frame_content_size(data)
        if size < 0 or size > limit:
            raise McapProblem(f'zstd frame states {size} bytes' if size >= 0 else 'zstd frame states no size')
        return _zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    except _zstandard.ZstdError as err:
        raise McapProblem(f'zstd data does not decompress ({err})') from None


def zstd_file(source: str | Path, target: str | Path, limit: int) -> None:
    """Decompress the zstd file ``source`` (one or more frames) into ``target``, at most ``limit`` bytes.

    Raises :class:`McapProblem` when it does not decompress or would grow past ``limit``.
    """
    if _zstandard is None:  # pragma: no cover - zstandard comes with mcap
        raise McapProblem('zstd data cannot be read without the zstandard package')
    written = 0
    try:
        with open(source, 'rb') as stream_in, open(target, 'wb') as stream_out:
            reader = _zstandard.ZstdDecompressor().stream_reader(stream_in, read_across_frames=True)
            while piece := reader.read(1 << 20):
                written += len(piece)
                if written > limit:
                    raise McapProblem(f'decompresses to more than {limit} bytes')
                stream_out.write(piece)
    except _zstandard.ZstdError as err:
        raise McapProblem(f'zstd data does not decompress ({err})') from None


def _zstd_prefix(data: bytes | memoryview, size: int) -> bytes:
    """As much of the start of a cut zstd stream as decompresses, never more than ``size`` bytes."""
    pieces: list[bytes] = []
    got = 0
    assert _zstandard is not None  # decompress calls this only with zstandard installed
    reader = _zstandard.ZstdDecompressor().stream_reader(bytes(data))
    try:
        while got < size:
            piece = reader.read(min(size - got, 1 << 20))
            if not piece:
                break
            pieces.append(piece)
            got += len(piece)
    except _zstandard.ZstdError:
        pass
    return b''.join(pieces)


# -- splitting chunk records ------------------------------------------------------------------------

def walk_records(buf: bytes | memoryview, start: int = 0, stop: int | None = None) -> Iterator[tuple[int, int, int]]:
    """Yield ``(opcode, content_start, content_end)`` of consecutive records in ``buf[start:stop]``.

    Stops quietly at a record that does not fit (the caller compares the last
    end with ``stop`` to notice).
    """
    stop = len(buf) if stop is None else stop
    pos = start
    while pos + RECORD_PREFIX <= stop:
        opcode, length = _RECORD.unpack_from(buf, pos)
        end = pos + RECORD_PREFIX + length
        if end > stop:
            return
        yield opcode, pos + RECORD_PREFIX, end
        pos = end


def split_records(buffers: list[_Bytes], start_time: int, file_offset: int, on_record: _RecordSink,
                  on_problem: ProblemSink | None = None, offsets: list[int] | None = None) -> tuple[RawChunk, int]:
    """Split the records of several buffers (chunks' records, top-level records) into one chunk.

    Walks every record (no message index); each buffer is walked on its own,
    so one that ends in a cut record cannot shift the next.  Returns the chunk
    (over the buffers joined) and the bytes of the last buffer used.
    ``on_record(opcode, content)`` receives every non-message record.  A
    record whose length runs past its buffer (a corrupt length inside a chunk)
    ends that buffer's walk; ``on_problem`` (if given) hears it in one line
    with the bytes lost, the buffer named by its file offset (``offsets``,
    one per buffer; default ``file_offset``).
    """
    per_channel: dict[int, list[tuple[int, int, int]]] = {}
    base = used = 0
    for number, buf in enumerate(buffers):
        used = 0
        for opcode, begin, end in walk_records(buf):
            used = end
            if opcode == OP_MESSAGE:
                if end - begin < MESSAGE_HEADER:
                    continue
                channel_id, _, log_time, _ = _MESSAGE.unpack_from(buf, begin)
                per_channel.setdefault(channel_id, []).append(
                    (base + begin + MESSAGE_HEADER, end - begin - MESSAGE_HEADER, signed(log_time)))
            else:
                on_record(opcode, memoryview(buf)[begin:end])
        if used != len(buf) and on_problem is not None:
            at = offsets[number] if offsets else file_offset
            on_problem(_overrun_problem(at, used, len(buf)))
        base += len(buf)
    groups = {}
    for channel_id, rows in per_channel.items():
        table = np.array(rows, dtype=np.int64).reshape(-1, 3)
        groups[channel_id] = MessageGroup(table[:, 0].copy(), table[:, 1].copy(), table[:, 2].copy())
    joined = buffers[0] if len(buffers) == 1 else b''.join(buffers)
    return RawChunk(start_time, np.frombuffer(joined, np.uint8), groups, file_offset), used


def split_sequential(buf: bytes | memoryview, start_time: int, file_offset: int, on_record: _RecordSink,
                     on_problem: ProblemSink | None = None) -> tuple[RawChunk, int]:
    """Split one buffer's records by walking them one by one (no message index); return the chunk and bytes used.

    ``on_record(opcode, content)`` receives every non-message record (schemas,
    channels); ``on_problem`` a record overrunning the buffer (:func:`split_records`).
    """
    return split_records([buf], start_time, file_offset, on_record, on_problem)


def _overrun_problem(file_offset: int, used: int, size: int) -> str:
    """The line for a chunk (or record run) whose walk stopped ``size - used`` bytes before its end."""
    return (f'chunk at byte {file_offset}: a record length at byte {used} of its {size} bytes of records runs past '
            f'the chunk (corrupt); its last {size - used} bytes are not readable')


def split_indexed(buf: bytes | memoryview, start_time: int, file_offset: int, indexes: dict[int, bytes],
                  on_record: _RecordSink, on_problem: ProblemSink | None = None) -> RawChunk | None:
    """Split a chunk with its MessageIndex records, vectorised; None if the index does not fit.

    The index is trusted only after checking that every entry points at a
    Message record of its channel inside the chunk and that the bytes between
    indexed messages hold no other Message record.  Log times are the
    messages' own (as the reference readers give them); index times that
    disagree are said to ``on_problem`` (if given) in one line.
    """
    data = np.frombuffer(buf, np.uint8)
    size = data.size
    ids, tables = [], []
    for channel_id, content in indexes.items():
        ids.append(channel_id)
        tables.append(np.frombuffer(content, '<u8'))
    counts = [table.size // 2 for table in tables]
    if not sum(counts) or size < RECORD_PREFIX + MESSAGE_HEADER:
        return None
    table = np.concatenate(tables).view(np.int64).reshape(-1, 2)
    log_times, offsets = table[:, 0], table[:, 1]
    if offsets.min() < 0 or offsets.max() > size - RECORD_PREFIX - MESSAGE_HEADER:
        return None
    # Unaligned views of the buffer at every byte offset: one gather per field.
    uint64_at = np.ndarray((size - 7,), '<u8', data, 0, (1,))
    uint16_at = np.ndarray((size - 1,), '<u2', data, 0, (1,))
    lengths = uint64_at[offsets + 1].view(np.int64)
    channels = np.repeat(np.array(ids, np.int64), counts)
    if lengths.min() < MESSAGE_HEADER or lengths.max() > size:
        return None
    ends = offsets + RECORD_PREFIX + lengths
    if (np.any(data[offsets] != OP_MESSAGE) or np.any(uint16_at[offsets + 9] != channels)
            or ends.max() > size):
        return None
    # Sorted separately, starts and ends pair up exactly when no two records overlap.
    starts_sorted, ends_sorted = np.sort(offsets, kind='stable'), np.sort(ends, kind='stable')
    if np.any(starts_sorted[1:] < ends_sorted[:-1]):
        return None
    # Gaps between indexed messages may hold schemas/channels, never unindexed messages.
    if not _gaps_hold_no_message(buf, size, starts_sorted, ends_sorted, on_record):
        return None
    own_times = uint64_at[offsets + RECORD_PREFIX + 6].view(np.int64)   # after channel_id u16, sequence u32
    wrong = int(np.count_nonzero(own_times != log_times))
    if wrong and on_problem is not None:
        on_problem(f'chunk at byte {file_offset}: {wrong} message index time(s) disagree with the messages\' own '
                   'log times (corrupt index); the messages\' times are used')
    groups = {}
    start = 0
    for channel_id, count in zip(ids, counts):
        stop = start + count
        groups[channel_id] = MessageGroup(offsets[start:stop] + RECORD_PREFIX + MESSAGE_HEADER,
                                          lengths[start:stop] - MESSAGE_HEADER, own_times[start:stop])
        start = stop
    return RawChunk(start_time, data, groups, file_offset)


def _gaps_hold_no_message(buf: bytes | memoryview, size: int, starts_sorted: np.ndarray, ends_sorted: np.ndarray,
                          on_record: _RecordSink) -> bool:
    """True when the ``size`` bytes of ``buf`` around indexed messages hold whole records, none of them a message.

    ``starts_sorted``/``ends_sorted``: where the indexed messages' records
    begin and end, each sorted.  Each record found between them (a schema, a
    channel) goes to ``on_record``.
    """
    gap_after = np.nonzero(starts_sorted[1:] != ends_sorted[:-1])[0]
    gaps = [(0, int(starts_sorted[0]))] + [(int(ends_sorted[i]), int(starts_sorted[i + 1])) for i in gap_after]
    gaps.append((int(ends_sorted[-1]), size))
    for gap_start, gap_end in gaps:
        if gap_start == gap_end:
            continue
        last = gap_start
        for opcode, begin, end in walk_records(buf, gap_start, gap_end):
            if opcode == OP_MESSAGE:
                return False
            on_record(opcode, memoryview(buf)[begin:end])
            last = end
        if last != gap_end:
            return False
    return True


# -- the file ---------------------------------------------------------------------------------------

def _definitions_into(summary: Summary, on_problem: ProblemSink) -> _RecordSink:
    """A sink for the Schema and Channel records met while reading, filling ``summary``.

    It hears the records among messages (inside chunks, or gathered top-level
    ones): any other spec opcode there (a Footer, a Chunk, 0x00) is damage --
    most often a Message whose opcode byte changed -- and said in one line.
    """
    def on_record(opcode: int, content: bytes | memoryview) -> None:
        try:
            if opcode == OP_SCHEMA:
                schema = parse_schema(content)
                summary.schemas.setdefault(schema.id, schema)
            elif opcode == OP_CHANNEL:
                channel = parse_channel(content)
                summary.channels.setdefault(channel.id, channel)
            elif opcode < FIRST_USER_OPCODE:
                on_problem(f'a record of opcode {opcode:#04x} among the messages (corrupt; a message with a damaged '
                           'opcode?) left out')
        except McapProblem as problem:
            on_problem(f'bad schema/channel record ({problem})')
    return on_record


def _add_index(indexes: dict[int, bytes], content: bytes) -> None:
    """Add one MessageIndex record's entries to a chunk's ``indexes``; a bad one makes them all unusable."""
    if len(content) >= _INDEX_HEAD.size:
        channel_id, entries = _INDEX_HEAD.unpack_from(content, 0)
        if not entries % 16 and _INDEX_HEAD.size + entries <= len(content):
            indexes[channel_id] = content[_INDEX_HEAD.size:_INDEX_HEAD.size + entries]
            return
    indexes.clear()
    indexes[-1] = b''  # marks the index unusable


@lru_cache(maxsize=64)
def _compression_name(raw: bytes) -> str:
    try:
        return raw.decode('utf-8')
    except UnicodeDecodeError:
        raise McapProblem('record string is not UTF-8') from None


def _chunk_header(content: bytes, at: int) -> tuple[int, int, int, str, int, int]:
    """A Chunk record's fields before its data, read from ``content`` at ``at``.

    Returns ``(message_start_time, uncompressed_size, uncompressed_crc,
    compression, data_offset, compressed_size)``; ``data_offset`` is where the
    compressed records begin in ``content``.
    """
    head_end = at + _CHUNK_HEAD.size
    if head_end > len(content):
        raise McapProblem('record field runs past the end of its record')
    start_time, _, size, crc, name_length = _CHUNK_HEAD.unpack_from(content, at)
    name_end = head_end + name_length
    if name_end + 8 > len(content):
        raise McapProblem('record field runs past the end of its record')
    compression = _compression_name(bytes(content[head_end:name_end]))
    return start_time, size, crc, compression, name_end + 8, _U64.unpack_from(content, name_end)[0]


class _CrcReader:
    """Reads of a data section in file order, keeping the CRC-32 of every byte read or skipped (magic included)."""

    def __init__(self, stream: BinaryIO) -> None:
        self.stream = stream
        self.crc = crc32(MAGIC)

    def read(self, size: int) -> bytes:
        """The next ``size`` bytes (fewer at the end of the file)."""
        data = self.stream.read(size)
        self.crc = crc32(data, self.crc)
        return data

    def skip(self, size: int) -> None:
        """Pass over ``size`` bytes, a MiB at a time."""
        while size > 0:
            piece = self.read(min(size, 1 << 20))
            if not piece:
                return
            size -= len(piece)


def _check_data_crc(stream: BinaryIO, pos: int, opcode: int, length: int, crc: int,
                    on_problem: ProblemSink) -> None:
    """Say when the DataEnd record at ``pos`` states a data-section CRC other than ``crc`` (0: none stated)."""
    if opcode != OP_DATA_END or length < 4:
        return
    stream.seek(pos + RECORD_PREFIX)
    stated = _U32.unpack(stream.read(4))[0]
    if stated and stated != crc:
        on_problem('its data section does not match the CRC its DataEnd record states (corrupt bytes where no '
                   'chunk CRC covers them)')


class _Gathered:
    """Top-level messages and the records of small chunks, gathered into pseudo-chunks of about ``size`` bytes.

    One message per chunk (or none at all) would otherwise cost a split, a
    decode and a slice step per message; gathered, they cost one per batch.
    """

    def __init__(self, on_record: _RecordSink, size: int, on_problem: ProblemSink | None = None) -> None:
        self.on_record = on_record
        self.on_problem = on_problem
        self.size = size
        self.buffers: list[_Bytes] = []
        self.offsets: list[int] = []
        self.bytes = 0
        self.file_offset = 0
        self.start_time: int | None = None

    def add(self, buffer: bytes | memoryview, start_time: int | None, file_offset: int) -> RawChunk | None:
        """Gather ``buffer`` (records); return a pseudo-chunk when enough is gathered."""
        if not self.buffers:
            self.file_offset = file_offset
        self.buffers.append(buffer)
        self.offsets.append(file_offset)
        self.bytes += len(buffer)
        if start_time is not None:
            self.start_time = start_time if self.start_time is None else min(self.start_time, start_time)
        return self.take() if self.bytes >= self.size else None

    def take(self) -> RawChunk | None:
        """What is gathered as one pseudo-chunk (None if nothing)."""
        if not self.buffers:
            return None
        chunk, _ = split_records(self.buffers, self.start_time or 0, self.file_offset, self.on_record,
                                 self.on_problem, self.offsets)
        self.buffers, self.offsets, self.bytes, self.start_time = [], [], 0, None
        return chunk


def _summary_records(section: bytes) -> tuple[Summary, list[int], bool] | None:
    """The records of an intact summary section: ``(summary, chunk offsets, Statistics record seen)``.

    None when a record runs past the section's end; a record that does not
    parse raises :class:`McapProblem`.
    """
    summary = Summary(complete=True)
    statistics = False
    chunk_index: list[int] = []
    last = 0
    for opcode, begin, end in walk_records(section):
        last = end
        content = memoryview(section)[begin:end]
        if opcode == OP_CHUNK_INDEX and end - begin >= 24:
            chunk_index.append(_U64.unpack_from(content, 16)[0])     # chunk_start_offset
        elif opcode == OP_SCHEMA:
            schema = parse_schema(content)
            summary.schemas[schema.id] = schema
        elif opcode == OP_CHANNEL:
            channel = parse_channel(content)
            summary.channels[channel.id] = channel
        elif opcode == OP_STATISTICS:
            _read_statistics(content, summary)
            statistics = True
    if last != len(section):
        return None
    return summary, chunk_index, statistics


def _read_statistics(content: memoryview, summary: Summary) -> None:
    """Put what a Statistics record says (definition counts, time span, messages per channel) into ``summary``."""
    fields = _Fields(content)
    fields.u64()
    summary.schema_count = fields.u16()
    summary.channel_count = fields.u32()
    fields.u32()
    fields.u32()
    fields.u32()
    summary.start_time, summary.end_time = fields.u64(), fields.u64()
    counts_end = fields.u32() + fields.pos
    while fields.pos + 10 <= counts_end:
        channel_id = fields.u16()
        summary.message_counts[channel_id] = fields.u64()


@dataclass
class _DataWalk:
    """What :meth:`McapFile.chunks` reads a data section with, and where its walk of the records stopped."""

    stream: BinaryIO
    data: _CrcReader                        # ``stream`` read in file order, keeping the data section's CRC
    gathered: _Gathered
    on_record: _RecordSink
    on_problem: ProblemSink
    pos: int = len(MAGIC)                   # file offset where the walk stopped
    pending: _PendingChunk | None = None    # chunk still waiting for its message index records there
    cut: int | None = None                  # where a cut-off or damaged record header stopped it (None: none did)
    ended: bool = False                     # the DataEnd record or the footer ended the data section


def _few_messages(records: bytes | memoryview, indexes: dict[int, bytes]) -> bool:
    """True for a chunk small enough that gathering it with its neighbours is cheaper than splitting it alone."""
    if indexes and -1 not in indexes:
        return sum(len(entries) for entries in indexes.values()) <= 16 * SMALL_CHUNK_MESSAGES
    return len(records) <= SMALL_CHUNK_BYTES


class McapFile:
    """One MCAP file opened for listing and streaming; problems raise :class:`McapProblem`."""

    def __init__(self, path: str | Path) -> None:
        self.path = path
        self.summary_problem = ''     # why the summary section was not used (a problem line), '' when it was
        self.chunk_index: list[int] = []    # chunk offsets an intact summary's ChunkIndex records give
        with open_regular(path, 'MCAP file', error=RecordingError) as stream:
            stream.seek(0, 2)
            self.size = stream.tell()
            stream.seek(0)
            if stream.read(len(MAGIC)) != MAGIC:
                raise McapProblem('not an MCAP file (no MCAP magic at its start)')
            self.summary = self._read_summary(stream)
        if self.summary is not None and self.summary.lacks_definitions():
            self._definitions_from_data(self.summary)

    def _definitions_from_data(self, summary: Summary) -> None:
        """Schemas and channels the summary does not repeat (``noRepeatedChannels``), from the data section."""
        found = Summary()
        for _ in self.chunks(lambda line: None, found):
            if not Summary(found.schemas, found.channels, summary.message_counts, schema_count=summary.schema_count,
                           channel_count=summary.channel_count).lacks_definitions():
                break
        for key, schema in found.schemas.items():
            summary.schemas.setdefault(key, schema)
        for key, channel in found.channels.items():
            summary.channels.setdefault(key, channel)

    # summary ------------------------------------------------------------------------------------
    def _read_summary(self, stream: BinaryIO) -> Summary | None:
        """The summary section, or None when the file has none or it is damaged."""
        footer_at = self.size - len(MAGIC) - RECORD_PREFIX - 20
        if footer_at < len(MAGIC):
            return None
        stream.seek(footer_at)
        tail = stream.read(RECORD_PREFIX + 20 + len(MAGIC))
        if tail[-len(MAGIC):] != MAGIC or tail[0] != OP_FOOTER or _U64.unpack_from(tail, 1)[0] != 20:
            return None
        summary_start = _U64.unpack_from(tail, RECORD_PREFIX)[0]
        if summary_start == 0:
            return None
        damaged = 'its summary section is damaged; the listing was rebuilt from the data section'
        if not len(MAGIC) <= summary_start <= footer_at:
            self.summary_problem = damaged
            return None
        stream.seek(summary_start)
        section = stream.read(footer_at - summary_start)
        # Footer summary_crc: CRC-32 of the summary section and the footer up to summary_offset_start (0: none).
        summary_crc = _U32.unpack_from(tail, RECORD_PREFIX + 16)[0]
        if summary_crc and crc32(tail[:RECORD_PREFIX + 16], crc32(section)) != summary_crc:
            self.summary_problem = ('its summary section does not match its CRC (corrupt); the listing was rebuilt '
                                    'from the data section')
            return None
        try:
            parsed = _summary_records(section)
        except McapProblem:
            parsed = None
        if parsed is None:
            self.summary_problem = damaged
            return None
        summary, chunk_index, statistics = parsed
        self.chunk_index = chunk_index
        return summary if statistics else None

    def index_problem(self, layout: DataLayout) -> str:
        """A line when chunks the summary's chunk index lists are not where it says ('' when all are).

        A chunk whose opcode became another (a user opcode, which readers
        skip) leaves no other trace in a file without statistics; the
        reference readers, which seek by this index, refuse such a file.
        """
        missing = sorted(set(self.chunk_index) - set(layout.offsets.tolist()))
        if not missing:
            return ''
        return (f'{len(missing)} chunk(s) the chunk index lists (at byte {missing[0]}'
                f'{" ..." if len(missing) > 1 else ""}) are not in the data section (damaged records): not read')

    def scan(self) -> tuple[Summary, list[str]]:
        """Rebuild the listing by reading the data section (file without a usable summary)."""
        summary = Summary()
        problems: list[str] = []
        for chunk in self.chunks(problems.append, summary):
            for channel_id, group in chunk.groups.items():
                if group.log_times.size == 0:
                    continue
                summary.message_counts[channel_id] = (summary.message_counts.get(channel_id, 0)
                                                      + int(group.log_times.size))
                low, high = int(group.log_times.min()), int(group.log_times.max())
                summary.start_time = low if summary.start_time is None else min(summary.start_time, low)
                summary.end_time = high if summary.end_time is None else max(summary.end_time, high)
        return summary, problems

    # data section -------------------------------------------------------------------------------
    def chunks(self, on_problem: ProblemSink, summary: Summary | None = None,
               unchunked_batch: int = GATHER_BYTES) -> Iterator[RawChunk]:
        """Yield the file's messages chunk by chunk, in file order.

        Top-level messages and consecutive small chunks come gathered into
        pseudo-chunks of about ``unchunked_batch`` bytes.  Schemas and channels
        met on the way go into ``summary`` (if given).  Damage ends or skips
        with one line to ``on_problem``: a truncated file yields everything
        before the cut (including the readable start of a cut chunk), a chunk
        that does not decompress is skipped.
        """
        summary = summary if summary is not None else Summary()
        on_record = _definitions_into(summary, on_problem)
        gathered = _Gathered(on_record, unchunked_batch, on_problem)
        with open_regular(self.path, 'MCAP file', error=RecordingError) as stream:
            stream.seek(len(MAGIC))
            walk = _DataWalk(stream, _CrcReader(stream), gathered, on_record, on_problem)
            yield from self._data_records(walk)
            yield from self._end_of_data(walk)

    def _data_records(self, walk: _DataWalk) -> Iterator[RawChunk]:
        """The chunks of the data section's records in file order, up to its end or the first damaged record header.

        Leaves in ``walk`` where it stopped, the chunk still waiting for its
        message index, where a record header was cut off or damaged, and
        whether the DataEnd record (or the footer) ended the section.
        """
        data, gathered, on_problem = walk.data, walk.gathered, walk.on_problem
        pos = len(MAGIC)
        pending: _PendingChunk | None = None    # chunk waiting for its message index records
        previous = None       # opcode of the last record not a MessageIndex of a pending chunk
        while True:
            crc_before = data.crc
            head = data.read(RECORD_PREFIX)
            if len(head) < RECORD_PREFIX:
                walk.cut = pos if head else None
                break
            opcode, length = _RECORD.unpack_from(head, 0)
            known = 0 < opcode <= Opcode.DATA_END or opcode >= FIRST_USER_OPCODE
            if length > self.size - pos - RECORD_PREFIX or not known:
                walk.cut = pos
                break
            if opcode == OP_MESSAGE_INDEX and pending is not None:
                _add_index(pending[2], data.read(length))
                pos += RECORD_PREFIX + length
                continue
            if opcode == OP_MESSAGE_INDEX and previous not in (OP_CHUNK, OP_MESSAGE_INDEX):
                on_problem(f'a MessageIndex record at byte {pos} follows no chunk (corrupt; a chunk whose opcode '
                           'was damaged?): skipped')
            previous = opcode
            if pending is not None:
                yield from self._finish_or_gather(pending, gathered)
                pending = None
            if opcode == OP_MESSAGE or (gathered.buffers and opcode in (OP_SCHEMA, OP_CHANNEL)):
                record = head + data.read(length)
                start_time = (signed(_MESSAGE.unpack_from(record, RECORD_PREFIX)[2])
                              if opcode == OP_MESSAGE and length >= MESSAGE_HEADER else None)
                chunk = gathered.add(record, start_time, pos)
                if chunk is not None:
                    yield chunk
                pos += RECORD_PREFIX + length
                continue
            if opcode != OP_CHUNK and gathered.buffers:
                yield cast(RawChunk, gathered.take())   # not None: buffers were gathered
            pending = self._other_record(walk, pos, opcode, length, crc_before)
            if walk.ended:
                break
            pos += RECORD_PREFIX + length
        walk.pos, walk.pending = pos, pending

    def _other_record(self, walk: _DataWalk, pos: int, opcode: int, length: int,
                      crc_before: int) -> _PendingChunk | None:
        """Act on the record at ``pos`` of the data section: not a message, nor a pending chunk's MessageIndex.

        Its header has been read.  Returns the chunk a Chunk record opens (None
        for any other record, or a chunk that cannot be read); sets
        ``walk.ended`` at the DataEnd record or footer that ends the data
        section (``crc_before``: the CRC of the data section before it).
        """
        data, stream, on_problem = walk.data, walk.stream, walk.on_problem
        if opcode in (OP_DATA_END, OP_FOOTER):
            if _ends_data(stream, pos, opcode, length, self.size):
                walk.cut, walk.ended = None, True
                _check_data_crc(stream, pos, opcode, length, crc_before, on_problem)
                return None
            on_problem(f'a {"DataEnd" if opcode == OP_DATA_END else "Footer"} record at byte {pos} in the '
                       f'middle of the data section (corrupt; a damaged opcode?): its {length} bytes skipped')
            stream.seek(pos + RECORD_PREFIX)    # the skip below passes its content
        if opcode == OP_CHUNK:
            content = data.read(length)
            try:
                return self._open_chunk(content, pos, on_problem)
            except McapProblem as problem:
                on_problem(f'chunk at byte {pos} skipped: {problem}')
                return None
        if opcode in (OP_SCHEMA, OP_CHANNEL):
            walk.on_record(opcode, data.read(length))
        else:
            if opcode in SUMMARY_OPCODES or (opcode == OP_HEADER and pos != len(MAGIC)):
                on_problem(f'a record of opcode {opcode:#04x} at byte {pos} where it does not belong in the '
                           'data section (corrupt; a damaged opcode?): skipped')
            data.skip(length)
        return None

    def _end_of_data(self, walk: _DataWalk) -> Iterator[RawChunk]:
        """What is left where the walk of the data section stopped; how it ended, if not at DataEnd or the footer.

        The chunk still waiting for its message index, what is gathered, and
        the readable beginning of a chunk cut off by the end of the file.
        """
        if walk.pending is not None:
            yield from self._finish_or_gather(walk.pending, walk.gathered)
        if walk.gathered.buffers:
            yield cast(RawChunk, walk.gathered.take())   # not None: buffers were gathered
        if walk.cut is None and not walk.ended:
            walk.on_problem(f'ends at byte {walk.pos} without a DataEnd record or footer (truncated: what followed '
                            'is lost)')
        if walk.cut is not None:
            salvage = self._salvage(walk.stream, walk.cut, walk.on_record)
            lost = f'{self.size - walk.cut} bytes'
            if salvage is not None:
                yield salvage
                lost += f' (recovered {salvage.message_count()} messages from the cut chunk)'
            walk.on_problem(f'truncated or corrupt at byte {walk.cut} of {self.size}: '
                            f'the last {lost} are not readable')

    def _finish_or_gather(self, pending: _PendingChunk, gathered: _Gathered) -> Iterator[RawChunk]:
        """A read chunk: gathered when small, else split on its own (after what was gathered before it)."""
        records, start_time, indexes, pos = pending
        if _few_messages(records, indexes):
            chunk = gathered.add(records, start_time, pos)
            if chunk is not None:
                yield chunk
            return
        if gathered.buffers:
            yield cast(RawChunk, gathered.take())   # not None: buffers were gathered
        yield self._finish_chunk(records, start_time, indexes, pos, gathered.on_record, gathered.on_problem)

    def chunks_at(self, offsets: Iterable[int] | np.ndarray, on_problem: ProblemSink,
                  summary: Summary | None = None) -> Iterator[RawChunk]:
        """The chunks starting at ``offsets`` (from :func:`data_layout`), in the order given, by seeking.

        Reads each chunk with the MessageIndex records that follow it: what
        the reference readers do to give messages in log time order from a
        file whose chunks are not, holding one chunk at a time.  A chunk that
        cannot be read is left out with one line to ``on_problem``.
        """
        summary = summary if summary is not None else Summary()
        gathered = _Gathered(_definitions_into(summary, on_problem), GATHER_BYTES, on_problem)
        with open_regular(self.path, 'MCAP file', error=RecordingError) as stream:
            for pos in offsets:
                pos = int(pos)
                stream.seek(pos)
                head = stream.read(RECORD_PREFIX)
                opcode, length = _RECORD.unpack_from(head, 0) if len(head) == RECORD_PREFIX else (0, 0)
                if opcode != OP_CHUNK or length > self.size - pos - RECORD_PREFIX:
                    on_problem(f'chunk at byte {pos} skipped: no chunk record there')
                    continue
                try:
                    pending = self._open_chunk(stream.read(length), pos, on_problem)
                except McapProblem as problem:
                    on_problem(f'chunk at byte {pos} skipped: {problem}')
                    continue
                at = pos + RECORD_PREFIX + length
                while True:     # its message index records
                    head = stream.read(RECORD_PREFIX)
                    if len(head) < RECORD_PREFIX:
                        break
                    opcode, length = _RECORD.unpack_from(head, 0)
                    if opcode != OP_MESSAGE_INDEX or length > self.size - at - RECORD_PREFIX:
                        break
                    _add_index(pending[2], stream.read(length))
                    at += RECORD_PREFIX + length
                yield from self._finish_or_gather(pending, gathered)
        if gathered.buffers:
            yield cast(RawChunk, gathered.take())   # not None: buffers were gathered

    def _open_chunk(self, content: bytes, pos: int, on_problem: ProblemSink) -> _PendingChunk:
        """Chunk record -> ``(records, start_time, indexes, pos)`` awaiting its message index."""
        start_time, size, crc, compression, at, compressed_size = _chunk_header(content, 0)
        if compressed_size > len(content) - at:
            raise McapProblem('compressed data runs past its chunk record')
        compressed = memoryview(content)[at:at + compressed_size]
        records = decompress(compressed, compression, size)
        if crc and crc32(records) != crc:
            raise McapProblem(f'its records do not match their CRC ({size} bytes, corrupt)')
        return (records, signed(start_time), {}, pos)

    def _finish_chunk(self, records: bytes | memoryview, start_time: int, indexes: dict[int, bytes], pos: int,
                      on_record: _RecordSink, on_problem: ProblemSink | None = None) -> RawChunk:
        indexed = indexes and -1 not in indexes
        if indexed:
            chunk = split_indexed(records, start_time, pos, indexes, on_record, on_problem)
            if chunk is not None:
                return chunk
        chunk, _ = split_sequential(records, start_time, pos, on_record, on_problem)
        listed = sum(len(entries) for entries in indexes.values()) // 16 if indexed else 0
        if indexed and on_problem is not None and chunk.message_count() < listed:   # more: an index cut short
            on_problem(f'chunk at byte {pos}: its message index lists {listed} message(s), its records hold '
                       f'{chunk.message_count()} (corrupt)')
        return chunk

    def _salvage(self, stream: BinaryIO, cut: int, on_record: _RecordSink) -> RawChunk | None:
        """The readable beginning of a chunk cut off by the end of the file, if any."""
        stream.seek(cut)
        content = stream.read(min(self.size - cut, MAX_CHUNK_BYTES))
        if len(content) < RECORD_PREFIX + 28 or content[0] != OP_CHUNK:
            return None
        try:
            start_time, size, _, compression, at, _ = _chunk_header(content, RECORD_PREFIX)
            records = decompress(memoryview(content)[at:], compression, size, partial=True)
        except McapProblem:
            return None
        chunk, _ = split_sequential(records, signed(start_time), cut, on_record)
        return chunk if chunk.message_count() else None


@dataclass
class DataLayout:
    """Where the chunks and unchunked messages of a data section start, and their earliest log times."""

    offsets: np.ndarray     # (n,) int64 file offsets of the records
    times: np.ndarray       # (n,) int64 ns: a chunk's message_start_time, a message's log time
    only_chunks: bool       # no message outside a chunk
    complete: bool          # every record fits and the section ends with DataEnd or the Footer


#: Opcodes of the summary section (after DataEnd): Schema, Channel, ChunkIndex, AttachmentIndex, Statistics,
#: MetadataIndex, SummaryOffset.
SUMMARY_OPCODES = frozenset((OP_SCHEMA, OP_CHANNEL, OP_CHUNK_INDEX, Opcode.ATTACHMENT_INDEX, OP_STATISTICS,
                             Opcode.METADATA_INDEX, Opcode.SUMMARY_OFFSET))


def _ends_data(stream: BinaryIO, pos: int, opcode: int, length: int, size: int) -> bool:
    """True when the DataEnd or Footer record at ``pos`` really ends the data section.

    Only (part of) the closing magic may follow a Footer; after a DataEnd only
    summary records, up to a Footer or to where a truncation cut them.  Any
    other record after it (a Chunk, a Message, an index) makes it an end
    opcode in the middle of the data (a damaged byte), which the reference
    readers refuse.  Seeks ``stream`` over record headers only.
    """
    at = pos + RECORD_PREFIX + length
    if opcode == OP_FOOTER:
        return at >= size - len(MAGIC)
    while at + RECORD_PREFIX <= size:
        stream.seek(at)
        kind, record_length = _RECORD.unpack_from(stream.read(RECORD_PREFIX), 0)
        if kind == OP_FOOTER:
            return True
        if not (kind in SUMMARY_OPCODES or kind >= FIRST_USER_OPCODE):
            return False
        at += RECORD_PREFIX + record_length
    return True


def data_layout(path: str | Path, size: int) -> DataLayout:
    """The :class:`DataLayout` of a file's data section, from its record headers only.

    Seeks over chunk data, so it is cheap; a damaged record ends the list
    quietly with ``complete`` False (:meth:`McapFile.chunks` reports it).
    """
    offsets = array('q')          # 8 bytes an entry, not a Python int: files of one message per chunk are long
    times = array('Q')
    only_chunks, complete = True, False
    with open_regular(path, 'MCAP file', error=RecordingError) as stream:
        pos = len(MAGIC)
        stream.seek(pos)
        while True:
            head = stream.read(RECORD_PREFIX + MESSAGE_HEADER)
            if len(head) < RECORD_PREFIX:
                break
            opcode, length = _RECORD.unpack_from(head, 0)
            if length > size - pos - RECORD_PREFIX:
                break
            if opcode in (OP_DATA_END, OP_FOOTER):
                complete = _ends_data(stream, pos, opcode, length, size)   # else: McapFile.chunks reports it
                break
            if opcode == OP_CHUNK and length >= 8 and len(head) >= RECORD_PREFIX + 8:
                offsets.append(pos)
                times.append(_U64.unpack_from(head, RECORD_PREFIX)[0])
            elif opcode == OP_MESSAGE:
                only_chunks = False
                if length >= MESSAGE_HEADER and len(head) == RECORD_PREFIX + MESSAGE_HEADER:
                    offsets.append(pos)
                    times.append(_MESSAGE.unpack_from(head, RECORD_PREFIX)[2])
            pos += RECORD_PREFIX + length
            stream.seek(pos)
    return DataLayout(np.frombuffer(offsets, np.int64).copy(), np.frombuffer(times, np.uint64).view(np.int64).copy(),
                      only_chunks, complete)


class ReadCheck:
    """What reading a file found, held against its intact summary at the end.

    Damage that leaves no trace where it happened -- a chunk whose opcode
    became a user opcode (skipped, as the spec says), a message whose channel
    id changed in a chunk without CRC -- still disagrees with the Statistics
    record (fewer messages than it counts) or the definitions (a channel
    defined nowhere).  Log times are not held against the Statistics span:
    rosbag2's writer leaves a log time of 0 out of it.
    """

    def __init__(self, summary: Summary | None, summary_problem: str = '') -> None:
        self.summary = summary if summary is not None and summary.complete else None
        self.summary_problem = summary_problem
        self.counts: dict[int, int] = {}
        self.undefined = 0

    def add(self, chunk: RawChunk, channels: dict[int, Channel]) -> None:
        """Count one chunk's messages (``channels``: those defined so far)."""
        for channel_id, group in chunk.groups.items():
            self.counts[channel_id] = self.counts.get(channel_id, 0) + int(group.log_times.size)
            if channel_id not in channels:
                self.undefined += int(group.log_times.size)

    def lines(self) -> list[str]:
        """One line per kind of disagreement (none for an intact file)."""
        lines = [self.summary_problem] if self.summary_problem else []
        if self.undefined:
            lines.append(f'{self.undefined} message(s) on a channel defined nowhere in the file (a damaged record?)')
        summary = self.summary
        if summary is None:
            return lines
        short = [(key, self.counts.get(key, 0), listed) for key, listed in sorted(summary.message_counts.items())
                 if self.counts.get(key, 0) < listed]
        if short:
            def name(key: int) -> str:
                return summary.channels[key].topic if key in summary.channels else f'channel {key}'
            lost = sum(listed - got for _, got, listed in short)
            lines.append(f'{lost} message(s) listed in the summary were not read (damaged data): '
                         + ', '.join(f'{name(key)} {got} of {listed}' for key, got, listed in short))
        return lines


def channel_messages(path: str | Path,
                     on_problem: ProblemSink) -> Iterator[tuple[Channel | None, int, int, bytes]]:
    """Every message of an MCAP file in file order: ``(channel, sequence, log_time, data)``, undecoded.

    ``channel`` is None for a message whose channel is nowhere defined.
    Problems go to ``on_problem`` as in :meth:`McapFile.chunks`.
    """
    mcap = McapFile(path)
    summary = Summary()
    if mcap.summary is not None:
        summary.channels.update(mcap.summary.channels)
    check = ReadCheck(mcap.summary, mcap.summary_problem)
    index_problem = mcap.index_problem(data_layout(path, mcap.size)) if mcap.chunk_index else ''
    if index_problem:
        on_problem(index_problem)
    for chunk in mcap.chunks(on_problem, summary):
        check.add(chunk, summary.channels)
        ids = np.concatenate([np.full(g.data_offsets.size, key, np.int64) for key, g in chunk.groups.items()]
                             + [np.zeros(0, np.int64)])
        starts = np.concatenate([g.data_offsets for g in chunk.groups.values()] + [np.zeros(0, np.int64)])
        lengths = np.concatenate([g.data_lengths for g in chunk.groups.values()] + [np.zeros(0, np.int64)])
        buffer = chunk.buffer
        for index in np.argsort(starts, kind='stable'):
            begin = int(starts[index])
            # ndarray has the buffer protocol; numpy's stubs declare __buffer__ for Python >= 3.12 only
            sequence, log_time = struct.unpack_from('<IQ', buffer, begin - MESSAGE_HEADER + 2)  # type: ignore[arg-type]
            yield (summary.channels.get(int(ids[index])), sequence, log_time,
                   bytes(buffer[begin:begin + int(lengths[index])]))
    for line in check.lines():
        on_problem(line)
