# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The assessment history: one folder per recording holding its runs and windows, committed in one rename.

Layout (Hive partitioning, read as it is by DuckDB, polars, pandas and
pyarrow)::

    HISTORY/recordings/actuator=<id>/recording=<content key>/runs.parquet
    HISTORY/recordings/actuator=<id>/recording=<content key>/windows.parquet
    HISTORY/calibrations/<calibration id>.yaml
    HISTORY/.staging/                      (work in progress; never read)

``<content key>`` is the first 16 hex digits of the recording's content hash
(SHA-256 of its files): a recording is its content.  Re-assessing the same
bytes (at the same path or another one, under the same actuator or another)
replaces its folder; new bytes at a path already seen (a logger overwriting
``latest.mcap`` daily) are a new recording beside the earlier ones.

Kill-safe for plain readers.  Both tables of a recording are written into a
folder under ``.staging`` (fsynced), then that folder is renamed into place in
one step: a new recording by ``rename``, a re-assessed one by an atomic
exchange with its old folder (``renameat2(RENAME_EXCHANGE)``; where the
kernel lacks it the old folder is moved aside first, so the recording is
briefly absent, never doubled).  A recording re-assessed under another
actuator is first moved (one rename) to its new place.  So a plain
``read_parquet('HISTORY/recordings/*/*/runs.parquet')`` in DuckDB sees, at any
moment and after a kill at any point, each recording once and with both of
its tables, or not at all (``benchmarks/history_kill.py`` kills writers
100 times).  What a killed writer left under ``.staging`` (and the hidden
``.tmp`` files of :mod:`prsm_lube_ros.atomic_file`) is removed by the next
writer once its process is gone.

