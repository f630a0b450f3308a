# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The defect screen: impulsive and periodic at a defect order, against the healthy baseline of the calibration."""
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.calibration_file import (baseline_note, calibration_from_dict, calibration_to_dict,
                                                       load_calibration, save_calibration)
from prsm_lube_ros.estimation.condition_indicators import EnvelopePeak, ORDER_GRID
from prsm_lube_ros.estimation.defect_screen import (ConditionBaseline, DefectRules, RunCondition, screen)
from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.physics.defect_orders import prsm_defect_orders

ORDERS = prsm_defect_orders(Actuator())


def run(kurtosis=3.0, crest=4.0, line_order=None, line_db=0.0):
    """A pooled run whose envelope spectrum is flat with one line of ``line_db`` at ``line_order``."""
    envelope = np.ones(ORDER_GRID.size)
    peaks = ()
    if line_order is not None:
        envelope[np.argmin(np.abs(ORDER_GRID - line_order))] = 10 ** (line_db / 10)
        peaks = (EnvelopePeak(line_order, line_db, ''),)
    return RunCondition(kurtosis, crest, peaks, 10, 0.1, envelope)


@pytest.fixture(scope='module')
def paper_calibration(paper_experiment):
    from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
    return calibrate_recordings([recording_windows(paper_experiment / 'stage_3', lead=0.005)])


BASELINE = ConditionBaseline(6, 3.0, 3.4, 4.0, 4.6, ((6.25, 5.0), (3.75, 9.0)))


def test_healthy_runs_are_not_suspected():
    assert not screen(run(3.1, 4.2, 6.25, 4.0), ORDERS, BASELINE).suspected
    assert not screen(run(3.1, 4.2), ORDERS, None).suspected


def test_strongly_impulsive_alone_is_suspected_with_the_evidence_in_words():
    finding = screen(run(kurtosis=6.0, crest=8.0), ORDERS, BASELINE)
    assert finding.suspected and 'kurtosis 6.0' in finding.evidence and finding.component == ''


def test_a_strong_line_at_a_strike_order_alone_is_suspected_and_names_the_component():
    finding = screen(run(3.1, 4.2, 6.25, 14.0), ORDERS, BASELINE)
    assert finding.suspected and finding.component == 'screw raceway'
    assert '6.25x screw speed' in finding.evidence


def test_a_line_the_healthy_runs_have_too_is_not_enough_alone():
    # 11 dB at 3.75 is above the absolute 10 dB, but healthy runs reached 9 dB there (margin 3 dB).
    assert not screen(run(3.1, 4.2, 3.75, 11.0), ORDERS, BASELINE).suspected
    # ... with impulsiveness beyond the healthy (kurtosis 4.1 >= 1.25 x 3.0 and >= 4) it is.
    assert screen(run(4.1, 4.2, 3.75, 11.0), ORDERS, BASELINE).suspected


def test_a_strike_line_below_a_line_no_component_explains_is_not_enough_alone():
    # 14 dB at the screw raceway order clears the baseline by 9 dB, but the run holds a 14.5 dB line at 2.1x that
    # no defect order explains: modulation the machine makes, so the strike-order line is no evidence by itself.
    line = run(3.1, 4.2, 6.25, 14.0)
    crowded = RunCondition(line.kurtosis, line.crest_factor, line.envelope_peaks + (EnvelopePeak(2.1, 14.5, ''),),
                           line.windows, line.order_resolution, line.envelope)
    assert screen(line, ORDERS, BASELINE).suspected
    assert not screen(crowded, ORDERS, BASELINE).suspected
    assert screen(crowded, ORDERS, BASELINE, DefectRules(unexplained_margin_db=None)).suspected
    # ... and a line the run's own unexplained lines do not pass still is (a tie too), as is impulsiveness beside it.
    lower = RunCondition(3.1, 4.2, line.envelope_peaks + (EnvelopePeak(2.1, 11.0, ''),), 10, 0.1, line.envelope)
    assert screen(lower, ORDERS, BASELINE).suspected
    tie = RunCondition(3.1, 4.2, line.envelope_peaks + (EnvelopePeak(2.1, 14.0, ''),), 10, 0.1, line.envelope)
    assert screen(tie, ORDERS, BASELINE).suspected
    assert not screen(tie, ORDERS, BASELINE, DefectRules(unexplained_margin_db=0.5)).suspected
    assert screen(RunCondition(4.1, 4.2, crowded.envelope_peaks, 10, 0.1, line.envelope), ORDERS, BASELINE).suspected
    with pytest.raises(InputError, match='unexplained_margin_db'):
        DefectRules(unexplained_margin_db=-1.0)
    with pytest.raises(InputError, match='envelope_db'):
        DefectRules(envelope_db=True)
    assert DefectRules(envelope_db=np.float32(12.0), healthy_kurtosis=np.int64(4)).envelope_db == 12.0


def test_carrier_lines_modulate_and_are_no_strike_evidence():
    assert not screen(run(3.1, 4.2, 0.375, 30.0), ORDERS, BASELINE).suspected


def test_without_a_baseline_only_impulsive_and_periodic_together_count():
    assert not screen(run(9.0, 9.0), ORDERS, None).suspected
    assert not screen(run(3.0, 4.0, 6.25, 20.0), ORDERS, None).suspected
    assert screen(run(5.0, 6.0, 6.25, 12.0), ORDERS, None).suspected


def test_rules_are_one_typed_object_and_change_the_decision():
    strict = DefectRules(envelope_db=20.0)
    assert screen(run(3.1, 4.2, 6.25, 14.0), ORDERS, BASELINE).suspected
    assert not screen(run(3.1, 4.2, 6.25, 14.0), ORDERS, BASELINE, strict).suspected
    with pytest.raises(InputError, match='envelope_db'):
        DefectRules(envelope_db=-1.0)


def test_the_baseline_round_trips_through_a_calibration_file_and_old_files_load_without_one(
        tmp_path, paper_calibration):
    from dataclasses import replace
    calibration = replace(paper_calibration, condition_baseline=BASELINE)
    path = save_calibration(calibration, tmp_path / 'with.yaml')
    assert paper_calibration.condition_baseline is not None        # calibrating keeps one
    assert paper_calibration.condition_baseline.runs == 6 and paper_calibration.condition_baseline.kurtosis_max < 4
    assert load_calibration(path).condition_baseline == BASELINE
    assert baseline_note(load_calibration(path)) == ''
    document = calibration_to_dict(calibration)
    del document['condition_baseline']
    old = calibration_from_dict(document, 'old.yaml')
    assert old.condition_baseline is None and 'no healthy condition baseline' in baseline_note(old)


@pytest.mark.parametrize('field, value', [('kurtosis_max', -1.0), ('runs', 0), ('crest_median', float('nan')),
                                          ('envelope_levels', [{'order': 'x', 'db': 3}])])
def test_a_damaged_baseline_is_refused_in_one_line_naming_the_field(field, value, paper_calibration):
    from dataclasses import replace
    document = calibration_to_dict(replace(paper_calibration, condition_baseline=BASELINE))
    document['condition_baseline'][field] = value
    with pytest.raises(InputError, match=r'cal\.yaml: condition_baseline') as error:
        calibration_from_dict(document, 'cal.yaml')
    assert '\n' not in str(error.value) and (field in str(error.value))


def test_runs_with_no_indicators_are_not_judged():
    assert not screen(RunCondition(math.nan, math.nan, (), 0, math.nan), ORDERS, BASELINE).suspected
