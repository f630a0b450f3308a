# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Real bearings (FEMTO-ST PRONOSTIA): the installed command tells damaged bearings from lubrication.

Calibrated on the 6 healthy early runs with the PRONOSTIA bearing's geometry,
``prsm-lube assess`` flags none of 11 other healthy units and most of the 17
late runs before failure (14 when written; the textbook indicators of the
data's README mark 11), each with the evidence, and the JSON carries the
contract's ``defect_suspected`` and ``condition_indicators`` for every run and
window.  ``benchmarks/femto_defects.py`` prints the table of docs/benchmarks.md.
"""
import json
from pathlib import Path

import pytest

from installed_command import prsm_lube

ROOT = Path(__file__).resolve().parents[2]
FEMTO = ROOT / 'test' / 'data' / 'realdata' / 'femto'
ACTUATOR = ROOT / 'config' / 'femto_pronostia_bearing.yaml'


@pytest.fixture(scope='module')
def assessed(tmp_path_factory):
    folder = tmp_path_factory.mktemp('femto_defects')
    calibration = folder / 'calibration.yaml'
    result = prsm_lube('calibrate', FEMTO / 'learn_early', '--out', calibration, '--actuator', ACTUATOR)
    assert result.returncode == 0, result.stderr
    assert 'condition_baseline:' in calibration.read_text()
    out = {}
    for subset in ('test_early', 'all_late'):
        result = prsm_lube('assess', FEMTO / subset, '--calibration', calibration, '--actuator', ACTUATOR,
                           '--json', folder / f'{subset}.json')
        assert result.returncode == 0, result.stderr
        out[subset] = (json.loads((folder / f'{subset}.json').read_text()), result.stdout)
    return out


def test_healthy_units_are_flagged_on_none(assessed):
    document, stdout = assessed['test_early']
    assert len(document['runs']) == 11
    assert not any(run['defect_suspected'] for run in document['runs'])
    assert document['runs_defect_suspected'] == 0 and '\nD ' not in stdout


def test_most_late_runs_are_flagged_with_the_bearing_component_in_the_evidence(assessed):
    document, stdout = assessed['all_late']
    flagged = [run for run in document['runs'] if run['defect_suspected']]
    assert len(flagged) >= 12, [run['condition_indicators']['kurtosis'] for run in document['runs']]
    assert all(run['defect_evidence'] for run in flagged)
    assert sum('support bearing' in run['defect_component'] for run in flagged) >= 10
    assert stdout.count('theta_oil is not a lubrication measure') == len(flagged)
    # The lowest theta readings (read as oil loss before) are among the flagged.
    lowest = sorted(document['runs'], key=lambda run: run['theta_oil'])[:3]
    assert all(run['defect_suspected'] for run in lowest)


def test_every_run_and_window_carries_the_contract_fields(assessed):
    document, _ = assessed['all_late']
    for item in document['runs'] + [w for w in document['windows'] if w['steady']]:
        assert isinstance(item['defect_suspected'], bool)
        indicators = item['condition_indicators']
        assert isinstance(indicators['kurtosis'], float) and isinstance(indicators['crest_factor'], float)
        for peak in indicators['envelope_peaks']:
            assert set(peak) == {'order', 'db', 'component'}
            assert isinstance(peak['order'], float) and isinstance(peak['component'], str)
