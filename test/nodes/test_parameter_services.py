# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Both nodes answer the rcl_interfaces parameter services ``ros2 param`` uses, on a real graph.

The services are called with plain rclpy clients from a probe node in another
context, as ``ros2 param list/describe/get/set`` would: nothing here goes
through the node object itself.
"""
import os

import pytest
from spinning import SpinningContext, answered

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterType, ParameterValue  # noqa: E402
from rcl_interfaces.srv import (DescribeParameters, GetParameters, ListParameters,  # noqa: E402
                                SetParameters)
from rclpy.parameter import Parameter  # noqa: E402

from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import SensorBridge  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(90)]

#: This module's own DDS domain (100..199), apart from other test modules'.
DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 67) % 100 + 100
TIMEOUT = 10.0


class Side(SpinningContext):
    """One context with an executor thread: the node side or the probe side."""

    def __init__(self):
        super().__init__(DOMAIN_ID)


@pytest.fixture
def sides():
    """(nodes, probe) sides, always torn down."""
    nodes, probe = Side(), Side()
    probe.add(rclpy.create_node('param_test_probe', context=probe.context))
    try:
        yield nodes, probe
    finally:
        probe.close()
        nodes.close()


def call(probe, srv_type, name, request):
    """Call service ``name`` from the probe node and return the response (sent again when unanswered)."""
    client = probe.nodes[0].create_client(srv_type, name)
    assert client.wait_for_service(timeout_sec=TIMEOUT), f'{name} is not served'
    return answered(lambda: client.call_async(request), name, TIMEOUT)


def double(value):
    """A ParameterValue holding ``value`` as a double."""
    return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=float(value))


def check_parameter_services(probe, node_name, name, valid, invalid, reason_words):
    """list, describe, get, set ``name`` to ``valid`` (accepted) and ``invalid`` (refused with a reason)."""
    base = f'/prsm/{node_name}'   # the nodes' default namespace
    listed = call(probe, ListParameters, f'{base}/list_parameters', ListParameters.Request())
    assert name in listed.result.names

    described = call(probe, DescribeParameters, f'{base}/describe_parameters',
                     DescribeParameters.Request(names=[name]))
    descriptor = described.descriptors[0]
    assert descriptor.name == name and descriptor.type == ParameterType.PARAMETER_DOUBLE
    assert descriptor.description and descriptor.floating_point_range

    def get():
        return call(probe, GetParameters, f'{base}/get_parameters', GetParameters.Request(names=[name])).values[0]

    before = get().double_value
    accepted = call(probe, SetParameters, f'{base}/set_parameters',
                    SetParameters.Request(parameters=[ParameterMsg(name=name, value=double(valid))]))
    assert accepted.results[0].successful, accepted.results[0].reason
    assert get().double_value == pytest.approx(valid) != before

    refused = call(probe, SetParameters, f'{base}/set_parameters',
                   SetParameters.Request(parameters=[ParameterMsg(name=name, value=double(invalid))]))
    assert not refused.results[0].successful and refused.results[0].reason
    assert all(word in refused.results[0].reason for word in reason_words), refused.results[0].reason
    assert get().double_value == pytest.approx(valid)        # a refused set changes nothing


def test_the_estimator_serves_its_parameters(sides, tmp_path):
    nodes, probe = sides
    node = nodes.add(LubricationEstimator(context=nodes.context, parameter_overrides=[
        Parameter('calibration_file', value=str(tmp_path / 'calibration_{actuator}.yaml')),
        Parameter('recordings_dir', value=str(tmp_path))]))
    names = [name for name, _ in node.get_service_names_and_types_by_node(node.get_name(), node.get_namespace())]
    assert len(names) == len(set(names)), f'a service listed twice: {sorted(names)}'
    # warn_below 0.9 is fine; 0.5 (below error_below 0.7) is refused by the node's own check, with its reason.
    check_parameter_services(probe, 'lubrication_estimator', 'warn_below', 0.9, 0.5, ['error_below', 'warn_below'])
    check_parameter_services(probe, 'lubrication_estimator', 'window_length', 2.0, -1.0, [])


def test_the_sensor_bridge_serves_its_parameters(sides):
    nodes, probe = sides
    nodes.add(SensorBridge(context=nodes.context, parameter_overrides=[
        Parameter('source', value='simulator'), Parameter('namespace', value='/paramtest/prsm')]))
    check_parameter_services(probe, 'sensor_bridge', 'theta_oil', 0.5, 5.0, ['theta_oil'])


def test_a_setting_for_another_source_is_refused_with_its_reason(sides):
    nodes, probe = sides
    nodes.add(SensorBridge(context=nodes.context, parameter_overrides=[
        Parameter('source', value='simulator'), Parameter('namespace', value='/paramtest/prsm')]))
    refused = call(probe, SetParameters, '/prsm/sensor_bridge/set_parameters',
                   SetParameters.Request(parameters=[ParameterMsg(name='playback_rate', value=double(2.0))]))
    assert not refused.results[0].successful
    assert 'playback' in refused.results[0].reason


def test_defect_windows_is_an_integer_with_its_range_and_changes_at_run_time(sides, tmp_path):
    nodes, probe = sides
    node = nodes.add(LubricationEstimator(context=nodes.context, parameter_overrides=[
        Parameter('calibration_file', value=str(tmp_path / 'calibration_{actuator}.yaml')),
        Parameter('recordings_dir', value=str(tmp_path))]))
    base = '/prsm/lubrication_estimator'
    descriptor = call(probe, DescribeParameters, f'{base}/describe_parameters',
                      DescribeParameters.Request(names=['defect_windows'])).descriptors[0]
    assert descriptor.type == ParameterType.PARAMETER_INTEGER and not descriptor.read_only
    assert (descriptor.integer_range[0].from_value, descriptor.integer_range[0].to_value) == (1, 1000)
    assert 'surface defect' in descriptor.description

    def set_to(value):
        request = SetParameters.Request(parameters=[ParameterMsg(name='defect_windows', value=ParameterValue(
            type=ParameterType.PARAMETER_INTEGER, integer_value=value))])
        return call(probe, SetParameters, f'{base}/set_parameters', request).results[0]
    assert set_to(25).successful and node.channels[0].surface.windows == 25
    refused = set_to(0)
    assert not refused.successful and refused.reason and node.channels[0].surface.windows == 25
