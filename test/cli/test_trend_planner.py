# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend`` for planners and against bad input, run as users run it (a fresh process).

Bad files are one line each and the rest is reported (status 2); the
planner's figures are stated as of a date; the backtest scores a forecast
made from the history cut earlier.
"""
import json
import shutil
import sys

import pytest

from trend_command import actuators, error_lines, table_rows, trend


def test_a_corrupt_file_and_a_stray_file_are_named_and_the_rest_reported(small_fleet, tmp_path):
    history = tmp_path / 'history'
    shutil.copytree(small_fleet['history'], history)
    broken = sorted((history / 'runs' / 'actuator=A02').glob('*.parquet'))[0]
    broken.write_bytes(b'PAR1 this is not parquet PAR1')
    (history / 'runs' / 'README.txt').write_text('notes')
    report = tmp_path / 'report'
    result = trend(history, '--report', report, '--as-of', '2026-01-07')
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 2, result.stderr
    assert any('README.txt' in line for line in lines) and any(str(broken) in line for line in lines)
    found = actuators(report)
    assert sorted(found) == ['A01', 'A02', 'A03', 'A04'] and found['A02']['recordings'] == 5


@pytest.mark.parametrize('kind', ['missing', 'empty', 'recordings folder'])
def test_an_empty_or_wrong_history_is_one_line_and_non_zero(small_fleet, tmp_path, kind):
    folder = {'missing': tmp_path / 'nothing', 'empty': tmp_path / 'empty',
              'recordings folder': small_fleet['root']}[kind]
    if kind == 'empty':
        (folder / 'recordings').mkdir(parents=True)
    result = trend(folder, '--report', tmp_path / 'r')
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 1 and str(folder) in lines[0], result.stderr


def test_odometer_problems_are_file_line_messages_and_the_actuators_reason(small_fleet, tmp_path):
    source = (small_fleet['root'] / 'odometer.csv').read_text().splitlines()
    header, rows = source[0], source[1:]
    a03 = [i for i, row in enumerate(rows) if row.startswith('A03,')]
    name, time, _ = rows[a03[-1]].split(',')
    rows[a03[-1]] = f'{name},{time},1'                   # A03's last reading goes backwards
    log = tmp_path / 'odometer.csv'
    log.write_text('\n'.join(['# exported from the drives', header, *rows, 'B99,2026-01-02T00:00:00,5']) + '\n')
    report = tmp_path / 'report'
    result = trend(small_fleet['history'], '--report', report, '--odometer', log, '--as-of', '2026-01-07')
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 2, result.stderr
    backwards = f'{log}:{a03[-1] + 3}:'                 # comment and header lines come first
    assert any(line.startswith(f'warning: {backwards}') and 'backwards' in line for line in lines)
    assert any(f'{log}:{len(rows) + 3}:' in line and 'B99' in line for line in lines)
    found = actuators(report)
    assert backwards in found['A03']['revolutions']['reason']
    assert found['A01']['revolutions']['depletion_revolutions'] > 0       # the header after the comment is a header
    markdown = table_rows((report / 'trend.md').read_text())
    assert len({row.count('|') for row in markdown}) == 1, 'every row has as many cells as the header'


def test_as_of_days_to_go_overdue_and_probability_by_date(small_fleet, tmp_path):
    early, late = tmp_path / 'early', tmp_path / 'late'
    assert trend(small_fleet['history'], '--report', early, '--as-of', '2026-01-04').returncode == 0
    assert trend(small_fleet['history'], '--report', late, '--as-of', '2026-03-01', '--by', '2026-03-02',
                 entry=[sys.executable, '-m', 'prsm_lube_ros.cli']).returncode == 0
    before, after = actuators(early), actuators(late)
    truth = json.loads((small_fleet['root'] / 'truth.json').read_text())
    as_of = json.loads((early / 'trend.json').read_text())['as_of']
    for name, item in before.items():
        assert all(point['time'] <= as_of for point in item['points'])     # only what was known by then
        assert item['recordings'] < after[name]['recordings'] == 6
    for name, item in after.items():
        warn = item['planner'][0]
        assert warn['status'] == 'overdue' and warn['days_to_go'] < 0 and warn['probability_crossed'] > 0.99
        assert 'overdue by' in (late / 'trend.md').read_text()
    for name, item in before.items():
        for planned, crossing in zip(item['planner'], item['crossings']):
            if crossing['time'] is not None:
                assert planned['days_to_go'] == pytest.approx((crossing['time'] - as_of) / 86400.0)
            if planned['probability_by'] is not None:
                assert planned['probability_crossed'] <= planned['probability_by']
    assert len(truth['actuators']) == len(after)


def test_the_level_sets_the_interval_and_bad_dates_are_one_line(small_fleet, tmp_path):
    wide, narrow = tmp_path / 'wide', tmp_path / 'narrow'
    assert trend(small_fleet['history'], '--report', wide, '--as-of', '2026-01-04').returncode == 0
    assert trend(small_fleet['history'], '--report', narrow, '--as-of', '2026-01-04', '--level', '0.5').returncode == 0
    for name, item in actuators(wide).items():
        crossing, half = item['crossings'][1], actuators(narrow)[name]['crossings'][1]
        if crossing['low'] is not None and crossing['high'] is not None:
            assert half['high'] - half['low'] < crossing['high'] - crossing['low']
    assert '50% interval' in (narrow / 'trend.md').read_text()
    for bad in (['--as-of', 'last tuesday'], ['--level', '95']):
        result = trend(small_fleet['history'], '--report', tmp_path / 'x', *bad)
        lines = error_lines(result)
        assert result.returncode == 2 and len(lines) == 1 and bad[0] in lines[0]


def test_the_backtest_scores_the_forecast_on_later_recordings(small_fleet, tmp_path):
    report = tmp_path / 'backtest'
    result = trend(small_fleet['history'], '--report', report, '--backtest', '2')
    assert result.returncode == 0, result.stderr
    document = json.loads((report / 'backtest.json').read_text())
    assert document['days'] == 2 and document['recordings_scored'] >= 4
    assert 0.0 <= document['band_coverage'] <= 1.0 and 'band coverage' in result.stdout
    assert sum(a['later'] for a in document['actuators']) == document['recordings_scored']


def test_an_as_of_date_before_every_recording_is_one_line(small_fleet, tmp_path):
    result = trend(small_fleet['history'], '--report', tmp_path / 'r', '--as-of', '2020-01-01')
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 1 and '--as-of 2020-01-01' in lines[0], result.stderr
