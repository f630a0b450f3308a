# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The calibration's band and domain in its file, old files, the domain flag, and refusals naming the real lack."""
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.assessment import Assessor
from prsm_lube_ros.estimation.calibration import check_identifiable, fit_constants
from prsm_lube_ros.estimation.calibration_file import band_note, load_calibration, save_calibration
from prsm_lube_ros.estimation.conditioning import RAW_BAND_TEXT
from prsm_lube_ros.estimation.domain import CalibrationDomain, domain_flag
from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.physics.vibration_model import acceleration_amplitude, ModelConstants

OLD_FILE = Path(__file__).resolve().parents[1] / 'data' / 'calibration' / 'before_band.yaml'


@pytest.fixture(scope='module')
def reference(paper_experiment):
    """Windows of the paper experiment's stage 3 and the calibration fitted on them."""
    recording = recording_windows(paper_experiment / 'stage_3', lead=0.005)
    return recording, calibrate_recordings([recording])


def test_the_band_and_domain_go_to_the_file_and_come_back(reference, tmp_path):
    _, calibration = reference
    path = save_calibration(calibration, tmp_path / 'c.yaml')
    data = yaml.safe_load(path.read_text())
    assert data['band'] == {'low_hz': 0.5, 'high_hz': 1600.0, 'anti_alias_margin': 0.8, 'min_sample_rate_hz': 4000.0,
                            'method': 'rfft of each window, mean square of the bins from low_hz to high_hz (Parseval)'}
    assert data['domain']['sample_rate_hz'] == [4000.0, 4000.0]
    low, high = data['domain']['speed_rad_s']
    assert low == pytest.approx(100 * math.pi / 30, rel=0.01) and high == pytest.approx(200 * math.pi / 30, rel=0.01)
    low, high = data['domain']['load_n']
    assert low == pytest.approx(100.0, rel=0.01) and high == pytest.approx(200.0, rel=0.01)
    assert data['fit']['windows_used'] == calibration.windows_used        # the keys before stay as they were
    again = load_calibration(path)
    assert again.band == calibration.band and again.domain == calibration.domain
    assert band_note(again) == ('band 0.5-1600 Hz (per window: FFT bins in the band, the window mean out; '
                                'sample rate at least 4000 Hz)')


def test_an_old_file_loads_with_the_raw_band_it_implies_and_a_domain_from_its_levels():
    calibration = load_calibration(OLD_FILE)
    assert calibration.band is None
    assert band_note(calibration) == RAW_BAND_TEXT == (
        'raw RMS: DC included, 0 Hz to half the sample rate of the recording (calibration without band)')
    assert calibration.domain == CalibrationDomain(speed=(10.471975511965976, 20.94395102393195),
                                                   load=(99.99225396108586, 199.9985134443617))
    assert calibration.constants.c_sys == pytest.approx(0.08057110882497324)


def test_the_domain_flag_says_how_far_outside_and_nothing_inside():
    domain = CalibrationDomain(speed=(63.0, 188.0), load=(4000.0, 5000.0), temperature=(25.0, 35.0))
    assert domain_flag(domain, 37.8, 4500.0) == 'extrapolated: speed 40 % below the calibrated 63-188 rad/s'
    assert domain_flag(domain, 100.0, 500.0, 50.0) == (
        'extrapolated: load 88 % below the calibrated 4000-5000 N; '
        'temperature 15.0 K above the calibrated 25-35 degC')
    assert domain_flag(domain, 61.0, 5200.0, 36.0) == ''          # within the 5 % and 2 K margins
    assert domain_flag(None, 1.0, 1.0) == ''


def test_assessed_windows_and_runs_outside_the_domain_are_flagged(reference):
    recording, calibration = reference
    assessor = Assessor(calibration)
    inside = assessor.assess_windows(recording.windows)
    assert all(item.domain_flag == '' for item in inside)
    steady = next(w for w in recording.windows if w.steady)
    fields = {name: getattr(steady, name) for name in Window.__dataclass_fields__}
    slow = Window(**{**fields, 'screw_speed': 0.6 * calibration.domain.speed[0]})
    item = assessor.assess_window(slow)
    assert math.isfinite(item.theta_oil)
    assert item.domain_flag == (f'extrapolated: speed 40 % below the calibrated {calibration.domain.speed[0]:.4g}-'
                                f'{calibration.domain.speed[1]:.4g} rad/s')
    run = assessor.assess_run([slow, slow])
    assert run.domain_flag == item.domain_flag and run.as_json()['domain_flag'] == item.domain_flag


REFUSALS = {
    'merged loads are named, not called missing': (
        [10.0] * 4 + [20.0] * 4, [4000.0, 4000.0, 4200.0, 4200.0] * 2,
        'record a second axial load more than 5 % from the others (loads 4000 and 4200 N were recorded, but lie '
        'within 5 % of each other and count as one level); C_sys and C_F cannot be told apart at one load'),
    'two speeds and two loads in two pairs are told the missing pairs': (
        [10.0] * 4 + [20.0] * 4, [100.0] * 4 + [200.0] * 4,
        'record a third operating condition: the windows hold 2 distinct (speed, load) pairs (10 rad/s at 100 N, '
        '20 rad/s at 200 N) for 3 constants, each speed at one load only; a speed at a second load would do '
        '(3 speeds x 2 loads as in the paper)'),
}


@pytest.mark.parametrize('case', REFUSALS)
def test_refusals_name_the_real_lack(case):
    speeds, loads, lack = REFUSALS[case]
    with pytest.raises(InputError) as refused:
        check_identifiable(speeds, loads)
    assert str(refused.value) == 'calibration cannot identify C_sys, C_F and C_lambda: ' + lack


def test_conditions_that_leave_the_fit_degenerate_are_counted_in_the_refusal():
    # Three pairs whose film term is linear in the load (omega^0.68 F^-0.073 = F / 100): the three columns
    # of Eq. 22 are then dependent although speeds, loads and pairs are all distinct.
    loads = np.array([100.0, 200.0, 300.0])
    speeds = (loads ** 1.073 / 100.0) ** (1 / 0.68)
    truth = ModelConstants(0.08, 1e-3, 0.3)
    rms = acceleration_amplitude(speeds, loads, 1.0, truth)
    with pytest.raises(InputError) as refused:
        fit_constants(np.repeat(speeds, 3), np.repeat(loads, 3), np.repeat(rms, 3))
    assert str(refused.value) == (
        'calibration cannot identify C_sys, C_F and C_lambda: the 3 (speed, load) conditions recorded leave the '
        'fit degenerate; record each speed at a second load (3 speeds x 2 loads as in the paper)')
