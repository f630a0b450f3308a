# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The assessment history: one Parquet dataset per table, hive-partitioned by actuator, one file per recording.

Layout (read as it is by DuckDB, polars, pandas and pyarrow: each table
folder is one dataset of one schema)::

    HISTORY/runs/actuator=<key>/<recording key>.parquet
    HISTORY/windows/actuator=<key>/<recording key>.parquet
    HISTORY/calibrations/<calibration id>.yaml
    HISTORY/.staging/                      (work in progress; never read)

``pandas.read_parquet('HISTORY/runs')``, ``pyarrow.dataset.dataset('HISTORY/runs',
partitioning='hive')``, DuckDB's ``read_parquet('HISTORY/runs/*/*.parquet',
hive_partitioning = true)`` and polars' ``read_parquet('HISTORY/runs/**/*.parquet')``
each give the runs table and nothing else.

``<recording key>`` is the first 16 hex digits of the recording's content
hash (SHA-256 of its files): a recording is its content.  Re-assessing the
same bytes (at the same path or another one, under the same actuator or
another) replaces its files; new bytes at a path already seen (a logger
overwriting ``latest.mcap`` daily) are a new recording beside the earlier ones.

Kill-safe for plain readers.  Both tables of a recording are written under
``.staging`` (fsynced), then put in place under the commit lock: the
recording's old runs file is removed, the windows file renamed into place,
the runs file last, each in one step (a recording re-assessed under another
actuator leaves its old place first).  So a plain reader of either table
sees, at any moment and after a kill at any point, each recording once or
not at all, never two assessments of it (``benchmarks/history_kill.py`` kills
writers 100 times).  Across the two tables, a kill between the renames
leaves windows without runs: :func:`read_table` leaves them out, the next
writer removes them; a plain reader joining the tables sees them until then.

