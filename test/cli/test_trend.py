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
    warn_times = [a['crossings'][0]['time'] for a in actuators]
    assert warn_times == sorted(warn_times)
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
