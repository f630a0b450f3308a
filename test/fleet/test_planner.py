# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The planner's view of a forecast (may have crossed, overdue, probability by a date) and the backtest."""
import json
import math
import warnings

import pytest

from prsm_lube_ros.experiments.fleet_study import synthetic_points
from prsm_lube_ros.fleet.backtest import backtest
from prsm_lube_ros.fleet.forecast import DAY, fit_depletion, RecordingPoint
from prsm_lube_ros.fleet.planner import CrossingStatus, plan, planner_text
from prsm_lube_ros.simulation.fleet import FleetPlan, simulate_fleet


def falling(sigma=0.003, days=10, tau=40.0):
    """Exact theta = 0.95 exp(-t / tau), one recording a day, each with one-sigma ``sigma``."""
    return [RecordingPoint((d + 0.5) * DAY, 0.95 * math.exp(-(d + 0.5) / tau), sigma) for d in range(days)]


def test_a_level_the_last_recording_reads_above_by_its_noise_may_already_have_been_crossed():
    """The true theta fell below the level before the last recording, which reads 2 sigma high."""
    points = falling()
    law = points[-1]
    last = RecordingPoint(law.time, law.theta_oil + 2 * law.theta_oil_std, law.theta_oil_std)
    points[-1] = last
    level = law.theta_oil + law.theta_oil_std                  # below the reading, above the truth
    forecast = fit_depletion('A', points, levels=(level,))
    warn, = plan(forecast, as_of=last.time, by=last.time + DAY)
    assert warn.status is CrossingStatus.MAY_HAVE_CROSSED
    assert 0.5 < warn.probability_crossed < 0.975 and warn.probability_by > 0.99
    assert warn.days_low <= 0.0 and warn.days_to_go < 0.0      # the interval reaches back before the last recording
    assert 'may have crossed, p 0.' in planner_text(warn)
    later, = plan(forecast, as_of=last.time + 3 * DAY, by=last.time + 4 * DAY)
    assert later.status is CrossingStatus.OVERDUE and later.days_to_go < -2.0
    assert planner_text(later).startswith('overdue by 3.')


def test_a_level_far_below_is_ahead_with_a_probability_growing_with_the_date():
    points = falling()
    forecast = fit_depletion('A', points, levels=(0.5,))
    last = points[-1].time
    near, = plan(forecast, as_of=last, by=last + 5 * DAY)
    far, = plan(forecast, as_of=last, by=last + 30 * DAY)
    assert near.status is CrossingStatus.AHEAD and near.probability_crossed == 0.0
    true_days = 40.0 * math.log(points[-1].theta_oil / 0.5)                 # 16.7 d after the last recording
    assert near.days_to_go == pytest.approx(true_days, rel=0.05)
    assert near.probability_by < 0.05 and far.probability_by > 0.95


@pytest.fixture(scope='module')
def fleets(tmp_path_factory):
    """Two simulated fleets of 20 actuators x 10 days, each with two draws of the assessment's noise."""
    found = []
    for seed in (0, 1):
        folder = tmp_path_factory.mktemp(f'fleet{seed}')
        simulate_fleet(folder, fleet=FleetPlan(actuators=20, days=10), seed=seed, write_recordings=False)
        truth = json.loads((folder / 'truth.json').read_text())
        found += [synthetic_points(truth, seed=draw) for draw in (0, 1)]
    return found


def test_backtest_coverage_on_simulated_fleets_is_near_the_stated_level(fleets):
    """Forecasts made 5 days before the end: later recordings inside the band about as often as stated."""
    for confidence, least, most in ((0.95, 0.9, 1.0), (0.8, 0.7, 0.95)):
        inside = total = hits = crossings = 0
        with warnings.catch_warnings():
            warnings.simplefilter('error')           # no numpy warning reaches the user
            results = [backtest(points, 5.0, levels=(0.85, 0.70), confidence=confidence) for points in fleets]
        for result in results:
            inside += sum(a.inside_band for a in result.actuators)
            total += sum(a.later for a in result.actuators)
            hits += sum(c.inside for a in result.actuators for c in a.crossings)
            crossings += sum(len(a.crossings) for a in result.actuators)
        assert total > 300 and least <= inside / total <= most, (confidence, inside, total)
        assert crossings >= 20 and hits / crossings >= least - 0.1


def test_the_backtest_stops_scoring_at_a_relubrication_it_could_not_know(fleets):
    result = backtest(fleets[0], 5.0, levels=(0.85,))
    for item in result.actuators:
        assert item.later <= 5 and item.inside_band <= item.later
