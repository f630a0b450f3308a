# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What the ``ros2`` tools do to the nodes, on a real graph (rclpy + Fast DDS on loopback).

``ros2 param dump/load/get/set/describe`` are rclpy's :class:`AsyncParameterClient`
calling the rcl_interfaces parameter services (ros2param does exactly that, in
Jazzy); ``ros2 lifecycle set`` is ``<node>/change_state``.  Everything is called
from a probe node in another context: nothing here goes through the node object.
"""
import os

import pytest
import yaml
from polling import wait_for
from spinning import SpinningContext, answered

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from lifecycle_msgs.msg import Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState  # noqa: E402
from rcl_interfaces.msg import Log  # noqa: E402
from rclpy.parameter import Parameter, parameter_value_to_python  # noqa: E402
from rclpy.parameter_client import AsyncParameterClient  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402

from prsm_lube_ros.errors import InputError  # noqa: E402
from prsm_lube_ros.nodes.launch_arguments import LAUNCH_ARGUMENTS  # noqa: E402
from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import ManagedSensorBridge, SensorBridge  # noqa: E402
from prsm_lube_ros.srv import Calibrate  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

#: This module's own DDS domain (100..199), apart from other test modules'.
DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 71) % 100 + 100
TIMEOUT = 15.0


class Side(SpinningContext):
    """One context with an executor thread: the node side or the probe side."""

    def __init__(self, probe_name=''):
        super().__init__(DOMAIN_ID, probe_name)


@pytest.fixture
def sides():
    """(nodes, probe) sides, always torn down."""
    nodes, probe = Side(), Side('ros_tools_probe')
    try:
        yield nodes, probe
    finally:
        probe.close()
        nodes.close()


def answer(send, what):
    """The result of the future ``send()`` returns, sent again when unanswered (idempotent requests only)."""
    return answered(send, what, TIMEOUT)


def parameter_client(probe, node_name):
    """What ``ros2 param`` makes for ``node_name`` (fully qualified)."""
    client = AsyncParameterClient(probe.probe, node_name)
    assert client.wait_for_services(timeout_sec=TIMEOUT), f'{node_name}: parameter services not served'
    return client


def dump(probe, node_name, path):
    """``ros2 param dump node_name > path``: list, get, written as its YAML."""
    client = parameter_client(probe, node_name)
    names = sorted(answer(lambda: client.list_parameters(), 'list_parameters').result.names)
    values = answer(lambda: client.get_parameters(names), 'get_parameters').values
    path.write_text(yaml.dump({node_name: {'ros__parameters': {
        name: parameter_value_to_python(value) for name, value in zip(names, values)}}}))
    return dict(zip(names, (parameter_value_to_python(v) for v in values)))


def load(probe, node_name, path):
    """``ros2 param load node_name path``: {name: (successful, reason)} of each parameter in the file."""
    client = parameter_client(probe, node_name)
    names = list(yaml.safe_load(path.read_text())[node_name]['ros__parameters'])
    results = answer(lambda: client.load_parameter_file(str(path)), 'set_parameters').results
    return {name: (r.successful, r.reason) for name, r in zip(names, results)}


def get(probe, node_name, name):
    """``ros2 param get node_name name``."""
    client = parameter_client(probe, node_name)
    return parameter_value_to_python(answer(lambda: client.get_parameters([name]), 'get_parameters').values[0])


def set_value(probe, node_name, name, value):
    """``ros2 param set node_name name value``: (successful, reason)."""
    client = parameter_client(probe, node_name)
    result = answer(lambda: client.set_parameters([Parameter(name, value=value)]), 'set_parameters').results[0]
    return result.successful, result.reason


def estimator(nodes, tmp_path, *args, **kwargs):
    """An estimator whose calibrate may read tmp_path/recordings and writes tmp_path/cal_{actuator}.yaml."""
    (tmp_path / 'recordings').mkdir(exist_ok=True)
    return nodes.add(LubricationEstimator(*args, context=nodes.context, parameter_overrides=[
        Parameter('calibration_file', value=str(tmp_path / 'cal_{actuator}.yaml')),
        Parameter('recordings_dir', value=str(tmp_path / 'recordings'))], **kwargs))


# -- 1. what may be read or written is fixed after start-up ------------------------------------------
@pytest.mark.parametrize('name', ['recordings_dir', 'calibration_file', 'history_dir'])
def test_what_may_be_read_or_written_is_read_only_with_its_reason(sides, tmp_path, name):
    nodes, probe = sides
    estimator(nodes, tmp_path)
    before = get(probe, '/prsm/lubrication_estimator', name)
    client = parameter_client(probe, '/prsm/lubrication_estimator')
    described = answer(lambda: client.describe_parameters([name]), 'describe_parameters').descriptors[0]
    assert described.read_only                                   # ros2 param describe says so
    successful, reason = set_value(probe, '/prsm/lubrication_estimator', name, '/')
    assert not successful and 'read-only after start-up' in reason and name in reason, reason
    assert get(probe, '/prsm/lubrication_estimator', name) == before
    assert set_value(probe, '/prsm/lubrication_estimator', name, before) == (True, '')   # its own value passes


def test_calibrate_still_reads_only_inside_the_recordings_folder(sides, tmp_path):
    nodes, probe = sides
    estimator(nodes, tmp_path)
    outside = tmp_path / 'outside'
    outside.mkdir()
    assert not set_value(probe, '/prsm/lubrication_estimator', 'recordings_dir', str(tmp_path))[0]
    client = probe.probe.create_client(Calibrate, '/prsm/calibrate')
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    for path in (str(outside), '../outside', '/etc/passwd'):
        response = answer(lambda: client.call_async(Calibrate.Request(bag_paths=[path])), 'calibrate')
        assert not response.success and 'outside the recordings folder' in response.message, path


# -- 5. ros2 param load of the node's own dump -------------------------------------------------------
def test_loading_the_estimators_own_dump_succeeds_and_a_changed_read_only_value_is_refused(sides, tmp_path):
    nodes, probe = sides
    node = estimator(nodes, tmp_path)
    windows = node.channels[0].builder
    dumped = tmp_path / 'estimator_dump.yaml'
    values = dump(probe, '/prsm/lubrication_estimator', dumped)
    assert {'recordings_dir', 'start_type_description_service', 'use_sim_time', 'actuators'} <= set(values)
    results = load(probe, '/prsm/lubrication_estimator', dumped)
    assert results and all(ok for ok, _ in results.values()), {k: r for k, (ok, r) in results.items() if not ok}
    assert node.channels[0].builder is windows              # unchanged window settings: open windows kept
    changed = yaml.safe_load(dumped.read_text())
    changed['/prsm/lubrication_estimator']['ros__parameters'].update(recordings_dir='/', window_length=2.0)
    dumped.write_text(yaml.dump(changed))
    results = load(probe, '/prsm/lubrication_estimator', dumped)
    assert not results['recordings_dir'][0] and 'read-only' in results['recordings_dir'][1]
    assert [name for name, (ok, _) in results.items() if not ok] == ['recordings_dir']
    assert get(probe, '/prsm/lubrication_estimator', 'window_length') == 2.0
    assert get(probe, '/prsm/lubrication_estimator', 'recordings_dir') == str(tmp_path / 'recordings')


def test_loading_the_bridges_own_dump_succeeds_also_for_another_sources_settings(sides, tmp_path):
    nodes, probe = sides
    nodes.add(SensorBridge(context=nodes.context, parameter_overrides=[
        Parameter('source', value='simulator'), Parameter('namespace', value='/tools_rig')]))
    dumped = tmp_path / 'bridge_dump.yaml'
    values = dump(probe, '/prsm/sensor_bridge', dumped)
    assert values['playback_rate'] == 1.0 and values['namespace'] == '/tools_rig'
    results = load(probe, '/prsm/sensor_bridge', dumped)
    assert len(results) == len(values) and all(ok for ok, _ in results.values()), \
        {k: r for k, (ok, r) in results.items() if not ok}
    successful, reason = set_value(probe, '/prsm/sensor_bridge', 'playback_rate', 2.0)     # a change still is not
    assert not successful and 'playback' in reason


# -- 3. relative names, resolved in the node's namespace ---------------------------------------------
def test_names_are_relative_and_parameters_report_them_resolved(sides, tmp_path):
    nodes, probe = sides
    estimator(nodes, tmp_path)
    estimator(nodes, tmp_path, cli_args=['--ros-args', '-r', '__ns:=/rig/left'])
    nodes.add(SensorBridge(context=nodes.context, cli_args=['--ros-args', '-r', '__ns:=/rig/left'],
                           parameter_overrides=[Parameter('source', value='simulator')]))
    for namespace in ('/prsm', '/rig/left'):
        node_name = f'{namespace}/lubrication_estimator'
        assert get(probe, node_name, 'calibrate_service') == f'{namespace}/calibrate'
        assert get(probe, node_name, 'actuators') == [namespace]
        wait_for(lambda: probe.probe.count_subscribers(f'{namespace}/vibration') >= 1, TIMEOUT, 'subscribed')
        services = {name for name, _ in probe.probe.get_service_names_and_types()}
        assert {f'{namespace}/calibrate', f'{namespace}/calibrate/_action/send_goal'} <= services
    assert get(probe, '/rig/left/sensor_bridge', 'namespace') == '/rig/left'
    assert get(probe, '/rig/left/sensor_bridge', 'imu_topic') == '/rig/left/imu/data'
    wait_for(lambda: probe.probe.count_publishers('/rig/left/vibration') == 1, TIMEOUT, 'the bridge publishes')


def test_an_actuator_entry_that_is_not_a_name_is_one_line():
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID)
    try:
        with pytest.raises(InputError, match='parameter actuators'):
            LubricationEstimator(context=context, parameter_overrides=[
                Parameter('actuators', value=['rig left!']), Parameter('calibration_file', value='')])
    finally:
        rclpy.try_shutdown(context=context)


# -- 2. lifecycle transitions are logged once (the launch file's arguments: test_launch_arguments.py) ----
def test_each_lifecycle_transition_is_logged_once(sides):
    nodes, probe = sides
    lines = []
    qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    probe.probe.create_subscription(Log, '/rosout', lambda m: lines.append(m.msg)
                                    if m.name == 'prsm.managed_tools' else None, qos)
    nodes.add(ManagedSensorBridge('managed_tools', context=nodes.context, parameter_overrides=[
        Parameter('source', value='simulator'), Parameter('namespace', value='/lifecycle_rig')]))
    client = probe.probe.create_client(ChangeState, '/prsm/managed_tools/change_state')
    assert client.wait_for_service(timeout_sec=TIMEOUT)
    for transition in (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_ACTIVATE,
                       Transition.TRANSITION_DEACTIVATE, Transition.TRANSITION_CLEANUP):
        request = ChangeState.Request(transition=Transition(id=transition))
        assert answered(lambda: client.call_async(request), 'change_state', TIMEOUT, attempts=1).success
    expected = ['configure: unconfigured -> inactive', 'activate: inactive -> active',
                'deactivate: active -> inactive', 'cleanup: inactive -> unconfigured']
    wait_for(lambda: all(e in lines for e in expected), TIMEOUT, 'the transitions logged')
    assert [line for line in lines if ' -> ' in line] == expected


def test_the_launch_file_loads_where_launch_is_installed():
    """Only where launch and launch_ros are installed (not from PyPI): the description and its arguments."""
    pytest.importorskip('launch')
    pytest.importorskip('launch_ros')
    import importlib.util
    from pathlib import Path
    path = Path(__file__).resolve().parents[2] / 'launch' / 'prsm_lube.launch.py'
    spec = importlib.util.spec_from_file_location('prsm_lube_launch', path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    declared = {a.name for a in module.generate_launch_description().get_launch_arguments()}
    assert declared == {a[0] for a in LAUNCH_ARGUMENTS}
