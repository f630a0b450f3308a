# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Recordings (rosbag2 directories, bare ``.mcap`` files) in, numpy batches of the contract's topics out.

::

    recording = open_recording('run.mcap', namespace='/prsm')   # InputError if unusable
    print(recording.describe())
    for batches in recording.slices(on_problem=print):           # one list per time slice
        ...                                                      # VibrationBatch, ScrewStateBatch, ...

What is read: ``<ns>/vibration`` (the VibrationBlock layout under any package
name), ``<ns>/joint_states`` (the ``screw`` entry), ``<ns>/axial_load``
(``wrench.force.z``) and, if present, ``<ns>/temperature``.  A namespace
ending in ``/`` or ``_`` is used as a plain prefix (``/rig/left_`` reads
``/rig/left_vibration``...).  :func:`find_actuators` lists the namespaces of a
recording that carry a vibration topic.

Slices are consecutive spans of ``slice_seconds`` of log time on a grid
starting at the first message; each holds one batch per topic that has data in
it, with values taken from the header stamps.  Memory stays at about one MCAP
chunk plus one slice, however long the recording and in whatever order its
chunks are.  A cheap pre-scan of the chunk headers gives every chunk's start
time; when they go back in log time (chunks written topic after topic,
reversed, shuffled), the chunks are read by seeking, in order of start time
across all files, as the reference readers do -- the result is that of the
plainly written file.  Only a damaged file, or one with messages outside
chunks, is read in file order; a slice is then handed out once nothing later
in the file can fall into it, and memory grows with how far back chunks go.

MCAP storage is read by :mod:`prsm_lube_ros.recording.mcap_file`, sqlite3
storage (a bag folder or a bare ``.db3``) by
:mod:`prsm_lube_ros.recording.sqlite_file`, and both are decoded in bulk by
:mod:`prsm_lube_ros.recording.cdr`; sqlite3 bags with zstd file or message
compression are decompressed on the way; other compressed bags are read
through rosbags' Reader and decoded the same way.  A folder without
metadata.yaml is read when it holds one storage file or the parts of one split
bag (``<folder>_0``, ``<folder>_1``...).  ``engine='rosbags'`` reads
through rosbags (or, for a bare ``.mcap``, the ``mcap`` package) and
deserializes every message with rosbags: the slow reference path.

Problems: :func:`open_recording` raises :class:`InputError` (one line naming
the file) for a missing path, something that is not a bag, a bag without the
vibration topic, a contract topic with the wrong layout, or no readable data.
While streaming, everything readable is yielded first; then each problem is
passed once to ``on_problem`` as one line without the path (truncation, chunks
that do not decompress, per topic: messages that do not decode, JointStates
without a ``screw`` entry).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path
import tempfile
from typing import Any, cast
from collections.abc import Callable, Iterable, Iterator

import numpy as np
import yaml

from . import mcap_file, sqlite_file
from ..contract import (AXIAL_LOAD_TOPIC as AXIAL_LOAD, DEFAULT_NAMESPACE, JOINT_STATES_TOPIC as JOINT_STATES,
                        namespace_of, topic_name, VIBRATION_TOPIC as VIBRATION)
from ..errors import ConfigError, exception_text, ProblemSink, RecordingError
from ..input_file import (check_regular, confine, MAX_METADATA_BYTES, MAX_RECORDING_BYTES, open_regular,
                          read_text)
from .batches import AxialLoadBatch, InputBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch
from .cdr import check_layout, decode_messages, Decoded, KINDS, ragged_take
from .plausibility import RATE_SPIKE_FRACTION, SpikeCount, STAMP_SPIKE_SECONDS

__all__ = ['DEFAULT_SLICE_SECONDS', 'HELD_BACK_SECONDS', 'MAX_STORAGE_FILES', 'Recording', 'SQLITE_MAGIC', 'TopicInfo',
           'bare_read', 'find_actuators', 'iter_batches', 'list_topics', 'open_recording', 'raw_messages',
           'topic_messages']

#: default length of one time slice, s of log time (the offline pipeline streams longer ones:
#: :data:`prsm_lube_ros.estimation.pipeline.ASSESSMENT_SLICE_SECONDS`)
DEFAULT_SLICE_SECONDS = 10.0
#: log time a file read in file order may go back before that is reported (memory held), s
HELD_BACK_SECONDS = 60.0
#: most storage files a bag's metadata.yaml may list (a split bag of a day in 1-minute parts has 1440)
MAX_STORAGE_FILES = 10_000
#: libyaml's safe loader where installed (a few MB of metadata.yaml in a second, not ten)
_YAML_LOADER = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)
#: the first 16 bytes of every sqlite3 database file
SQLITE_MAGIC = b'SQLite format 3\x00'
#: raw bytes gathered per pseudo-chunk when reading through rosbags
_ROSBAGS_CHUNK_BYTES = 1 << 20


@dataclass
class TopicInfo:
    """One topic of a recording as listed at opening."""

    name: str
    msgtype: str
    message_count: int
    layout_problem: str | None = None   # why it is not the contract layout (contract topics only)


# -- sources: where raw messages come from ---------------------------------------------------------

@dataclass
class _RawChunk:
    """Serialized messages of some topics, one chunk's worth: views into ``buffer``."""

    start_time: int                                   # ns log time; nothing later in the file is earlier
    buffer: np.ndarray
    groups: dict[str, mcap_file.MessageGroup]         # by topic
    progress: float                                   # fraction of the recording read


