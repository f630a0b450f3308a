# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What a calibration and an assessment cannot vouch for is said: untested form, merged levels, clustered
standard errors, theta_Oil outside its physical range."""
import math

import numpy as np
import pytest

from prsm_lube_ros.estimation.assessment import Assessor, theta_range_flag
from prsm_lube_ros.estimation.calibration import fit_constants, fit_windows, form_flag
from prsm_lube_ros.estimation.calibration_file import load_calibration, save_calibration
from prsm_lube_ros.estimation.pipeline import assessment_json, RecordingAssessment
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.physics.vibration_model import acceleration_amplitude, ModelConstants

TRUE = ModelConstants(c_sys=0.08, c_f=1e-3, c_lambda=0.30)
RPM = 2 * math.pi / 60


def window(speed, load, rms, run=1):
    return Window(start=0.0, end=1.0, vibration_rms=rms, sample_count=4000, coverage=1.0, screw_speed=speed,
                  speed_spread=0.0, axial_load=load, temperature=30.0, nut_position=0.05, revolutions=3.0,
                  run_index=run, reason_kind='', reason='')


def runs_of(conditions, runs_each=3, windows_each=20, run_scatter=0.0, window_scatter=0.01, seed=0):
    """Windows of runs at (speed rad/s, load N) conditions: a run-level offset plus window scatter in ln RMS."""
    rng = np.random.default_rng(seed)
    windows, run = [], 0
    for speed, load in conditions:
        for _ in range(runs_each):
            run += 1
            offset = run_scatter * rng.standard_normal()
            amplitude = float(acceleration_amplitude(speed, load, 1.0, TRUE))
            for noise in rng.standard_normal(windows_each):
                speed_i = speed * (1 + 0.002 * rng.standard_normal())
                windows.append(window(speed_i, load, amplitude * math.exp(offset + window_scatter * noise), run))
    return windows


# Three conditions on one line, loads of 4000 and 4200 N among them (the run-to-failure rig of issue 10).
ON_A_LINE = [(1800 * RPM, 4000.0), (2400 * RPM, 4200.0), (3000 * RPM, 5500.0)]
PAPER = [(s * RPM, f) for s in (100, 150, 200) for f in (100.0, 200.0)]


def test_three_conditions_fit_but_the_form_is_flagged_untested(tmp_path):
    cal = fit_windows(runs_of(ON_A_LINE))
    assert cal.conditions == 3
    assert cal.flags and cal.flags[0].startswith('form untested: record 2 more conditions')
    assert 'form untested: record 2 more conditions' in cal.summary
    back = load_calibration(save_calibration(cal, tmp_path / 'calib.yaml'))
    assert back.flags == cal.flags and back.conditions == 3 and back.merged == cal.merged
    assert back.standard_errors == cal.standard_errors and back.runs == cal.runs == 9


def test_the_paper_plan_tests_the_form_and_four_conditions_test_it_weakly():
    assert fit_windows(runs_of(PAPER)).flags == ()
    assert form_flag(6) == '' and form_flag(5) == ''
    assert form_flag(4).startswith('form weakly tested: record 1 more condition')


def test_merged_set_points_are_named_in_the_plan_summary():
    cal = fit_windows(runs_of(ON_A_LINE))
    assert cal.plan_summary.startswith('3 speeds x 2 loads (loads 4000 and 4200 N merged)')
    assert fit_windows(runs_of(PAPER)).merged == ()      # window scatter of one set-point is not a merge


def test_standard_errors_come_from_the_run_level_model():
    """Runs with their own offset (set-up scatter): window-independent errors are far too small, the run-level
    model's match the spread of repeated calibrations and its run scatter is the one drawn."""
    fits = [fit_windows(runs_of(PAPER, runs_each=2, run_scatter=0.03, window_scatter=0.01, seed=s))
            for s in range(150)]
    spread = np.std([f.constants.c_lambda for f in fits])
    run_level = np.median([f.c_lambda_std for f in fits])
    assert 'random run effect' in fits[0].standard_errors and 'REML over 12 runs' in fits[0].standard_errors
    assert run_level == pytest.approx(spread, rel=0.35)
    assert np.median([f.run_scatter.run_std for f in fits]) == pytest.approx(0.03, rel=0.2)
    assert np.median([f.run_scatter.window_std for f in fits]) == pytest.approx(0.01, rel=0.1)
    windows = runs_of(PAPER, runs_each=2, run_scatter=0.03, window_scatter=0.01, seed=0)
    ordinary = fit_constants([w.screw_speed for w in windows], [w.axial_load for w in windows],
                             [w.vibration_rms for w in windows])
    assert ordinary.c_lambda_std < 0.5 * spread


