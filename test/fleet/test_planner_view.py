# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The planner's fleet view: ranked by the next crossing of either level, data age and staleness, theta_Oil at the
as-of date; intervals that widen with the horizon and hold their estimate; the backtest per horizon."""
import json
import math

import numpy as np

from prsm_lube_ros.experiments.fleet_study import draw_conditions, synthetic_points, true_points
from prsm_lube_ros.fleet.backtest import horizon_class, horizon_coverage, rolling_backtest
from prsm_lube_ros.fleet.forecast import DAY, fit_depletion, forecast_points, RecordingPoint
from prsm_lube_ros.fleet.planner import CrossingStatus, planner_rows
from prsm_lube_ros.simulation.fleet import FleetPlan, simulate_fleet


def law(theta0, tau_days, days=20, sigma=0.002, seed=0):
    """theta0 exp(-t / tau), one recording a day for ``days`` days, noise of one-sigma ``sigma``."""
    rng = np.random.default_rng(seed)
    return [RecordingPoint((d + 0.5) * DAY, theta0 * math.exp(-(d + 0.5) / tau_days) + sigma * rng.standard_normal(),
                           sigma) for d in range(days)]


def fleet_past_warn():
    """Five actuators past warn long ago with error 10-25 d ahead, and X past warn lately with error 4 d ahead."""
    last = 19.5
    points = {}
    for number, ahead in enumerate((10.0, 13.0, 16.0, 20.0, 25.0)):
        tau = (last + ahead) / math.log(0.87 / 0.70)
        points[f'S{number}'] = law(0.87, tau, seed=number)
    points['X'] = law(0.95, (last + 4.0) / math.log(0.95 / 0.70), seed=9)
    return points


def test_the_next_crossing_of_either_level_ranks_an_actuator_4_days_from_error_first():
    points = fleet_past_warn()
    forecasts = forecast_points(points, levels=(0.85, 0.70))
    as_of = max(p.time for items in points.values() for p in items)
    # warn first (the crossings' order) puts X last: it crossed warn latest, though it reaches error first
    assert [f.actuator for f in forecasts][-1] == 'X'
    rows = planner_rows(forecasts, as_of, as_of + 30 * DAY)
    assert [row.rank for row in rows] == list(range(1, 7))
    first = rows[0]
    assert first.actuator == 'X' and first.next.level == 0.70 and first.next.status is CrossingStatus.AHEAD
    assert 2.0 < first.next.days_to_go < 6.0 and first.next.probability_by > 0.99
    for row in rows:
        assert row.planned[0].status is CrossingStatus.OVERDUE           # every warn level is long past
        assert row.next.level == 0.70
    days = [row.next.days_to_go for row in rows]
    assert days == sorted(days) and days[-1] > 15.0


def test_a_warn_crossing_ahead_comes_before_an_error_crossing_further_ahead():
    points = fleet_past_warn()
    points['W'] = law(0.95, 25.0 / math.log(0.95 / 0.85), seed=11)      # warn about 5 d after the last recording
    as_of = max(p.time for items in points.values() for p in items)
    rows = planner_rows(forecast_points(points, levels=(0.85, 0.70)), as_of, as_of + 30 * DAY)
    ranked = [row.actuator for row in rows]
    assert ranked.index('X') < ranked.index('W') < ranked.index('S1')
    w = rows[ranked.index('W')]
    assert w.next.level == 0.85 and 2.0 < w.next.days_to_go < 9.0


def test_stale_data_is_flagged_and_theta_is_forecast_at_the_as_of_date_not_the_last_measurement():
    points = {'A': law(0.95, 60.0, days=10)}
    forecast, = forecast_points(points, levels=(0.85, 0.70))
    last = points['A'][-1]
    fresh, = planner_rows([forecast], last.time + 0.5 * DAY, last.time + 30 * DAY)
    assert not fresh.stale and fresh.data_age_days == 0.5
    assert abs(fresh.theta_as_of[0] - 0.95 * math.exp(-10.0 / 60.0)) < 0.01
    old, = planner_rows([forecast], last.time + 316 * DAY, last.time + 346 * DAY)
    assert old.stale and abs(old.data_age_days - 316.0) < 1e-9 and old.last_seen == last.time
    centre, low, high = old.theta_as_of
    assert low < centre < high < last.theta_oil - 0.5           # 316 more days of depletion, with a wide band
    assert high / low > fresh.theta_as_of[2] / fresh.theta_as_of[1]
    assert old.next.level == 0.70 and old.next.status is CrossingStatus.OVERDUE
    assert planner_rows([forecast], last.time + 5 * DAY, last.time + 6 * DAY, stale_days=4.0)[0].stale


def test_the_interval_widens_with_the_horizon_and_holds_its_estimate():
    forecast = fit_depletion('A', law(0.95, 60.0, days=10), levels=(0.85, 0.70, 0.5))
    widths = [c.high - c.low for c in forecast.crossings]
    assert widths == sorted(widths) and widths[-1] > 3 * widths[0]
    times = forecast.last_recording + np.array([1.0, 7.0, 14.0, 30.0]) * DAY
    _, low, high = forecast.band(times)
    spread = np.log(high) - np.log(low)
    assert np.all(np.diff(spread) > 0)
    for crossing in forecast.crossings:
        assert crossing.low <= crossing.time <= crossing.high


def test_no_estimate_outside_its_interval_over_drawn_fleets(tmp_path):
    """Fleets drawn over wide ranges (conditions of :func:`draw_conditions`), both levels, every cut."""
    outside = scored = 0
    for seed in (11, 12):
        plan, noise = draw_conditions(seed, 8, 30)
        simulate_fleet(tmp_path / str(seed), fleet=plan, seed=seed, write_recordings=False)
        truth = json.loads((tmp_path / str(seed) / 'truth.json').read_text())
        points = synthetic_points(truth, noise=noise, seed=seed)
        for cut in (20.0, 10.0, 0.0):
            newest = max(p.time for items in points.values() for p in items)
            for forecast in forecast_points(points, levels=(0.85, 0.70), as_of=newest - cut * DAY):
                for crossing in forecast.crossings:
                    if crossing.time is not None:
                        scored += 1
                        high = math.inf if crossing.high is None else crossing.high
                        outside += not (crossing.low <= crossing.time <= high)
    assert scored > 40 and outside == 0


def test_the_backtest_scores_both_levels_per_horizon_and_the_error_level_is_reached(tmp_path):
    plan = FleetPlan(actuators=12, days=40, days_to_reference=(6 / 40, 20 / 40), relubricate_below_range=(0.55, 0.68),
                     relubrication_put_off=0.3, recording_missed=0.2)
    simulate_fleet(tmp_path, fleet=plan, seed=21, write_recordings=False)
    truth = json.loads((tmp_path / 'truth.json').read_text())
    recorded = [r['theta_oil'] for a in truth['actuators'] for r in a['recordings']]
    assert min(recorded) < 0.70                                  # the error level is reached and recorded
    assert sum(len(a['recordings']) for a in truth['actuators']) < 12 * 40     # days without a recording
    points = synthetic_points(truth, noise=0.004, seed=21)
    results = rolling_backtest(points, levels=(0.85, 0.70), step_days=5.0)
    assert len(results) == 6 and [r.days for r in results] == [5.0, 10.0, 15.0, 20.0, 25.0, 30.0]
    table = horizon_coverage(results)
    assert [(c.level, c.horizon_days) for c in table] == [(lv, h) for lv in (0.85, 0.70) for h in (3, 7, 14, 30)]
    error = [c for c in table if c.level == 0.70]
    assert sum(c.scored for c in error) >= 10 and sum(c.scored for c in error if c.horizon_days >= 14) >= 2
    assert sum(c.inside for c in table) >= 0.9 * sum(c.scored for c in table)
    assert all(c.estimates_outside == 0 for c in table)
    against_truth = horizon_coverage(rolling_backtest(points, levels=(0.85, 0.70), step_days=5.0,
                                                      truth=true_points(truth)))
    assert sum(c.scored for c in against_truth) >= 20
    assert horizon_class(0.5) == 3 and horizon_class(7.0) == 7 and horizon_class(7.01) == 14
    assert horizon_class(31.0) is None


def test_a_relubrication_placed_before_the_cut_but_after_the_last_recording_ends_the_scoring():
    """The jump up lies between the last recording before the cut and the first after it."""
    points = law(0.80, 30.0, days=10)
    refill = [RecordingPoint(p.time + 10 * DAY, 0.97 * math.exp(-(p.time / DAY - 0.5) / 30.0), 0.002)
              for p in points[:8]]
    gap_free = points + refill
    from prsm_lube_ros.fleet.backtest import backtest
    newest = refill[-1].time
    # cut just after the half-way point of the last old recording and the first new one
    cut_days = (newest - 0.5 * (points[-1].time + refill[0].time)) / DAY - 0.01
    result = backtest({'A': gap_free}, cut_days, levels=(0.85, 0.70))
    assert result.actuators[0].later == 0 and not result.actuators[0].crossings


def test_the_horizon_study_writes_its_tables_and_a_json_a_plain_reader_loads(tmp_path):
    from prsm_lube_ros.experiments.fleet_study import main
    status = main(['--out', str(tmp_path / 'out'), '--results', str(tmp_path / 'results'), '--horizons', '3', '7',
                   '--synthetic', '--seeds', '5', '--actuators', '4', '--days', '16', '--step', '4'])
    document = json.loads((tmp_path / 'results' / 'results.json').read_text())
    assert status == (0 if document['pass'] else 1)
    assert document['horizons'] == [3.0, 7.0] and document['estimates_outside'] == 0
    table = document['coverage']['truth']
    assert [(c['level'], c['horizon_days']) for c in table] == [(0.85, 3.0), (0.85, 7.0), (0.7, 3.0), (0.7, 7.0)]
    assert all(isinstance(c['inside'], int) and 0 <= c['inside'] <= c['scored'] for c in table)
    conditions = document['fleets'][0]['conditions']
    assert 0 <= conditions['recording_missed'] < 1 and conditions['relubricate_below_range'][0] >= 0.55
    text = (tmp_path / 'results' / 'coverage.md').read_text()
    assert '| 0.85 |' in text and '| 0.7 |' in text and '| 5 |' in text