class _Source:
    """What the three storage sources share: their listing (topics, definitions, span) and the stream's shape.

    A source lists every topic with its definition ``(msgtype, encoding, text,
    message encoding)`` and streams the named topics in :class:`_RawChunk` pieces
    through :meth:`raw_chunks`.
    """

    def __init__(self, label: str) -> None:
        self.label = label
        self.problems: list[str] = []
        self.topics: dict[str, TopicInfo] = {}
        #: topic -> (msgtype, encoding, text, message encoding)
        self.definitions: dict[str, tuple[str, str, str, str]] = {}
        self.start_time: int | None = None
        self.end_time: int | None = None

    def list_topic(self, name: str, msgtype: str, count: int, definition: tuple[str, str, str, str]) -> None:
        """Add ``count`` messages of ``name`` to the listing (the first file to name a topic defines it)."""
        if name in self.topics:
            self.topics[name].message_count += count
            return
        self.topics[name] = TopicInfo(name, msgtype, count)
        self.definitions[name] = definition

    def widen_span(self, start: int | None, end: int | None) -> None:
        """Widen ``start_time``/``end_time`` (ns) to cover ``start``/``end`` (None: not known)."""
        if start is not None:
            self.start_time = start if self.start_time is None else min(self.start_time, start)
        if end is not None:
            self.end_time = end if self.end_time is None else max(self.end_time, end)

    def layout_problem(self, topic: str, kind: str) -> str | None:
        """Why ``topic`` cannot carry the contract's ``kind`` (None: it can)."""
        msgtype, encoding, text, message_encoding = self.definitions[topic]
        if message_encoding != 'cdr':
            return f'has message encoding {message_encoding!r}, not cdr'
        return check_layout(kind, msgtype, encoding, text)

    def raw_chunks(self, topics: list[str], on_problem: ProblemSink) -> Iterator[_RawChunk]:
        """The messages of ``topics`` in chunks; damage is reported through ``on_problem``."""
        raise NotImplementedError


class _McapSource(_Source):
    """One or more MCAP files (a bare file, or the files of a rosbag2 directory)."""

    def __init__(self, label: str, paths: list[Path]) -> None:
        super().__init__(label)
        self.paths = paths
        self.files: list[mcap_file.McapFile] = []
        self.listings: list[mcap_file.Summary] = []       # per file: its summary, or what a scan found
        for path in paths:
            try:
                mcap = mcap_file.McapFile(path)
                summary = mcap.summary
                if summary is None:
                    summary, problems = mcap.scan()
                    if mcap.summary_problem:
                        problems.insert(0, mcap.summary_problem)
                    self.problems.extend(self._about(mcap, line) for line in problems)
            except mcap_file.McapProblem as problem:
                raise RecordingError(f'{path}: {problem}') from None
            except OSError as err:
                raise RecordingError(f'{path}: cannot be read ({err.strerror or err})') from None
            self.files.append(mcap)
            self.listings.append(summary)
            self._add_listing(summary)

    def _about(self, mcap: mcap_file.McapFile, line: str) -> str:
        """A problem line of one file of a bag names that file (a bare file is named by the label already)."""
        return line if str(mcap.path) == self.label else f'{mcap.path}: {line}'

    def _add_listing(self, summary: mcap_file.Summary) -> None:
        for channel_id, channel in summary.channels.items():
            schema = summary.schemas.get(channel.schema_id)
            msgtype = schema.name if schema else '(no schema)'
            text = schema.data.decode('utf-8', 'replace') if schema else ''
            self.list_topic(channel.topic, msgtype, summary.message_counts.get(channel_id, 0),
                            (msgtype, schema.encoding if schema else '', text, channel.message_encoding))
        if summary.message_counts or summary.complete:
            self.widen_span(summary.start_time, summary.end_time)

    @staticmethod
    def _horizons(layouts: list[mcap_file.DataLayout]) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per file: chunk offsets and, for each, the earliest log time from that chunk on (later files too).

        For a file read in file order although its chunks go back in log time
        (one that is damaged or has unchunked messages): a slice can be handed
        out only once no chunk still to come starts before its end, so memory
        grows with how far back chunks go.
        """
        later = np.iinfo(np.int64).max
        horizons: list[tuple[np.ndarray, np.ndarray]] = []
        for layout in reversed(layouts):
            times = layout.times
            suffix = np.minimum.accumulate(times[::-1])[::-1] if times.size else times
            suffix = np.append(np.minimum(suffix, later), later)
            horizons.append((layout.offsets, suffix))
            later = int(suffix[0])
        return horizons[::-1]

    def _groups(self, chunk: mcap_file.RawChunk, channels: dict[int, mcap_file.Channel],
                topics: list[str]) -> dict[str, mcap_file.MessageGroup]:
        groups = {}
        for channel_id, group in chunk.groups.items():
            channel = channels.get(channel_id)
            if channel is not None and channel.topic in topics:
                groups[channel.topic] = group
        return groups

    def _sink(self, mcap: mcap_file.McapFile, on_problem: ProblemSink) -> ProblemSink:
        return lambda line: on_problem(self._about(mcap, line))

    def _summary_of(self, index: int) -> mcap_file.Summary:
        """A summary to fill while reading file ``index``, knowing the channels its listing found."""
        summary = mcap_file.Summary()
        summary.channels.update(self.listings[index].channels)
        return summary

    def raw_chunks(self, topics: list[str], on_problem: ProblemSink) -> Iterator[_RawChunk]:
        """The files' chunks in log time order of their start: in file order, or by seeking when they go back."""
        layouts = [mcap_file.data_layout(mcap.path, mcap.size) for mcap in self.files]
        times = np.concatenate([layout.times for layout in layouts] + [np.zeros(0, np.int64)])
        read = [mcap_file.ReadCheck(listing, mcap.summary_problem) for listing, mcap in zip(self.listings, self.files)]
        for mcap, layout in zip(self.files, layouts):
            if mcap.chunk_index and (problem := mcap.index_problem(layout)):
                on_problem(self._about(mcap, problem))
        if times.size and np.any(times[1:] < times[:-1]) and all(
                layout.complete and layout.only_chunks for layout in layouts):
            chunks = self._chunks_by_start_time(layouts, times, topics, on_problem, read)
        else:
            chunks = self._chunks_in_file_order(layouts, times, topics, on_problem, read)
        return self._checked_counts(chunks, read, on_problem)

    def _checked_counts(self, chunks: Iterator[_RawChunk], checks: list[mcap_file.ReadCheck],
                        on_problem: ProblemSink) -> Iterator[_RawChunk]:
        """``chunks``, then what each file's :class:`~.mcap_file.ReadCheck` found wrong, one line each."""
        yield from chunks
        for mcap, check in zip(self.files, checks):
            for line in check.lines():
                on_problem(self._about(mcap, line))

    def _chunks_by_start_time(self, layouts: list[mcap_file.DataLayout], times: np.ndarray, topics: list[str],
                              on_problem: ProblemSink, read: list[mcap_file.ReadCheck]) -> Iterator[_RawChunk]:
        """Chunks that go back in time (reversed, shuffled, topic after topic), read by seeking.

        Sorted by their start times across all files, as the reference readers
        read them: each slice is complete once a chunk starting after its end
        is reached, so memory stays at about one chunk and one slice.  ``times``:
        every file's chunk start times, one after the other (ns).
        """
        offsets = np.concatenate([layout.offsets for layout in layouts])
        files = np.concatenate([np.full(layout.times.size, index) for index, layout in enumerate(layouts)])
        order = np.lexsort((offsets, files, times))
        summaries = [self._summary_of(index) for index in range(len(self.files))]
        # runs of consecutive chunks from one file, each read with one open file
        breaks = np.flatnonzero(np.diff(files[order])) + 1
        first, span = int(times[order[0]]), max(int(times[order[-1]]) - int(times[order[0]]), 1)
        for run in np.split(order, breaks):
            index = int(files[run[0]])
            mcap, summary = self.files[index], summaries[index]
            for chunk in mcap.chunks_at(offsets[run], self._sink(mcap, on_problem), summary):
                read[index].add(chunk, summary.channels)
                yield _RawChunk(chunk.start_time, chunk.buffer, self._groups(chunk, summary.channels, topics),
                                (chunk.start_time - first) / span)

    def _chunks_in_file_order(self, layouts: list[mcap_file.DataLayout], times: np.ndarray, topics: list[str],
                              on_problem: ProblemSink, read: list[mcap_file.ReadCheck]) -> Iterator[_RawChunk]:
        back = float(np.max(np.maximum.accumulate(times) - times)) * 1e-9 if times.size else 0.0
        if back > HELD_BACK_SECONDS:
            on_problem(f'chunks go back in log time by up to {back:.0f} s and cannot be read by seeking (damaged, '
                       'or messages outside chunks): up to that much of the recording was held in memory')
        total = sum(f.size for f in self.files) or 1
        done = 0
        for index, (mcap, (offsets, suffix)) in enumerate(zip(self.files, self._horizons(layouts))):
            summary = self._summary_of(index)
            for chunk in mcap.chunks(self._sink(mcap, on_problem), summary):
                read[index].add(chunk, summary.channels)
                # nothing from this chunk on is earlier than the horizon
                horizon = int(suffix[np.searchsorted(offsets, chunk.file_offset, 'left')])
                yield _RawChunk(min(chunk.start_time, horizon), chunk.buffer,
                                self._groups(chunk, summary.channels, topics), (done + chunk.file_offset) / total)
            done += mcap.size


