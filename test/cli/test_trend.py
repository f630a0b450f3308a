# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend``: table most urgent first, JSON and plots; bad input is one line."""
import json

import pytest

from prsm_lube_ros.cli import main


def test_trend_writes_json_table_and_plots_most_urgent_first(small_fleet, tmp_path, capsys):
    report = tmp_path / 'report'
    assert main(['trend', str(small_fleet['history']), '--report', str(report)]) == 0
    document = json.loads((report / 'trend.json').read_text())
    actuators = document['actuators']
    assert sorted(a['actuator'] for a in actuators) == ['A01', 'A02', 'A03', 'A04']
    assert [a['rank'] for a in actuators] == [1, 2, 3, 4]            # by the next crossing of either level
    assert all(a['next']['level'] in (0.85, 0.70) for a in actuators)
    assert (report / 'trend.html').is_file() and (report / 'trend.csv').read_text().count('\n') == 5
    assert all((report / f'{a["actuator"]}.png').stat().st_size > 1000 for a in actuators)
    assert (report / 'trend.md').read_text().count('| A0') == 4
    out = capsys.readouterr().out
    assert out.index(actuators[0]['actuator']) < out.index(actuators[-1]['actuator'])


def test_trend_of_one_actuator_with_given_relubrications(small_fleet, tmp_path):
    truth = json.loads((small_fleet['root'] / 'truth.json').read_text())
    csv = tmp_path / 'relub.csv'
    csv.write_text('actuator,time\n' + ''.join(f'{a["actuator_id"]},{r["time_utc"]}\n' for a in truth['actuators']
                                               for r in a['relubrications']))
    report = tmp_path / 'one'
    assert main(['trend', str(small_fleet['history']), '--actuator', 'A02', '--report', str(report),
                 '--relubrications', str(csv)]) == 0
    document = json.loads((report / 'trend.json').read_text())
    assert [a['actuator'] for a in document['actuators']] == ['A02']


def test_bad_input_is_one_line(small_fleet, tmp_path, capsys):
    csv = tmp_path / 'bad.csv'
    csv.write_text('A01,yesterday\n')
    assert main(['trend', str(small_fleet['history']), '--report', str(tmp_path / 'r'),
                 '--relubrications', str(csv)]) == 2
    assert main(['trend', str(tmp_path / 'nothing'), '--report', str(tmp_path / 'r')]) == 2
    assert main(['trend', str(small_fleet['history']), '--report', str(tmp_path / 'r'), '--warn-below', '0.6']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and 'yesterday' in err[0] and 'nothing' in err[1] and 'error_below' in err[2]
    assert 'Traceback' not in '\n'.join(err)


def test_trend_with_an_odometer_fits_the_depletion_revolutions(small_fleet, tmp_path, capsys):
    truth = json.loads((small_fleet['root'] / 'truth.json').read_text())
    report = tmp_path / 'odometer'
    assert main(['trend', str(small_fleet['history']), '--report', str(report),
                 '--odometer', str(small_fleet['root'] / 'odometer.csv')]) == 0
    assert 'N_d rev' in capsys.readouterr().out
    fitted = {a['actuator']: a['revolutions'] for a in json.loads((report / 'trend.json').read_text())['actuators']}
    for actuator in truth['actuators']:
        revolutions = fitted[actuator['actuator_id']]
        assert revolutions['depletion_revolutions'] == pytest.approx(actuator['depletion_revolutions'], rel=0.25)
        assert len(revolutions['crossings']) == 2


def test_a_non_utf8_log_and_a_report_that_is_a_file_are_one_line(small_fleet, tmp_path, capsys):
    binary = tmp_path / 'log.csv'
    binary.write_bytes(b'A01,\xff\xfe2026\n')
    for option in ('--relubrications', '--odometer'):
        assert main(['trend', str(small_fleet['history']), '--report', str(tmp_path / 'r'),
                     option, str(binary)]) == 2
    a_file = tmp_path / 'taken'
    a_file.write_text('x')
    assert main(['trend', str(small_fleet['history']), '--report', str(a_file)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and 'UTF-8' in err[0] and 'UTF-8' in err[1] and 'taken' in err[2]
    assert 'Traceback' not in '\n'.join(err)


def test_the_help_shows_a_plain_percent_sign(capsys):
    with pytest.raises(SystemExit):
        main(['trend', '--help'])
    out = capsys.readouterr().out
    assert '95 %' in out and '%%' not in out


def test_a_recording_assessed_twice_at_one_start_time_does_not_break_the_trend(small_fleet, tmp_path):
    """A02's recordings also stored in another format (other bytes, the same start): steps of zero days."""
    import shutil
    import pyarrow as pa
    import pyarrow.parquet as pq
    from prsm_lube_ros.fleet.history import read_table
    history = tmp_path / 'history'
    shutil.copytree(small_fleet['history'], history)
    for runs in sorted((history / 'runs' / 'actuator=A02').glob('*.parquet')):
        for table in ('runs', 'windows'):
            rows = pq.read_table(history / table / runs.parent.name / runs.name)
            twin = rows.set_column(rows.schema.get_field_index('content_hash'), 'content_hash',
                                   pa.array(['f' + h[1:] for h in rows.column('content_hash').to_pylist()]))
            twin = twin.set_column(twin.schema.get_field_index('recording_path'), 'recording_path',
                                   pa.array([p + '.db3' for p in twin.column('recording_path').to_pylist()]))
            pq.write_table(twin, history / table / runs.parent.name / f'f{runs.name[1:]}')
    starts = read_table(history, actuator='A02').column('start').to_pylist()
    assert len(starts) == 2 * len(set(starts))
    report = tmp_path / 'report'
    assert main(['trend', str(history), '--report', str(report)]) == 0
    actuators = {a['actuator']: a for a in json.loads((report / 'trend.json').read_text())['actuators']}
    assert sorted(actuators) == ['A01', 'A02', 'A03', 'A04']
    assert not actuators['A02']['reason'] and actuators['A02']['tau_days'] > 0
