# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnosis texts say only what was shown (issue 15, item 4): not testable vs rejected, located only when
located, calibrate's flags carried, and the same refusal as calibrate, with no traceback."""
import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from prsm_lube_ros.diagnosis import diagnose_table
from prsm_lube_ros.simulation.rig_config import ExperimentPlan, RigConfig, RPM
from prsm_lube_ros.simulation.recordings import simulate_experiment
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table

ON_A_LINE = SyntheticPlan(speeds_rpm=(100.0, 150.0, 200.0), loads=(100.0,), repeats=3)


def three_conditions_on_a_line(seed=1):
    """Three (speed, load) conditions, each repeated: speeds with loads 100, 150 and 200 N in step."""
    table, _ = synthetic_table(np.random.default_rng(seed), None, ON_A_LINE)
    load = 100.0 + 100.0 * (table.speed - table.speed.min()) / np.ptp(table.speed)
    return dataclasses.replace(table, load=load)


def test_laws_of_speed_and_load_are_not_testable_on_three_conditions():
    result = diagnose_table(three_conditions_on_a_line())
    # The loads were changed after the amplitudes were drawn, so the model's load law is wrong: on three
    # conditions that is no evidence against the model's form either.
    assert result.verdict == 'cannot tell'
    status = {c.effect.id: (c.status, c.reason) for c in result.candidates}
    for effect in ('resonance', 'background_vibration'):
        assert status[effect][0] == 'not testable', status[effect]
    assert 'cannot be tested on so few conditions' in status['background_vibration'][1]
    # Laws of other covariates are still fitted and judged.
    assert status['position_dependent_stiffness'][0] in ('rejected', 'earns')


def test_nothing_said_located_when_nothing_is_located():
    """Runs that jump between repeats far beyond set-up scatter, along no recorded covariate: unexplained, but
    neither 'located' nor a missing 'candidate for the located mismatch'."""
    plan = SyntheticPlan(repeats=4, sessions=1, run_noise=0.12)
    table, _ = synthetic_table(np.random.default_rng(3), None, plan)
    result = diagnose_table(table)
    assert result.location.located == 'none'
    assert result.verdict == 'unexplained'
    assert 'located' not in result.what_to_record
    assert any('no covariate carries it' in note for note in result.notes)


def test_plain_set_up_scatter_is_adequate_not_unexplained():
    plan = SyntheticPlan(repeats=2, sessions=2, run_noise=0.035)
    verdicts = [diagnose_table(synthetic_table(np.random.default_rng(seed), None, plan)[0]).verdict
                for seed in range(4)]
    assert verdicts.count('adequate') >= 3, verdicts


def test_no_repeated_condition_cannot_tell_and_says_to_repeat():
    plan = SyntheticPlan(repeats=1, sessions=1, run_noise=0.03)
    result = diagnose_table(synthetic_table(np.random.default_rng(4), None, plan)[0])
    assert result.verdict == 'cannot tell'
    assert 'two runs or more' in result.what_to_record
    assert result.baseline_fit_test.reason.startswith('no condition repeated')
    assert not any('misses' in note for note in result.notes)


def cli(*args):
    return subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', *map(str, args)], capture_output=True,
                          text=True, timeout=600)


@pytest.fixture(scope='module')
def two_conditions(tmp_path_factory):
    """Two speeds and two loads recorded as two (speed, load) conditions only, each in its own bag."""
    folder = tmp_path_factory.mktemp('two_conditions')
    bags = []
    for seed, (speed, load) in enumerate([(100 * RPM, 100.0), (200 * RPM, 200.0)]):
        plan = ExperimentPlan(speeds=(speed,), loads=(load,), stage_thetas=(1.0,))
        bags += simulate_experiment(folder / f'c{seed}', plan=plan, rig=RigConfig(), seed=seed)
    return folder, bags


@pytest.mark.slow
def test_diagnose_refuses_what_calibrate_refuses_with_the_same_line(two_conditions):
    folder, bags = two_conditions
    calibrate = cli('calibrate', *bags, '--out', folder / 'c.yaml')
    diagnose = cli('diagnose', *bags, '--json', folder / 'd.json', '--calibration-out', folder / 'd.yaml')
    for result in (calibrate, diagnose):
        assert result.returncode != 0 and 'Traceback' not in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1
    assert 'distinct (speed, load) pairs' in calibrate.stderr
    assert diagnose.stderr.split(': error: ')[1] == calibrate.stderr.split(': error: ')[1]
    assert not (folder / 'd.yaml').exists()


@pytest.mark.slow
def test_calibrate_flags_reach_the_diagnosis(tmp_path):
    plan = ExperimentPlan(speeds=(100 * RPM, 150 * RPM, 200 * RPM), loads=(100.0,), stage_thetas=(1.0, 1.0),
                          run_order='random')
    bags = simulate_experiment(tmp_path / 'sim', plan=plan, rig=RigConfig(run_scatter=0.02), seed=5)
    result = cli('diagnose', *bags, '--json', tmp_path / 'd.json', '--calibration-out', tmp_path / 'd.yaml')
    # One load only: refused by both, with what to record.
    assert result.returncode != 0 and 'a second axial load' in result.stderr
    loads = ExperimentPlan(speeds=(100 * RPM, 200 * RPM), loads=(100.0, 200.0), stage_thetas=(1.0,))
    bags = simulate_experiment(tmp_path / 'four', plan=loads, rig=RigConfig(run_scatter=0.02), seed=6)
    result = cli('diagnose', *bags, '--json', tmp_path / 'd.json', '--calibration-out', tmp_path / 'd.yaml')
    assert result.returncode == 0, result.stderr
    document = json.loads((tmp_path / 'd.json').read_text())
    assert any(flag.startswith('form weakly tested') for flag in document['flags'])
    assert 'warning: form weakly tested' in result.stdout
    assert document['verdict'] == 'cannot tell'
    assert math.isfinite(json.loads(json.dumps(document['baseline']['rmse'])))
