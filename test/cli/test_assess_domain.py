# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""prsm-lube assess: runs outside the calibration's domain marked, the band stated, no table after an error."""
import json
import math
from pathlib import Path

import pytest

from prsm_lube_ros.cli import main
from prsm_lube_ros.estimation.pipeline import recording_windows
from prsm_lube_ros.estimation.windowing import WindowSettings
from prsm_lube_ros.simulation.recordings import simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan

RPM = 2 * math.pi / 60
OLD_FILE = Path(__file__).resolve().parents[1] / 'data' / 'calibration' / 'before_band.yaml'


@pytest.fixture(scope='module')
def calibration(paper_experiment, tmp_path_factory):
    """A calibration of the paper's stage 3 (100-200 r/min, 100-200 N)."""
    path = tmp_path_factory.mktemp('calibration') / 'c.yaml'
    assert main(['calibrate', str(paper_experiment / 'stage_3'), '--out', str(path)]) == 0
    return path


def test_runs_at_a_speed_below_the_calibrated_ones_are_marked_with_how_far(calibration, tmp_path, capsys):
    slow = simulate_experiment(tmp_path / 'slow', seed=5, plan=ExperimentPlan(
        speeds=(60 * RPM,), loads=(100.0, 200.0), stage_thetas=(1.0,)))[0]
    capsys.readouterr()
    out = tmp_path / 'a.json'
    assert main(['assess', str(slow), '--calibration', str(calibration), '--json', str(out)]) == 0
    printed = capsys.readouterr().out
    document = json.loads(out.read_text())
    flag = 'extrapolated: speed 40 % below the calibrated 10.47-20.94 rad/s'
    assert len(document['runs']) == 2 and all(run['domain_flag'] == flag for run in document['runs'])
    assert document['runs_extrapolated'] == 2
    assessed = [w for w in document['windows'] if w['theta_oil'] is not None]
    assert assessed and all(w['domain_flag'] == flag and w['sample_rate'] == 4000.0 for w in assessed)
    rows = [line for line in printed.splitlines() if line.startswith('stage_1')]
    assert len(rows) == 4 and sum(row.endswith(' ~') for row in rows) == 2     # the two loaded runs
    assert sum(line.startswith('~ stage_1 run') and line.endswith(flag) for line in printed.splitlines()) == 2
    assert 'band 0.5-1600 Hz' in printed and 'domain speed 10.47-20.94 rad/s, load ' in printed


def test_runs_inside_the_domain_carry_no_mark(calibration, paper_experiment, tmp_path, capsys):
    out = tmp_path / 'a.json'
    assert main(['assess', str(paper_experiment / 'stage_1'), '--calibration', str(calibration),
                 '--json', str(out)]) == 0
    document = json.loads(out.read_text())
    assert len(document['runs']) == 6 and document['runs_extrapolated'] == 0
    assert not any(line.endswith(' ~') for line in capsys.readouterr().out.splitlines())


def test_an_old_calibration_is_assessed_on_the_raw_rms_it_was_fitted_on(paper_experiment, tmp_path, capsys):
    out = tmp_path / 'a.json'
    bag = paper_experiment / 'stage_1'
    assert main(['assess', str(bag), '--calibration', str(OLD_FILE), '--json', str(out)]) == 0
    printed = capsys.readouterr().out
    assert (f'calibration {OLD_FILE}: raw RMS: DC included, 0 Hz to half the sample rate of the recording '
            '(calibration without band); domain speed 10.47-20.94 rad/s, load 99.99-200 N') in printed
    document = json.loads(out.read_text())
    raw = recording_windows(bag, lead=0.005, settings=WindowSettings(band=None)).windows
    by_start = {w.start: w.vibration_rms for w in raw}
    assert document['calibration']['band'].startswith('raw RMS')
    assert all(w['vibration_rms'] == pytest.approx(by_start[w['start']], rel=1e-12)
               for w in document['windows'] if w['vibration_rms'] is not None)


def test_no_table_header_after_an_error(calibration, tmp_path, capsys):
    missing = tmp_path / 'no_such_bag'
    status = main(['assess', str(missing), '--calibration', str(calibration), '--json', str(tmp_path / 'a.json')])
    captured = capsys.readouterr()
    assert status == 2 and 'theta_oil' not in captured.out and captured.out.strip() == ''
    assert captured.err.strip().splitlines()[-1].startswith(f'prsm-lube assess: error: {missing}')


@pytest.fixture(scope='module')
def two_rates(tmp_path_factory):
    """Reference recordings (theta 1) of the paper's plan at 2 kHz and at 8 kHz."""
    from prsm_lube_ros.simulation.rig_config import RigConfig
    folder = tmp_path_factory.mktemp('rates')
    plan = ExperimentPlan(stage_thetas=(1.0,))
    return {rate: simulate_experiment(folder / f'{rate:g}', seed=7, plan=plan, rig=RigConfig(
        vibration_rate=rate, contact_mode_frequency=600.0))[0] for rate in (2000.0, 8000.0)}


def test_recordings_at_two_rates_calibrate_in_the_band_of_the_first_and_a_slower_second_is_refused(
        two_rates, tmp_path, capsys):
    slow, fast = two_rates[2000.0], two_rates[8000.0]
    assert main(['calibrate', str(slow), str(fast), '--out', str(tmp_path / 'c.yaml')]) == 0
    assert 'band: 0.5-800 Hz' in capsys.readouterr().out          # the 8 kHz recording filtered to the common band
    status = main(['calibrate', str(fast), str(slow), '--out', str(tmp_path / 'd.yaml')])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and not (tmp_path / 'd.yaml').exists()
    assert err[-1] == (f'prsm-lube calibrate: error: {slow}: vibration: sample rate 2000 Hz cannot cover the '
                       'analysis band 0.5-3200 Hz (needs at least 8000 Hz: upper edge at most 0.8 x the Nyquist '
                       'frequency); record faster, or calibrate in a band every recording covers '
                       '(prsm-lube calibrate --band-high HZ, at most 800 Hz for this rate; '
                       '1600 Hz serves every rate from 4000 Hz up)')
    # One calibration for both rates: the band both cover, asked for.
    assert main(['calibrate', str(fast), str(slow), '--band-high', '800', '--out', str(tmp_path / 'e.yaml')]) == 0
    assert 'band: 0.5-800 Hz' in capsys.readouterr().out
