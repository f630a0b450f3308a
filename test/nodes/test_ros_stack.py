# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The nodes dropped into an integrator's stack (issue 38), on a real graph (rclpy, Fast DDS, loopback).

Every node here is started as ``ros2 run`` would start it under another
namespace (``--ros-args -r __ns:=/robot/...``); the probe sees it only
through the graph: lifecycle_msgs ``change_state`` / ``get_state`` (what
``ros2 lifecycle`` calls), rcl_interfaces ``get_parameters`` (what ``ros2
param get`` calls), ``get_publishers_info_by_topic`` (``ros2 topic info
-v``), /diagnostics and /rosout.
"""
import os
from pathlib import Path
import threading
import time

import numpy as np
import pytest
import yaml

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from lifecycle_msgs.msg import Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState, GetState  # noqa: E402
from rcl_interfaces.srv import GetParameters  # noqa: E402
from rclpy.parameter import Parameter, parameter_value_to_python  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import Imu, JointState  # noqa: E402

from prsm_lube_ros.estimation.health import ERROR, OK, WARN  # noqa: E402
from prsm_lube_ros.msg import VibrationBlock  # noqa: E402
from prsm_lube_ros.nodes import ros_convert  # noqa: E402
from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator  # noqa: E402
from prsm_lube_ros.nodes.ros_convert import status_level  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import ManagedSensorBridge  # noqa: E402
from bridge_graph import BridgeGraph, values_of  # noqa: E402
from polling import wait_for  # noqa: E402
from spinning import answered  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 83) % 100 + 100
CONFIG = Path(__file__).resolve().parents[2] / 'config'
TIMEOUT = 20.0
SENSOR = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)


class Graph(BridgeGraph):
    """The probe's view: lifecycle and parameter services, graph queries; nodes started under ``__ns``."""

    def node(self, node_class, namespace, name, params_file=None, **params):
        """A ``node_class`` as ``ros2 run ... --ros-args -r __ns:=<namespace> [--params-file F] -p ...``."""
        cli = ['--ros-args', '-r', f'__ns:={namespace}'] + (['--params-file', str(params_file)] if params_file else [])
        return self.add(node_class(name, context=self.context, cli_args=cli, parameter_overrides=[
            Parameter(k, value=v) for k, v in params.items()]))

    def call(self, service_type, name, request):
        client = self.probe.create_client(service_type, name)
        try:
            assert client.wait_for_service(timeout_sec=TIMEOUT), f'service {name}'
            return answered(lambda: client.call_async(request), name, TIMEOUT)
        finally:
            self.probe.destroy_client(client)

    def state(self, node_path):
        return self.call(GetState, f'{node_path}/get_state', GetState.Request()).current_state.label

    def transition(self, node_path, transition_id):
        request = ChangeState.Request(transition=Transition(id=transition_id))
        client = self.probe.create_client(ChangeState, f'{node_path}/change_state')
        try:
            assert client.wait_for_service(timeout_sec=TIMEOUT)
            return answered(lambda: client.call_async(request), 'change_state', TIMEOUT, attempts=1).success
        finally:
            self.probe.destroy_client(client)

    def parameter(self, node_path, name):
        response = self.call(GetParameters, f'{node_path}/get_parameters', GetParameters.Request(names=[name]))
        return parameter_value_to_python(response.values[0])

    def services(self):
        return {name for name, _ in self.probe.get_service_names_and_types()}

    def publishes(self, topic, node_name):
        return any(i.node_name == node_name for i in self.probe.get_publishers_info_by_topic(topic))

    def subscribes(self, topic, node_name):
        return any(i.node_name == node_name for i in self.probe.get_subscriptions_info_by_topic(topic))


@pytest.fixture
def graph():
    with Graph(DOMAIN_ID, 'ros_stack_probe') as g:
        yield g


def block(stamp, rate=1000.0, n=100):
    """A VibrationBlock stamped ``stamp`` (s)."""
    return ros_convert.vibration_block_msg(stamp, rate, np.sin(np.arange(n) * 0.3))