Self-description.  Each file's schema metadata holds the actuator id
(``prsm_lube_ros.actuator``) and where it came from
(``prsm_lube_ros.actuator_source``, :mod:`.identity`), the table, the
calibration id, the package version (``prsm_lube_ros.package_version``), the
layout version and the unit of every column (``prsm_lube_ros.units``, JSON;
also each field's ``unit``).  The columns that plain readers need to tell
rows apart are in every row too: ``actuator_id``, ``actuator_source``,
``calibration_id``, ``recording`` (the key), ``package_version`` and
``layout``.  ``calibration_id`` is the first 16 hex digits of the SHA-256 of
the calibration file, whose bytes are kept as ``calibrations/<id>.yaml``
(:func:`history_calibration`).  ``recording_path`` is the path as it was given
on the command line (with ``content_hash`` beside it to find it again),
``date`` the UTC day the recording starts, typed as a date.

Columns of both tables: ``recording_path``, ``content_hash``,
``calibration_id``, ``assessed_at`` (UTC), ``namespace``, ``run_index``,
``start``/``end`` (UTC), ``screw_speed`` (rad/s), ``axial_load`` (N),
``vibration_rms`` (m/s^2), ``theta_oil`` and ``theta_oil_std`` (null where not
assessable), ``reason``, ``date``; runs add ``windows``, ``temperature``
(degC) and ``theta_oil_std_calibration`` (the calibration's share of the
one-sigma, common to all recordings assessed with it), windows add ``steady``
and ``nut_position`` (m).  Both carry the surface defect screen
(:mod:`prsm_lube_ros.estimation.defect_screen`, the contract's
``defect_suspected`` and ``condition_indicators``): ``defect_suspected``,
``kurtosis`` and ``crest_factor`` (the run's medians over its windows, or the
window's; null where not computed), ``defect_component``, ``defect_order``
(envelope line in multiples of the screw speed, null without one) and
``defect_evidence`` (in words).  The partition column ``actuator`` (the id
made a folder name, :func:`actuator_key`) comes from the folder names.

Reading (:func:`read_table`).  Every file is checked on its footer before
its rows are loaded (:data:`MAX_PARQUET_ROWS`, :data:`MAX_PARQUET_BYTES`), read
alone and its columns taken by name; every row is checked for values the
assessment never writes (NaN or infinite numbers, a theta_Oil at or below
zero, a negative one-sigma, RMS, speed or load, a time before 1970 or after 2200): such a row is
one line naming the file and the row, and left out, the rest is read.

Layouts.  ``4`` (this one) put each table in its own dataset and the
identity, package and layout columns in the rows; ``3`` (one folder per
recording holding both tables, ``recordings/actuator=ID/recording=KEY/``)
added the defect columns; ``2`` had none.  Layouts 2 and 3 still read
(:func:`read_table` says so once through ``on_note``) and the next writer
moves them into layout 4 (:func:`migrate`); files of layout 2 read
``defect_suspected`` false, ``defect_component`` and ``defect_evidence`` ''
and the three numbers null.
"""
from __future__ import annotations

import datetime
import hashlib
import json
import os
from pathlib import Path
import re
import shutil
import tempfile
from typing import TYPE_CHECKING
from collections.abc import Callable, Iterable, Mapping, Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from ..atomic_file import file_lock, remove_stale, temporary_prefix, write_atomically
from ..config_file import MAX_YAML_BYTES
from ..errors import ConfigError, InputError, RecordingError
from ..input_file import confine, MAX_RECORDING_BYTES, open_regular, read_bytes
from ..stopping import note_written
from ..validation import finite_or_none as _finite, utc_or_none as _utc

if TYPE_CHECKING:
    from ..estimation.assessment import RunAssessment
    from ..estimation.calibration import Calibration
    from ..estimation.condition_indicators import ConditionIndicators
    from ..estimation.defect_screen import DefectFinding, RunCondition
    from ..estimation.pipeline import RecordingAssessment
    from .identity import Identity, Span
    from .parallel import BagOutcome

__all__ = ['CALIBRATIONS', 'DEFECT_COLUMNS', 'IDENTITY_COLUMNS', 'LAYOUT_VERSION', 'LOCK', 'MAX_PARQUET_BYTES',
           'MAX_PARQUET_FOOTER', 'MAX_PARQUET_ROWS', 'RECORDINGS', 'SCHEMAS', 'STAGING', 'TABLES', 'UNITS', 'UTC_TIME',
           'actuator_key', 'add_assessment', 'assessment_tables', 'calibration_id', 'content_hash',
           'history_calibration', 'history_writer', 'migrate', 'package_version', 'path_text', 'read_history',
           'read_table', 'register_calibration', 'stored_sources']

TABLES = ('runs', 'windows')
#: ``RECORDINGS``: the folder of layouts 2 and 3 (read, and moved into layout 4 by the next writer)
RECORDINGS, CALIBRATIONS, STAGING = 'recordings', 'calibrations', '.staging'
#: the file whose lock serialises commits (hidden: readers pass it by)
LOCK = '.commit.lock'
#: Bounds on one Parquet file of the history, checked on its footer before its rows are loaded: bytes, rows
#: (a recording of a month of 1 s windows has 2.6 million), and the footer's own bytes.
MAX_PARQUET_BYTES, MAX_PARQUET_ROWS, MAX_PARQUET_FOOTER = 1 << 30, 5_000_000, 16 << 20
#: '4': one dataset per table, identity/package/layout columns; '3': the defect screen's columns; '2' still read
LAYOUT_VERSION = '4'
UTC_TIME = pa.timestamp('us', tz='UTC')
#: unit of each column that has one
UNITS = {'start': 'UTC', 'end': 'UTC', 'assessed_at': 'UTC', 'screw_speed': 'rad/s', 'axial_load': 'N',
         'vibration_rms': 'm/s^2', 'temperature': 'degC', 'nut_position': 'm', 'theta_oil': '1',
         'theta_oil_std': '1', 'theta_oil_std_calibration': '1', 'date': 'UTC day', 'kurtosis': '1',
         'crest_factor': '1', 'defect_order': 'x screw speed'}
_COMMON = [('recording_path', pa.string()), ('content_hash', pa.string()), ('calibration_id', pa.string()),
           ('assessed_at', UTC_TIME), ('namespace', pa.string()), ('run_index', pa.int64()),
           ('start', UTC_TIME), ('end', UTC_TIME), ('screw_speed', pa.float64()), ('axial_load', pa.float64()),
           ('vibration_rms', pa.float64()), ('theta_oil', pa.float64()), ('theta_oil_std', pa.float64()),
           ('reason', pa.string())]
_RUN_ONLY = [('windows', pa.int64()), ('temperature', pa.float64()), ('theta_oil_std_calibration', pa.float64())]
_WINDOW_ONLY = [('steady', pa.bool_()), ('nut_position', pa.float64())]
_DEFECT = [('defect_suspected', pa.bool_()), ('kurtosis', pa.float64()), ('crest_factor', pa.float64()),
           ('defect_component', pa.string()), ('defect_order', pa.float64()), ('defect_evidence', pa.string())]
_DATE = [('date', pa.date32())]
#: who the rows are and what wrote them (layout 4): in every row, for readers that see rows only
_IDENTITY = [('actuator_id', pa.string()), ('actuator_source', pa.string()), ('recording', pa.string()),
             ('package_version', pa.string()), ('layout', pa.string())]
IDENTITY_COLUMNS = tuple(name for name, _ in _IDENTITY)
#: the surface defect screen's columns and what a file written before them (layout 2) reads as
DEFECT_COLUMNS = {'defect_suspected': False, 'kurtosis': None, 'crest_factor': None, 'defect_component': '',
                  'defect_order': None, 'defect_evidence': ''}
#: us since the epoch of 2200-01-01: no recording starts or ends after it (nor before 1970)
_LATEST_US = 7_258_118_400_000_000
#: columns that hold no value below zero (a row with one is not what the assessment writes)
_NOT_NEGATIVE = ('theta_oil_std', 'vibration_rms', 'screw_speed', 'axial_load', 'theta_oil_std_calibration',
                 'windows')


def _schema(columns: Iterable[tuple[str, pa.DataType]]) -> pa.Schema:
    return pa.schema([pa.field(name, kind, metadata={'unit': UNITS[name]} if name in UNITS else None)
                      for name, kind in columns])


SCHEMAS = {'runs': _schema(_COMMON + _RUN_ONLY + _DEFECT + _DATE + _IDENTITY),
           'windows': _schema(_COMMON + _WINDOW_ONLY + _DEFECT + _DATE + _IDENTITY)}
_HASH_BLOCK = 1 << 20
_KEY = re.compile(r'^[0-9a-f]{16}$')


def package_version() -> str:
    """The installed prsm_lube_ros version (``unknown`` when it is not installed as a distribution)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version('prsm_lube_ros')
    except PackageNotFoundError:
        return 'unknown'


def content_hash(path: str | Path) -> str:
    """SHA-256 (hex) of a recording: a file's bytes, or a folder's files in sorted order with their names."""
    path = Path(path)
    digest = hashlib.sha256()
    try:
        files = [path] if path.is_file() else sorted(p for p in path.rglob('*') if p.is_file())
        if not files:
            raise RecordingError(f'{path}: no file to hash')
        root = path.resolve() if path.is_dir() else None     # a bag folder's files may not link out of it
        for file in files:
            if file is not path:
                digest.update(os.fsencode(file.relative_to(path).as_posix()) + b'\0')
            with open_regular(file, 'recording', max_bytes=MAX_RECORDING_BYTES, root=root,
                              error=RecordingError) as stream:
                for block in iter(lambda: stream.read(_HASH_BLOCK), b''):
                    digest.update(block)
    except OSError as exc:
        raise RecordingError(f'{path}: cannot read ({exc.strerror or exc})') from None
    return digest.hexdigest()


def calibration_id(path: str | Path) -> str:
    """First 16 hex digits of the SHA-256 of a calibration file's bytes."""
    return hashlib.sha256(_calibration_bytes(path)).hexdigest()[:16]


def _calibration_bytes(path: str | Path) -> bytes:
    """A calibration file's bytes, read as every calibration file is: a regular file, bounded."""
    return read_bytes(path, 'calibration file', max_bytes=MAX_YAML_BYTES, error=ConfigError)


def register_calibration(history: str | Path, path: str | Path) -> str:
    """Keep the calibration file's bytes as ``HISTORY/calibrations/<id>.yaml``; returns its id."""
    data = _calibration_bytes(path)
    identifier = hashlib.sha256(data).hexdigest()[:16]
    target = Path(history) / CALIBRATIONS / f'{identifier}.yaml'
    if not target.is_file():
        try:
            write_atomically(target, lambda stream: stream.write(data))
        except OSError as exc:
            raise ConfigError(f'{history}: cannot write the history ({exc.strerror or exc})') from None
    return identifier


def history_calibration(history: str | Path, identifier: str) -> Calibration:
    """The :class:`~prsm_lube_ros.estimation.calibration.Calibration` a ``calibration_id`` of the history names."""
    from ..estimation.calibration_file import load_calibration
    path = Path(history) / CALIBRATIONS / f'{identifier}.yaml'
    if not _KEY.match(str(identifier)) or not path.is_file():
        raise ConfigError(f'{history}: no calibration {identifier!r} in {CALIBRATIONS}/')
    confine(path, history, 'kept calibration', ConfigError)
    return load_calibration(path)


def actuator_key(actuator_id: str) -> str:
    """The partition folder value of an actuator id (namespace slashes become dots): ``/ema/prsm`` -> ``ema.prsm``."""
    key = re.sub(r'[^A-Za-z0-9_.-]', '_', str(actuator_id).strip('/').replace('/', '.'))
    if not key or key in ('.', '..'):
        raise InputError(f'actuator id {actuator_id!r} is empty once made a folder name')
    return key


def assessment_tables(assessment: RecordingAssessment, *, content: str, calibration: str, namespace: str = '/prsm',
                      assessed_at: datetime.datetime | None = None, fit: Calibration | None = None,
                      actuator_id: str = '', actuator_source: str = '') -> dict[str, pa.Table]:
    """The ``runs`` and ``windows`` rows of one ``RecordingAssessment`` as pyarrow tables.

    ``fit`` (the :class:`~prsm_lube_ros.estimation.calibration.Calibration`
    used) fills ``theta_oil_std_calibration``: the part of each run's
    one-sigma that comes from the constants' covariance, shared by every
    recording assessed with that calibration (null without ``fit``).
    ``actuator_id`` and ``actuator_source`` (:class:`~.identity.Identity`) go
    into every row and into the schema metadata.
    """
    assessed_at = assessed_at or datetime.datetime.now(datetime.UTC)
    common = {'recording_path': path_text(assessment.path), 'content_hash': content, 'calibration_id': calibration,
              'assessed_at': assessed_at, 'namespace': namespace, 'actuator_id': str(actuator_id),
              'actuator_source': path_text(actuator_source), 'recording': content[:16],
              'package_version': package_version(), 'layout': LAYOUT_VERSION}
    shared = _calibration_std(fit, assessment.runs)
    runs = [dict(common, run_index=run.run_index, start=_utc(run.start), end=_utc(run.end),
                 screw_speed=_finite(run.screw_speed), axial_load=_finite(run.axial_load),
                 vibration_rms=_finite(run.vibration_rms),
                 theta_oil=None if run.reason else _finite(run.theta_oil),
                 theta_oil_std=None if run.reason else _finite(run.theta_oil_std), reason=run.reason,
                 windows=run.windows, temperature=_finite(run.temperature),
                 theta_oil_std_calibration=None if run.reason else _finite(std),
                 **_defect_columns(run.defect, run.condition))
            for run, std in zip(assessment.runs, shared)]
    windows = [dict(common, run_index=item.window.run_index, start=_utc(item.window.start),
                    end=_utc(item.window.end), screw_speed=_finite(item.window.screw_speed),
                    axial_load=_finite(item.window.axial_load), vibration_rms=_finite(item.window.vibration_rms),
                    theta_oil=_finite(item.theta_oil), theta_oil_std=_finite(item.theta_oil_std),
                    reason=item.reason, steady=bool(item.window.steady),
                    nut_position=_finite(item.window.nut_position),
                    **_defect_columns(item.defect, item.window.condition)) for item in assessment.windows]
    day = _first_start([*runs, *windows], assessed_at).date()
    for row in (*runs, *windows):
        row['date'] = day
    return {name: pa.Table.from_pylist(rows, schema=_described(name, common))
            for name, rows in (('runs', runs), ('windows', windows))}


def _defect_columns(defect: DefectFinding, condition: RunCondition | ConditionIndicators | None) -> dict:
    """The defect screen's columns of a run or window (numbers null where the indicators were not computed)."""
    return {'defect_suspected': bool(defect.suspected),
            'kurtosis': None if condition is None else _finite(condition.kurtosis),
            'crest_factor': None if condition is None else _finite(condition.crest_factor),
            'defect_component': defect.component, 'defect_order': _finite(defect.order),
            'defect_evidence': defect.evidence}


def _described(table: str, common: dict) -> pa.Schema:
    """The table's schema with actuator, source, calibration, table, package and layout version, units as metadata."""
    return SCHEMAS[table].with_metadata({'prsm_lube_ros.actuator': common['actuator_id'],
                                         'prsm_lube_ros.actuator_source': common['actuator_source'],
                                         'prsm_lube_ros.calibration_id': str(common['calibration_id']),
                                         'prsm_lube_ros.table': table,
                                         'prsm_lube_ros.package_version': common['package_version'],
                                         'prsm_lube_ros.history_layout': LAYOUT_VERSION,
                                         'prsm_lube_ros.units': json.dumps(UNITS)})


def _calibration_std(fit: Calibration | None, runs: Sequence[RunAssessment]) -> list[float | None]:
    """Per run, the one-sigma of theta_Oil from the calibration's covariance alone (Eq. 23 propagation)."""
    if fit is None:
        return [None] * len(runs)
    from ..estimation.assessment import Assessor
    assessor = Assessor(fit)
    return [assessor.theta(run.vibration_rms, run.screw_speed, run.axial_load, 0.0)[1] if not run.reason else None
            for run in runs]


def _first_start(rows: list[dict], fallback: datetime.datetime) -> datetime.datetime:
    starts = [row['start'] for row in rows if row['start'] is not None]
    return min(starts) if starts else fallback


def history_writer(history: str | Path, calibration_path: str | Path, fit: Calibration | None, *,
                   actuator_id: str = '', namespace: str = '/prsm',
                   identities: Mapping[str, Identity] | None = None) -> Callable[[BagOutcome], str]:
    """``on_done`` for :func:`~.parallel.assess_bags`: each assessed recording into the history as it finishes.

    Each recording's actuator is ``identities[path]`` (:func:`.identity.name_actuators`);
    without it, ``actuator_id`` ``folder`` names each recording by the real
    folder it lies in, any other value names them all.  Recordings that
    failed are left out, and so is a recording that would merge two
    actuators (:mod:`.identity`): its span overlaps another one of its
    actuator, or its folder-named id is already another folder's in the
    history.  ``write`` returns the line saying so.  The calibration is
    registered, what killed writers left is removed and layouts 2 and 3 are
    moved into this one first (:func:`migrate`).
    """
    from .identity import assessment_span, clash_line, folder_clash, Identity as Named, table_spans, Timeline
    identifier = register_calibration(history, calibration_path)
    migrate(history)
    sources: dict[str, list[tuple[str, str]]] = {}
    timeline = Timeline(lambda key: _existing_spans(history, key, table_spans, sources))

    def identity_of(path: str) -> Identity:
        if identities is not None:
            return identities[path]
        if actuator_id == 'folder':
            folder = Path(path).resolve().parent
            return Named(folder.name, f'folder {folder}')
        return Named(actuator_id)

    def write(outcome: BagOutcome) -> str:
        """Add the outcome's recording; '' when added or failed, else the line saying why it was refused."""
        if outcome.assessment is None:
            return ''
        identity = identity_of(outcome.path)
        span, key = assessment_span(outcome.assessment, outcome.content), actuator_key(identity.actuator)
        clash = timeline.clash(key, span) if span is not None else None
        if clash is not None:
            assert span is not None  # a clash needs a span
            return clash_line(span, clash, identity.actuator)
        other = folder_clash(identity, [item for item in sources.get(key, []) if item[0] != path_text(outcome.path)])
        if other is not None:
            return f'{outcome.path}: not added to the history: {other}'
        add_assessment(history, outcome.assessment, actuator_id=identity.actuator, content=outcome.content,
                       calibration=identifier, namespace=namespace, fit=fit, actuator_source=identity.source)
        sources.setdefault(key, []).append((path_text(outcome.path), path_text(identity.source)))
        if span is not None:
            timeline.add(key, span)
        return ''
    return write


def _existing_spans(history: str | Path, key: str, spans: Callable[[pa.Table], list[Span]],
                    sources: dict[str, list[tuple[str, str]]]) -> list[Span]:
    """Spans of one actuator's recordings already in the history (none for a new history); their sources too."""
    runs = read_table(history, 'runs', actuator=key, on_problem=lambda line: None) \
        if (Path(history) / TABLES[0]).is_dir() else SCHEMAS['runs'].empty_table()
    sources.setdefault(key, []).extend(stored_sources(runs))
    return spans(runs)


def stored_sources(runs: pa.Table) -> list[tuple[str, str]]:
    """(recording path, actuator source) of each recording of a ``runs`` table that knows its source."""
    pairs = zip(runs.column('recording_path').to_pylist(), runs.column('actuator_source').to_pylist())
    return list(dict.fromkeys((path, source) for path, source in pairs if source))


def add_assessment(history: str | Path, assessment: RecordingAssessment, *, actuator_id: str, content: str,
                   calibration: str, namespace: str = '/prsm', assessed_at: datetime.datetime | None = None,
                   before_commit: Callable[[Path], None] | None = None, fit: Calibration | None = None,
                   actuator_source: str = '') -> Path:
    """Write one recording's runs and windows into the history, replacing its earlier ones; returns its runs file.

    ``content`` is the recording's :func:`content_hash`, ``calibration`` the
    :func:`calibration_id` of the calibration used and ``fit`` the calibration
    itself (for ``theta_oil_std_calibration``).  ``before_commit(staged)``, if
    given, runs after both files are written and before they are renamed
    into place (tests inject a crash there).
    """
    history = Path(history)
    tables = assessment_tables(assessment, content=content, calibration=calibration, namespace=namespace,
                               assessed_at=assessed_at, fit=fit, actuator_id=actuator_id,
                               actuator_source=actuator_source)
    return _add_tables(history, tables, content[:16], actuator_key(actuator_id), before_commit)


def _add_tables(history: Path, tables: dict[str, pa.Table], key: str, actuator: str,
                before_commit: Callable[[Path], None] | None = None) -> Path:
    """Stage both tables of recording ``key`` and commit them under partition ``actuator``; the runs file."""
    try:
        staged = _stage(history / STAGING, key, tables)
        try:
            if before_commit is not None:
                before_commit(staged)
            with file_lock(history / LOCK):    # one commit at a time, across processes: never split or doubled
                _commit(staged, history, actuator, key)
        finally:
            shutil.rmtree(staged, ignore_errors=True)     # empty after a commit; the half-done work otherwise
    except OSError as exc:
        raise ConfigError(f'{history}: cannot write the history ({exc.strerror or exc})') from None
    return _file(history, 'runs', actuator, key)


def _file(history: Path, table: str, actuator: str, key: str) -> Path:
    return history / table / f'actuator={actuator}' / f'{key}.parquet'


def _stage(staging: Path, key: str, tables: dict[str, pa.Table]) -> Path:
    """Both tables written and fsynced into a new folder under ``staging``."""
    staging.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix=temporary_prefix(key), suffix='.tmp', dir=staging))
    try:
        for name in TABLES:
            with open(folder / f'{name}.parquet', 'wb') as stream:
                pq.write_table(tables[name], stream)
                stream.flush()
                os.fsync(stream.fileno())
        _fsync_folder(folder)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return folder


