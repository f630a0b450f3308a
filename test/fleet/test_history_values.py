# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Any value in a history file: one line naming file and row (or column), the other actuators still forecast.

Issue 37: a row with theta = inf gave ``trend`` a TypeError traceback, and a
1.3 MB Parquet file of 300 M rows made it take 2.3 GB.
"""
import io
import json
import shutil
import struct

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from prsm_lube_ros.cli import main
from prsm_lube_ros.fleet import history as history_module
from prsm_lube_ros.fleet.history import read_table


def copied(small_fleet, tmp_path):
    target = tmp_path / 'history'
    shutil.copytree(small_fleet['history'], target)
    return target


def first_runs_file(history, actuator):
    return sorted((history / 'runs' / f'actuator={actuator}').glob('*.parquet'))[0]


def rewrite(file, change):
    """Rewrite a Parquet file with ``change(table)`` applied, its schema metadata kept."""
    table = pq.read_table(file)
    changed = change(table)
    pq.write_table(changed.replace_schema_metadata(table.schema.metadata), file)


def with_value(table, column, row, value):
    values = table.column(column).to_pylist()
    values[row] = value
    index = table.schema.get_field_index(column)
    return table.set_column(index, table.schema.field(column), pa.array(values, table.schema.field(column).type))


def _varint(number):
    out = bytearray()
    while True:
        low, number = number & 0x7F, number >> 7
        out.append(low | (0x80 if number else 0))
        if not number:
            return bytes(out)


def planted(path, rows=300_000_000):
    """A small Parquet file whose footer declares ``rows`` rows (its row counts rewritten in the Thrift footer)."""
    written = 123457
    buffer = io.BytesIO()
    pq.write_table(pa.table({'theta_oil': pa.nulls(written, pa.float64())}), buffer)
    data = buffer.getvalue()
    length = struct.unpack('<I', data[-8:-4])[0]
    footer = data[-8 - length:-8].replace(b'\x16' + _varint(2 * written), b'\x16' + _varint(2 * rows))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(data[:-8 - length] + footer + struct.pack('<I', len(footer)) + b'PAR1')
    assert pq.read_metadata(path).num_rows == rows
    return path


def trend(history, report, capsys):
    status = main(['trend', str(history), '--report', str(report)])
    captured = capsys.readouterr()
    assert 'Traceback' not in captured.err
    return status, [line for line in captured.err.splitlines() if line.strip()], \
        json.loads((report / 'trend.json').read_text())


def test_inf_nan_and_a_wrong_type_are_each_one_line_and_the_others_are_forecast(small_fleet, tmp_path, capsys):
    history = copied(small_fleet, tmp_path)
    infinite, not_a_number, mistyped = (first_runs_file(history, name) for name in ('A02', 'A03', 'A04'))
    rewrite(infinite, lambda t: with_value(t, 'theta_oil', 0, float('inf')))
    rewrite(not_a_number, lambda t: with_value(with_value(t, 'theta_oil', 1, float('nan')),
                                               'vibration_rms', 0, -1.0))
    rewrite(mistyped, lambda t: t.set_column(t.schema.get_field_index('theta_oil'), 'theta_oil',
                                             pa.array(['dry'] * t.num_rows)))
    status, lines, document = trend(history, tmp_path / 'report', capsys)
    assert status == 2
    assert any(str(infinite) in line and 'row 0' in line and 'theta_oil = inf' in line for line in lines), lines
    assert any(str(not_a_number) in line and 'row 1' in line and 'theta_oil = nan' in line for line in lines)
    assert any(str(not_a_number) in line and 'row 0' in line and 'vibration_rms = -1.0' in line for line in lines)
    assert any(str(mistyped) in line and 'column theta_oil' in line for line in lines), lines
    assert all('\n' not in line for line in lines)
    forecast = {a['actuator'] for a in document['actuators'] if not a.get('reason')}
    assert forecast == {'A01', 'A02', 'A03', 'A04'}
    # the rows left out are those only: the rest of each file is read
    runs = read_table(history, on_problem=lambda line: None)
    assert runs.num_rows == read_table(small_fleet['history']).num_rows - 3 - \
        pq.read_metadata(mistyped).num_rows


def test_a_planted_file_of_300_million_rows_is_refused_before_it_is_loaded(small_fleet, tmp_path, capsys,
                                                                           monkeypatch):
    history = copied(small_fleet, tmp_path)
    big = planted(history / 'runs' / 'actuator=A09' / f'{"0" * 16}.parquet')
    loaded = []
    real = pq.read_table
    monkeypatch.setattr(history_module.pq, 'read_table', lambda source, *a, **k: loaded.append(str(source)) or
                        real(source, *a, **k))
    status, lines, document = trend(history, tmp_path / 'report', capsys)
    assert status == 2 and len(lines) == 1, lines
    assert str(big) in lines[0] and '300000000 rows' in lines[0]
    assert str(big) not in loaded and len(loaded) > 0
    assert {a['actuator'] for a in document['actuators']} == {'A01', 'A02', 'A03', 'A04'}


def with_start(table, row, microseconds):
    """``table`` with the ``start`` of ``row`` set to ``microseconds`` since the epoch."""
    values = table.column('start').cast(pa.int64()).to_pylist()
    values[row] = microseconds
    field = table.schema.field('start')
    return table.set_column(table.schema.get_field_index('start'), field, pa.array(values, pa.int64()).cast(field.type))


@pytest.mark.parametrize('start', [-1, 2 ** 62])
def test_a_time_no_recording_has_is_one_line(small_fleet, tmp_path, start):
    history = copied(small_fleet, tmp_path)
    file = first_runs_file(history, 'A01')
    rewrite(file, lambda t: with_start(t, 0, start))
    problems = []
    runs = read_table(history, actuator='A01', on_problem=problems.append)
    assert len(problems) == 1 and str(file) in problems[0] and 'row 0: start' in problems[0]
    assert runs.num_rows == read_table(small_fleet['history'], actuator='A01').num_rows - 1


def test_an_earlier_layout_reads_with_a_note_and_the_next_writer_moves_it(small_fleet, tmp_path):
    """Layout 3 (recordings/actuator=ID/recording=KEY/{runs,windows}.parquet) as written before layout 4."""
    from prsm_lube_ros.fleet.history import migrate, RECORDINGS
    history = tmp_path / 'history'
    for file in small_fleet['history'].glob('runs/*/*.parquet'):
        for table in ('runs', 'windows'):
            source = small_fleet['history'] / table / file.parent.name / file.name
            old = pq.read_table(source)
            old = old.drop_columns(list(history_module.IDENTITY_COLUMNS))
            target = history / RECORDINGS / file.parent.name / f'recording={file.stem}' / f'{table}.parquet'
            target.parent.mkdir(parents=True, exist_ok=True)
            pq.write_table(old, target)
    shutil.copytree(small_fleet['history'] / 'calibrations', history / 'calibrations')
    notes = []
    before = read_table(history, on_note=notes.append)
    assert len(notes) == 1 and RECORDINGS in notes[0] and 'next prsm-lube assess --history' in notes[0]
    expected = read_table(small_fleet['history'])
    assert before.num_rows == expected.num_rows
    assert sorted(before.column('actuator_id').to_pylist()) == sorted(expected.column('actuator').to_pylist())
    assert migrate(history) == len(list(small_fleet['history'].glob('runs/*/*.parquet')))
    assert not (history / RECORDINGS).exists()
    after = read_table(history, on_note=notes.append)
    assert len(notes) == 1 and after.num_rows == expected.num_rows
    import pandas
    assert len(pandas.read_parquet(history / 'windows')) == read_table(small_fleet['history'], 'windows').num_rows
