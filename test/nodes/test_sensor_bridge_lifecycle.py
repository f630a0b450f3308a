# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The managed (lifecycle) sensor bridge driven through its lifecycle services, as ``ros2 lifecycle set`` does.

The probe calls ``<node>/change_state`` and ``<node>/get_state``
(lifecycle_msgs) on a real graph; what the bridge publishes, subscribes to
and acquires must follow: nothing before configure, the source open but
silent after it, data while active, silence again after deactivate, and
nothing left after cleanup.
"""
import os
import subprocess
import sys
from pathlib import Path

import pytest

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from lifecycle_msgs.msg import Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState, GetState  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

from prsm_lube_ros.estimation.health import OK, STALE  # noqa: E402
from prsm_lube_ros.msg import VibrationBlock  # noqa: E402
from prsm_lube_ros.nodes.ros_convert import status_level  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import ManagedSensorBridge  # noqa: E402
from bridge_graph import BridgeGraph, publish_at_1khz  # noqa: E402
from polling import stop_process, wait_for  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 61) % 100 + 100
ROOT = Path(__file__).resolve().parents[2]


class Graph(BridgeGraph):
    """This module's graph: managed bridges, and lifecycle service calls from the probe."""

    def bridge(self, name, **params):
        """A ManagedSensorBridge named ``name`` (unconfigured)."""
        return super().bridge(ManagedSensorBridge, name, **params)

    def call(self, service_type, name, request, timeout=20.0):
        """``request`` to the service ``name``; the response."""
        client = self.probe.create_client(service_type, name)
        try:
            wait_for(lambda: client.service_is_ready(), timeout, f'service {name}')
            future = client.call_async(request)
            wait_for(future.done, timeout, f'the answer of {name}')
            return future.result()
        finally:
            self.probe.destroy_client(client)

    def state(self, node):
        """Label of the node's lifecycle state, read through ``<node>/get_state``."""
        return self.call(GetState, f'/prsm/{node}/get_state', GetState.Request()).current_state.label

    def transition(self, node, transition_id):
        """Ask ``<node>/change_state`` for a transition; whether it succeeded."""
        return self.call(ChangeState, f'/prsm/{node}/change_state',
                         ChangeState.Request(transition=Transition(id=transition_id))).success


@pytest.fixture
def graph():
    """A fresh ROS graph for one test, always torn down."""
    with Graph(DOMAIN_ID, 'lifecycle_test_probe') as g:
        yield g


