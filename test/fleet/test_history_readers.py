# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Each table folder of the history reads as one table in pandas, pyarrow, DuckDB and polars, as read_table gives it.

Issue 37: ``pandas.read_parquet('history/recordings')`` returned runs and
windows mixed in one frame without an error.  Now ``history/runs`` and
``history/windows`` are each one dataset, hive-partitioned by actuator.
"""
import math

import pytest

from prsm_lube_ros.fleet.history import read_table

EXPECTED_COLUMNS = {'actuator', 'actuator_id', 'actuator_source', 'calibration_id', 'package_version', 'layout',
                    'recording', 'date', 'content_hash', 'recording_path', 'theta_oil'}


def ours(history, table='runs'):
    """actuator -> (rows, sum of finite theta_Oil) from read_table."""
    found = {}
    for row in read_table(history, table).to_pylist():
        rows, total = found.get(row['actuator'], (0, 0.0))
        theta = row['theta_oil']
        found[row['actuator']] = (rows + 1, total + (theta if theta is not None and math.isfinite(theta) else 0.0))
    return found


def summary(rows):
    """actuator -> (rows, sum of finite theta_Oil) of (actuator, theta) pairs."""
    found = {}
    for actuator, theta in rows:
        count, total = found.get(str(actuator), (0, 0.0))
        ok = theta is not None and math.isfinite(theta)
        found[str(actuator)] = (count + 1, total + (theta if ok else 0.0))
    return found


def same(found, expected):
    assert found.keys() == expected.keys()
    for actuator, (rows, total) in found.items():
        assert rows == expected[actuator][0] and total == pytest.approx(expected[actuator][1], rel=1e-12)


@pytest.mark.parametrize('table', ['runs', 'windows'])
def test_pandas_reads_a_table_folder_as_that_table_alone(small_fleet, table):
    pandas = pytest.importorskip('pandas')
    frame = pandas.read_parquet(small_fleet['history'] / table)
    assert EXPECTED_COLUMNS <= set(frame.columns)
    assert ('steady' in frame.columns) == (table == 'windows') and ('windows' in frame.columns) == (table == 'runs')
    same(summary(zip(frame['actuator'], frame['theta_oil'])), ours(small_fleet['history'], table))


@pytest.mark.parametrize('table', ['runs', 'windows'])
def test_pyarrow_reads_a_table_folder_as_that_table_alone(small_fleet, table):
    import pyarrow.dataset as ds
    found = ds.dataset(small_fleet['history'] / table, partitioning='hive').to_table()
    assert EXPECTED_COLUMNS <= set(found.column_names)
    assert str(found.schema.field('date').type) == 'date32[day]'
    same(summary(zip(found.column('actuator').to_pylist(), found.column('theta_oil').to_pylist())),
         ours(small_fleet['history'], table))


@pytest.mark.parametrize('table', ['runs', 'windows'])
def test_duckdb_reads_a_table_folder_as_that_table_alone(small_fleet, table):
    duckdb = pytest.importorskip('duckdb')
    history = small_fleet['history']
    relation = duckdb.sql(f"select * from read_parquet('{history}/{table}/*/*.parquet', hive_partitioning = true)")
    assert EXPECTED_COLUMNS <= set(relation.columns)
    rows = duckdb.sql(f"select actuator, theta_oil from read_parquet('{history}/{table}/*/*.parquet', "
                      "hive_partitioning = true)").fetchall()
    same(summary(rows), ours(history, table))
    kinds = duckdb.sql(f"select distinct typeof(date) from read_parquet('{history}/{table}/*/*.parquet')").fetchall()
    assert kinds == [('DATE',)]


@pytest.mark.parametrize('table', ['runs', 'windows'])
def test_polars_reads_a_table_folder_as_that_table_alone(small_fleet, table):
    polars = pytest.importorskip('polars')
    found = polars.read_parquet(f"{small_fleet['history']}/{table}/**/*.parquet", hive_partitioning=True)
    assert EXPECTED_COLUMNS <= set(found.columns)
    same(summary(zip(found['actuator'].to_list(), found['theta_oil'].to_list())),
         ours(small_fleet['history'], table))


def test_a_file_read_alone_says_whose_rows_they_are_and_what_wrote_them(small_fleet):
    import pyarrow.parquet as pq
    import prsm_lube_ros
    from prsm_lube_ros.fleet.history import LAYOUT_VERSION, package_version
    history = small_fleet['history']
    file = next(history.glob('runs/actuator=A01/*.parquet'))
    alone = pq.read_table(file)
    metadata = alone.schema.metadata
    assert metadata[b'prsm_lube_ros.actuator'] == b'A01'
    assert metadata[b'prsm_lube_ros.actuator_source'] == f'folder {small_fleet["root"].resolve() / "A01"}'.encode()
    assert metadata[b'prsm_lube_ros.package_version'] == package_version().encode() == \
        prsm_lube_ros.__version__.encode()
    assert metadata[b'prsm_lube_ros.history_layout'] == LAYOUT_VERSION.encode()
    assert metadata[b'prsm_lube_ros.calibration_id'] == alone.column('calibration_id')[0].as_py().encode()
    assert set(alone.column('actuator_id').to_pylist()) == {'A01'}
    assert set(alone.column('recording').to_pylist()) == {file.stem}
    assert alone.schema.field('screw_speed').metadata == {b'unit': b'rad/s'}


def test_duckdb_joins_the_calibration_registry(small_fleet):
    from prsm_lube_ros.fleet.history import history_calibration
    history = small_fleet['history']
    identifier, = {row['calibration_id'] for row in read_table(history).to_pylist()}
    assert (history / 'calibrations' / f'{identifier}.yaml').read_bytes() == small_fleet['calibration'].read_bytes()
    assert history_calibration(history, identifier).constants.c_sys > 0
