# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Least-squares calibration, its refusals, calibration files and theta_Oil with uncertainty."""
import math

import numpy as np
import pytest

from prsm_lube_ros.estimation.assessment import Assessor
from prsm_lube_ros.estimation.calibration import fit_constants, operating_levels
from prsm_lube_ros.estimation.calibration_file import load_calibration, save_calibration
from prsm_lube_ros.errors import InputError
from prsm_lube_ros.physics.vibration_model import ModelConstants, acceleration_amplitude
from prsm_lube_ros.estimation.windowing import Window

TRUE = ModelConstants(c_sys=0.08, c_f=1e-3, c_lambda=0.30)
RPM = 2 * math.pi / 60


def paper_grid(repeats=20, theta=1.0, scatter=0.0, seed=1):
    """3 speeds x 2 loads, `repeats` windows each, log-normal RMS scatter."""
    rng = np.random.default_rng(seed)
    speeds, loads = np.meshgrid([100 * RPM, 150 * RPM, 200 * RPM], [100.0, 200.0])
    speeds = np.repeat(speeds.ravel(), repeats)
    loads = np.repeat(loads.ravel(), repeats)
    rms = acceleration_amplitude(speeds, loads, theta, TRUE) * np.exp(scatter * rng.standard_normal(speeds.size))
    return speeds, loads, rms


def test_noise_free_data_give_back_the_constants_exactly():
    cal = fit_constants(*paper_grid(repeats=1))
    assert cal.constants.c_sys == pytest.approx(TRUE.c_sys, rel=1e-9)
    assert cal.constants.c_f == pytest.approx(TRUE.c_f, rel=1e-9)
    assert cal.constants.c_lambda == pytest.approx(TRUE.c_lambda, rel=1e-9)
    assert cal.fit_rmse == pytest.approx(0.0, abs=1e-9)
    assert cal.windows_used == 6
    assert len(cal.speed_levels) == 3 and len(cal.load_levels) == 2


def test_a_reference_theta_below_one_is_honoured():
    cal = fit_constants(*paper_grid(repeats=1, theta=0.9), theta=0.9)
    assert cal.constants.c_lambda == pytest.approx(TRUE.c_lambda, rel=1e-9)


def test_standard_errors_match_the_scatter_of_repeated_fits():
    fits = [fit_constants(*paper_grid(scatter=0.02, seed=s)) for s in range(200)]
    spread = np.std([f.constants.c_lambda for f in fits])
    reported = np.median([f.c_lambda_std for f in fits])
    assert reported == pytest.approx(spread, rel=0.2)
    rmse = np.median([f.fit_rmse for f in fits])
    assert rmse == pytest.approx(0.02, rel=0.15)   # relative RMS error ~ the 2 % log scatter


@pytest.mark.parametrize('speeds_rpm, loads, needed', [
    ([100, 150, 200], [100], 'a second axial load'),
    ([150], [100, 200], 'a second screw speed'),
    ([150], [150], 'a second axial load'),
])
def test_data_that_cannot_identify_the_constants_say_what_to_record(speeds_rpm, loads, needed):
    s, f = np.meshgrid(np.array(speeds_rpm) * RPM, loads)
    s, f = np.repeat(s.ravel(), 5), np.repeat(f.ravel(), 5)
    with pytest.raises(InputError, match=needed):
        fit_constants(s, f, acceleration_amplitude(s, f, 1.0, TRUE))


def test_too_few_windows_are_refused():
    s = np.array([100, 200, 100]) * RPM
    f = np.array([100.0, 100.0, 200.0])
    with pytest.raises(InputError, match='more windows'):
        fit_constants(s, f, acceleration_amplitude(s, f, 1.0, TRUE))


def test_operating_levels_merge_values_within_five_percent():
    assert operating_levels([100, 101, 99.5, 200, 198]) == pytest.approx([100.1666, 199.0], rel=1e-3)


def test_calibration_file_round_trip_and_atomic_replace(tmp_path):
    cal = fit_constants(*paper_grid(scatter=0.01))
    path = save_calibration(cal, tmp_path / 'calib.yaml')
    back = load_calibration(path)
    assert back.constants == cal.constants
    assert np.allclose(back.covariance, cal.covariance)
    assert back.c_lambda_std == pytest.approx(cal.c_lambda_std)
    # A failing write leaves the old file whole and no temporary behind.
    before = path.read_text()
    bad = fit_constants(*paper_grid(scatter=0.01, seed=5))
    object.__setattr__(bad, 'covariance', 'not an array')   # makes serialisation fail mid-way
    with pytest.raises(Exception):
        save_calibration(bad, path)
    assert path.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ['calib.yaml']


