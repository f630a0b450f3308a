# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated fleet's truth follows its law: depletion with revolutions, relubrications when low."""
import json
import math

from prsm_lube_ros.simulation.fleet import FleetPlan, simulate_fleet


def test_truth_follows_the_depletion_law_and_the_relubrication_rule(tmp_path):
    fleet = FleetPlan(actuators=6, days=8)
    simulate_fleet(tmp_path, fleet=fleet, seed=5, write_recordings=False)
    truth = json.loads((tmp_path / 'truth.json').read_text())
    assert len(truth['actuators']) == 6 and not list(tmp_path.glob('A*'))
    relubricated = 0
    for actuator in truth['actuators']:
        recordings = actuator['recordings']
        assert len(recordings) == 8
        for before, after in zip(recordings, recordings[1:]):
            jump = any(before['start'] < r['time'] < after['start'] for r in actuator['relubrications'])
            assert (after['theta_oil'] > before['theta_oil']) == jump
            if jump:
                assert before['theta_oil'] < fleet.relubricate_below
                relubricated += 1
        for r in recordings:   # theta = theta_r exp(-N / N_d) within the cycle
            cycle = [x for x in actuator['relubrications'] if x['time'] < r['start']]
            theta_r = cycle[-1]['theta_oil_after'] if cycle else 1.0
            depleted = math.exp(-r['revolutions_since_lubrication'] / actuator['depletion_revolutions'])
            assert math.isclose(r['theta_oil'], theta_r * depleted)
        warn = actuator['crossings']['0.85']['time']
        last = recordings[-1]
        assert (last['theta_oil'] > 0.85) == (warn > last['start'])
    assert relubricated >= 1


def test_recordings_and_reference_are_written(tmp_path):
    paths = simulate_fleet(tmp_path, fleet=FleetPlan(actuators=2, days=2), seed=1, storage='mcap-file')
    assert len(paths) == 4 and all(p.is_file() for p in paths)
    assert (tmp_path / 'reference.mcap').is_file() and (tmp_path / 'truth.json').is_file()
