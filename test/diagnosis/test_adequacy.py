# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Honest adequacy: the paper's model is adequate only when it fits within the window scatter."""
import dataclasses
import json

import numpy as np
import pytest

from prsm_lube_ros.diagnosis import diagnose_table
from prsm_lube_ros.diagnosis.adequacy import lack_of_fit
from prsm_lube_ros.diagnosis.fitting import fit_model
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table

PLAN = SyntheticPlan()


def test_unaffected_table_passes_the_lack_of_fit_test_and_is_adequate():
    table, _ = synthetic_table(np.random.default_rng(1), None, PLAN)
    result = diagnose_table(table)
    assert result.verdict == 'adequate'
    document = json.loads(json.dumps(result.as_json(), allow_nan=False))
    assert document['confident'] is True
    assert document['adequacy']['baseline']['significant'] is False
    assert document['adequacy']['baseline']['p_value'] is not None


@pytest.mark.parametrize('run_noise', [0.005, 0.03])
def test_pure_error_is_the_scatter_of_repeated_runs(run_noise):
    """Run levels scatter by the run noise plus the window noise averaged over the run's windows."""
    plan = dataclasses.replace(PLAN, run_noise=run_noise, repeats=4)
    table, _ = synthetic_table(np.random.default_rng(2), None, plan)
    test = lack_of_fit(table, fit_model(table).log_residual, 3)
    windows_per_run = len(table) / table.runs.size
    expected = np.sqrt(run_noise ** 2 + PLAN.window_noise ** 2 / windows_per_run)
    assert test.pure_error_rms == pytest.approx(expected, rel=0.3)
    assert test.window_scatter_rms == pytest.approx(PLAN.window_noise, rel=0.15)
    assert test.testable and not test.significant
    assert (test.runs, test.conditions, test.dof_pure) == (24, 6, 18)


def _with(table, factor):
    return dataclasses.replace(table, rms=table.rms * factor)


@pytest.mark.parametrize('shape', ['sinusoid in revolutions', 'step in time'])
def test_a_miss_no_candidate_makes_is_unexplained_not_adequate(shape):
    table, _ = synthetic_table(np.random.default_rng(11), None, PLAN)
    if shape == 'sinusoid in revolutions':
        factor = 1 + 0.12 * np.sin(2 * np.pi * table.revolutions / 90.0)
    else:
        # A step up for a middle third of the recording, unrelated to speed, load or position.
        t = table.time / table.time.max()
        factor = np.where((t > 0.35) & (t < 0.65), 1.2, 1.0)
    result = diagnose_table(_with(table, factor))
    assert result.verdict == 'unexplained'
    document = result.as_json()
    assert document['confident'] is False
    baseline = document['adequacy']['baseline']
    assert baseline['significant'] is True
    # Repeated runs of one condition differ far beyond set-up scatter: not noise.
    assert baseline['excess_scatter'] is True and baseline['pure_error_rms'] > 0.05
    assert any('no candidate explains it' in note and 'beyond the 5 % a rig' in note for note in result.notes)