def _commit(staged: Path, history: Path, actuator: str, key: str) -> None:
    """Rename the staged files into place: the recording's old runs go first, then windows, then the new runs.

    A kill between two steps leaves windows without runs (never runs without
    their windows, nor runs beside windows of another assessment): left out
    by :func:`read_table`, removed by the next writer (:func:`migrate`).
    """
    for table in ('runs', 'windows'):                     # runs first: the recording leaves, then its windows
        for stale in (history / table).glob(f'actuator=*/{key}.parquet'):
            if table == 'runs' or stale.parent.name != f'actuator={actuator}':
                stale.unlink()                            # never in two places, never runs of two assessments
                _fsync_folder(stale.parent)
    for table in ('windows', 'runs'):                     # runs last: a recording with runs has its windows
        target = _file(history, table, actuator, key)
        target.parent.mkdir(parents=True, exist_ok=True)
        os.replace(staged / f'{table}.parquet', target)
        note_written(target)
        _fsync_folder(target.parent)


def _fsync_folder(folder: Path) -> None:
    handle = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(handle)
    finally:
        os.close(handle)


def migrate(history: str | Path) -> int:
    """Prepare ``history`` for a writer: stale work removed, windows without runs removed, old layouts moved.

    Under the commit lock: each recording of layouts 2 and 3
    (``recordings/actuator=ID/recording=KEY/``) is rewritten into layout 4
    (its identity from the file's metadata, source unknown) and its old
    folder removed.  Returns how many recordings were moved.
    """
    history = Path(history)
    remove_stale(history / STAGING)
    moved = 0
    try:
        with file_lock(history / LOCK):
            for orphan in (history / 'windows').glob('actuator=*/*.parquet'):
                if not (history / 'runs' / orphan.parent.name / orphan.name).exists():
                    orphan.unlink()                         # a writer killed between its two renames
            old = history / RECORDINGS
            for folder in sorted(old.glob('actuator=*/recording=*')) if old.is_dir() else []:
                tables = {}
                for table in TABLES:
                    tables[table] = _read_file(str(folder / f'{table}.parquet'), table, _raise)
                staged = _stage(history / STAGING, folder.name.removeprefix('recording='),
                                {name: _as_layout(found, name) for name, found in tables.items()})
                try:
                    _commit(staged, history, folder.parent.name.removeprefix('actuator='),
                            folder.name.removeprefix('recording='))
                finally:
                    shutil.rmtree(staged, ignore_errors=True)
                shutil.rmtree(folder)
                moved += 1
            if old.is_dir():
                for leftover in sorted(old.glob('*'), reverse=True):
                    if leftover.is_dir() and not any(leftover.iterdir()):
                        leftover.rmdir()
                if not any(old.iterdir()):
                    old.rmdir()
    except OSError as exc:
        raise ConfigError(f'{history}: cannot write the history ({exc.strerror or exc})') from None
    return moved