def _pack(messages: list[tuple[str, int, bytes]], progress: float) -> _RawChunk:
    """``(topic, log_time, bytes)`` in log time order -> one pseudo-chunk."""
    sizes = np.fromiter((len(m[2]) for m in messages), np.int64, len(messages))
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    log_times = np.fromiter((m[1] for m in messages), np.int64, len(messages))
    topics = np.array([m[0] for m in messages])
    buffer = np.frombuffer(b''.join(m[2] for m in messages), np.uint8)
    groups = {}
    for topic in np.unique(topics):
        mask = topics == topic
        groups[str(topic)] = mcap_file.MessageGroup(starts[mask], sizes[mask], log_times[mask])
    return _RawChunk(int(log_times[0]), buffer, groups, progress)


def _pseudo_chunks(messages: Iterable[tuple[str, int, bytes]], start: int, end: int) -> Iterator[_RawChunk]:
    """Gather a time-ordered stream of ``(topic, log_time, bytes)`` into chunks of about 1 MiB."""
    pending, size = [], 0
    for message in messages:
        pending.append(message)
        size += len(message[2])
        if size >= _ROSBAGS_CHUNK_BYTES:
            yield _pack(pending, (message[1] - start) / max(end - start, 1))
            pending, size = [], 0
    if pending:
        yield _pack(pending, 1.0)