# -- 2. both nodes are lifecycle nodes; a lifecycle manager gates them ---------------------------------
def test_a_lifecycle_manager_gates_the_estimator(graph, tmp_path):
    ns, node = '/robot/gate', '/robot/gate/lubrication_estimator'
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', autostart=False, calibration_file='',
               hardware_ids=['EMA-G 7'])
    inputs = [f'{ns}/{leaf}' for leaf in ('vibration', 'joint_states', 'axial_load', 'temperature')]
    assert graph.state(node) == 'unconfigured'
    assert graph.parameter(node, 'autostart') is False
    assert not graph.publishes(f'{ns}/lubrication_state', 'lubrication_estimator')
    assert not any(graph.subscribes(t, 'lubrication_estimator') for t in inputs)
    assert f'{ns}/calibrate' not in graph.services()

    assert graph.transition(node, Transition.TRANSITION_CONFIGURE) and graph.state(node) == 'inactive'
    wait_for(lambda: graph.publishes(f'{ns}/lubrication_state', 'lubrication_estimator'), TIMEOUT, 'state publisher')
    assert not any(graph.subscribes(t, 'lubrication_estimator') for t in inputs)
    assert f'{ns}/calibrate' not in graph.services()

    assert graph.transition(node, Transition.TRANSITION_ACTIVATE) and graph.state(node) == 'active'
    wait_for(lambda: all(graph.subscribes(t, 'lubrication_estimator') for t in inputs), TIMEOUT, 'inputs')
    wait_for(lambda: {f'{ns}/calibrate', f'{ns}/calibrate/_action/send_goal'} <= graph.services(), TIMEOUT,
             'calibrate service and action')

    assert graph.transition(node, Transition.TRANSITION_DEACTIVATE) and graph.state(node) == 'inactive'
    wait_for(lambda: not any(graph.subscribes(t, 'lubrication_estimator') for t in inputs)
             and f'{ns}/calibrate' not in graph.services(), TIMEOUT, 'inputs and calibrate gone')
    assert graph.publishes(f'{ns}/lubrication_state', 'lubrication_estimator')

    assert graph.transition(node, Transition.TRANSITION_CLEANUP) and graph.state(node) == 'unconfigured'
    wait_for(lambda: not graph.publishes(f'{ns}/lubrication_state', 'lubrication_estimator'), TIMEOUT,
             'state publisher gone')
    # and back again: a manager may cycle it
    assert graph.transition(node, Transition.TRANSITION_CONFIGURE)
    assert graph.transition(node, Transition.TRANSITION_ACTIVATE) and graph.state(node) == 'active'
    wait_for(lambda: graph.subscribes(f'{ns}/vibration', 'lubrication_estimator'), TIMEOUT, 'inputs again')


def test_autostart_drives_both_nodes(graph):
    """Estimator: autostart true by default (prsm-lube run, ros2 run as before); bridge: the parameter."""
    graph.node(LubricationEstimator, '/robot/auto', 'lubrication_estimator', calibration_file='',
               hardware_ids=['EMA-A 1'])
    graph.node(ManagedSensorBridge, '/robot/auto', 'sensor_bridge', source='simulator', autostart=True,
               hardware_id='ACC-1')
    graph.node(ManagedSensorBridge, '/robot/manual', 'sensor_bridge', source='simulator', hardware_id='ACC-2')
    assert graph.state('/robot/auto/lubrication_estimator') == 'active'
    assert graph.parameter('/robot/auto/lubrication_estimator', 'autostart') is True
    assert graph.state('/robot/auto/sensor_bridge') == 'active'
    assert graph.state('/robot/manual/sensor_bridge') == 'unconfigured'       # the default: a manager decides
    wait_for(lambda: graph.probe.count_publishers('/robot/auto/vibration') >= 1
             and graph.subscribes('/robot/auto/vibration', 'lubrication_estimator'), TIMEOUT, 'bridge to estimator')


# -- 3. diagnostics: input rate and stamps, fixed texts, hardware ids ---------------------------------
def feed(publisher, period, seconds, stamp_offset=0.0, stop=None):
    """Publish a block every ``period`` s of wall time for ``seconds``, stamped wall time + ``stamp_offset``."""
    end = time.monotonic() + seconds
    while time.monotonic() < end and not (stop and stop.is_set()):
        publisher.publish(block(time.time() + stamp_offset))
        time.sleep(period)


