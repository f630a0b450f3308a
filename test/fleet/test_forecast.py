# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Depletion fit and threshold-crossing forecast: against exact laws, and against a simulated fleet's truth."""
import json
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.experiments.fleet_study import compare_with_truth, coverage_rows, synthetic_points
from prsm_lube_ros.fleet.forecast import DAY, detect_relubrications, fit_depletion, forecast_points, RecordingPoint
from prsm_lube_ros.fleet.forecast_summary import forecast_summary
from prsm_lube_ros.simulation.fleet import FleetPlan, simulate_fleet

from fleet_histories import exponential_points


def test_an_exact_law_gives_its_time_constant_and_crossings():
    forecast = fit_depletion('A', exponential_points(), levels=(0.85, 0.70))
    assert not forecast.reason
    assert forecast.tau_days == pytest.approx(40.0, rel=1e-6)
    warn, error = forecast.crossings
    assert warn.time / DAY == pytest.approx(40.0 * math.log(0.95 / 0.85), abs=1e-3)     # 4.45 d: seen, interpolated
    assert error.time / DAY == pytest.approx(40.0 * math.log(0.95 / 0.70), rel=1e-3)    # 12.2 d: ahead of the data
    assert error.low <= error.time <= error.high


def test_a_jump_up_is_a_relubrication_and_the_new_cycle_is_forecast():
    points = exponential_points(tau_days=30.0, days=12, relubricate_at=6.0, noise=0.003)
    found = detect_relubrications(points)
    assert len(found) == 1 and 5.5 * DAY < found[0] < 6.5 * DAY
    forecast = fit_depletion('A', points, levels=(0.85,))
    true = (6.0 + 30.0 * math.log(0.98 / 0.85)) * DAY
    crossing = forecast.crossings[0]
    assert crossing.low <= true <= crossing.high and forecast.tau_days == pytest.approx(30.0, rel=0.15)


def test_too_few_recordings_say_so():
    forecast = fit_depletion('A', exponential_points(days=2))
    assert 'need at least 3' in forecast.reason and not forecast.crossings


def test_warn_crossing_inside_its_interval_for_nine_in_ten_of_a_simulated_fleet(tmp_path):
    """20 actuators x 10 days (200 recordings) from the fleet simulator's truth, assessment noise drawn."""
    simulate_fleet(tmp_path, fleet=FleetPlan(actuators=20, days=10), seed=0, write_recordings=False)
    truth = json.loads((tmp_path / 'truth.json').read_text())
    inside = total = 0
    for seed in range(3):
        rows = coverage_rows(forecast_points(synthetic_points(truth, seed=seed), levels=(0.85,)), truth, 0.85)
        inside += sum(row['inside'] for row in rows)
        total += len(rows)
        assert sum(r['true_relubrications'] == r['found_relubrications'] for r in rows) == len(rows)
    assert total == 60 and inside >= 0.9 * total


def test_recordings_assessed_into_a_history_forecast_the_truth(small_fleet):
    rows = compare_with_truth(small_fleet['history'], small_fleet['root'] / 'truth.json')
    assert len(rows) == 4 and all(not row['reason'] for row in rows)
    assert sum(row['inside'] for row in rows) >= 3


def test_forecast_summary_for_one_actuator(small_fleet):
    summary = forecast_summary(small_fleet['history'], 'A01')
    assert summary['forecast'] == 'ok' and set(summary) >= {'tau_days', 'theta_now', 'warn_crossing',
                                                            'warn_interval', 'error_crossing', 'error_interval'}
    assert all(isinstance(value, str) for value in summary.values())
    with pytest.raises(InputError, match='no assessed run'):
        forecast_summary(small_fleet['history'], 'A99')


def test_against_an_odometer_the_depletion_revolutions_and_the_crossing_reading_are_recovered():
    """Uneven usage: exponential in revolutions, not in time; the fit against the odometer is exact."""
    rng = np.random.default_rng(4)
    daily = rng.uniform(2000.0, 8000.0, 12)
    odometer = 1e6 + np.concatenate(([0.0], np.cumsum(daily)))[:12]
    depletion = 600_000.0     # warn (0.85) after 79,000 rev, beyond the 12 days recorded
    points = [RecordingPoint((day + 0.5) * DAY, 0.97 * math.exp(-(reading - 1e6) / depletion), 1e-4)
              for day, reading in enumerate(odometer)]
    forecast = fit_depletion('A', points, levels=(0.85, 0.70), odometer=list(odometer))
    assert forecast.depletion_revolutions == pytest.approx(depletion, rel=1e-3)
    warn, error = forecast.revolution_crossings
    assert warn.time == pytest.approx(1e6 + depletion * math.log(0.97 / 0.85), rel=1e-6)
    assert error.low <= 1e6 + depletion * math.log(0.97 / 0.70) <= error.high