class _SqliteSource(_Source):
    """The ``.db3`` files of a sqlite3 rosbag2 bag, read with Python's sqlite3 module.

    ``compression``: ``''``, ``'message'`` (every message a zstd frame) or
    ``'file'`` (every ``.db3.zstd`` file decompressed into a temporary folder
    that lives as long as this source, at most 64 times its size or 1 GiB,
    whichever is larger).
    """

    #: messages per topic as metadata.yaml lists them (a bag folder's: set by :func:`_with_metadata_counts`)
    metadata_counts: dict[str, int]

    def __init__(self, label: str, paths: list[Path], compression: str = '') -> None:
        super().__init__(label)
        self.files: list[sqlite_file.SqliteFile] = []
        self._scratch = tempfile.TemporaryDirectory(prefix='prsm_lube_bag_') if compression == 'file' else None
        for path in paths:
            try:
                if self._scratch is not None:
                    plain = Path(self._scratch.name) / path.name.removesuffix('.zstd')
                    mcap_file.zstd_file(path, plain, max(64 * path.stat().st_size, 1 << 30))
                db = sqlite_file.SqliteFile(plain if self._scratch is not None else path,
                                            compressed_messages=compression == 'message')
            except (sqlite_file.SqliteProblem, mcap_file.McapProblem) as problem:
                raise RecordingError(f'{path}: {problem}') from None
            except OSError as err:
                raise RecordingError(f'{path}: cannot be read ({err.strerror or err})') from None
            self.files.append(db)
            for topic in db.topics.values():
                self.widen_span(topic.start_time, topic.end_time)
                encoding, text = db.definitions.get(topic.msgtype, ('', ''))
                self.list_topic(topic.name, topic.msgtype, topic.message_count,
                                (topic.msgtype, encoding, text, topic.serialization_format))

    def raw_chunks(self, topics: list[str], on_problem: ProblemSink) -> Iterator[_RawChunk]:
        wanted = set(topics)

        def messages() -> Iterator[tuple[str, int, bytes]]:
            for db in self.files:      # split bags: one file after the other, as rosbag2 plays them
                names = {key: topic.name for key, topic in db.topics.items() if topic.name in wanted}
                for topic_id, log_time, data in db.messages(list(names), on_problem):
                    yield names[topic_id], log_time, data
        return _pseudo_chunks(messages(), self.start_time or 0, self.end_time or 0)


class _RosbagsSource(_Source):
    """A rosbag2 directory read through rosbags' Reader (sqlite3, compressed bags, reference path)."""

    def __init__(self, path: Path) -> None:
        from rosbags.rosbag2 import Reader
        from rosbags.interfaces import MessageDefinitionFormat
        super().__init__(str(path))
        self.path = path
        try:
            with Reader(path) as reader:
                encodings = {MessageDefinitionFormat.MSG: 'ros2msg', MessageDefinitionFormat.IDL: 'ros2idl'}
                for connection in reader.connections:      # rosbags' Reader gives CDR messages
                    self.list_topic(connection.topic, connection.msgtype, connection.msgcount,
                                    (connection.msgtype, encodings.get(connection.msgdef.format, ''),
                                     connection.msgdef.data or '', 'cdr'))
                count = reader.message_count
                self.start_time = reader.start_time if count else None
                self.end_time = reader.end_time - 1 if count else None
        except Exception as err:  # rosbags/sqlite3/yaml raise assorted types on damaged bags
            raise RecordingError(f'{path}: not a readable rosbag2 bag ({exception_text(err)})') from None

    def raw_chunks(self, topics: list[str], on_problem: ProblemSink) -> Iterator[_RawChunk]:
        from rosbags.rosbag2 import Reader
        streamed = dict.fromkeys(topics, 0)

        def counted(messages: Iterable[tuple[str, int, bytes]]) -> Iterator[tuple[str, int, bytes]]:
            for topic, log_time, data in messages:
                streamed[topic] += 1
                yield topic, log_time, data
        try:
            with Reader(self.path) as reader:
                connections = [c for c in reader.connections if c.topic in topics]
                messages = ((c.topic, t, data) for c, t, data in reader.messages(connections=connections))
                yield from _pseudo_chunks(counted(messages), self.start_time or 0, self.end_time or 0)
        except Exception as err:  # keep what was read, report the rest in one line
            on_problem(f'reading stopped early: {exception_text(err)}')
            return
        for topic, count in streamed.items():   # rosbags matches metadata.yaml to the storage by QoS too
            if count < self.topics[topic].message_count:
                on_problem(f'{topic}: {self.topics[topic].message_count} message(s) listed, {count} streamed '
                           "(rosbags' Reader could not match the rest to metadata.yaml)")


def _mcap_library_chunks(path: Path, topics: list[str], on_problem: ProblemSink) -> Iterator[_RawChunk]:
    """Reference reading of a bare ``.mcap`` file with the ``mcap`` package."""
    from mcap.reader import make_reader
    try:
        with open(path, 'rb') as stream:
            reader = make_reader(stream)
            messages = ((channel.topic, message.log_time, message.data)
                        for _, channel, message in reader.iter_messages(topics=topics, log_time_order=True))
            yield from _pseudo_chunks(messages, 0, 0)
    except Exception as err:
        on_problem(f'reading stopped early: {exception_text(err)}')


def _split_index(path: Path) -> tuple[str, int]:
    """Sort key of the files of a split bag: ``name_2`` before ``name_10``."""
    stem, _, number = path.stem.rpartition('_')
    return (stem, int(number)) if stem and number.isdigit() else (path.stem, -1)


def _storage_file(path: Path, root: Path) -> Path:
    """A storage file of a bag folder, checked before anything opens it: inside ``root``, a regular file, bounded.

    ``sqlite3`` and rosbags open storage by name: a FIFO there would block the
    reader for good, a link out of ``root`` would read what was not offered.
    """
    check_regular(path, 'storage file', max_bytes=MAX_RECORDING_BYTES, root=root, error=RecordingError)
    return path


def _source_without_metadata(path: Path, root: Path) -> _Source:
    """A bag folder without metadata.yaml (what ``ros2 bag reindex`` repairs): its files in split order.

    Taken when it holds one storage file, or only the files of one split bag
    (``<folder>_0``, ``<folder>_1``...); a folder of unrelated recordings is refused.
    """
    for suffix, source in (('.mcap', _McapSource), ('.db3', _SqliteSource)):
        files = sorted(path.glob('*' + suffix), key=_split_index)
        if len(files) == 1 or (files and all(_split_index(f)[0] == path.name for f in files)):
            return source(str(path), [_storage_file(f, root) for f in files])
        if files:
            names = ', '.join(f.name for f in files)
            raise RecordingError(f'{path}: no metadata.yaml, and its {suffix} files ({names}) are not the parts '
                                 'of one split bag; give one file')
    raise RecordingError(f'{path}: not a rosbag2 directory (no metadata.yaml, no .mcap or .db3 file)')


