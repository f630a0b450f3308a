# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The ROS layer (prsm_lube_ros/nodes) under mypy with the core's rules, where rclpy is installed.

setup.cfg's ``[mypy]`` leaves ``nodes/`` out so that the core's check
(test/test_typing.py) runs on machines without ROS; here the same
configuration, with ``nodes/`` taken back in, checks the ROS layer against
the installed rclpy and generated interfaces (which carry no type hints:
setup.cfg says how they are treated).
"""
import configparser
from pathlib import Path
import subprocess
import sys

import pytest

pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

ROOT = Path(__file__).resolve().parents[2]
ROS_LAYER = 'prsm_lube_ros/nodes'


def ros_layer_config(path: Path) -> Path:
    """setup.cfg's mypy sections with the ROS layer no longer excluded nor skipped when imported."""
    config = configparser.ConfigParser(interpolation=None)
    config.read(ROOT / 'setup.cfg')
    mypy = config['mypy']
    kept = [part for part in mypy['exclude'].replace('(?x)(', '').rstrip(')').split('|') if ROS_LAYER not in part]
    assert len(kept) < len(mypy['exclude'].split('|')), 'setup.cfg no longer excludes the ROS layer: simplify this'
    mypy['exclude'] = '(?x)(' + ' | '.join(part.strip() for part in kept) + ')'
    config.remove_section('mypy-prsm_lube_ros.nodes.*')
    with path.open('w') as out:
        config.write(out)
    return path


@pytest.mark.linter
def test_mypy_on_the_ros_layer(tmp_path):
    config = ros_layer_config(tmp_path / 'mypy.ini')
    result = subprocess.run([sys.executable, '-m', 'mypy', '--config-file', str(config), '--cache-dir',
                             str(tmp_path / 'mypy_cache'), 'prsm_lube_ros'], cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, f'mypy found problems:\n{result.stdout}{result.stderr}'
    checked = [p for p in (ROOT / 'prsm_lube_ros').rglob('*.py')
               if p.relative_to(ROOT).as_posix() != 'prsm_lube_ros/cli/run.py']
    assert f'in {len(checked)} source files' in result.stdout          # nodes/ among them
