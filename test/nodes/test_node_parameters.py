# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A parameter override that breaks its declared range ends a node with one line, not a traceback."""
import subprocess
import sys

import pytest

pytestmark = pytest.mark.ros


@pytest.mark.parametrize('module, override, name', [
    ('prsm_lube_ros.nodes.lubrication_estimator', 'window_length:=-1.0', 'window_length'),
    ('prsm_lube_ros.nodes.lubrication_estimator', 'warn_below:=not_a_number', 'warn_below'),
    ('prsm_lube_ros.nodes.sensor_bridge', 'playback_rate:=-3.0', 'playback_rate'),
])
def test_out_of_range_override_is_one_line_naming_the_parameter(module, override, name):
    result = subprocess.run([sys.executable, '-m', module, '--ros-args', '-p', override],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and 'Traceback' not in result.stderr, result.stderr
    assert f'parameter {name}' in lines[0]