def _open_source(path: Path, root: str | Path | None = None) -> _Source:
    """The source for a bare ``.mcap``/``.db3`` file or a rosbag2 directory; InputError if neither.

    Every file opened (the path itself, ``metadata.yaml``, the storage files a
    folder holds or its metadata lists) must resolve inside ``root`` (default:
    the path itself, so a bag folder's files may not link out of it) and be a
    regular file within :mod:`..input_file`'s bounds.
    """
    if not path.exists():
        raise RecordingError(f'{path}: no such file or directory')
    if path.is_dir():
        inside = confine(path, root, 'recording', RecordingError)
        return _bag_folder(path, inside if root is None else Path(root))
    if path.name == 'metadata.yaml':
        return _open_source(path.parent, root)
    with open_regular(path, 'recording', max_bytes=MAX_RECORDING_BYTES, root=root, error=RecordingError) as stream:
        magic = stream.read(len(SQLITE_MAGIC))
    if magic.startswith(mcap_file.MAGIC):
        return _McapSource(str(path), [path])
    if magic == SQLITE_MAGIC:    # one storage file of a sqlite3 bag, read as rosbag2 reads a bare .db3
        return _SqliteSource(str(path), [path])
    raise RecordingError(f'{path}: not a recording (neither an MCAP or sqlite3 file nor a rosbag2 directory)')


def _bag_folder(path: Path, root: Path) -> _Source:
    """The source of a rosbag2 folder whose files must lie inside ``root``."""
    metadata_path = path / 'metadata.yaml'
    if not metadata_path.exists() and not metadata_path.is_symlink():
        return _source_without_metadata(path, root)
    text = read_text(metadata_path, 'rosbag2 metadata', max_bytes=MAX_METADATA_BYTES, root=root,
                     error=RecordingError)
    try:
        info = yaml.load(text, Loader=_YAML_LOADER)['rosbag2_bagfile_information']
        storage = info['storage_identifier']
        files = [path / Path(name).name for name in info['relative_file_paths']]
        compression = (info.get('compression_mode') or '').lower()
        compression_format = (info.get('compression_format') or '').lower()
    except Exception as err:   # what the file holds is not repeated: it may be anything a link led to
        raise RecordingError(f'{metadata_path}: not rosbag2 metadata ({type(err).__name__})') from None
    if len(files) > MAX_STORAGE_FILES or len(set(files)) != len(files):
        raise RecordingError(f'{metadata_path}: lists {len(files)} storage files ({len(set(files))} different; at most '
                             f'{MAX_STORAGE_FILES}, each once)')
    if missing := [str(f) for f in files if not f.exists()]:
        raise RecordingError(f'{path}: storage file(s) listed in metadata.yaml missing: {", ".join(missing[:5])}'
                             + (f' and {len(missing) - 5} more' if len(missing) > 5 else ''))
    files = [_storage_file(f, root) for f in files]
    if compression in ('', 'none'):
        if storage == 'mcap':
            return _McapSource(str(path), files)
        if storage == 'sqlite3':
            return _with_metadata_counts(_SqliteSource(str(path), files), info)
    if storage == 'sqlite3' and compression in ('message', 'file') and compression_format == 'zstd':
        return _with_metadata_counts(_SqliteSource(str(path), files, compression), info)
    if storage not in ('mcap', 'sqlite3'):
        raise RecordingError(f'{path}: storage {str(storage)[:40]!r} is not supported (mcap or sqlite3)')
    return _RosbagsSource(path)


def _with_metadata_counts(source: _SqliteSource, info: dict[str, Any]) -> _SqliteSource:
    """``source`` with ``metadata_counts``: messages per topic as metadata.yaml lists them (unreadable: none)."""
    counts = {}
    try:
        for entry in info.get('topics_with_message_count') or ():
            counts[str(entry['topic_metadata']['name'])] = int(entry['message_count'])
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError):
        counts = {}
    source.metadata_counts = counts
    return source


# -- slicing -----------------------------------------------------------------------------------------

def _merge(parts: list[Decoded], kind: str) -> Decoded:
    """Parts of one topic -> one, ordered by log time (stable)."""
    if len(parts) == 1:
        merged = parts[0]
    else:
        columns = {name: np.concatenate([p.columns[name] for p in parts]) for name in parts[0].columns}
        merged = Decoded(np.concatenate([p.log_times for p in parts]), columns)
        if kind == VIBRATION:
            ragged = cast(list[Any], parts)   # vibration parts carry their samples and offsets
            merged.samples = np.concatenate([p.samples[p.offsets[0]:p.offsets[-1]] for p in ragged])
            counts = np.concatenate([np.diff(p.offsets) for p in ragged])
            merged.offsets = np.concatenate([[0], np.cumsum(counts, dtype=np.int64)])
    log_times = merged.log_times
    if log_times.size > 1 and (log_times[1:] < log_times[:-1]).any():
        order = np.argsort(log_times, kind='stable')
        merged = Decoded(log_times[order], {k: v[order] for k, v in merged.columns.items()},
                         merged.offsets, merged.samples)
        if kind == VIBRATION:
            assert merged.samples is not None and merged.offsets is not None  # vibration data carry them
            merged.samples, merged.offsets = ragged_take(merged.samples, merged.offsets - merged.offsets[0],
                                                         order)
    return merged


