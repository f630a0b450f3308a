# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The assessment history: a Parquet dataset of runs and windows, partitioned by actuator and date.

Layout (Hive partitioning, read as it is by pyarrow, pandas, polars, DuckDB
and Spark)::

    HISTORY/runs/actuator=<id>/date=<YYYY-MM-DD>/<path key>-<content key>.parquet
    HISTORY/windows/actuator=<id>/date=<YYYY-MM-DD>/<path key>-<content key>.parquet

One file per recording and table: ``date`` is the UTC day the recording
starts, ``<path key>`` the first 16 hex digits of the SHA-256 of its resolved
path and ``<content key>`` those of its content hash (SHA-256 of its files).
A recording is its content: re-assessing the same content (at the same path
or another one) writes its new file and removes the old ones, so its rows are
replaced, never duplicated; new content at a path already seen (a logger
overwriting ``latest.mcap`` every day) is a new recording, added beside the
earlier ones.  Every file is written to a hidden temporary file in the same
folder (readers skip names starting with ``.``), flushed to disk and renamed
over the final name in one ``os.replace``: a writer killed at any moment leaves
the dataset readable.  A writer killed between renaming the new file and
removing an old one leaves two versions of a recording; :func:`read_table`
keeps only the newest assessment of each content hash, so readers of this
module never see duplicates.

Columns of both tables: ``recording_path``, ``content_hash``,
``calibration_id``, ``assessed_at`` (UTC), ``namespace``, ``run_index``,
``start``/``end`` (UTC), ``screw_speed`` (rad/s), ``axial_load`` (N),
``vibration_rms`` (m/s^2), ``theta_oil`` and ``theta_oil_std`` (null where not
assessable), ``reason``; runs add ``windows``, ``temperature`` (degC) and
``theta_oil_std_calibration`` (the calibration's share of the one-sigma, common
to all recordings assessed with it), windows add ``steady`` and
``nut_position`` (m).  The partition columns
``actuator`` and ``date`` come from the folder names.
"""
from __future__ import annotations

import datetime
import hashlib
import os
from pathlib import Path
import re
import tempfile

import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq

from ..errors import ConfigError, InputError, RecordingError
from ..validation import finite_or_none as _finite, utc_or_none as _utc

TABLES = ('runs', 'windows')
UTC_TIME = pa.timestamp('us', tz='UTC')
_COMMON = [('recording_path', pa.string()), ('content_hash', pa.string()), ('calibration_id', pa.string()),
           ('assessed_at', UTC_TIME), ('namespace', pa.string()), ('run_index', pa.int64()),
           ('start', UTC_TIME), ('end', UTC_TIME), ('screw_speed', pa.float64()), ('axial_load', pa.float64()),
           ('vibration_rms', pa.float64()), ('theta_oil', pa.float64()), ('theta_oil_std', pa.float64()),
           ('reason', pa.string())]
_RUN_ONLY = [('windows', pa.int64()), ('temperature', pa.float64()), ('theta_oil_std_calibration', pa.float64())]
SCHEMAS = {'runs': pa.schema(_COMMON + _RUN_ONLY),
           'windows': pa.schema(_COMMON + [('steady', pa.bool_()), ('nut_position', pa.float64())])}
PARTITIONING = ds.partitioning(pa.schema([('actuator', pa.string()), ('date', pa.string())]), flavor='hive')
_HASH_BLOCK = 1 << 20


def content_hash(path: str | Path) -> str:
    """SHA-256 (hex) of a recording: a file's bytes, or a folder's files in sorted order with their names."""
    path = Path(path)
    digest = hashlib.sha256()
    try:
        files = [path] if path.is_file() else sorted(p for p in path.rglob('*') if p.is_file())
        if not files:
            raise RecordingError(f'{path}: no file to hash')
        for file in files:
            if file is not path:
                digest.update(file.relative_to(path).as_posix().encode() + b'\0')
            with open(file, 'rb') as stream:
                for block in iter(lambda: stream.read(_HASH_BLOCK), b''):
                    digest.update(block)
    except OSError as exc:
        raise RecordingError(f'{path}: cannot read ({exc.strerror or exc})') from None
    return digest.hexdigest()


def calibration_id(path: str | Path) -> str:
    """First 16 hex digits of the SHA-256 of a calibration file's bytes."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]
    except OSError as exc:
        raise ConfigError(f'{path}: cannot read ({exc.strerror or exc})') from None