@pytest.mark.parametrize('content, message', [
    ('', 'not a prsm_lube_ros calibration'),
    ('format: other\n', 'not a prsm_lube_ros calibration'),
    ('{{{', 'not valid YAML'),
    ('format: prsm_lube_ros/calibration\nconstants: {c_sys: 1}\n', 'malformed calibration'),
])
def test_bad_calibration_files_are_named_in_one_line(tmp_path, content, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(content)
    with pytest.raises(InputError, match=message) as err:
        load_calibration(path)
    assert str(path) in str(err.value) and '\n' not in str(err.value)
    with pytest.raises(InputError, match='not found'):
        load_calibration(tmp_path / 'missing.yaml')


def window(speed, load, rms, steady=True, reason='', run=1, n=4000):
    return Window(start=0.0, end=1.0, vibration_rms=rms, sample_count=n, coverage=1.0, screw_speed=speed,
                  speed_spread=0.0, axial_load=load, temperature=30.0, nut_position=0.05, revolutions=3.0,
                  run_index=run, reason_kind='' if steady else 'at_rest', reason=reason)


def test_assessment_recovers_theta_and_its_uncertainty_covers_the_truth():
    cal = fit_constants(*paper_grid(scatter=0.02))
    assessor = Assessor(cal)
    speeds, loads, rms = paper_grid(theta=0.72, scatter=0.02, seed=9)
    results = [assessor.assess_window(window(s, f, a)) for s, f, a in zip(speeds, loads, rms)]
    thetas = np.array([r.theta_oil for r in results])
    stds = np.array([r.theta_oil_std for r in results])
    assert np.mean(thetas) == pytest.approx(0.72, abs=0.02)
    z = (thetas - 0.72) / stds
    assert 0.7 < np.std(z) < 1.4     # the one-sigma figure describes the real scatter
    run = assessor.assess_run([window(s, f, a) for s, f, a in zip(speeds[:20], loads[:20], rms[:20])])
    assert run.theta_oil == pytest.approx(0.72, abs=3 * run.theta_oil_std + 0.01)
    # Without run labels every window counts as its own run: all scatter may be run scatter, so pooling twenty
    # windows of one run does not shrink its sigma (a new run carries the run-to-run scatter whole).
    assert run.theta_oil_std == pytest.approx(np.mean(stds[:20]), rel=0.1)


@pytest.mark.parametrize('speed, load, rms, steady, reason', [
    (0.0, 100.0, 1.0, False, 'screw at rest'),
    (10.0, 0.0, 1.0, True, 'below 5 N'),
    (10.0, 100.0, 0.0, True, 'RMS is zero'),
    (10.0, 100.0, math.nan, True, 'RMS is zero or missing'),
])
def test_where_eq23_means_nothing_theta_is_nan_with_a_reason(speed, load, rms, steady, reason):
    cal = fit_constants(*paper_grid(repeats=1))
    result = Assessor(cal).assess_window(window(speed, load, rms, steady, 'screw at rest' if not steady else ''))
    assert math.isnan(result.theta_oil) and math.isnan(result.theta_oil_std)
    assert reason in result.reason


def test_no_floating_point_warnings_on_degenerate_windows():
    cal = fit_constants(*paper_grid(repeats=1))
    with np.errstate(all='raise'):
        for args in [(0.0, 100.0, 1.0), (10.0, 0.0, 1.0), (10.0, 100.0, 0.0), (math.inf, 100.0, 1.0)]:
            assert math.isnan(Assessor(cal).assess_window(window(*args)).theta_oil)


def test_unsteady_windows_carry_a_code_and_steady_derives_from_it():
    from prsm_lube_ros.estimation.windowing import AT_REST, UNSTEADY_KINDS
    at_rest = window(0.01, 100.0, 1.0, steady=False, reason='screw at rest or crawling')
    assert at_rest.reason_kind == AT_REST and AT_REST in UNSTEADY_KINDS and not at_rest.steady
    assert window(10.0, 100.0, 1.0).steady


def test_one_assessable_rule_serves_assessment_calibration_and_diagnosis():
    """Eq. 23's domain is defined once (estimation.windowing.assessable) and each user applies it."""
    from prsm_lube_ros.estimation.windowing import assessable, not_assessable_reason, usable_windows
    speed = np.array([10.0, 10.0, 0.0, 10.0, 10.0])
    load = np.array([100.0, 1.0, 100.0, 100.0, np.nan])
    rms = np.array([1.0, 1.0, 1.0, 0.0, 1.0])
    assert assessable(speed, load, rms).tolist() == [True, False, False, False, False]
    assert 'below' in not_assessable_reason(10.0, 1.0, 1.0) and 'rest' in not_assessable_reason(0.0, 100.0, 1.0)
    windows = [window(s, f, a) for s, f, a in zip(speed, load, rms)] + [window(10.0, 100.0, 1.0, steady=False)]
    assert usable_windows(windows) == windows[:1]
