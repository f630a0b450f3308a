# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Run-level variance model: REML as a reference mixed model gives it, and theta's sigma of a new run."""
import math
import warnings

import numpy as np
import pytest

from prsm_lube_ros.estimation.assessment import Assessor
from prsm_lube_ros.estimation.calibration import fit_windows
from prsm_lube_ros.estimation.run_scatter import (ASSUMED_RUN_STD, estimate_run_scatter, ols_covariance, RunScatter,
                                                  student_t_quantile)
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.physics.vibration_model import acceleration_amplitude, ModelConstants

TRUE = ModelConstants(c_sys=0.08, c_f=1e-3, c_lambda=0.30)
RPM = 2 * math.pi / 60
PAPER = [(s * RPM, f) for s in (100, 150, 200) for f in (100.0, 200.0)]


def unbalanced_design(seed, runs=14, run_std=0.03, window_std=0.01):
    rng = np.random.default_rng(seed)
    x, y, groups = [], [], []
    for g in range(runs):
        m = int(rng.integers(3, 40))
        level = np.array([1.0, rng.uniform(1, 2), rng.uniform(1, 3)])
        rows = np.tile(level, (m, 1))
        rows[:, 1] += rng.normal(0, 0.01, m)
        x.append(rows)
        y.append(rows @ [1.0, 0.1, -0.3] + run_std * rng.normal() + window_std * rng.normal(size=m))
        groups += [g] * m
    return np.vstack(x), np.concatenate(y), np.array(groups)


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_reml_matches_statsmodels_mixedlm(seed):
    sm = pytest.importorskip('statsmodels.api')
    x, y, groups = unbalanced_design(seed)
    ours = estimate_run_scatter(x, y, groups)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        reference = sm.MixedLM(y, x, groups=groups).fit(reml=True)
    assert ours.run_std == pytest.approx(math.sqrt(float(np.asarray(reference.cov_re)[0, 0])), rel=1e-3)
    assert ours.window_std == pytest.approx(math.sqrt(reference.scale), rel=1e-3)
    assert ours.dof == 14 - 3 and ours.estimated


def test_no_run_scatter_is_estimated_near_zero():
    x, y, groups = unbalanced_design(4, runs=20, run_std=0.0)
    ours = estimate_run_scatter(x, y, groups)
    assert ours.run_std < 0.004 and ours.window_std == pytest.approx(0.01, rel=0.15)


def test_ols_covariance_matches_the_spread_of_repeated_fits():
    """The sandwich under the fitted V describes how OLS estimates scatter when runs carry their own offset."""
    estimates, stated = [], []
    for seed in range(200):
        x, y, groups = unbalanced_design(seed, runs=20)
        beta, *_ = np.linalg.lstsq(x, y, rcond=None)
        estimates.append(beta[2])
        scatter = estimate_run_scatter(x, y - x @ beta, groups)
        stated.append(math.sqrt(ols_covariance(x, groups, scatter)[2, 2] / scatter.predictive_factor))
    assert np.median(stated) == pytest.approx(np.std(estimates), rel=0.25)


def test_predictive_factor_spans_68_percent_of_a_student_t_and_is_bounded():
    stats = pytest.importorskip('scipy.stats')
    for dof in (2, 3, 9, 30):
        half_width = math.sqrt(RunScatter(0.03, 0.01, dof + 3, dof).predictive_factor)
        assert stats.t.cdf(half_width, dof) - stats.t.cdf(-half_width, dof) == pytest.approx(0.6827, abs=1e-4)
    assert RunScatter(0.03, 0.01, 4, 1).predictive_factor == 3.0
    assert RunScatter(0.03, 0.01, 3, 0).predictive_factor == 3.0
    one = RunScatter(0.03, 0.02, 12, 1000)
    assert one.new_run_variance(1) == pytest.approx((0.03 ** 2 + 0.02 ** 2) * one.predictive_factor)
    assert one.new_run_variance(100) > 0.03 ** 2


def test_too_few_runs_fall_back_to_the_assumed_scatter():
    x, y, groups = unbalanced_design(5, runs=3)
    ours = estimate_run_scatter(x, y, groups)
    assert not ours.estimated and ours.run_std == ASSUMED_RUN_STD and ours.window_std > 0
    assert 'assumed' in ours.summary


def window(speed, load, rms, run):
    return Window(start=0.0, end=1.0, vibration_rms=rms, sample_count=4000, coverage=1.0, screw_speed=speed,
                  speed_spread=0.0, axial_load=load, temperature=30.0, nut_position=0.05, revolutions=3.0,
                  run_index=run, reason_kind='', reason='')


def runs_of(theta, run_std, seed, runs_each=2, windows_each=30, first_run=0):
    rng = np.random.default_rng(seed)
    windows, run = [], first_run
    for speed, load in PAPER:
        for _ in range(runs_each):
            offset = run_std * rng.normal()
            amplitude = float(acceleration_amplitude(speed, load, theta, TRUE))
            windows += [window(speed, load, amplitude * math.exp(offset + 0.01 * rng.normal()), run)
                        for _ in range(windows_each)]
            run += 1
    return windows


def test_a_run_sigma_carries_the_run_scatter_and_covers_new_runs():
    """Runs of many windows: their sigma is not the window scatter over sqrt(n) but that of a new run."""
    z, sigmas = [], []
    for seed in range(40):
        calibration = fit_windows(runs_of(1.0, 0.03, seed))
        assessor = Assessor(calibration)
        windows = runs_of(0.8, 0.03, 1000 + seed)
        for run in assessor.assess_runs(assessor.assess_windows(windows)):
            z.append((run.theta_oil - 0.8) / run.theta_oil_std)
            sigmas.append(run.theta_oil_std)
    z = np.array(z)
    assert 0.85 < np.sqrt(np.mean(z ** 2)) < 1.25
    assert 0.60 < np.mean(np.abs(z) < 1) < 0.76 and np.mean(np.abs(z) < 2) > 0.92
    # Thirty windows at 1 % scatter alone would give a sigma a fifth the size.
    window_only = fit_windows(runs_of(1.0, 0.0, 0))
    assert np.median(sigmas) > 3 * Assessor(window_only).assess_runs(
        Assessor(window_only).assess_windows(runs_of(0.8, 0.0, 7)))[0].theta_oil_std


def test_a_condition_recorded_in_one_run_never_gets_sigma_zero():
    calibration = fit_windows(runs_of(1.0, 0.02, 3, runs_each=1))
    assessor = Assessor(calibration)
    run = assessor.assess_run([window(*PAPER[0], 0.1, 0)] * 2)
    assert run.theta_oil_std > 0.01


@pytest.mark.parametrize('dof', [1, 2, 3, 4, 5, 9, 10, 57, 299, 300, 301, 1000, 10 ** 6])
@pytest.mark.parametrize('probability', [0.5, 0.6, 0.8413447460685429, 0.9, 0.975])
def test_the_pure_python_t_quantile_is_scipys(dof, probability):
    """The predictive factor's quantile, computed without importing scipy, equals scipy.special.stdtrit."""
    from scipy.special import stdtrit
    expected = float(stdtrit(dof, probability))
    assert student_t_quantile(dof, probability) == pytest.approx(expected, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize('dof, probability', [(0, 0.8), (2.5, 0.8), (3, 1.0), (3, 0.2)])
def test_the_t_quantile_refuses_what_it_cannot_compute(dof, probability):
    with pytest.raises(ValueError, match='Student t quantile'):
        student_t_quantile(dof, probability)