def _as_layout(found: pa.Table, table: str) -> pa.Table:
    """A table read from an old layout as this layout writes it (identity columns filled, package version ours)."""
    version = package_version()
    found = _screen_defaults(found)
    actuator_id = found.column('actuator_id').to_pylist()
    recordings = found.column('recording').to_pylist()
    columns = {name: found.column(name) for name in SCHEMAS[table].names}
    columns['package_version'] = pa.array([version] * found.num_rows, pa.string())
    columns['layout'] = pa.array([LAYOUT_VERSION] * found.num_rows, pa.string())
    columns['recording'] = pa.array(recordings, pa.string())
    columns['actuator_id'] = pa.array([a or k for a, k in zip(actuator_id, found.column('actuator').to_pylist())],
                                      pa.string())
    common = {'actuator_id': actuator_id[0] if actuator_id else '', 'actuator_source': '',
              'calibration_id': found.column('calibration_id')[0].as_py() if found.num_rows else '',
              'package_version': version}
    return pa.table(columns, schema=_described(table, common))


def read_history(history: str | Path, table: str = 'runs', actuator: str | None = None,
                 on_problem: Callable[[str], None] | None = None,
                 on_note: Callable[[str], None] | None = None) -> pa.Table:
    """:func:`read_table` (the name other modules may call; same arguments, same table)."""
    return read_table(history, table, actuator, on_problem, on_note)


