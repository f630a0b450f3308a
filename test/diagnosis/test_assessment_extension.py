# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""theta_Oil assessed through the chosen extension lands closer to the truth than with the paper's model."""
import dataclasses

import numpy as np
import pytest

from prsm_lube_ros.estimation.assessment import Assessor
from prsm_lube_ros.estimation.calibration import fit_constants
from prsm_lube_ros.estimation.calibration_file import calibration_from_dict, calibration_to_dict
from prsm_lube_ros.diagnosis import diagnose_table
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
from prsm_lube_ros.estimation.windowing import Window

CASES = {
    'position_dependent_stiffness': {'free_length_start': 0.2, 'free_length_end': 0.03, 'ratio_long': 0.3,
                                     'long_length': 0.2, 'change': 0.2},
    'thermal_viscosity': {'rise': 20.0, 'tau': 300.0, 'beta': 0.03},
    'background_vibration': {'fraction': 0.5, 'tones': (480.0, 870.0)},
}


def windows_of(table):
    rows = zip(table.time, table.rms, table.speed, table.load, table.temperature, table.position,
               table.revolutions, table.run)
    return [Window(start=float(t), end=float(t) + 1.0, vibration_rms=float(a), sample_count=4000, coverage=1.0,
                   screw_speed=float(s), speed_spread=0.0, axial_load=float(f), temperature=float(c),
                   nut_position=float(x), revolutions=float(n), run_index=int(r))
            for t, a, s, f, c, x, n, r in rows]


@pytest.mark.parametrize('effect', sorted(CASES))
def test_extension_brings_theta_closer_to_the_truth(effect):
    plan = SyntheticPlan(spectrum_bins=128)
    reference, _ = synthetic_table(np.random.default_rng(21), effect, plan, params=CASES[effect])
    result = diagnose_table(reference)
    assert result.verdict == effect
    extended = result.calibration()
    # The extension survives the calibration file.
    extended = calibration_from_dict(calibration_to_dict(extended))
    paper = fit_constants(reference.speed, reference.load, reference.rms, 1.0)

    starved = dataclasses.replace(plan, theta=0.8)
    assessed, truth = synthetic_table(np.random.default_rng(22), effect, starved, params=CASES[effect])
    windows = windows_of(assessed)
    true_theta = 0.8
    errors = {}
    for name, calibration in (('paper', paper), ('extended', extended)):
        assessor = Assessor(calibration)
        assessed_windows = assessor.assess_windows(windows)
        theta = np.array([item.theta_oil for item in assessed_windows])
        runs = np.array([run.theta_oil for run in assessor.assess_runs(assessed_windows)])
        assert np.all(np.isfinite(theta)) and np.all(np.isfinite(runs))
        errors[name] = (float(np.sqrt(np.mean((theta - true_theta) ** 2))),
                        float(np.sqrt(np.mean((runs - true_theta) ** 2))))
    # Windows and runs both land closer to the truth; where the effect is large against the scatter,
    # by a wide margin (position: along the stroke, windows; temperature: run to run).
    assert errors['extended'][0] < errors['paper'][0]
    assert errors['extended'][1] < errors['paper'][1]
    if effect == 'position_dependent_stiffness':
        assert errors['extended'][0] < 0.5 * errors['paper'][0]
    if effect == 'thermal_viscosity':
        assert errors['extended'][1] < 0.5 * errors['paper'][1]


def test_calibration_without_extension_assesses_as_before():
    table, _ = synthetic_table(np.random.default_rng(3), None, SyntheticPlan())
    calibration = fit_constants(table.speed, table.load, table.rms, 1.0)
    window = windows_of(table)[0]
    assessed = Assessor(calibration).assess_window(window)
    # Eq. 23 by hand from the fitted constants.
    c = calibration.constants
    w, f, a = abs(window.screw_speed), abs(window.axial_load), window.vibration_rms
    expected = (c.c_f * f - np.log(a / (c.c_sys * w ** 2 * f ** (-1 / 3)))) / (c.c_lambda * w ** 0.68 * f ** -0.073)
    assert assessed.theta_oil == pytest.approx(expected, rel=1e-12)


def test_two_named_effects_are_both_stored_and_both_undone_in_assessment():
    effects = ('position_dependent_stiffness', 'thermal_viscosity')
    params = {name: CASES[name] for name in effects}
    plan = SyntheticPlan(sessions=2)
    reference, _ = synthetic_table(np.random.default_rng(21), effects, plan, params=params)
    result = diagnose_table(reference)
    assert {effect.id for effect, _, _ in result.named_effects()} == set(effects)
    extended = calibration_from_dict(calibration_to_dict(result.calibration()))
    stored = extended.extension['effects']
    assert sorted(item['effect'] for item in stored) == sorted(effects)
    assert extended.extension['effect'] == result.chosen.effect.id
    paper = fit_constants(reference.speed, reference.load, reference.rms, 1.0)
    assessed, _ = synthetic_table(np.random.default_rng(22), effects, dataclasses.replace(plan, theta=0.8),
                                  params=params)
    windows = windows_of(assessed)
    errors = {}
    for name, calibration in (('paper', paper), ('extended', extended)):
        assessor = Assessor(calibration)
        runs = np.array([run.theta_oil for run in assessor.assess_runs(assessor.assess_windows(windows))])
        errors[name] = float(np.sqrt(np.mean((runs - 0.8) ** 2)))
    assert errors['extended'] < errors['paper']