def _cut(decoded: Decoded, count: int) -> tuple[Decoded, Decoded]:
    """The first ``count`` messages and the rest, as views (vibration offsets stay absolute)."""
    head = Decoded(decoded.log_times[:count], {k: v[:count] for k, v in decoded.columns.items()})
    rest = Decoded(decoded.log_times[count:], {k: v[count:] for k, v in decoded.columns.items()})
    if decoded.offsets is not None:
        head.offsets, head.samples = decoded.offsets[:count + 1], decoded.samples
        rest.offsets, rest.samples = decoded.offsets[count:], decoded.samples
    return head, rest


def _batch(kind: str, pieces: list[Decoded]) -> InputBatch:
    """Pieces of one topic in log time order -> one batch."""
    decoded = pieces[0] if len(pieces) == 1 else _merge(pieces, kind)
    columns = decoded.columns
    if kind == VIBRATION:
        offsets = decoded.offsets
        assert offsets is not None and decoded.samples is not None  # vibration data carry them
        return VibrationBatch(columns['stamps'], columns['sample_rates'], offsets - offsets[0],
                              decoded.samples[offsets[0]:offsets[-1]])
    if kind == JOINT_STATES:
        return ScrewStateBatch(columns['stamps'], columns['angles'], columns['speeds'])
    if kind == AXIAL_LOAD:
        return AxialLoadBatch(columns['stamps'], columns['forces'])
    return TemperatureBatch(columns['stamps'], columns['temperatures'])