def test_the_vibration_input_status_follows_its_rate_and_stamps(graph):
    ns = '/robot/rate'
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', calibration_file='', hardware_ids=['EMA-R 3'],
               diagnostic_period=0.2, rate_window=5, vibration_rate=10.0, rate_tolerance=0.5)
    statuses = graph.statuses(f'lubrication_estimator: {ns} vibration input')
    vibration = graph.probe.create_publisher(VibrationBlock, f'{ns}/vibration', SENSOR)
    wait_for(lambda: graph.subscribes(f'{ns}/vibration', 'lubrication_estimator'), TIMEOUT, 'subscribed')
    wait_for(lambda: statuses and status_level(statuses[-1]) == ERROR, TIMEOUT, 'ERROR before any block')
    assert statuses[-1].message == 'No events recorded.'          # the stamps' WARN is below the ERROR
    assert statuses[-1].hardware_id == 'EMA-R 3'

    stop = threading.Event()
    worker = threading.Thread(target=feed, args=(vibration, 0.1, 60.0), kwargs={'stop': stop}, daemon=True)
    worker.start()
    try:
        wait_for(lambda: status_level(statuses[-1]) == OK, 30, 'OK at 10 blocks/s')
        first_ok = len(statuses) - 1
        time.sleep(2.0)
        ok = [s for s in statuses[first_ok:] if status_level(s) == OK]
        assert {s.message for s in ok} == {'Desired frequency met; Timestamps are reasonable.'}
        values = values_of(ok[-1])
        assert float(values['Target frequency (Hz)']) == 10.0 and float(values['Actual frequency (Hz)']) > 5.0
        assert values['topic'] == f'{ns}/vibration'
    finally:
        stop.set()
        worker.join()

    stop.clear()
    worker = threading.Thread(target=feed, args=(vibration, 0.5, 60.0), kwargs={'stop': stop}, daemon=True)
    worker.start()
    try:
        wait_for(lambda: status_level(statuses[-1]) == WARN, 30, 'WARN at 2 blocks/s')
        assert statuses[-1].message == 'Frequency too low.'      # the stamps: judged over the same window
        assert float(values_of(statuses[-1])['Actual frequency (Hz)']) < 5.0
    finally:
        stop.set()
        worker.join()

    for offset, words in ((30.0, 'Timestamps too far in future seen.'), (-60.0, 'Timestamps too far in past seen.')):
        vibration.publish(block(time.time() + offset))
        wait_for(lambda: status_level(statuses[-1]) == ERROR and words in statuses[-1].message, TIMEOUT, words)


def test_the_lubrication_status_text_changes_only_with_its_state(graph):
    """Lubrication, surface and input statuses: while a level holds, its message holds too."""
    ns = '/robot/text'
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', calibration_file='', hardware_ids=['EMA-T 4'],
               diagnostic_period=0.2, vibration_rate=10.0, rate_tolerance=0.9)
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    vibration = graph.probe.create_publisher(VibrationBlock, f'{ns}/vibration', SENSOR)
    wait_for(lambda: graph.subscribes(f'{ns}/vibration', 'lubrication_estimator'), TIMEOUT, 'subscribed')
    feed(vibration, 0.1, 3.0)
    seen = {}
    for array in list(arrays):
        for status in array.status:
            if ns in status.name:
                seen.setdefault((status.name, status_level(status)), set()).add(status.message)
    assert len(seen) >= 3
    assert all(len(messages) == 1 for messages in seen.values()), seen


def test_a_default_hardware_id_warns_once_at_start_up(graph):
    lines = graph.log_lines('lubrication_estimator')
    bridge_lines = graph.log_lines('sensor_bridge')
    graph.node(LubricationEstimator, '/robot/hw1', 'lubrication_estimator', calibration_file='')
    graph.node(LubricationEstimator, '/robot/hw2', 'lubrication_estimator', calibration_file='',
               hardware_ids=['EMA-H 9'])
    graph.node(ManagedSensorBridge, '/robot/hw1', 'sensor_bridge', source='simulator', autostart=True)
    wait_for(lambda: any('hardware_id not set' in m.msg for m in bridge_lines), TIMEOUT, 'the bridge WARN')
    wait_for(lambda: any('activate' in m.msg for m in lines if m.name.startswith('robot.hw2')), TIMEOUT, 'hw2 up')
    warned = [m for m in lines if 'hardware_ids not set' in m.msg]
    assert [m.name for m in warned] == ['robot.hw1.lubrication_estimator']
    assert warned[0].level == 30 and '/robot/hw1' in warned[0].msg          # WARN
    assert sum('hardware_id not set' in m.msg for m in bridge_lines) == 1
    assert graph.parameter('/robot/hw2/lubrication_estimator', 'hardware_ids') == ['EMA-H 9']


