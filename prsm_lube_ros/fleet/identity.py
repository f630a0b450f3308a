# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""One actuator id, one piece of hardware: where an id comes from, and why two actuators never share one.

Where the id comes from (:func:`name_actuators`, before anything is
assessed): ``--actuator-id ID`` (the user's word), ``--actuator-map FILE``
(lines ``PATH,ID``: each recording belongs to the entry that is its real
path or its nearest enclosing folder), the recording itself (``custom_data``
``actuator_id``, as ``ros2 bag record --custom-data actuator_id=A05`` writes
it: in a bag folder's ``metadata.yaml``, and in a bare ``.mcap`` file's
``rosbag2`` metadata record), or the folder holding it: the
name of its real folder (symlinks resolved, so a link never changes the id),
with the folder's whole real path kept as the id's ``source``.  By default
the recording's own id is used, else the folder's; the default is refused
when the recordings lie in several folders (a multi-actuator call: one line
saying how to name them).  An id a folder gave belongs to that folder: two
recordings of folders with one name but different paths (``s1/A01`` and
``s2/A01``) are refused in one line naming both, in one call and across calls
(the history keeps each file's source, :func:`folder_clash`).  A recording
that says it is actuator X while the option or map says Y is refused too.

Recordings of one actuator cannot overlap in time.

An actuator records one thing at a time, so two recordings filed under one
actuator id whose spans (first run start to last run end) overlap must come
from two actuators: the id merges distinct hardware, and its trend would
invent relubrications.  The same content again (a re-assessment) is no
clash, nor is the same span to within :data:`SAME_RECORDING` (one recording
stored twice, as MCAP and as sqlite3).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import datetime
from pathlib import Path
from typing import TYPE_CHECKING
from collections.abc import Callable, Iterable, Sequence

from ..errors import InputError

if TYPE_CHECKING:
    import pyarrow as pa

    from ..estimation.pipeline import RecordingAssessment

__all__ = ['FOLDER', 'GIVEN', 'MAX_MAP_BYTES', 'RECORDED_KEY', 'RECORDING', 'SAME_RECORDING', 'Identity', 'Span',
           'Timeline', 'assessment_span', 'clash_line', 'folder_clash', 'name_actuators', 'read_actuator_map',
           'recorded_actuator', 'table_spans']

#: ``--actuator-id`` values that are no id: the folder's name, the recording's own id
FOLDER, RECORDING = 'folder', 'recording'
#: the ``source`` of an id the user gave (``--actuator-id ID``)
GIVEN = 'given'
#: key of the actuator id in a rosbag2 ``metadata.yaml``'s ``custom_data``
RECORDED_KEY = 'actuator_id'
#: largest ``--actuator-map`` file read (bytes)
MAX_MAP_BYTES = 1 << 20

#: s: spans whose start and end agree to within this are one recording stored twice
SAME_RECORDING = 1.0


@dataclass(frozen=True)
class Span:
    """A recording's time span (s since the epoch), content hash and path."""

    start: float
    end: float
    content: str
    path: str

    def clashes_with(self, other: Span) -> bool:
        """True when ``other`` is another recording whose span overlaps this one."""
        if self.content == other.content:
            return False
        if abs(self.start - other.start) <= SAME_RECORDING and abs(self.end - other.end) <= SAME_RECORDING:
            return False
        return self.start < other.end and other.start < self.end


def assessment_span(assessment: RecordingAssessment, content: str) -> Span | None:
    """The span of an assessed recording's runs, None without runs."""
    runs = assessment.runs
    if not runs:
        return None
    return Span(min(r.start for r in runs), max(r.end for r in runs), content, str(assessment.path))


@dataclass(frozen=True)
class Identity:
    """An actuator id and where it came from: ``folder PATH``, ``recording PATH``, ``map FILE`` or ``given``."""

    actuator: str
    source: str = GIVEN

    @property
    def folder(self) -> str | None:
        """The real folder path that named this id, None when the id came from elsewhere."""
        return self.source[len('folder '):] if self.source.startswith('folder ') else None


def recorded_actuator(bag: str | Path) -> str | None:
    """The actuator id a recording carries in its rosbag2 ``custom_data`` (:data:`RECORDED_KEY`), or None.

    A bag folder's ``metadata.yaml`` (``rosbag2_bagfile_information.custom_data``)
    or, for a bare ``.mcap`` file, the ``rosbag2`` metadata record rosbag2's MCAP
    storage writes (``serialized_metadata``, found through the summary's
    metadata index).  A recording that cannot be read for it says nothing here
    (the assessment reports what is wrong with it).
    """
    import struct
    import yaml
    from ..input_file import MAX_METADATA_BYTES, read_text
    bag = Path(bag)
    try:
        if (bag / 'metadata.yaml').is_file():
            document = yaml.safe_load(read_text(bag / 'metadata.yaml', 'bag metadata', max_bytes=MAX_METADATA_BYTES))
            custom = document['rosbag2_bagfile_information'].get('custom_data') or {}
        elif bag.is_file():
            custom = (yaml.safe_load(_mcap_rosbag2_metadata(bag, MAX_METADATA_BYTES) or '{}') or {}).get(
                'custom_data') or {}
        else:
            return None
        value = custom.get(RECORDED_KEY)
    except (InputError, OSError, yaml.YAMLError, KeyError, TypeError, AttributeError, ValueError, struct.error):
        return None
    return (str(value).strip() or None) if value is not None else None


def _mcap_rosbag2_metadata(path: Path, limit: int) -> str | None:
    """``serialized_metadata`` of the ``rosbag2`` metadata record of an MCAP file (found from its footer), or None.

    MCAP layout: the file ends with the footer record (opcode 0x02: summary
    start u64, ...) and the 8-byte magic; the summary holds MetadataIndex
    records (0x0D: offset u64, length u64, name) pointing at Metadata records
    (0x0C: name, then a map of strings, u32 byte length first).
    """
    import struct
    with open(path, 'rb') as stream:
        size = stream.seek(0, 2)
        if size < 45:
            return None
        stream.seek(size - 37)
        footer = stream.read(37)
        if footer[0] != 0x02 or footer[29:] != b'\x89MCAP0\r\n':
            return None
        summary_start = struct.unpack_from('<Q', footer, 9)[0]
        if not 0 < summary_start <= size - 37 or size - 37 - summary_start > limit:
            return None
        stream.seek(summary_start)
        summary = stream.read(size - 37 - summary_start)
        pos = 0
        while pos + 9 <= len(summary):
            opcode, length = summary[pos], struct.unpack_from('<Q', summary, pos + 1)[0]
            content = summary[pos + 9:pos + 9 + length]
            pos += 9 + length
            if opcode != 0x0D or len(content) < 20:
                continue
            offset, record_length, name_length = struct.unpack_from('<QQI', content)
            if content[20:20 + name_length] != b'rosbag2' or record_length > limit:
                continue
            stream.seek(offset)
            record = stream.read(record_length)
            return _metadata_value(record, 'serialized_metadata')
    return None


def _metadata_value(record: bytes, key: str) -> str | None:
    """The value of ``key`` in an MCAP Metadata record (opcode, length, then name and map)."""
    import struct
    if len(record) < 13 or record[0] != 0x0C:
        return None
    (name_length,) = struct.unpack_from('<I', record, 9)
    pos = 13 + name_length
    (map_length,) = struct.unpack_from('<I', record, pos)
    pos, end = pos + 4, min(pos + 4 + map_length, len(record))
    while pos + 4 <= end:
        (size,) = struct.unpack_from('<I', record, pos)
        found = record[pos + 4:pos + 4 + size].decode('utf-8')
        pos += 4 + size
        (size,) = struct.unpack_from('<I', record, pos)
        value = record[pos + 4:pos + 4 + size].decode('utf-8')
        pos += 4 + size
        if found == key:
            return value
    return None


def read_actuator_map(path: str | Path) -> list[tuple[Path, str]]:
    """``--actuator-map`` lines ``PATH,ID`` (``#`` comments, blank lines): (real path, id), deepest path first.

    A relative PATH is taken from the map file's folder.  One line naming
    ``file:line`` for anything wrong.
    """
    from ..input_file import read_text
    path = Path(path)
    entries: dict[Path, str] = {}
    for number, line in enumerate(read_text(path, 'actuator map', max_bytes=MAX_MAP_BYTES).splitlines(), 1):
        text = line.split('#', 1)[0].strip()
        if not text:
            continue
        where, _, actuator = text.rpartition(',')
        where, actuator = where.strip(), actuator.strip()
        if not where or not actuator:
            raise InputError(f'{path}:{number}: expected "PATH,ACTUATOR_ID", got {line.strip()!r}')
        real = (path.parent / where).resolve()
        if entries.get(real, actuator) != actuator:
            raise InputError(f'{path}:{number}: {where} is actuator {entries[real]!r} on an earlier line and '
                             f'{actuator!r} here')
        entries[real] = actuator
    if not entries:
        raise InputError(f'{path}: no "PATH,ACTUATOR_ID" line in the actuator map')
    return sorted(entries.items(), key=lambda item: len(item[0].parts), reverse=True)


def _folder_identity(bag: str | Path, namespace: str) -> Identity:
    """The id of a recording's real folder: its name (and the namespace, unless the default), its path as source."""
    from ..contract import DEFAULT_NAMESPACE
    folder = Path(bag).resolve().parent
    suffix = '' if namespace == DEFAULT_NAMESPACE else namespace.rstrip('/')
    return Identity(f'{folder.name}{suffix}', f'folder {folder}{suffix}')


def name_actuators(bags: Sequence[str], *, given: str | None = None, actuator_map: str | None = None,
                   namespace: str = '/prsm') -> dict[str, Identity]:
    """Each recording's :class:`Identity` (keyed by the path as given); :class:`InputError` in one line if not sure.

    ``given`` is ``--actuator-id`` (an id, :data:`FOLDER` or :data:`RECORDING`),
    ``actuator_map`` the ``--actuator-map`` file; neither: the recording's own
    id, else its folder's, refused when the recordings without their own id lie
    in more than one folder.
    """
    if given and actuator_map:
        raise InputError('--actuator-id and --actuator-map name the actuators twice: give one of them')
    entries = read_actuator_map(actuator_map) if actuator_map else None
    found: dict[str, Identity] = {}
    for bag in dict.fromkeys(bags):
        recorded = recorded_actuator(bag)
        if entries is not None:
            identity = _mapped(bag, entries, actuator_map or '')
        elif given == RECORDING:
            if recorded is None:
                raise InputError(f'{bag}: --actuator-id recording: the recording names no actuator (no custom_data '
                                 f'{RECORDED_KEY} in its metadata.yaml)')
            identity = Identity(recorded, f'recording {Path(bag).resolve()}')
        elif given and given != FOLDER:
            identity = Identity(given, GIVEN)
        elif recorded is not None and given != FOLDER:
            identity = Identity(recorded, f'recording {Path(bag).resolve()}')
        else:
            identity = _folder_identity(bag, namespace)
        if recorded is not None and recorded != identity.actuator:
            raise InputError(f'{bag}: the recording says it is actuator {recorded!r} (custom_data {RECORDED_KEY}), '
                             f'but {_said_by(identity, actuator_map)} says {identity.actuator!r}')
        found[bag] = identity
    if not given and not actuator_map:
        _refuse_several_folders(found)
    _refuse_shared_names(found)
    return found


def _mapped(bag: str, entries: Iterable[tuple[Path, str]], map_file: str) -> Identity:
    real = Path(bag).resolve()
    for where, actuator in entries:
        if real == where or where in real.parents:
            return Identity(actuator, f'map {Path(map_file).resolve()}')
    raise InputError(f'{bag}: not in --actuator-map {map_file} (no line names it or a folder holding it, real path '
                     f'{real})')


def _said_by(identity: Identity, actuator_map: str | None) -> str:
    if identity.source.startswith('map '):
        return f'--actuator-map {actuator_map}'
    return '--actuator-id' if identity.source == GIVEN else f'its folder {identity.folder}'


def _refuse_several_folders(found: dict[str, Identity]) -> None:
    """The default over recordings of several folders: refused, with how to name them."""
    folders = sorted({identity.folder for identity in found.values() if identity.folder})
    if len(folders) > 1:
        names = ', '.join(folders[:3]) + (', ...' if len(folders) > 3 else '')
        raise InputError(f'--history: the recordings lie in {len(folders)} folders ({names}), so they may be '
                         'several actuators; say which actuator each is: --actuator-id folder (each folder is one '
                         'actuator, named by its folder), --actuator-map FILE (lines "PATH,ID"), --actuator-id ID '
                         f'(all one actuator), or record the id in the bag (custom_data {RECORDED_KEY})')


def _refuse_shared_names(found: dict[str, Identity]) -> None:
    """Two folders of one name (``s1/A01``, ``s2/A01``) would be one actuator: refused, naming a recording of each."""
    first: dict[str, tuple[str, str]] = {}
    for bag, identity in found.items():
        if identity.folder is None:
            continue
        seen = first.setdefault(identity.actuator, (bag, identity.folder))
        if seen[1] != identity.folder:
            raise InputError(f'{bag} and {seen[0]}: both would be actuator {identity.actuator!r}, but they lie in '
                             f'two folders ({identity.folder} and {seen[1]}); name them apart with --actuator-map '
                             'FILE (lines "PATH,ID") or assess each folder with its own --actuator-id ID')


def folder_clash(identity: Identity, stored: Iterable[tuple[str, str]]) -> str | None:
    """Why ``identity`` may not join the history's recordings of its id, or None.

    ``stored`` holds (recording path, source) of the recordings already filed
    under the id.  An id named by a folder joins only recordings named by that
    same folder: a folder of the same name elsewhere is another actuator.
    """
    if identity.folder is None:
        return None
    for path, source in stored:
        if source != identity.source:
            where = source.removeprefix('folder ') if source.startswith('folder ') else f'({source or "no source"})'
            return (f'actuator {identity.actuator!r} of folder {identity.folder} is already in the history from '
                    f'{where} (recording {path}), another actuator with the same name; name them apart with '
                    '--actuator-map FILE (lines "PATH,ID") or --actuator-id ID')
    return None


def table_spans(runs: pa.Table) -> list[Span]:
    """One span per content hash of a history ``runs`` table."""
    found: dict[str, tuple] = {}
    for content, path, start, end in zip(*(runs.column(name).to_pylist() for name in
                                           ('content_hash', 'recording_path', 'start', 'end'))):
        if start is None or end is None:
            continue
        low, high, _ = found.get(content, (start, end, path))
        found[content] = (min(low, start), max(high, end), path)
    return [Span(low.timestamp(), high.timestamp(), content, path) for content, (low, high, path) in found.items()]


@dataclass
class Timeline:
    """Spans of each actuator: those already in the history (``load(key)``, read once) and those added since."""

    load: Callable[[str], list[Span]]
    known: dict[str, list[Span]] = field(default_factory=dict)

    def clash(self, key: str, span: Span) -> Span | None:
        """The first recording of actuator ``key`` whose span overlaps ``span``, if any."""
        if key not in self.known:
            self.known[key] = self.load(key)
        return next((other for other in self.known[key] if span.clashes_with(other)), None)

    def add(self, key: str, span: Span) -> None:
        """Record ``span`` under actuator ``key`` (replacing an earlier span of its content)."""
        self.known[key] = [s for s in self.known.get(key, []) if s.content != span.content] + [span]


def clash_line(span: Span, other: Span, actuator: str) -> str:
    """The one line refusing ``span``: which recording it overlaps and what to do."""
    def utc(seconds: float) -> str:
        return datetime.datetime.fromtimestamp(seconds, datetime.UTC).isoformat(timespec='seconds')
    return (f'{span.path}: not added to the history: it overlaps {other.path} in time ({utc(span.start)} .. '
            f'{utc(span.end)} against {utc(other.start)} .. {utc(other.end)}) under actuator {actuator!r}, so they '
            'come from two actuators; give each its own id (--actuator-id ID or folder)')