def read_table(history: str | Path, table: str = 'runs', actuator: str | None = None,
               on_problem: Callable[[str], None] | None = None,
               on_note: Callable[[str], None] | None = None) -> pa.Table:
    """One table of the history with ``actuator`` (the partition key) beside the file's columns.

    ``actuator`` keeps one actuator (its id or partition key).  A file that
    cannot be read, is over a bound, or is not part of the layout, and a row
    holding a value the assessment never writes, are each a line passed to
    ``on_problem`` and skipped (without ``on_problem``: a
    :class:`ConfigError`).  Files of layouts 2 and 3 are read too, and
    ``on_note`` gets one line saying so; those of layout 2 (before the defect
    screen) get the :data:`DEFECT_COLUMNS` values and a line saying how many
    recordings that is.  An empty table (with the schema) when the history
    has no recording; :class:`ConfigError` when ``history`` is not a history.
    """
    if table not in TABLES:
        raise InputError(f'history table must be one of {", ".join(TABLES)}, got {table!r}')
    history = Path(history)
    _check_history(history)
    report = on_problem or _raise
    partition = f'actuator={actuator_key(actuator)}' if actuator else 'actuator=*'
    root, old = history / table, history / RECORDINGS
    files = sorted(str(p) for p in root.glob(f'{partition}/*.parquet') if _KEY.match(p.stem)) \
        if root.is_dir() else []
    if table == 'windows':          # a recording whose runs file is not there yet (a writer killed between them)
        files = [f for f in files if Path(history, 'runs', Path(f).parent.name, Path(f).name).is_file()]
    for stray in _strays(root, old):
        report(f'{stray}: not part of the history layout ({table}/actuator=ID/KEY.parquet), skipped')
    earlier = sorted(str(p / f'{table}.parquet') for p in old.glob(f'{partition}/recording=*')
                     if _KEY.match(p.name.removeprefix('recording='))) if old.is_dir() else []
    if earlier and on_note is not None:
        on_note(f'{history}: {len(earlier)} recording(s) in the layout before version {LAYOUT_VERSION} '
                f'({RECORDINGS}/): read as they are; the next prsm-lube assess --history moves them into '
                f'{", ".join(f"{name}/" for name in TABLES)}')
    parts = [_read_file(file, table, report) for file in (*files, *earlier) if _bounded(file, history, report)]
    found = pa.concat_tables([part for part in parts if part is not None] or [_empty(table)])
    return _screen_columns_filled(found, history, on_note)