def test_few_runs_without_repeats_are_flagged_and_widen_the_errors():
    windows = runs_of(PAPER[:4] + PAPER[5:], runs_each=1, run_scatter=0.05, window_scatter=0.01, seed=3)
    cal = fit_windows(windows)
    ordinary = fit_constants([w.screw_speed for w in windows], [w.axial_load for w in windows],
                             [w.vibration_rms for w in windows])
    assert cal.run_scatter.dof == 2 and cal.run_scatter.predictive_factor == pytest.approx(1.746, abs=1e-3)
    assert any(flag.startswith('no condition repeated') for flag in cal.flags)
    assert cal.c_lambda_std > 2 * ordinary.c_lambda_std


def test_too_few_runs_assume_a_run_scatter_and_say_so():
    windows = runs_of(PAPER[:2] + PAPER[3:4], runs_each=1, window_scatter=0.01, seed=4)
    cal = fit_windows(windows)
    assert not cal.run_scatter.estimated and cal.run_scatter.run_std == 0.03
    assert any(flag.startswith('run scatter not estimable: 3 runs for 3 constants') for flag in cal.flags)


def test_a_negative_c_f_is_flagged_unphysical():
    falling = ModelConstants(c_sys=0.08, c_f=-2e-3, c_lambda=0.30)
    rng = np.random.default_rng(5)
    speeds, loads, rms, runs = [], [], [], []
    for run, (speed, load) in enumerate(PAPER * 2):
        for _ in range(10):
            speeds.append(speed)
            loads.append(load)
            rms.append(float(acceleration_amplitude(speed, load, 1.0, falling)) * math.exp(0.01 * rng.normal()))
            runs.append(run)
    cal = fit_constants(speeds, loads, rms, clusters=runs)
    assert any(flag.startswith('C_F = -0.002') and 'unphysical' in flag for flag in cal.flags)
    assert not any('C_F' in flag for flag in fit_windows(runs_of(PAPER)).flags)


def test_c_sys_is_reported_as_a_factor(tmp_path):
    cal = fit_windows(runs_of(PAPER, runs_each=2, run_scatter=0.03, seed=6))
    assert cal.c_sys_factor == pytest.approx(math.exp(math.sqrt(cal.covariance[0, 0])))
    assert cal.c_sys_text.startswith(f'{cal.constants.c_sys:.6g} (x/ ') and 'one sigma' in cal.c_sys_text
    back = load_calibration(save_calibration(cal, tmp_path / 'calib.yaml'))
    assert back.run_scatter == cal.run_scatter and back.c_sys_factor == pytest.approx(cal.c_sys_factor)


@pytest.mark.parametrize('theta, words', [(-0.48, 'below 0 is not physical'), (1.8, 'far above 1')])
def test_theta_outside_its_physical_range_is_flagged_in_json_with_its_reason(theta, words):
    cal = fit_windows(runs_of(PAPER))
    speed, load = 150 * RPM, 200.0
    rms = float(acceleration_amplitude(speed, load, theta, cal.constants))
    assessor = Assessor(cal)
    assessed = assessor.assess_windows([window(speed, load, rms, run=1) for _ in range(5)])
    runs = assessor.assess_runs(assessed, 'bag')
    assert runs[0].theta_oil == pytest.approx(theta, abs=1e-6)
    document = assessment_json([RecordingAssessment('bag', assessed, runs)], cal)
    assert words in document['runs'][0]['theta_oil_flag'] and document['runs_flagged'] == 1
    assert words in document['windows'][0]['theta_oil_flag']


def test_theta_in_range_has_no_flag():
    assert theta_range_flag(0.72, 0.05) == '' and theta_range_flag(1.3) == '' and theta_range_flag(math.nan) == ''
    assert theta_range_flag(-0.48, 1.18).startswith('theta_oil -0.48 +/- 1.18 below 0')
