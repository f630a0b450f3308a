# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""One reference-theta rule for the command line and the calibrate service: 0 means 1.0, bad values refused."""
import math

import pytest

from prsm_lube_ros.cli import main
from prsm_lube_ros.errors import ConfigError
from prsm_lube_ros.validation import reference_theta


@pytest.mark.parametrize('value, expected', [(0, 1.0), (0.0, 1.0), (1.0, 1.0), (0.8, 0.8)])
def test_zero_means_one_and_positive_values_stay(value, expected):
    assert reference_theta(value) == expected


@pytest.mark.parametrize('value', [-0.8, math.nan, math.inf, -math.inf, True, 'one'])
def test_negative_nan_infinite_and_non_numbers_are_refused(value):
    with pytest.raises(ConfigError, match='must be a positive number'):
        reference_theta(value)


@pytest.mark.parametrize('command', ['calibrate', 'diagnose'])
@pytest.mark.parametrize('theta', ['-0.8', 'nan'])
def test_the_command_line_refuses_a_bad_theta_in_one_line(command, theta, tmp_path, capsys):
    """Before the fix, calibrate --theta -0.8 calibrated as fully lubricated."""
    extra = ['--out', str(tmp_path / 'c.yaml')] if command == 'calibrate' else ['--json', str(tmp_path / 'd.json')]
    assert main([command, str(tmp_path / 'anything'), f'--theta={theta}', *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert '--theta' in err and 'positive' in err and len(err.splitlines()) == 1
    assert not (tmp_path / 'c.yaml').exists()


def test_the_service_rule_is_the_same():
    from prsm_lube_ros.nodes.calibration_request import reference_theta as service_rule
    assert service_rule(0.0) == 1.0
    with pytest.raises(ConfigError, match='reference_theta'):
        service_rule(-0.8)
