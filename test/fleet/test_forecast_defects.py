# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""An actuator with a suspected surface defect gets no lubrication forecast, ranks first, and changes no other."""
import math

import pyarrow
import pytest

from prsm_lube_ros.fleet.backtest import backtest
from prsm_lube_ros.fleet.defects import before_onsets, defect_marks, defect_onset, DefectMark
from prsm_lube_ros.fleet.forecast import DAY, forecast_points, history_records
from prsm_lube_ros.fleet.forecast_summary import forecast_summaries

from fleet_histories import exponential_points, recording, screened, write

LEVELS = (0.85, 0.70)


def fleet():
    """Three actuators of daily recordings at different rates and noise."""
    return {'A': exponential_points(40.0, noise=0.004, seed=1), 'B': exponential_points(25.0, noise=0.004, seed=2),
            'C': exponential_points(60.0, noise=0.004, seed=3)}


def mark(point, component='screw raceway', order=6.25, evidence='envelope line at 6.25x'):
    return DefectMark(point.time + 5.0, point.time, 'b.mcap', component, order, evidence, 1, 2)


def numbers(forecast):
    """Everything a forecast states, for comparing two of them."""
    document = forecast.as_json()
    return (document['tau_days'], document['theta_now'], document['crossings'],
            {level: list(days) for level, days in forecast.passage_days.items()})


def test_a_defect_stops_the_forecast_ranks_first_and_says_why():
    points = fleet()
    onset = points['B'][6]
    forecasts = forecast_points(points, levels=LEVELS, defects={'B': [mark(onset), mark(points['B'][8], '')]})
    assert [f.actuator for f in forecasts][0] == 'B'
    flagged = forecasts[0]
    assert flagged.reason.startswith('surface defect suspected since ') and 'screw raceway' in flagged.reason
    assert flagged.reason.endswith('theta_Oil is no lubrication measure, no lubrication forecast')
    document = flagged.as_json()
    assert document['defect_suspected'] is True and document['defect_component'] == 'screw raceway'
    assert document['defect_since'] == onset.time + 5.0 and document['defect_recordings'] == 2
    assert document['tau_days'] is None and document['theta_now'] is None and document['crossings'] == []
    assert len(document['points']) == len(points['B'])              # its recordings are still shown
    assert all(f.as_json()['defect_suspected'] is False for f in forecasts[1:])


def test_the_other_actuators_are_forecast_as_from_the_lubrication_record_alone():
    points = fleet()
    onset = points['B'][6]
    with_defect_ = {f.actuator: f for f in forecast_points(points, levels=LEVELS, defects={'B': [mark(onset)]})}
    cut = dict(points, B=points['B'][:6])                            # B's recordings before the onset only
    without = {f.actuator: f for f in forecast_points(cut, levels=LEVELS)}
    for name in ('A', 'C'):
        assert numbers(with_defect_[name]) == numbers(without[name])
    # and with no defect anywhere, nothing changes at all
    plain = {f.actuator: f for f in forecast_points(points, levels=LEVELS)}
    assert all(numbers(plain[n]) == numbers(f) for n, f in
               ((f.actuator, f) for f in forecast_points(points, levels=LEVELS, defects={})))


def test_before_its_onset_the_actuator_is_forecast_and_after_a_relubrication_the_defect_stays():
    points = {'A': exponential_points(40.0, days=12, relubricate_at=7.0, noise=0.002, seed=4)}
    onset = points['A'][3]
    early = forecast_points(points, levels=LEVELS, defects={'A': [mark(onset)]}, as_of=onset.time)[0]
    assert early.defect is None and not early.reason and early.tau_days > 0
    late = forecast_points(points, levels=LEVELS, defects={'A': [mark(onset)]}, relubrications={'A': [7.0 * DAY]})[0]
    assert late.defect is not None and late.relubrications == [7.0 * DAY]
    assert late.defect.since == onset.time + 5.0                     # relubricated since, still suspected
    # jumps after the onset are no relubrications found: theta_Oil reads the damage there
    assert forecast_points(points, levels=LEVELS, defects={'A': [mark(onset)]})[0].relubrications == []


def test_the_component_comes_from_the_first_mark_that_names_one():
    points = exponential_points()
    onset = defect_onset([mark(points[2], '', math.nan, 'impulsive (kurtosis 7.0)'), mark(points[4], 'roller', 3.75)])
    assert onset.since == points[2].time + 5.0 and onset.component == 'roller' and onset.order == 3.75
    assert defect_onset([mark(points[2], '', math.nan)]).reason.split(': ')[1].startswith('no defect order')
    assert before_onsets({'A': points, 'B': points[:3]}, {'A': onset}) == {'A': points[:2], 'B': points[:3]}


def test_marks_from_a_history_first_flagged_run_per_recording(tmp_path):
    history = tmp_path / 'history'
    healthy, spalled = recording(tmp_path, 'h.mcap', b'h'), recording(tmp_path, 's.mcap', b's')
    write(history, healthy, screened(healthy, flagged_runs=()))
    write(history, spalled, screened(spalled, flagged_runs=(2,)), actuator='A02')
    records = history_records(history)
    assert set(records.points) == {'A01', 'A02'} and records.notes == []
    (found,) = records.defects['A02']
    assert found.component == 'screw raceway' and found.flagged == 1 and found.runs == 2
    assert found.time > found.recording_start and 'A01' not in records.defects
    assert defect_marks(pyarrow.table({'actuator': ['A01']})) == {}      # a table without the defect columns


def test_the_diagnostics_summary_names_the_defect(tmp_path):
    history = tmp_path / 'history'
    for day in range(4):
        bag = recording(tmp_path, f'{day}.mcap', bytes([day]))
        found = screened(bag, theta=0.95 - 0.02 * day, flagged_runs=(2,) if day == 3 else (), days=day)
        write(history, bag, found)
    summary = forecast_summaries(history, ['A01'])['A01']
    assert summary['forecast'].startswith('surface defect suspected since')
    assert summary['defect_component'] == 'screw raceway' and summary['defect_since']


def test_the_backtest_scores_no_recording_after_the_onset():
    points = fleet()
    onset = points['B'][8]
    plain = backtest(points, 3.0, levels=LEVELS)
    flagged = backtest(points, 3.0, levels=LEVELS, defects={'B': [mark(onset)]})
    later = {a.actuator: a.later for a in plain.actuators}
    found = {a.actuator: a.later for a in flagged.actuators}
    assert found['B'] == later['B'] - 2 and found['A'] == later['A']
    cut = backtest(points, 1.0, levels=LEVELS, defects={'B': [mark(points['B'][2])]})
    (b,) = [a for a in cut.actuators if a.actuator == 'B']
    assert b.later == 0 and b.reason.startswith('surface defect suspected')


@pytest.mark.parametrize('as_of_day', [None, 20.0])
def test_an_actuator_known_only_by_its_flagged_runs_is_listed(as_of_day):
    points = fleet()
    forecasts = forecast_points({'A': points['A']}, levels=LEVELS, defects={'Z': [mark(points['A'][1])]},
                                as_of=None if as_of_day is None else as_of_day * DAY)
    assert forecasts[0].actuator == 'Z' and forecasts[0].points == [] and forecasts[0].defect is not None