def actuator_key(actuator_id: str) -> str:
    """The partition folder value of an actuator id (namespace slashes become dots): ``/ema/prsm`` -> ``ema.prsm``."""
    key = re.sub(r'[^A-Za-z0-9_.-]', '_', str(actuator_id).strip('/').replace('/', '.'))
    if not key or key in ('.', '..'):
        raise InputError(f'actuator id {actuator_id!r} is empty once made a folder name')
    return key


def _path_key(recording_path: str) -> str:
    return hashlib.sha256(str(Path(recording_path).resolve()).encode()).hexdigest()[:16]


def assessment_tables(assessment, *, content: str, calibration: str, namespace: str = '/prsm',
                      assessed_at: datetime.datetime | None = None, fit=None) -> dict[str, pa.Table]:
    """The ``runs`` and ``windows`` rows of one ``RecordingAssessment`` as pyarrow tables.

    ``fit`` (the :class:`~prsm_lube_ros.estimation.calibration.Calibration`
    used) fills ``theta_oil_std_calibration``: the part of each run's
    one-sigma that comes from the constants' covariance, shared by every
    recording assessed with that calibration (null without ``fit``).
    """
    assessed_at = assessed_at or datetime.datetime.now(datetime.timezone.utc)
    path = str(Path(assessment.path).resolve())
    common = {'recording_path': path, 'content_hash': content, 'calibration_id': calibration,
              'assessed_at': assessed_at, 'namespace': namespace}
    shared = _calibration_std(fit, assessment.runs)
    runs = [dict(common, run_index=run.run_index, start=_utc(run.start), end=_utc(run.end),
                 screw_speed=_finite(run.screw_speed), axial_load=_finite(run.axial_load),
                 vibration_rms=_finite(run.vibration_rms),
                 theta_oil=None if run.reason else _finite(run.theta_oil),
                 theta_oil_std=None if run.reason else _finite(run.theta_oil_std), reason=run.reason,
                 windows=run.windows, temperature=_finite(run.temperature),
                 theta_oil_std_calibration=None if run.reason else _finite(std))
            for run, std in zip(assessment.runs, shared)]
    windows = [dict(common, run_index=item.window.run_index, start=_utc(item.window.start),
                    end=_utc(item.window.end), screw_speed=_finite(item.window.screw_speed),
                    axial_load=_finite(item.window.axial_load), vibration_rms=_finite(item.window.vibration_rms),
                    theta_oil=_finite(item.theta_oil), theta_oil_std=_finite(item.theta_oil_std),
                    reason=item.reason, steady=bool(item.window.steady),
                    nut_position=_finite(item.window.nut_position)) for item in assessment.windows]
    return {'runs': pa.Table.from_pylist(runs, schema=SCHEMAS['runs']),
            'windows': pa.Table.from_pylist(windows, schema=SCHEMAS['windows'])}


def _calibration_std(fit, runs) -> list[float | None]:
    """Per run, the one-sigma of theta_Oil from the calibration's covariance alone (Eq. 23 propagation)."""
    if fit is None:
        return [None] * len(runs)
    from ..estimation.assessment import Assessor
    assessor = Assessor(fit)
    return [assessor.theta(run.vibration_rms, run.screw_speed, run.axial_load, 0.0)[1] if not run.reason else None
            for run in runs]