def test_diagnostic_period_is_a_parameter_of_both_nodes(graph):
    graph.node(LubricationEstimator, '/robot/period', 'lubrication_estimator', calibration_file='',
               hardware_ids=['EMA-P 5'], diagnostic_period=0.25)
    graph.node(ManagedSensorBridge, '/robot/period', 'sensor_bridge', source='simulator', diagnostic_period=3.0,
               hardware_id='ACC-P')
    assert graph.parameter('/robot/period/lubrication_estimator', 'diagnostic_period') == 0.25
    assert graph.parameter('/robot/period/sensor_bridge', 'diagnostic_period') == 3.0
    assert graph.parameter('/robot/period/lubrication_estimator', 'diagnostics_period') == 1.0   # former name
    statuses = graph.statuses('lubrication_estimator: /robot/period vibration input')
    wait_for(lambda: len(statuses) >= 3, TIMEOUT, 'input statuses on the timer')


# -- 4. standard QoS overrides ------------------------------------------------------------------------
def test_qos_overrides_change_the_profiles_on_the_graph(graph):
    ns = '/robot/qos'
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', calibration_file='', hardware_ids=['EMA-Q 6'],
               **{f'qos_overrides.{ns}/lubrication_state.publisher.reliability': 'best_effort',
                  f'qos_overrides.{ns}/vibration.subscription.reliability': 'reliable'})
    bridge = graph.node(ManagedSensorBridge, ns, 'sensor_bridge', source='simulator', reliability='best_effort',
                        hardware_id='ACC-Q', **{f'qos_overrides.{ns}/vibration.publisher.reliability': 'reliable'})
    assert bridge.trigger_configure().name == 'SUCCESS'        # publishers exist from configure on

    def reliability(infos, node_name):
        found = [i.qos_profile.reliability for i in infos if i.node_name == node_name]
        return found[0] if found else None

    probe = graph.probe
    wait_for(lambda: reliability(probe.get_publishers_info_by_topic(f'{ns}/lubrication_state'),
                                 'lubrication_estimator') == ReliabilityPolicy.BEST_EFFORT, TIMEOUT, 'state writer')
    wait_for(lambda: reliability(probe.get_subscriptions_info_by_topic(f'{ns}/vibration'),
                                 'lubrication_estimator') == ReliabilityPolicy.RELIABLE, TIMEOUT, 'vibration reader')
    # without an override: the node's own profiles (sensor data best effort; reliability parameter of the bridge)
    assert reliability(probe.get_subscriptions_info_by_topic(f'{ns}/joint_states'),
                       'lubrication_estimator') == ReliabilityPolicy.BEST_EFFORT
    wait_for(lambda: reliability(probe.get_publishers_info_by_topic(f'{ns}/vibration'), 'sensor_bridge')
             == ReliabilityPolicy.RELIABLE, TIMEOUT, 'bridge vibration writer: the override')
    assert reliability(probe.get_publishers_info_by_topic(f'{ns}/joint_states'), 'sensor_bridge') \
        == ReliabilityPolicy.BEST_EFFORT                                # reliability: best_effort still works
    node = f'{ns}/lubrication_estimator'
    assert graph.parameter(node, f'qos_overrides.{ns}/lubrication_state.publisher.reliability') == 'best_effort'
    assert graph.parameter(node, f'qos_overrides.{ns}/axial_load.subscription.depth') == 500   # = qos_depth
    assert graph.parameter(node, 'qos_depth') == 500


# -- 5. calibrate can be switched off; a ros2_control stack relayed ------------------------------------
def test_calibrate_can_be_switched_off(graph):
    ns = '/robot/sealed'
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', calibration_file='', hardware_ids=['EMA-S 8'],
               calibrate_enabled=False, calibrate_service='/robot/sealed_extra')
    graph.node(LubricationEstimator, '/robot/open', 'lubrication_estimator', calibration_file='',
               hardware_ids=['EMA-O 8'])
    wait_for(lambda: '/robot/open/calibrate' in graph.services()
             and graph.subscribes(f'{ns}/vibration', 'lubrication_estimator'), TIMEOUT, 'both up')
    services = graph.services()
    assert not any(name.startswith(f'{ns}/calibrate') or name.startswith('/robot/sealed_extra') for name in services)
    assert graph.parameter(f'{ns}/lubrication_estimator', 'calibrate_enabled') is False