def _empty(table: str) -> pa.Table:
    return SCHEMAS[table].append(pa.field('actuator', pa.string())).empty_table()


def _read_file(file: str, table: str, report: Callable[[str], None]) -> pa.Table | None:
    """One file's rows in this layout's schema (columns by name, missing ones null) with ``actuator``.

    Its bad rows are reported and left out.  None (reported) when unreadable
    or a column has a type it cannot be read as.
    """
    path = Path(file)
    try:
        raw = pq.read_table(file)
    except (pa.ArrowException, OSError) as exc:
        report(f'{file}: unreadable Parquet ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}), '
               'skipped')
        return None
    old = path.parent.name.startswith('recording=')
    actuator = (path.parent.parent if old else path.parent).name.removeprefix('actuator=')
    key = path.parent.name.removeprefix('recording=') if old else path.stem
    metadata = raw.schema.metadata or {}
    columns = {}
    for field in SCHEMAS[table]:
        if field.name in raw.column_names:
            try:
                columns[field.name] = raw.column(field.name).cast(field.type)
            except (pa.ArrowException, ValueError) as exc:
                report(f'{file}: column {field.name} is {raw.schema.field(field.name).type}, not {field.type} '
                       f'({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}), skipped')
                return None
        elif field.name == 'actuator_id':
            columns[field.name] = pa.array([metadata.get(b'prsm_lube_ros.actuator', b'').decode(
                'utf-8', 'replace') or actuator] * raw.num_rows, pa.string())
        elif field.name == 'recording':
            columns[field.name] = pa.array([key] * raw.num_rows, pa.string())
        else:
            columns[field.name] = pa.nulls(raw.num_rows, field.type)
    columns['actuator'] = pa.array([actuator] * raw.num_rows, pa.string())
    found = pa.table(columns, schema=_empty(table).schema)
    bad = _bad_rows(found)
    for row, why in bad[:3]:
        report(f'{file}: row {row}: {why}: not a value the assessment writes, row skipped')
    if len(bad) > 3:
        report(f'{file}: {len(bad) - 3} more rows like that, skipped')
    if bad:
        keep = [True] * found.num_rows
        for row, _ in bad:
            keep[row] = False
        found = found.filter(pa.array(keep))
    return found


