# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnosis.calibration() carries the band and domain it was fitted in (issue 35, item 4: a trap before)."""
from prsm_lube_ros.diagnosis import diagnose_recordings
from prsm_lube_ros.estimation.calibration_file import calibration_from_dict, calibration_to_dict
from prsm_lube_ros.estimation.domain import CalibrationDomain
from prsm_lube_ros.estimation.pipeline import analysis_settings, calibrate_recordings, read_recordings
from prsm_lube_ros.estimation.windowing import usable_windows
from prsm_lube_ros.physics.actuator import load_actuator
from prsm_lube_ros.simulation.recordings import simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan


def test_a_diagnosis_calibration_has_the_band_and_domain_calibrate_gives(tmp_path):
    bags = simulate_experiment(tmp_path / 'sim', plan=ExperimentPlan(stage_thetas=(1.0, 1.0)), seed=3,
                               run_order='random')
    recordings = read_recordings(bags, lead=load_actuator(None).lead, settings=analysis_settings(spectra=True))
    assert recordings[0].band is not None and recordings[1].band == recordings[0].band   # the band rule
    result = diagnose_recordings(recordings)
    calibration = result.calibration()
    assert calibration.band == recordings[0].band == calibrate_recordings(recordings).band
    used = [w for recording in recordings for w in usable_windows(recording.windows)]
    assert calibration.domain == CalibrationDomain.of_windows(used)
    # what a library user saves is what assess reads back: the band survives the file
    assert calibration_from_dict(calibration_to_dict(calibration)).band == calibration.band
