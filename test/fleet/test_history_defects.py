# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The history keeps the surface defect screen per run and window; histories written before it still read."""
import json

import pyarrow.parquet as pq
import pytest

from prsm_lube_ros.fleet.history import DEFECT_COLUMNS, LAYOUT_VERSION, read_table, SCHEMAS

from fleet_histories import assessment, recording, screened, SPALL, write


def as_layout_2(runs_file):
    """Rewrite a recording's files as a writer before the defect screen wrote them (no defect columns, layout 2)."""
    for name in ('runs', 'windows'):
        file = runs_file.parents[2] / name / runs_file.parent.name / runs_file.name
        table = pq.read_table(file)
        table = table.drop_columns(list(DEFECT_COLUMNS))
        metadata = dict(table.schema.metadata)
        metadata[b'prsm_lube_ros.history_layout'] = b'2'
        pq.write_table(table.replace_schema_metadata(metadata), file)


def test_the_defect_columns_are_written_and_read_back_for_runs_and_windows(tmp_path):
    history, bag = tmp_path / 'history', recording(tmp_path, 'a.mcap')
    folder = write(history, bag, screened(bag))
    runs = read_table(history, 'runs').to_pylist()
    assert [r['defect_suspected'] for r in runs] == [False, True]
    flagged = runs[1]
    assert flagged['kurtosis'] == pytest.approx(9.1) and flagged['crest_factor'] == pytest.approx(8.0)
    assert flagged['defect_component'] == 'screw raceway' and flagged['defect_order'] == pytest.approx(6.25)
    assert flagged['defect_evidence'] == SPALL.evidence
    assert runs[0]['defect_component'] == '' and runs[0]['defect_order'] is None and runs[0]['kurtosis'] == 3.1
    windows = read_table(history, 'windows').to_pylist()
    assert [w['defect_suspected'] for w in windows] == [False] * 3 + [True] * 3
    assert windows[3]['kurtosis'] == pytest.approx(9.5) and windows[3]['defect_component'] == 'screw raceway'
    # plain Parquet: typed columns, the layout version and units in the metadata
    alone = pq.read_table(folder)
    assert alone.schema.metadata[b'prsm_lube_ros.history_layout'] == LAYOUT_VERSION.encode() == b'4'
    assert str(alone.schema.field('defect_suspected').type) == 'bool'
    assert {str(alone.schema.field(n).type) for n in ('kurtosis', 'crest_factor', 'defect_order')} == {'double'}
    assert json.loads(alone.schema.metadata[b'prsm_lube_ros.units'])['defect_order'] == 'x screw speed'
    assert set(DEFECT_COLUMNS) <= set(SCHEMAS['runs'].names) & set(SCHEMAS['windows'].names)


def test_without_indicators_the_numbers_are_null_and_no_defect_is_suspected(tmp_path):
    history, bag = tmp_path / 'history', recording(tmp_path, 'a.mcap')
    write(history, bag, assessment(bag, 0.9))
    for table in ('runs', 'windows'):
        rows = read_table(history, table).to_pylist()
        assert all(r['defect_suspected'] is False and r['kurtosis'] is None and r['crest_factor'] is None
                   and r['defect_component'] == '' and r['defect_evidence'] == '' for r in rows)


def test_a_history_written_before_the_screen_reads_with_the_columns_filled_and_says_so_once(tmp_path):
    history = tmp_path / 'history'
    old_bag, new_bag = recording(tmp_path, 'old.mcap', b'old'), recording(tmp_path, 'new.mcap', b'new')
    old = write(history, old_bag, screened(old_bag))
    as_layout_2(old)
    write(history, new_bag, screened(new_bag, days=1.0))
    assert 'defect_suspected' not in pq.read_table(old).column_names
    for table, rows in (('runs', 2), ('windows', 6)):
        notes = []
        found = read_table(history, table, on_note=notes.append)
        assert found.num_rows == 2 * rows
        by_path = {}
        for row in found.to_pylist():
            by_path.setdefault(row['recording_path'], []).append(row)
        assert all(r['defect_suspected'] is False and r['defect_component'] == '' and r['defect_evidence'] == ''
                   and r['kurtosis'] is None and r['crest_factor'] is None and r['defect_order'] is None
                   for r in by_path[str(old_bag)])
        assert any(r['defect_suspected'] for r in by_path[str(new_bag)])
        assert len(notes) == 1 and '1 recording(s) of 1 actuator(s)' in notes[0] and 'layout 2' in notes[0]
    # without on_note it reads all the same, quietly; an all-new history says nothing
    assert read_table(history, 'runs').column('defect_suspected').null_count == 0
    notes = []
    read_table(history, 'runs', actuator='other', on_note=notes.append)
    assert notes == []


def test_plain_duckdb_reads_a_history_of_both_layouts_by_name(tmp_path):
    duckdb = pytest.importorskip('duckdb')
    history = tmp_path / 'history'
    old_bag, new_bag = recording(tmp_path, 'old.mcap', b'old'), recording(tmp_path, 'new.mcap', b'new')
    as_layout_2(write(history, old_bag, screened(old_bag)))
    write(history, new_bag, screened(new_bag, days=1.0))
    rows = duckdb.sql(f"select recording_path, defect_suspected, defect_component from read_parquet("
                      f"'{history}/runs/*/*.parquet', hive_partitioning = true, union_by_name = true) "
                      "order by start").fetchall()
    assert rows == [(str(old_bag), None, None), (str(old_bag), None, None),
                    (str(new_bag), False, ''), (str(new_bag), True, 'screw raceway')]