def test_imu_bridge_follows_configure_activate_deactivate_cleanup(graph):
    name = 'managed_imu_a'
    blocks = graph.collect(VibrationBlock, '/lc/vibration')
    statuses = graph.statuses(f'{name}: /lc sensor source')
    bridge = graph.bridge(name, source='imu', namespace='/lc', imu_topic='/lc_imu/data', sample_rate=1000.0,
                          block_length=0.05, diagnostics_period=0.2, qos_depth=5000)
    imu = graph.probe.create_publisher(Imu, '/lc_imu/data', 5000)
    assert graph.state(name) == 'unconfigured'
    assert graph.probe.count_publishers('/lc/vibration') == 0 and imu.get_subscription_count() == 0

    assert graph.transition(name, Transition.TRANSITION_CONFIGURE)
    assert graph.state(name) == 'inactive'
    wait_for(lambda: graph.probe.count_publishers('/lc/vibration') == 1, 20, 'the vibration publisher')
    wait_for(lambda: statuses, 20, 'a source status while inactive')
    assert status_level(statuses[-1]) == STALE and statuses[-1].message.startswith('not active')
    assert imu.get_subscription_count() == 0                   # inactive: the IMU is not read

    assert graph.transition(name, Transition.TRANSITION_ACTIVATE)
    assert graph.state(name) == 'active'
    wait_for(lambda: imu.get_subscription_count() == 1, 20, 'the IMU subscription')
    wait_for(lambda: bridge._outputs['vibration'].get_subscription_count() >= 1, 20, 'the probe matched')
    publish_at_1khz(imu, range(200))
    wait_for(lambda: len(blocks) >= 4, 20, 'four blocks while active')
    wait_for(lambda: status_level(statuses[-1]) == OK, 20, 'status OK while active')

    assert graph.transition(name, Transition.TRANSITION_DEACTIVATE)
    assert graph.state(name) == 'inactive'
    wait_for(lambda: imu.get_subscription_count() == 0, 20, 'the IMU subscription gone')
    count = len(blocks)
    publish_at_1khz(imu, range(200, 400))
    wait_for(lambda: statuses[-1].message.startswith('not active'), 20, 'status: not active')
    assert len(blocks) == count                                # nothing published while inactive

    assert graph.transition(name, Transition.TRANSITION_ACTIVATE)          # the pause is not lost samples
    wait_for(lambda: imu.get_subscription_count() == 1, 20, 'the IMU subscription again')
    publish_at_1khz(imu, range(2000, 2200))
    wait_for(lambda: len(blocks) >= count + 4, 20, 'four blocks after re-activation')
    assert bridge._assembler.lost_samples == 0 and bridge._assembler.problems['gap'] == 0
    assert graph.transition(name, Transition.TRANSITION_DEACTIVATE)

    assert graph.transition(name, Transition.TRANSITION_CLEANUP)
    assert graph.state(name) == 'unconfigured'
    wait_for(lambda: graph.probe.count_publishers('/lc/vibration') == 0, 20, 'the vibration publisher gone')
    assert graph.transition(name, Transition.TRANSITION_CONFIGURE)       # and again
    assert graph.transition(name, Transition.TRANSITION_ACTIVATE)
    assert graph.state(name) == 'active'
    assert not graph.errors


def test_hardware_bridge_acquires_only_while_active(graph, fake_daq):
    name = 'managed_daq_b'
    blocks = graph.collect(VibrationBlock, '/lcdaq/vibration')
    graph.bridge(name, source='hardware', namespace='/lcdaq', block_length=0.05)
    assert fake_daq.instances == []                            # unconfigured: the card is not touched
    assert graph.transition(name, Transition.TRANSITION_CONFIGURE)
    task = fake_daq.instances[0]
    assert task.channel_args['physical_channel'] == 'Dev1/ai0' and not task.started
    assert graph.transition(name, Transition.TRANSITION_ACTIVATE)
    assert task.started
    wait_for(lambda: len(blocks) >= 3, 20, 'blocks from the card')
    assert graph.transition(name, Transition.TRANSITION_DEACTIVATE)
    assert task.stopped and not task.closed
    count = len(task.read_sizes)
    assert graph.transition(name, Transition.TRANSITION_CLEANUP)
    assert task.closed and len(task.read_sizes) == count


def test_a_source_that_cannot_open_fails_configure_and_stays_unconfigured(graph, tmp_path):
    name = 'managed_bag_c'
    graph.bridge(name, source='playback', bag=str(tmp_path / 'missing.mcap'))
    assert graph.transition(name, Transition.TRANSITION_CONFIGURE) is False
    assert graph.state(name) == 'unconfigured'


def test_the_managed_process_starts_unconfigured_and_ends_cleanly_on_ctrl_c(graph):
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID), PYTHONUNBUFFERED='1')
    process = subprocess.Popen([sys.executable, str(ROOT / 'scripts' / 'sensor_bridge_managed'), '--ros-args',
                                '-r', '__node:=managed_proc_d', '-p', 'source:=simulator'], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert graph.state('managed_proc_d') == 'unconfigured'
        assert graph.transition('managed_proc_d', Transition.TRANSITION_CONFIGURE)
        assert graph.transition('managed_proc_d', Transition.TRANSITION_ACTIVATE)
        assert graph.state('managed_proc_d') == 'active'
    finally:
        stderr = stop_process(process)
    assert process.returncode == 0 and 'Traceback' not in stderr
