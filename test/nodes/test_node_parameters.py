# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A parameter override that breaks its declared range ends a node with one line, not a traceback."""
import subprocess
import sys

import pytest

pytestmark = pytest.mark.ros


@pytest.mark.parametrize('module, override, line', [
    ('prsm_lube_ros.nodes.lubrication_estimator', 'window_length:=-1.0',
     'parameter window_length: -1.0 is out of its range 0.05 to 60'),
    ('prsm_lube_ros.nodes.lubrication_estimator', 'warn_below:=not_a_number',
     "parameter warn_below: 'not_a_number' is of type string, expected double"),
    ('prsm_lube_ros.nodes.lubrication_estimator', 'window_length:=2',
     'parameter window_length: 2 is of type integer, expected double'),
    ('prsm_lube_ros.nodes.sensor_bridge', 'playback_rate:=-3.0', 'parameter playback_rate: -3.0 is out of its range'),
])
def test_out_of_range_override_is_one_line_naming_the_parameter(module, override, line):
    """The line is ours (type and range checked before rclpy's descriptor), not rclpy's exception text."""
    result = subprocess.run([sys.executable, '-m', module, '--ros-args', '-p', override],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and 'Traceback' not in result.stderr, result.stderr
    assert line in lines[0], lines[0]
