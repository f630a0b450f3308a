# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend`` (the installed command) on a history with a suspected surface defect, and on an old history.

A02 of the simulated small fleet is marked as a spalled screw from its fourth
recording on (the simulator makes no defects; the screen's columns are set in
its Parquet files as ``assess`` writes them for a flagged run).
"""
import datetime
import json
import shutil

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from prsm_lube_ros.fleet.history import DEFECT_COLUMNS

from trend_command import actuators, error_lines, table_rows, trend

EVIDENCE = ('impulsive (kurtosis 8.3, crest factor 7.9; healthy up to 4.0); envelope line at 6.25x screw speed, '
            '21 dB over the floor: screw raceway defect suspected')
OTHERS = ('A01', 'A03', 'A04')


def recordings(history, actuator):
    """An actuator's runs files (history layout 4: one per recording) in time order."""
    files = (history / 'runs' / f'actuator={actuator}').glob('*.parquet')
    return sorted(files, key=lambda f: min(pq.read_table(f).column('start').to_pylist()))


def set_columns(path, **values):
    table = pq.read_table(path)
    for name, value in values.items():
        index = table.schema.get_field_index(name)
        table = table.set_column(index, table.schema.field(name), pa.array([value] * table.num_rows,
                                                                           table.schema.field(name).type))
    pq.write_table(table, path)


@pytest.fixture(scope='module')
def histories(small_fleet, tmp_path_factory):
    """``spalled`` (A02 flagged from its 4th recording), ``cut`` (those recordings left out), ``old`` (layout 2)."""
    root = tmp_path_factory.mktemp('defect_histories')
    spalled, cut, old = root / 'spalled', root / 'cut', root / 'old'
    for copy in (spalled, cut, old):
        shutil.copytree(small_fleet['history'], copy)
    for runs in recordings(spalled, 'A02')[3:]:
        set_columns(runs, defect_suspected=True, kurtosis=8.3, crest_factor=7.9,
                    defect_component='screw raceway', defect_order=6.25, defect_evidence=EVIDENCE)
    for runs in recordings(cut, 'A02')[3:]:
        runs.unlink()
        (cut / 'windows' / runs.parent.name / runs.name).unlink()
    for path in (*(old / 'runs').glob('*/*.parquet'), *(old / 'windows').glob('*/*.parquet')):
        table = pq.read_table(path).drop_columns(list(DEFECT_COLUMNS))
        pq.write_table(table.replace_schema_metadata({**table.schema.metadata,
                                                      b'prsm_lube_ros.history_layout': b'2'}), path)
    onset = min(pq.read_table(recordings(spalled, 'A02')[3]).column('start').to_pylist())
    return {'spalled': spalled, 'cut': cut, 'old': old, 'onset': onset}


def stated(entry):
    """What a forecast states (the planner's view included), for comparing two reports."""
    return {key: entry[key] for key in ('tau_days', 'tau_days_std', 'theta_now', 'crossings', 'planner',
                                        'relubrications', 'recordings')}


def test_a_suspected_defect_stops_the_forecast_comes_first_and_changes_no_other(small_fleet, histories, tmp_path):
    report, cut_report = tmp_path / 'spalled', tmp_path / 'cut'
    result = trend(histories['spalled'], '--report', report, '--as-of', '2026-01-07')
    assert result.returncode == 0 and not error_lines(result), result.stderr
    assert trend(histories['cut'], '--report', cut_report, '--as-of', '2026-01-07').returncode == 0
    document = json.loads((report / 'trend.json').read_text())
    first = document['actuators'][0]
    assert first['actuator'] == 'A02' and first['defect_suspected'] is True
    assert first['defect_component'] == 'screw raceway' and first['defect_order'] == 6.25
    assert first['defect_since_utc'] == histories['onset'].isoformat(timespec='minutes')
    assert first['defect_evidence'] == EVIDENCE and first['defect_recordings'] == 3
    assert first['tau_days'] is None and first['theta_now'] is None and first['crossings'] == []
    assert first['planner'] == [] and first['recordings'] == 6
    reason = f'surface defect suspected since {first["defect_since_utc"]}: screw raceway; theta_Oil is no ' \
             'lubrication measure, no lubrication forecast'
    assert first['reason'] == reason
    markdown = (report / 'trend.md').read_text()
    rows = table_rows(markdown)
    assert rows[2].startswith('| 1 | A02 |') and reason in rows[2] and len({r.count('|') for r in rows}) == 1
    assert 'Surface defect suspected: inspect' in markdown and EVIDENCE in markdown
    assert reason in result.stdout and (report / 'A02.png').stat().st_size > 1000
    # the others: exactly the numbers of a history holding A02's recordings before the defect only
    cut = actuators(cut_report)
    spalled = actuators(report)
    for name in OTHERS:
        assert spalled[name]['defect_suspected'] is False and spalled[name]['tau_days'] > 0
        assert stated(spalled[name]) == stated(cut[name])


def test_before_the_onset_the_actuator_is_forecast_as_before(histories, small_fleet, tmp_path):
    as_of = (histories['onset'] - datetime.timedelta(minutes=1)).isoformat()    # the onset's recording not yet made
    early, plain = tmp_path / 'early', tmp_path / 'plain'
    assert trend(histories['spalled'], '--report', early, '--as-of', as_of).returncode == 0
    assert trend(small_fleet['history'], '--report', plain, '--as-of', as_of).returncode == 0
    before, unmarked = actuators(early), actuators(plain)
    assert before['A02']['defect_suspected'] is False
    for name in ('A02', *OTHERS):
        assert stated(before[name]) == stated(unmarked[name])


def test_a_history_written_before_the_screen_is_forecast_and_said_once(histories, small_fleet, tmp_path):
    report, plain = tmp_path / 'old', tmp_path / 'plain'
    result = trend(histories['old'], '--report', report, '--as-of', '2026-01-07')
    assert result.returncode == 0 and not error_lines(result), result.stderr
    assert trend(small_fleet['history'], '--report', plain, '--as-of', '2026-01-07').returncode == 0
    notes = json.loads((report / 'trend.json').read_text())['notes']
    assert len(notes) == 1 and '24 recording(s) of 4 actuator(s)' in notes[0]
    assert 'before the surface defect screen' in notes[0]
    assert result.stdout.count('before the surface defect screen') == 1
    assert (report / 'trend.md').read_text().count('before the surface defect screen') == 1
    old, new = actuators(report), actuators(plain)
    assert sorted(old) == sorted(new) == ['A01', 'A02', 'A03', 'A04']
    for name in old:
        assert old[name]['defect_suspected'] is False and stated(old[name]) == stated(new[name])
    assert json.loads((plain / 'trend.json').read_text())['notes'] == []


def test_the_backtest_leaves_out_what_the_defect_made(histories, tmp_path):
    report = tmp_path / 'backtest'
    result = trend(histories['spalled'], '--report', report, '--backtest', '2')
    assert result.returncode == 0, result.stderr
    scored = {a['actuator']: a for a in json.loads((report / 'backtest.json').read_text())['actuators']}
    assert scored['A02']['reason'].startswith('surface defect suspected') and scored['A02']['later'] == 0