def _bad_rows(found: pa.Table) -> list[tuple[int, str]]:
    """(row, what is wrong) for each row holding a value the assessment never writes."""
    import numpy as np
    bad: dict[int, str] = {}
    for name in found.column_names:
        column = found.column(name)
        if pa.types.is_floating(column.type) or pa.types.is_integer(column.type):
            values = column.to_numpy(zero_copy_only=False).astype(float)      # nulls are NaN here
            nulls = np.asarray(column.is_null().to_pylist() if column.null_count else [False] * len(values))
            wrong = ~nulls & ~np.isfinite(values)
            if name in _NOT_NEGATIVE:
                wrong |= ~nulls & (values < 0)
            if name == 'theta_oil':
                wrong |= ~nulls & (values <= 0)
            for row in np.flatnonzero(wrong):
                bad.setdefault(int(row), f'{name} = {float(values[row])!r}')
        elif name in ('start', 'end'):
            stamps = column.cast(pa.int64()).to_numpy(zero_copy_only=False).astype(float)    # us; null is NaN
            for row in np.flatnonzero((stamps < 0) | (stamps >= _LATEST_US)):
                bad.setdefault(int(row), f'{name} = {column[int(row)].value} us since the epoch')
    return sorted(bad.items())


def _screen_columns_filled(found: pa.Table, history: Path, on_note: Callable[[str], None] | None) -> pa.Table:
    """Rows of files written before the defect screen (``defect_suspected`` null) with :data:`DEFECT_COLUMNS`."""
    import pyarrow.compute as pc
    unscreened = pc.is_null(found.column('defect_suspected'))
    if not pc.any(unscreened).as_py():
        return found
    if on_note is not None:
        old = found.filter(unscreened)
        recordings = len(set(zip(old.column('actuator').to_pylist(), old.column('recording').to_pylist())))
        actuators = len(set(old.column('actuator').to_pylist()))
        on_note(f'{history}: {recordings} recording(s) of {actuators} actuator(s) were assessed before the surface '
                f'defect screen (history layout 2): read as no defect suspected, kurtosis and crest factor unknown; '
                f'assess them again to screen them')
    return _screen_defaults(found)


