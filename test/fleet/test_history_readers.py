# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The history reads as it is in DuckDB, polars and pyarrow: same actuators, rows and theta_Oil as read_table gives."""
import math

import pytest

from prsm_lube_ros.fleet.history import read_table


def ours(history):
    """actuator -> (runs, sum of finite theta_Oil) from read_table."""
    table = read_table(history, 'runs').to_pylist()
    found = {}
    for row in table:
        runs, total = found.get(row['actuator'], (0, 0.0))
        theta = row['theta_oil']
        found[row['actuator']] = (runs + 1, total + (theta if theta is not None and math.isfinite(theta) else 0.0))
    return found


def test_duckdb_reads_the_hive_partitioned_runs(small_fleet):
    duckdb = pytest.importorskip('duckdb')
    rows = duckdb.sql(f"select actuator, count(*), coalesce(sum(theta_oil), 0) from read_parquet("
                      f"'{small_fleet['history']}/recordings/*/*/runs.parquet', hive_partitioning = true) "
                      "group by actuator").fetchall()
    expected = ours(small_fleet['history'])
    assert {a: n for a, n, _ in rows} == {a: n for a, (n, _) in expected.items()}
    for actuator, _, total in rows:
        assert total == pytest.approx(expected[actuator][1], rel=1e-12)


def test_polars_reads_the_hive_partitioned_windows_and_runs(small_fleet):
    polars = pytest.importorskip('polars')
    runs = polars.read_parquet(f"{small_fleet['history']}/recordings/**/runs.parquet", hive_partitioning=True)
    expected = ours(small_fleet['history'])
    counts = dict(runs.group_by('actuator').len().iter_rows())
    assert counts == {a: n for a, (n, _) in expected.items()}
    windows = polars.read_parquet(f"{small_fleet['history']}/recordings/**/windows.parquet", hive_partitioning=True)
    assert windows.height == read_table(small_fleet['history'], 'windows').num_rows > 0
    assert {'date', 'actuator', 'content_hash', 'calibration_id', 'recording_path'} <= set(windows.columns)


def test_pyarrow_reads_each_table_with_a_typed_date(small_fleet):
    import pyarrow.dataset as ds
    root = small_fleet['history'] / 'recordings'
    runs = ds.dataset(root, partitioning='hive', ignore_prefixes=['.', 'windows']).to_table()
    windows = ds.dataset(root, partitioning='hive', ignore_prefixes=['.', 'runs']).to_table()
    assert runs.num_rows == read_table(small_fleet['history'], 'runs').num_rows
    assert windows.num_rows == read_table(small_fleet['history'], 'windows').num_rows
    assert str(runs.schema.field('date').type) == 'date32[day]' and 'steady' in windows.column_names


def test_duckdb_types_the_date_and_joins_the_calibration_registry(small_fleet):
    duckdb = pytest.importorskip('duckdb')
    history = small_fleet['history']
    kinds = duckdb.sql(f"select distinct typeof(date) from read_parquet('{history}/recordings/*/*/runs.parquet', "
                       "hive_partitioning = true)").fetchall()
    assert kinds == [('DATE',)]
    from prsm_lube_ros.fleet.history import history_calibration
    identifier, = {row['calibration_id'] for row in read_table(history).to_pylist()}
    assert (history / 'calibrations' / f'{identifier}.yaml').read_bytes() == small_fleet['calibration'].read_bytes()
    assert history_calibration(history, identifier).constants.c_sys > 0