def test_a_ros2_control_stack_is_relayed_into_the_contract(graph, tmp_path):
    """joint_state_broadcaster, force_torque_sensor_broadcaster and an IMU broadcaster, as config/ says."""
    ns = '/robot/left'
    params = tmp_path / 'stack.yaml'
    stack = yaml.safe_load((CONFIG / 'ros2_control_stack.yaml').read_text())
    stack['/**/sensor_bridge']['ros__parameters']['hardware_id'] = 'ACC-L 11'
    stack['/**/lubrication_estimator']['ros__parameters'].update(hardware_ids=['EMA-L 11'], calibration_file='',
                                                                 diagnostic_period=0.2)
    params.write_text(yaml.safe_dump(stack))
    joints = graph.collect(JointState, f'{ns}/joint_states')
    loads = graph.collect(WrenchStamped, f'{ns}/axial_load')
    blocks = graph.collect(VibrationBlock, f'{ns}/vibration')
    inputs = {key: graph.statuses(f'lubrication_estimator: {ns} {key} input')
              for key in ('joint_states', 'axial_load', 'vibration')}
    graph.node(LubricationEstimator, ns, 'lubrication_estimator', params_file=params)
    graph.node(ManagedSensorBridge, ns, 'sensor_bridge', params_file=params)
    assert graph.state(f'{ns}/sensor_bridge') == 'active'               # autostart: true in the example
    assert graph.parameter(f'{ns}/sensor_bridge', 'relay_joint_states') == '/joint_states'
    joint_pub = graph.probe.create_publisher(JointState, '/joint_states', SENSOR)
    wrench_pub = graph.probe.create_publisher(WrenchStamped, '/force_torque_sensor_broadcaster/wrench', SENSOR)
    imu_pub = graph.probe.create_publisher(Imu, '/imu_sensor_broadcaster/imu', SENSOR)
    wait_for(lambda: graph.probe.count_subscribers('/joint_states') >= 1
             and graph.probe.count_subscribers('/force_torque_sensor_broadcaster/wrench') >= 1
             and graph.probe.count_subscribers('/imu_sensor_broadcaster/imu') >= 1, TIMEOUT, 'the bridge listening')
    start = time.time()
    for k in range(1500):                                      # 1.5 s: IMU at 1 kHz, joints 100 Hz, load 100 Hz
        stamp = start + k * 1e-3
        imu = Imu()
        imu.header.stamp = ros_convert.time_msg(stamp)
        imu.linear_acceleration.z = float(np.sin(k * 0.3))
        imu_pub.publish(imu)
        if k % 10 == 0:
            joint = JointState(name=['wheel_joint', 'screw_joint'], position=[0.0, k * 0.02], velocity=[0.0, 20.0])
            joint.header.stamp = ros_convert.time_msg(stamp)
            joint_pub.publish(joint)
            wrench = ros_convert.wrench_msg(stamp, -150.0, frame_id='load_cell')
            wrench_pub.publish(wrench)
        if k % 10 == 9:
            time.sleep(0.01)
    wait_for(lambda: joints and loads and blocks, TIMEOUT, 'the contract topics')
    assert list(joints[-1].name) == ['wheel_joint', 'screw'] and joints[-1].velocity[1] == 20.0
    assert loads[-1].wrench.force.z == -150.0 and loads[-1].header.frame_id == 'load_cell'
    for key, statuses in inputs.items():
        wait_for(lambda: statuses and int(values_of(statuses[-1])['Events since startup']) > 0, TIMEOUT,
                 f'the estimator counting {key}')
        assert statuses[-1].hardware_id == 'EMA-L 11'


def test_diagnostic_period_takes_the_former_name_only_when_the_new_one_is_left_alone():
    from prsm_lube_ros.nodes.parameters import diagnostic_period
    assert diagnostic_period({'diagnostic_period': 1.0, 'diagnostics_period': 0.2}) == 0.2
    assert diagnostic_period({'diagnostic_period': 0.5, 'diagnostics_period': 0.2}) == 0.5
    assert diagnostic_period({'diagnostic_period': 1.0, 'diagnostics_period': 1.0}) == 1.0