def test_service_logs_read_iso_and_epoch_times(tmp_path):
    from prsm_lube_ros.fleet.service_log import read_odometer, read_relubrications
    log = tmp_path / 'odometer.csv'
    log.write_text('actuator,time,revolutions\n# comment\nA,2026-01-01T00:00:00Z,10\nA,1767229200,20.5\n')
    assert read_odometer(log) == {'A': ([1767225600.0, 1767229200.0], [10.0, 20.5])}
    (tmp_path / 'r.csv').write_text('A,2026-01-01T01:00:00\n')
    assert read_relubrications(tmp_path / 'r.csv') == {'A': [1767229200.0]}
    log.write_text('A,2026-01-01,many\n')
    with pytest.raises(InputError, match=r'odometer.csv:1: revolutions .many. is not a number'):
        read_odometer(log)


def _daily(actuator_days=10, theta0=0.97, tau=20.0, std=2e-3, seed=0):
    rng = np.random.default_rng(seed)
    return [RecordingPoint((day + 0.5) * DAY, theta0 * math.exp(-day / tau) * (1 + std * rng.standard_normal()),
                           std) for day in range(actuator_days)]


def test_recordings_sharing_one_start_time_do_not_break_the_fleet():
    from prsm_lube_ros.fleet.forecast import forecast_points
    copies = [RecordingPoint(3 * DAY, 0.9, 2e-3, f'copy{j}') for j in range(3)]
    twins = [p for point in _daily(seed=1) for p in (point, RecordingPoint(point.time, point.theta_oil * 1.001,
                                                                           point.theta_oil_std, 'twin'))]
    forecasts = {f.actuator: f for f in forecast_points({'A': _daily(), 'copies': copies, 'twins': twins})}
    assert not forecasts['A'].reason and forecasts['A'].crossings
    assert 'start times' in forecasts['copies'].reason
    assert not forecasts['twins'].reason and forecasts['twins'].tau_days == pytest.approx(20.0, rel=0.1)
    # the twins' zero-day steps are left out of the walk, not divided by
    zero_only = [RecordingPoint(DAY, 0.9, 2e-3), RecordingPoint(DAY, 0.89, 2e-3), RecordingPoint(DAY, 0.88, 2e-3)]
    from prsm_lube_ros.fleet.forecast import drift_and_diffusion, increments
    days = np.array([p.time / DAY for p in zero_only])
    assert increments(days, np.log([p.theta_oil for p in zero_only]), np.full(3, 2e-3), np.zeros(3)) is None
    assert drift_and_diffusion(None) is None


def test_forecast_summaries_of_several_actuators_in_one_call(small_fleet):
    from prsm_lube_ros.fleet.forecast_summary import forecast_summaries
    summaries = forecast_summaries(small_fleet['history'], ['A01', 'A03', 'A99', '/'])
    assert summaries['A01'] == forecast_summary(small_fleet['history'], 'A01')
    assert summaries['A03']['forecast'] == 'ok'
    assert summaries['A99'] == {'forecast': f"none: {small_fleet['history']}: no assessed run of actuator 'A99'"}
    assert summaries['/']['forecast'].startswith('none: actuator id')
    with pytest.raises(InputError, match='no such history'):
        forecast_summaries(small_fleet['history'] / 'missing', ['A01'])


def test_without_pyarrow_the_forecast_is_one_input_error_line(small_fleet, monkeypatch):
    import sys
    from prsm_lube_ros.fleet.forecast_summary import forecast_summaries
    monkeypatch.delitem(sys.modules, 'prsm_lube_ros.fleet.history', raising=False)
    for name in [name for name in sys.modules if name == 'pyarrow' or name.startswith('pyarrow.')]:
        monkeypatch.setitem(sys.modules, name, None)
    with pytest.raises(InputError, match='needs pyarrow'):
        forecast_summaries(small_fleet['history'], ['A01'])


def test_a_crossing_never_estimated_shows_no_interval():
    from prsm_lube_ros.fleet.forecast import Crossing
    from prsm_lube_ros.fleet.forecast_summary import crossing_interval_text
    assert crossing_interval_text(Crossing(0.85, None, 1.8e9, None)) == 'never'
    assert crossing_interval_text(Crossing(0.85, 1.8e9, 1.7e9, None)).endswith('.. never')
