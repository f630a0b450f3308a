# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""launch/prsm_lube.launch.py included in another launch: under PushRosNamespace and without, on a real graph.

Only where ``launch`` and ``launch_ros`` are importable (they are not on PyPI:
in CI this module skips with the reason).  A child process runs a
LaunchService with the package's launch file included, the way an
integrator's bring-up does; the probe reads the resolved names from the
graph: node namespaces, the estimator's subscriptions and its calibrate
service, the bridge's publishers.
"""
import os
from pathlib import Path
import subprocess
import sys

import pytest

pytest.importorskip('launch.actions', reason='launch (ros2/launch) is not installed: not on PyPI')
pytest.importorskip('launch_ros.actions', reason='launch_ros (ros2/launch_ros) is not installed: not on PyPI')
rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from polling import stop_process, wait_for  # noqa: E402
from spinning import SpinningContext  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(180)]

DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 71) % 100 + 100
LAUNCH_FILE = Path(__file__).resolve().parents[2] / 'launch' / 'prsm_lube.launch.py'

#: The enclosing launch: the package's file included, under PushRosNamespace(argv[2]) unless it is '-'.
RUNNER = '''
import sys
from launch import LaunchDescription, LaunchService
from launch.actions import GroupAction, IncludeLaunchDescription
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch_ros.actions import PushRosNamespace
include = IncludeLaunchDescription(PythonLaunchDescriptionSource(sys.argv[1]),
                                   launch_arguments={'estimator_config': sys.argv[3]}.items())
actions = [include] if sys.argv[2] == '-' else [GroupAction([PushRosNamespace(sys.argv[2]), include])]
service = LaunchService()
service.include_launch_description(LaunchDescription(actions))
sys.exit(service.run())
'''


@pytest.fixture
def probe():
    side = SpinningContext(DOMAIN_ID, 'launch_probe')
    yield side.probe
    side.close()


def launched(pushed, tmp_path):
    """The enclosing launch as a child process (stopped with SIGINT by the caller)."""
    config = tmp_path / 'estimator.yaml'
    config.write_text("'/**/lubrication_estimator':\n  ros__parameters:\n    calibration_file: ''\n"
                      "    hardware_ids: ['EMA-L 0042']\n")
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID))
    return subprocess.Popen([sys.executable, '-c', RUNNER, str(LAUNCH_FILE), pushed or '-', str(config)], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize('pushed, expected', [('/robot/left', '/robot/left'), ('', '/prsm')])
def test_the_nodes_come_up_at_the_pushed_namespace_or_prsm(probe, tmp_path, pushed, expected):
    process = launched(pushed, tmp_path)
    try:
        nodes = {(expected, 'lubrication_estimator'), (expected, 'sensor_bridge')}
        wait_for(lambda: nodes <= {(ns, n) for n, ns in probe.get_node_names_and_namespaces()}, 60,
                 f'both nodes in {expected}')
        wait_for(lambda: probe.count_subscribers(f'{expected}/vibration') >= 1
                 and probe.count_publishers(f'{expected}/vibration') >= 1, 60, 'the bridge feeding the estimator')
        services = {name for name, _ in probe.get_service_names_and_types()}
        assert f'{expected}/calibrate' in services
        assert f'{expected}/lubrication_estimator/change_state' in services      # lifecycle, active (autostart)
        assert not any(name.startswith('/robot/left/prsm') or name.startswith('/prsm/robot')
                       for name, _ in probe.get_topic_names_and_types())          # nothing nested
    finally:
        output = stop_process(process)
    assert 'Traceback' not in (output or '')