def _screen_defaults(found: pa.Table) -> pa.Table:
    """Null defect columns (layout 2) filled with :data:`DEFECT_COLUMNS`."""
    import pyarrow.compute as pc
    for name, value in DEFECT_COLUMNS.items():
        if value is not None:
            index = found.schema.get_field_index(name)
            found = found.set_column(index, found.schema.field(name), pc.fill_null(found.column(name), value))
    return found


def _bounded(file: str, history: Path, report: Callable[[str], None]) -> bool:
    """True for a Parquet file inside ``history``, regular and within the bounds its footer gives; else reported."""
    try:
        with open_regular(file, 'history file', max_bytes=MAX_PARQUET_BYTES, root=history,
                          error=ConfigError) as stream:
            size = stream.seek(0, os.SEEK_END)
            stream.seek(max(size - 8, 0))
            tail = stream.read(8)
            footer = int.from_bytes(tail[:4], 'little') if len(tail) == 8 and tail[4:] == b'PAR1' else -1
            if not 0 <= footer <= min(MAX_PARQUET_FOOTER, size - 12):
                raise ConfigError(f'{file}: not a Parquet file (no footer), skipped')
            rows = pq.read_metadata(stream).num_rows
    except InputError as exc:
        report(str(exc).removesuffix(', skipped').removesuffix('; not read') + ', skipped')
        return False
    except (pa.ArrowException, OSError) as exc:
        report(f'{file}: unreadable Parquet ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__}), '
               'skipped')
        return False
    if rows > MAX_PARQUET_ROWS:
        report(f'{file}: {rows} rows in its footer, more than {MAX_PARQUET_ROWS} (not written by prsm-lube), '
               'skipped')
        return False
    return True


def path_text(path: str | Path) -> str:
    """A path as valid UTF-8 text: bytes the file system allows but UTF-8 lacks become backslash-x escapes."""
    return os.fsencode(path).decode('utf-8', 'backslashreplace')


def _raise(line: str) -> None:
    raise ConfigError(line)


def _check_history(history: Path) -> None:
    """:class:`ConfigError` when ``history`` is not a history folder."""
    if not history.is_dir():
        raise ConfigError(f'{history}: no such history folder')
    if not any((history / name).is_dir() for name in (*TABLES, RECORDINGS)):
        raise ConfigError(f'{history}: not a history folder (no {", ".join(f"{n}/" for n in TABLES)} in it; '
                          'prsm-lube assess --history writes one)')


def _strays(root: Path, old: Path) -> list[Path]:
    """Entries under a table's folder (and the old layouts' ``recordings/``) that the layout does not have.

    Hidden entries are left alone.
    """
    def belongs(entry: Path, layout_4: bool) -> bool:
        if layout_4:
            return entry.suffix == '.parquet' and _KEY.match(entry.stem) is not None
        return entry.is_dir() and _KEY.match(entry.name.removeprefix('recording=')) is not None

    found = []
    for folder, layout_4 in ((root, True), (old, False)):
        for actuator in sorted(folder.iterdir()) if folder.is_dir() else []:
            if actuator.name.startswith('.'):
                continue
            if not (actuator.is_dir() and actuator.name.startswith('actuator=')):
                found.append(actuator)
                continue
            found += [entry for entry in actuator.iterdir()
                      if not entry.name.startswith('.') and not belongs(entry, layout_4)]
    return sorted(found)