Self-description.  Each file's schema metadata holds the actuator id
(``prsm_lube_ros.actuator``), the table, the layout version and the unit of
every column (``prsm_lube_ros.units``, JSON; also each field's ``unit``).
``calibration_id`` is the first 16 hex digits of the SHA-256 of the
calibration file, whose bytes are kept as ``calibrations/<id>.yaml``
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
``defect_evidence`` (in words).  The partition columns ``actuator`` and
``recording`` come from the folder names.

Layouts.  ``3`` added the defect columns; files of layout ``2`` (written
before the screen) still read: :func:`read_table` gives them
``defect_suspected`` false, ``defect_component`` and ``defect_evidence`` ''
and the three numbers null, and tells ``on_note`` once how many recordings
were never screened.  Plain readers that mix both layouts need to unify by
name (``union_by_name = true`` in DuckDB, ``how='diagonal_relaxed'`` in
polars' ``concat``).
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
from collections.abc import Callable, Iterable, Sequence

import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq

from ..atomic_file import exchange, file_lock, remove_stale, temporary_prefix, write_atomically
from ..config_file import MAX_YAML_BYTES
from ..errors import ConfigError, InputError, RecordingError
from ..input_file import confine, MAX_RECORDING_BYTES, open_regular, read_bytes
from ..validation import finite_or_none as _finite, utc_or_none as _utc

if TYPE_CHECKING:
    from ..estimation.assessment import RunAssessment
    from ..estimation.calibration import Calibration
    from ..estimation.condition_indicators import ConditionIndicators
    from ..estimation.defect_screen import DefectFinding, RunCondition
    from ..estimation.pipeline import RecordingAssessment
    from .identity import Span
    from .parallel import BagOutcome

__all__ = ['CALIBRATIONS', 'DEFECT_COLUMNS', 'LAYOUT_VERSION', 'LOCK', 'MAX_PARQUET_BYTES', 'MAX_PARQUET_FOOTER',
           'MAX_PARQUET_ROWS', 'PARTITIONING', 'RECORDINGS', 'SCHEMAS', 'STAGING', 'TABLES', 'UNITS', 'UTC_TIME',
           'actuator_key', 'add_assessment', 'assessment_tables', 'calibration_id', 'content_hash',
           'history_calibration', 'history_writer', 'path_text', 'read_table', 'register_calibration']

TABLES = ('runs', 'windows')
RECORDINGS, CALIBRATIONS, STAGING = 'recordings', 'calibrations', '.staging'
#: the file whose lock serialises commits (hidden: readers pass it by)
LOCK = '.commit.lock'
#: Bounds on one Parquet file of the history, checked on its footer before its rows are loaded: bytes, rows
#: (a recording of a month of 1 s windows has 2.6 million), and the footer's own bytes.
MAX_PARQUET_BYTES, MAX_PARQUET_ROWS, MAX_PARQUET_FOOTER = 1 << 30, 5_000_000, 16 << 20
#: '3': the defect screen's columns (:data:`DEFECT_COLUMNS`) added to both tables; '2' files still read
LAYOUT_VERSION = '3'
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
#: the surface defect screen's columns and what a file written before them (layout 2) reads as
DEFECT_COLUMNS = {'defect_suspected': False, 'kurtosis': None, 'crest_factor': None, 'defect_component': '',
                  'defect_order': None, 'defect_evidence': ''}


def _schema(columns: Iterable[tuple[str, pa.DataType]]) -> pa.Schema:
    return pa.schema([pa.field(name, kind, metadata={'unit': UNITS[name]} if name in UNITS else None)
                      for name, kind in columns])


SCHEMAS = {'runs': _schema(_COMMON + _RUN_ONLY + _DEFECT + _DATE),
           'windows': _schema(_COMMON + _WINDOW_ONLY + _DEFECT + _DATE)}
PARTITIONING = ds.partitioning(pa.schema([('actuator', pa.string()), ('recording', pa.string())]), flavor='hive')
_HASH_BLOCK = 1 << 20
_KEY = re.compile(r'^[0-9a-f]{16}$')


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
                      actuator_id: str = '') -> dict[str, pa.Table]:
    """The ``runs`` and ``windows`` rows of one ``RecordingAssessment`` as pyarrow tables.

    ``fit`` (the :class:`~prsm_lube_ros.estimation.calibration.Calibration`
    used) fills ``theta_oil_std_calibration``: the part of each run's
    one-sigma that comes from the constants' covariance, shared by every
    recording assessed with that calibration (null without ``fit``).
    ``actuator_id`` goes into the schema metadata.
    """
    assessed_at = assessed_at or datetime.datetime.now(datetime.UTC)
    common = {'recording_path': path_text(assessment.path), 'content_hash': content, 'calibration_id': calibration,
              'assessed_at': assessed_at, 'namespace': namespace}
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
    return {name: pa.Table.from_pylist(rows, schema=_described(name, actuator_id))
            for name, rows in (('runs', runs), ('windows', windows))}


def _defect_columns(defect: DefectFinding, condition: RunCondition | ConditionIndicators | None) -> dict:
    """The defect screen's columns of a run or window (numbers null where the indicators were not computed)."""
    return {'defect_suspected': bool(defect.suspected),
            'kurtosis': None if condition is None else _finite(condition.kurtosis),
            'crest_factor': None if condition is None else _finite(condition.crest_factor),
            'defect_component': defect.component, 'defect_order': _finite(defect.order),
            'defect_evidence': defect.evidence}


def _described(table: str, actuator_id: str) -> pa.Schema:
    """The table's schema with the actuator id, table name, layout version and units as metadata."""
    return SCHEMAS[table].with_metadata({'prsm_lube_ros.actuator': str(actuator_id), 'prsm_lube_ros.table': table,
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


def history_writer(history: str | Path, calibration_path: str | Path, fit: Calibration | None, *, actuator_id: str,
                   namespace: str = '/prsm') -> Callable[[BagOutcome], str]:
    """``on_done`` for :func:`~.parallel.assess_bags`: each assessed recording into the history as it finishes.

    ``actuator_id`` ``folder`` names each recording's actuator by the folder it
    lies in; any other value names them all.  Recordings that failed are left
    out, and so is a recording whose span overlaps another one of its
    actuator (:mod:`.identity`: the id would merge two actuators): ``write``
    returns the line saying so.  The calibration is registered and what
    killed writers left is removed first.
    """
    from .identity import assessment_span, clash_line, table_spans, Timeline
    identifier = register_calibration(history, calibration_path)
    remove_stale(Path(history) / STAGING)
    timeline = Timeline(lambda key: _existing_spans(history, key, table_spans))

    def write(outcome: BagOutcome) -> str:
        """Add the outcome's recording; '' when added or failed, else the line saying why it was refused."""
        if outcome.assessment is None:
            return ''
        actuator = Path(outcome.path).resolve().parent.name if actuator_id == 'folder' else actuator_id
        span, key = assessment_span(outcome.assessment, outcome.content), actuator_key(actuator)
        clash = timeline.clash(key, span) if span is not None else None
        if clash is not None:
            assert span is not None  # a clash needs a span
            return clash_line(span, clash, actuator)
        add_assessment(history, outcome.assessment, actuator_id=actuator, content=outcome.content,
                       calibration=identifier, namespace=namespace, fit=fit)
        if span is not None:
            timeline.add(key, span)
        return ''
    return write


def _existing_spans(history: str | Path, key: str, spans: Callable[[pa.Table], list[Span]]) -> list[Span]:
    """Spans of one actuator's recordings already in the history (none for a new history)."""
    if not (Path(history) / RECORDINGS).is_dir():
        return []
    return spans(read_table(history, 'runs', actuator=key, on_problem=lambda line: None))


def add_assessment(history: str | Path, assessment: RecordingAssessment, *, actuator_id: str, content: str,
                   calibration: str, namespace: str = '/prsm', assessed_at: datetime.datetime | None = None,
                   before_commit: Callable[[Path], None] | None = None, fit: Calibration | None = None) -> Path:
    """Write one recording's runs and windows into the history, replacing its earlier ones; returns its folder.

    ``content`` is the recording's :func:`content_hash`, ``calibration`` the
    :func:`calibration_id` of the calibration used and ``fit`` the calibration
    itself (for ``theta_oil_std_calibration``).  ``before_commit(staged)``, if
    given, runs after both files are written and before the folder is
    renamed into place (tests inject a crash there).
    """
    history = Path(history)
    tables = assessment_tables(assessment, content=content, calibration=calibration, namespace=namespace,
                               assessed_at=assessed_at, fit=fit, actuator_id=actuator_id)
    key = content[:16]
    target = history / RECORDINGS / f'actuator={actuator_key(actuator_id)}' / f'recording={key}'
    try:
        staged = _stage(history / STAGING, key, tables)
        try:
            if before_commit is not None:
                before_commit(staged)
            with file_lock(history / LOCK):    # one commit at a time, across processes: never split or doubled
                _commit(staged, target)
        finally:
            shutil.rmtree(staged, ignore_errors=True)     # gone after a commit; the half-done work otherwise
    except OSError as exc:
        raise ConfigError(f'{history}: cannot write the history ({exc.strerror or exc})') from None
    return target


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


def _commit(staged: Path, target: Path) -> None:
    """Put the staged folder at ``target`` in one rename (or exchange); the recording's old folder goes."""
    target.parent.mkdir(parents=True, exist_ok=True)
    elsewhere = [p for p in target.parent.parent.glob(f'actuator=*/{target.name}') if p != target]
    if elsewhere and not target.exists():
        os.rename(elsewhere.pop(), target)               # moves to its new actuator: never in two places
    if target.exists():
        exchange(staged, target)                         # staged now holds the old folder (removed by the caller)
    else:
        os.rename(staged, target)
    for stale in elsewhere:                               # only after a crash of an earlier layout's writer
        shutil.rmtree(stale, ignore_errors=True)
    _fsync_folder(target.parent)


def _fsync_folder(folder: Path) -> None:
    handle = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(handle)
    finally:
        os.close(handle)


def read_table(history: str | Path, table: str = 'runs', actuator: str | None = None,
               on_problem: Callable[[str], None] | None = None,
               on_note: Callable[[str], None] | None = None) -> pa.Table:
    """One table of the history with ``actuator`` and ``recording`` (from the folders).

    ``actuator`` keeps one actuator (its id or partition key).  A file that
    cannot be read, or one that is not part of the layout, is a line passed
    to ``on_problem`` and skipped (without ``on_problem``: a
    :class:`ConfigError`).  Files of layout 2 (before the defect screen) get
    the :data:`DEFECT_COLUMNS` values, and ``on_note`` one line saying how
    many recordings that is.  An empty table (with the schema) when the
    history has no recording; :class:`ConfigError` when ``history`` is not a
    history.
    """
    if table not in TABLES:
        raise InputError(f'history table must be one of {", ".join(TABLES)}, got {table!r}')
    root = _recordings_root(history)
    report = on_problem or _raise
    pattern = f'actuator={actuator_key(actuator)}/*/{table}.parquet' if actuator else f'*/*/{table}.parquet'
    files = sorted(str(p) for p in root.glob(pattern) if _in_layout(p, root))
    for stray in _strays(root):
        report(f'{stray}: not part of the history layout (recordings/actuator=ID/recording=KEY/), skipped')
    files = [file for file in files if _bounded(file, Path(history), report)]
    schema = SCHEMAS[table].append(pa.field('actuator', pa.string())).append(pa.field('recording', pa.string()))
    if not files:
        return schema.empty_table()
    try:
        found = _dataset(files, schema, root).to_table()
    except (pa.ArrowException, OSError):
        found = _read_each(files, schema, root, report)
    return _screen_columns_filled(found, Path(history), on_note)


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


def _dataset(files: list[str], schema: pa.Schema, root: Path) -> ds.Dataset:
    return ds.dataset(files, format='parquet', schema=schema, partitioning=PARTITIONING, partition_base_dir=str(root))


def _read_each(files: list[str], schema: pa.Schema, root: Path, report: Callable[[str], None]) -> pa.Table:
    """The files one by one: each unreadable one reported and skipped."""
    parts = []
    for file in files:
        try:
            parts.append(_dataset([file], schema, root).to_table())
        except (pa.ArrowException, OSError) as exc:
            report(f'{file}: unreadable Parquet ({str(exc).splitlines()[0]}), skipped')
    return pa.concat_tables(parts) if parts else schema.empty_table()


def _raise(line: str) -> None:
    raise ConfigError(line)


def _recordings_root(history: str | Path) -> Path:
    """``HISTORY/recordings``; :class:`ConfigError` when ``history`` is not a history folder."""
    history = Path(history)
    if not history.is_dir():
        raise ConfigError(f'{history}: no such history folder')
    root = history / RECORDINGS
    if root.is_dir():
        return root
    if (history / 'runs').is_dir():
        raise ConfigError(f'{history}: a history of the earlier layout (runs/, windows/); assess the recordings '
                          'again into a new --history folder')
    raise ConfigError(f'{history}: not a history folder (no {RECORDINGS}/ in it; prsm-lube assess --history '
                      'writes one)')


def _in_layout(path: Path, root: Path) -> bool:
    actuator, recording = path.relative_to(root).parts[:2]
    return actuator.startswith('actuator=') and recording.startswith('recording=') and \
        _KEY.match(recording[len('recording='):]) is not None


def _strays(root: Path) -> list[Path]:
    """Entries under ``root`` that the layout does not have (hidden ones are left alone)."""
    found = []
    for actuator in root.iterdir():
        if actuator.name.startswith('.'):
            continue
        if not (actuator.is_dir() and actuator.name.startswith('actuator=')):
            found.append(actuator)
            continue
        for recording in actuator.iterdir():
            if recording.name.startswith('.'):
                continue
            if not (recording.is_dir() and _in_layout(recording / 'x', root)):
                found.append(recording)
                continue
            found += [f for f in recording.iterdir()
                      if not f.name.startswith('.') and f.name not in {f'{name}.parquet' for name in TABLES}]
    return sorted(found)