def write_table_atomically(table: pa.Table, path: Path, *, before_replace=None) -> None:
    """Write ``table`` to ``path``: a hidden temporary file in the same folder, fsync, then one rename.

    ``before_replace(temporary_path)``, if given, runs between the write and
    the rename (tests inject a crash there).
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f'.{path.name}.', suffix='.tmp', dir=path.parent)
    try:
        with os.fdopen(handle, 'wb') as stream:
            pq.write_table(table, stream)
            stream.flush()
            os.fsync(stream.fileno())
        if before_replace is not None:
            before_replace(Path(temporary))
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _first_start(tables: dict[str, pa.Table], fallback: datetime.datetime) -> datetime.datetime:
    starts = [value for name in TABLES for value in tables[name].column('start').to_pylist() if value is not None]
    return min(starts) if starts else fallback


def history_writer(history: str | Path, calibration_path: str | Path, fit, *, actuator_id: str,
                   namespace: str = '/prsm'):
    """``on_done`` for :func:`~.parallel.assess_bags`: each assessed recording into the history as it finishes.

    ``actuator_id`` ``folder`` names each recording's actuator by the folder it
    lies in; any other value names them all.  Recordings that failed are left out.
    """
    identifier = calibration_id(calibration_path)

    def write(outcome) -> None:
        if outcome.assessment is None:
            return
        actuator = Path(outcome.path).resolve().parent.name if actuator_id == 'folder' else actuator_id
        add_assessment(history, outcome.assessment, actuator_id=actuator, content=outcome.content,
                       calibration=identifier, namespace=namespace, fit=fit)
    return write


def add_assessment(history: str | Path, assessment, *, actuator_id: str, content: str, calibration: str,
                   namespace: str = '/prsm', assessed_at: datetime.datetime | None = None,
                   before_replace=None, after_replace=None, fit=None) -> list[Path]:
    """Write one recording's runs and windows into the history, replacing its earlier rows; returns the files.

    ``content`` is the recording's :func:`content_hash` (the rows of earlier
    assessments of that content are replaced, wherever it lay),
    ``calibration`` the :func:`calibration_id` of the calibration used and
    ``fit`` the calibration itself (for ``theta_oil_std_calibration``).
    ``before_replace`` is passed to :func:`write_table_atomically`;
    ``after_replace(path)``, if given, runs after each new file is in place
    and before the old ones are removed (tests inject a crash there).
    """
    history = Path(history)
    assessed_at = assessed_at or datetime.datetime.now(datetime.timezone.utc)
    tables = assessment_tables(assessment, content=content, calibration=calibration, namespace=namespace,
                               assessed_at=assessed_at, fit=fit)
    date = _first_start(tables, assessed_at).strftime('%Y-%m-%d')
    path_key, content_key = _path_key(assessment.path), content[:16]
    name = f'{path_key}-{content_key}.parquet'
    written = []
    try:
        for table_name in TABLES:
            root = history / table_name
            target = root / f'actuator={actuator_key(actuator_id)}' / f'date={date}' / name
            write_table_atomically(tables[table_name], target, before_replace=before_replace)
            written.append(target)
            if after_replace is not None:
                after_replace(target)
            for stale in set(root.glob(f'*/*/*-{content_key}.parquet')) - {target}:
                stale.unlink(missing_ok=True)
    except OSError as exc:
        raise ConfigError(f'{history}: cannot write the history ({exc.strerror or exc})') from None
    return written


def read_table(history: str | Path, table: str = 'runs', actuator: str | None = None) -> pa.Table:
    """One table of the history (with ``actuator`` and ``date``), the newest assessment of each recording.

    ``actuator`` keeps one actuator (its id or partition key).  An empty table
    (with the schema) when the history has none.
    """
    if table not in TABLES:
        raise InputError(f'history table must be one of {", ".join(TABLES)}, got {table!r}')
    root = Path(history) / table
    schema = SCHEMAS[table].append(pa.field('actuator', pa.string())).append(pa.field('date', pa.string()))
    if not root.is_dir():
        if not Path(history).is_dir():
            raise ConfigError(f'{history}: no such history folder')
        return schema.empty_table()
    try:
        dataset = ds.dataset(root, format='parquet', partitioning=PARTITIONING, schema=schema)
        data = dataset.to_table(filter=(ds.field('actuator') == actuator_key(actuator)) if actuator else None)
    except (pa.ArrowException, OSError) as exc:
        raise ConfigError(f'{root}: unreadable history ({exc})') from None
    return _newest_assessments(data)


def _newest_assessments(data: pa.Table) -> pa.Table:
    """Rows of the newest assessment of each recording (content hash)."""
    if data.num_rows == 0:
        return data
    contents, assessed = data.column('content_hash').to_pylist(), data.column('assessed_at').to_pylist()
    newest: dict[str, datetime.datetime] = {}
    for content, when in zip(contents, assessed):
        if content not in newest or when > newest[content]:
            newest[content] = when
    return data.filter(pa.array([when == newest[content] for content, when in zip(contents, assessed)]))