class _Slicer:
    """Holds decoded data until a whole time slice is complete, then hands it out."""

    def __init__(self, kinds: list[str], slice_ns: int) -> None:
        self.kinds = kinds
        self.slice_ns = slice_ns
        self.origin: int | None = None
        self.pending: dict[str, list[Decoded]] = {kind: [] for kind in kinds}
        #: end of the last slice handed out, ns; messages before it can no longer be placed
        self.handed_out: int | None = None
        #: messages left out because they came after their slice was handed out, by kind
        self.too_late: dict[str, int] = dict.fromkeys(kinds, 0)

    def add(self, kind: str, decoded: Decoded) -> None:
        """Queue decoded messages; parts are kept in log time order."""
        log_times = decoded.log_times
        if not log_times.size:
            return
        if log_times.size > 1 and (log_times[1:] < log_times[:-1]).any():
            decoded = _merge([decoded], kind)
        if self.handed_out is not None and decoded.log_times[0] < self.handed_out:
            late = int(np.searchsorted(decoded.log_times, self.handed_out, 'left'))
            self.too_late[kind] += late
            decoded = _cut(decoded, late)[1]
            if not decoded.log_times.size:
                return
        parts = self.pending[kind]
        if parts and decoded.log_times[0] < parts[-1].log_times[-1]:
            parts[:] = [_merge(parts + [decoded], kind)]     # overlapping chunks: rare
        else:
            parts.append(decoded)

    def flush(self, safe: int | None) -> Iterator[list[InputBatch]]:
        """Slices that end at or before log time ``safe`` (all when None)."""
        pending = self.pending
        while True:
            heads = [int(parts[0].log_times[0]) for parts in pending.values() if parts]
            if not heads:
                return
            earliest = min(heads)
            if self.origin is None:
                if safe is not None and safe < earliest:
                    return      # a message still to come may start the grid earlier
                self.origin = earliest
            end = self.origin + ((earliest - self.origin) // self.slice_ns + 1) * self.slice_ns
            if safe is not None and end > safe:
                return
            batches = []
            for kind in self.kinds:
                parts = pending[kind]
                pieces = []
                while parts and parts[0].log_times[0] < end:
                    count = int(np.searchsorted(parts[0].log_times, end, 'left'))
                    if count == parts[0].log_times.size:
                        pieces.append(parts.pop(0))
                    else:
                        head, parts[0] = _cut(parts[0], count)
                        pieces.append(head)
                        break
                if pieces:
                    batches.append(_batch(kind, pieces))
            self.handed_out = end
            yield batches


@dataclass
class _Tally:
    """What decoding a recording's topics counted, per kind, for the problem lines after the data."""

    undecodable: dict[str, int]             # messages that did not decode
    stamp_spikes: dict[str, SpikeCount]     # header stamps jumping away and back
    rate_spikes: SpikeCount                 # vibration sample rates jumping away and back
    streamed: dict[str, int]                # messages read
    without_screw: int = 0                  # JointState messages without a screw entry

    @classmethod
    def of(cls, kinds: list[str]) -> _Tally:
        """Nothing counted yet for ``kinds``."""
        return cls(dict.fromkeys(kinds, 0), {kind: SpikeCount(STAMP_SPIKE_SECONDS) for kind in kinds},
                   SpikeCount(RATE_SPIKE_FRACTION, relative=True), dict.fromkeys(kinds, 0))

    def add(self, kind: str, decoded: Decoded, group: mcap_file.MessageGroup) -> None:
        """Count the messages of one topic from one chunk (``group``) as decoded."""
        self.undecodable[kind] += decoded.undecodable
        self.without_screw += decoded.without_screw
        self.streamed[kind] += int(group.data_offsets.size)
        self.stamp_spikes[kind].add(decoded.columns['stamps'])
        if kind == VIBRATION:
            self.rate_spikes.add(decoded.columns['sample_rates'])


# -- the recording -----------------------------------------------------------------------------------

class Recording:
    """An opened recording: what it holds, and its contract topics as a stream of batches."""

    def __init__(self, path: str | Path, namespace: str = DEFAULT_NAMESPACE, root: str | Path | None = None) -> None:
        self.path = Path(path)
        self.namespace = namespace
        self._source = _open_source(self.path, root)
        #: every topic of the recording, by name
        self.topics: dict[str, TopicInfo] = self._source.topics
        #: problems noticed while opening (e.g. a missing summary section), one line each
        self.problems: list[str] = list(self._source.problems)
        for topic in self.topics.values():
            kind = self._kind_of(topic.name)
            if kind is not None:
                topic.layout_problem = self._source.layout_problem(topic.name, kind)
        #: namespaces with a vibration topic of the VibrationBlock layout
        self.actuators: list[str] = sorted(
            cast(str, namespace_of(t.name)) for t in self.topics.values()
            if namespace_of(t.name) is not None and t.layout_problem is None)
        #: contract topic of this namespace by kind (vibration, joint_states, axial_load, temperature)
        self.selected: dict[str, str] = {kind: topic_name(namespace, kind) for kind in KINDS
                                         if topic_name(namespace, kind) in self.topics}
        self._validate()

    @staticmethod
    def _kind_of(topic: str) -> str | None:
        for kind in KINDS:
            if topic.endswith(('/' + kind, '_' + kind)):
                return kind
        return None

    def _validate(self) -> None:
        label = self._source.label
        if not self.topics:
            raise RecordingError(f'{label}: holds no topics' + self._problem_hint())
        vibration = topic_name(self.namespace, VIBRATION)
        if VIBRATION not in self.selected:
            others = ', '.join(f'{t.name} ({t.msgtype})' for t in self.topics.values())
            hint = (f'; actuators found: {", ".join(self.actuators)} (choose one as namespace)'
                    if self.actuators else '')
            raise RecordingError(f'{label}: no {vibration} topic; it has {others}{hint}' + self._problem_hint())
        for kind, topic in self.selected.items():
            problem = self.topics[topic].layout_problem
            if problem:
                raise RecordingError(f'{label}: topic {topic} {problem}')
        if self.topics[vibration].message_count == 0:
            raise RecordingError(f'{label}: no messages on {vibration}' + self._problem_hint())

    def _problem_hint(self) -> str:
        return f' ({self.problems[-1]})' if self.problems else ''

    @property
    def start_time(self) -> float | None:
        """Log time of the first message, s since the epoch (None if empty)."""
        return None if self._source.start_time is None else self._source.start_time * 1e-9

    @property
    def end_time(self) -> float | None:
        """Log time of the last message, s since the epoch (None if empty)."""
        return None if self._source.end_time is None else self._source.end_time * 1e-9

    def describe(self) -> str:
        """What the recording holds, a few lines of text."""
        lines = [f'{self._source.label}: {len(self.topics)} topics']
        if self.start_time is not None:
            lines[0] += f', {cast(float, self.end_time) - self.start_time:.1f} s from {self.start_time:.3f}'
        for topic in sorted(self.topics.values(), key=lambda t: t.name):
            mark = ' <- ' + next(k for k, v in self.selected.items() if v == topic.name) \
                if topic.name in self.selected.values() else ''
            lines.append(f'  {topic.name}: {topic.msgtype}, {topic.message_count} messages{mark}')
        if self.actuators:
            lines.append('  actuators: ' + ', '.join(self.actuators))
        lines.extend('  problem: ' + line for line in self.problems)
        return '\n'.join(lines)

    def slices(self, on_problem: ProblemSink | None = None, progress: Callable[[float], None] | None = None,
               slice_seconds: float = DEFAULT_SLICE_SECONDS, engine: str = 'fast') -> Iterator[list[InputBatch]]:
        """The namespace's topics as lists of batches, one list per time slice, in log time order.

        ``on_problem`` gets each problem once, as one line, after all data has
        been yielded (default: appended to :attr:`problems`); ``progress`` gets
        the fraction of the recording read.  ``engine='rosbags'`` is the slow
        reference path (rosbags deserializer for every message).
        """
        if engine not in ('fast', 'rosbags'):
            raise ValueError(f'engine must be fast or rosbags, not {engine!r}')
        if not slice_seconds > 0 or not math.isfinite(slice_seconds):
            raise ConfigError(f'slice_seconds: must be a positive number of seconds, not {slice_seconds}')

        def remember(line: str) -> None:
            if line not in self.problems:
                self.problems.append(line)

        sink = on_problem or remember
        problems: list[str] = []
        kinds = [kind for kind in KINDS if kind in self.selected]
        by_topic = {topic: kind for kind, topic in self.selected.items()}
        slicer = _Slicer(kinds, int(round(slice_seconds * 1e9)))
        tally = _Tally.of(kinds)
        vectorised = engine == 'fast'
        for chunk in self._raw_chunks(list(by_topic), problems.append, engine):
            yield from slicer.flush(chunk.start_time)
            for topic, group in chunk.groups.items():
                kind = by_topic[topic]
                decoded = decode_messages(kind, chunk.buffer, group.data_offsets, group.data_lengths,
                                          group.log_times, vectorised)
                tally.add(kind, decoded, group)
                slicer.add(kind, decoded)
            if progress is not None:
                progress(min(max(chunk.progress, 0.0), 1.0))
        yield from slicer.flush(None)
        if progress is not None:
            progress(1.0)
        problems.extend(self._stream_lines(slicer.too_late, tally))
        for line in problems:
            sink(line)

    def _stream_lines(self, too_late: dict[str, int], tally: _Tally) -> list[str]:
        """Problem lines for what streaming left out or found damaged, once all data is yielded.

        ``too_late``: per kind, messages that came after their time slice was
        handed out; ``tally``: what decoding counted.
        """
        problems = []
        for kind, count in too_late.items():
            if count:
                problems.append(f'{self.selected[kind]}: {count} message(s) found after their time slice was '
                                'handed out (a chunk states a later start time than its messages) left out')
        for kind, count in tally.undecodable.items():
            if count:
                problems.append(f'{self.selected[kind]}: {count} message(s) could not be decoded and were '
                                'skipped')
        if tally.without_screw:
            problems.append(f'{self.selected[JOINT_STATES]}: {tally.without_screw} JointState message(s) without '
                            f'a "screw" entry skipped')
        problems.extend(self._damage_lines({kind: count.finish() for kind, count in tally.stamp_spikes.items()},
                                           tally.rate_spikes.finish(), tally.streamed))
        return problems

    def _damage_lines(self, spikes: dict[str, int], rate_spikes: int, streamed: dict[str, int]) -> list[str]:
        """Lines for damage the container does not show: stamp and rate spikes, messages metadata.yaml lists unread.

        A sqlite3 row whose topic id changed leaves its topic without a trace
        but for the metadata's count (MCAP files check their own summary).
        """
        lines = [f'{self.selected[kind]}: {count} message(s) with a header stamp that jumps more than '
                 f'{STAMP_SPIKE_SECONDS:g} s away from both neighbours and back (corrupt stamp?)'
                 for kind, count in spikes.items() if count]
        if rate_spikes:
            lines.append(f'{self.selected[VIBRATION]}: {rate_spikes} block(s) whose sample_rate differs by more than '
                         f'{100 * RATE_SPIKE_FRACTION:g}% from both neighbours\' (corrupt header?)')
        listed = getattr(self._source, 'metadata_counts', None) or {}
        for kind, count in streamed.items():
            topic = self.selected[kind]
            if count < listed.get(topic, 0):
                lines.append(f'{topic}: metadata.yaml lists {listed[topic]} message(s), {count} read '
                             '(damaged storage: the rest are lost)')
        return lines

    def _raw_chunks(self, topics: list[str], on_problem: ProblemSink, engine: str) -> Iterator[_RawChunk]:
        source = self._source
        if engine == 'rosbags':
            if isinstance(source, _McapSource) and self.path.is_file():
                return _mcap_library_chunks(self.path, topics, on_problem)
            if not isinstance(source, _RosbagsSource):
                source = _RosbagsSource(self.path if self.path.is_dir() else self.path.parent)
        return source.raw_chunks(topics, on_problem)


def open_recording(path: str | Path, namespace: str = DEFAULT_NAMESPACE, root: str | Path | None = None) -> Recording:
    """Open a rosbag2 directory or bare ``.mcap`` file for the actuator at ``namespace``.

    Every file it opens must resolve inside ``root`` (default: a bag folder's
    files inside that folder).  Raises :class:`InputError` (one line naming
    the file) when it cannot be used.
    """
    return Recording(path, namespace, root)


def find_actuators(path: str | Path) -> list[str]:
    """Namespaces (or prefixes) of a recording that carry a vibration topic of the VibrationBlock layout."""
    source = _open_source(Path(path))
    actuators = []
    for topic in source.topics:
        namespace = namespace_of(topic)
        if namespace is not None and source.layout_problem(topic, VIBRATION) is None:
            actuators.append(namespace)
    return sorted(actuators)


def iter_batches(path: str | Path, namespace: str = DEFAULT_NAMESPACE, on_problem: ProblemSink | None = None,
                 slice_seconds: float = DEFAULT_SLICE_SECONDS) -> Iterator[list[InputBatch]]:
    """Shorthand: ``open_recording(path, namespace).slices(on_problem, slice_seconds=...)``."""
    return open_recording(path, namespace).slices(on_problem, slice_seconds=slice_seconds)


def bare_read(path: str | Path) -> int:
    """Read, decompress and split every message of a recording without decoding; return the message count.

    The cheapest full pass over the data: the baseline the decoding is timed against.
    """
    source = _open_source(Path(path))
    count = 0
    for chunk in source.raw_chunks(list(source.topics), lambda line: None):
        count += sum(group.data_offsets.size for group in chunk.groups.values())
    return count


def topic_messages(path: str | Path, on_problem: ProblemSink | None = None) -> Iterator[tuple[str, int, bytes]]:
    """Every message of any recording as ``(topic, log_time, data)``, undecoded; per topic in reading order.

    Raises :class:`InputError` (one line naming the file) when it cannot be opened.
    """
    source = _open_source(Path(path))
    for chunk in source.raw_chunks(list(source.topics), on_problem or (lambda line: None)):
        buffer = chunk.buffer
        for topic, group in chunk.groups.items():
            for start, length, log_time in zip(group.data_offsets.tolist(), group.data_lengths.tolist(),
                                               group.log_times.tolist()):
                yield topic, log_time, bytes(buffer[start:start + length])


def list_topics(path: str | Path) -> dict[str, TopicInfo]:
    """Every topic of a recording with its type and message count, by name; InputError if it is unusable."""
    return _open_source(Path(path)).topics


def raw_messages(path: str | Path,
                 on_problem: ProblemSink | None = None) -> Iterator[tuple[str | None, int, int, bytes]]:
    """Every message of a bare ``.mcap`` file in file order: ``(topic, sequence, log_time, data)``, undecoded.

    ``topic`` is None for a message on a channel defined nowhere in the file.
    Raises :class:`InputError` (one line naming the file) when it cannot be read at all.
    """
    path = Path(path)
    try:
        for channel, sequence, log_time, data in mcap_file.channel_messages(path, on_problem or (lambda line: None)):
            yield (channel.topic if channel else None), sequence, log_time, data
    except mcap_file.McapProblem as problem:
        raise RecordingError(f'{path}: {problem}') from None
    except OSError as err:
        raise RecordingError(f'{path}: cannot be read ({err.strerror or err})') from None
