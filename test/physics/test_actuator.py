# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Actuator configuration: the shipped file, the contract's defaults and bad files."""
import math
from pathlib import Path

import pytest

from prsm_lube_ros.physics.actuator import Actuator, load_actuator
from prsm_lube_ros.errors import InputError

CONFIG = Path(__file__).resolve().parents[2] / 'config' / 'actuator.yaml'


def test_shipped_file_is_the_contract_default_actuator():
    actuator = load_actuator(CONFIG)
    assert actuator == Actuator()
    # CONTRACT.md: 24 mm screw, 8 mm roller, 5 mm lead, 45 deg flank, 10 rollers, 180 mm travel.
    assert (actuator.screw_mean_diameter, actuator.roller_mean_diameter, actuator.lead) == (0.024, 0.008, 0.005)
    assert math.degrees(actuator.flank_angle) == pytest.approx(45.0)
    assert (actuator.roller_count, actuator.nut_travel) == (10, 0.18)


def test_lead_angle_and_nut_travel():
    actuator = Actuator()
    # tan(alpha) = 5 mm / (pi * 24 mm) = 0.066315 -> atan = 3.7940 deg
    assert math.degrees(actuator.lead_angle) == pytest.approx(3.7940, abs=1e-4)
    # 36 revolutions of 5 mm = 180 mm
    assert actuator.nut_travel_from_angle(10.0 + 36 * 2 * math.pi, 10.0) == pytest.approx(0.18)


@pytest.mark.parametrize('content, message', [
    ('actuator: {lead: -0.005}\n', 'lead must be a positive number'),
    ('actuator: {flank_angle: 2.0}\n', 'flank_angle must lie between'),
    ('actuator: {pitch: 0.005}\n', 'unknown actuator field(s) pitch'),
    ('actuator: {lead: five}\n', 'lead must be a number'),
    ('- just a list\n', 'expected a mapping'),
    ('actuator: [\n', 'not valid YAML'),
])
def test_bad_actuator_files_get_one_line_naming_the_file(tmp_path, content, message):
    path = tmp_path / 'actuator.yaml'
    path.write_text(content)
    with pytest.raises(InputError) as err:
        load_actuator(path)
    assert message in str(err.value) and str(path) in str(err.value)


def test_a_partial_file_keeps_the_other_defaults(tmp_path):
    path = tmp_path / 'actuator.yaml'
    path.write_text('actuator:\n  lead: 0.004\n  roller_count: 8\n')
    actuator = load_actuator(path)
    assert actuator.lead == 0.004 and actuator.roller_count == 8
    assert actuator.screw_mean_diameter == Actuator().screw_mean_diameter
