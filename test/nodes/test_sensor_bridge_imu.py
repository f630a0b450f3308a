# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The sensor bridge on a real ROS graph: the imu source, and the bridge's own status on /diagnostics.

A probe node publishes ``sensor_msgs/Imu`` at 1 kHz with stamps of its own
(two gaps in them); the bridge's VibrationBlocks must carry exactly those
samples and stamps (gravity high-pass off), and each gap must close a block
while only the first is logged (read back from /rosout).  With the default
high-pass, gravity on the axis must leave the blocks and the vibration stay.
"""
import os
import time

import numpy as np
import pytest

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from sensor_msgs.msg import Imu  # noqa: E402

from prsm_lube_ros.estimation.health import ERROR, OK, STALE, WARN  # noqa: E402
from prsm_lube_ros.errors import InputError  # noqa: E402
from prsm_lube_ros.msg import VibrationBlock  # noqa: E402
from prsm_lube_ros.nodes.ros_convert import status_level  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import SensorBridge  # noqa: E402
from bridge_graph import (BridgeGraph, block_stamp, imu_message, MS, publish_at_1khz, T0,  # noqa: E402
                          values_of)
from polling import wait_for  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 57) % 100 + 100


class Graph(BridgeGraph):
    """This module's graph: SensorBridge nodes by name."""

    def bridge(self, name, **params):
        """A SensorBridge named ``name``."""
        return super().bridge(SensorBridge, name, **params)


@pytest.fixture
def graph():
    """A fresh ROS graph for one test, always torn down."""
    with Graph(DOMAIN_ID, 'imu_test_probe') as g:
        yield g


def test_imu_samples_become_vibration_blocks_and_a_gap_closes_a_block_logged_once(graph):
    blocks = graph.collect(VibrationBlock, '/imu_rig/vibration')
    logs = graph.log_lines('bridge_imu_a')
    bridge = graph.bridge('bridge_imu_a', source='imu', namespace='/imu_rig', imu_topic='/imu_test_a/data',
                          imu_axis='y', sample_rate=1000.0, block_length=0.1, qos_depth=5000, imu_highpass=0.0)
    assert bridge.topics == {'vibration': '/imu_rig/vibration'}
    publisher = graph.probe.create_publisher(Imu, '/imu_test_a/data', 5000)
    wait_for(lambda: publisher.get_subscription_count() >= 1, 20, 'the bridge subscribed to the IMU')
    wait_for(lambda: graph.probe.count_publishers('/imu_rig/vibration') >= 1 and bridge._outputs[
        'vibration'].get_subscription_count() >= 1, 20, 'the probe subscribed to the blocks')
    # 1 s at 1 kHz with two gaps: 620..669 (50 lost) and 900..909 (10 lost).
    indices = [k for k in range(1000) if not (620 <= k < 670 or 900 <= k < 910)]
    publish_at_1khz(publisher, indices)
    wait_for(lambda: len(blocks) >= 10, 30, 'ten blocks')
    assert [len(b.samples) for b in blocks] == [100] * 6 + [20, 100, 100, 30]
    assert [(block_stamp(b) - T0) // MS for b in blocks] == [0, 100, 200, 300, 400, 500, 600, 670, 770, 870]
    assert all(b.sample_rate == 1000.0 and b.header.frame_id == 'imu_link' for b in blocks)
    received = np.concatenate([np.asarray(b.samples) for b in blocks])
    expected = np.array([k / 100.0 for k in indices[:len(received)]], dtype=np.float32)
    np.testing.assert_array_equal(received, expected)          # the y axis, every sample, in order
    wait_for(lambda: any('gap' in m.msg for m in logs), 10, 'the gap logged')
    gap_lines = [m.msg for m in logs if 'gap' in m.msg]
    assert len(gap_lines) == 1 and 'about 50 lost at 1000 Hz' in gap_lines[0] and '\n' not in gap_lines[0]
    assert bridge._assembler.lost_samples == 60 and bridge._assembler.problems['gap'] == 2
    assert not graph.errors


def test_the_bridge_status_goes_stale_ok_warn_and_stale_again(graph):
    name = 'bridge_imu_b'
    statuses = graph.statuses(f'{name}: /diag_rig sensor source')
    bridge = graph.bridge(name, source='imu', namespace='/diag_rig', imu_topic='/imu_test_b/data',
                          sample_rate=0.0, block_length=0.05, stale_timeout=1.0, diagnostics_period=0.2,
                          qos_depth=5000)
    wait_for(lambda: statuses, 20, 'a source status on /diagnostics')
    first = statuses[-1]
    assert status_level(first) == STALE and first.message == 'no block published yet'
    assert first.hardware_id == '/imu_test_b/data'
    publisher = graph.probe.create_publisher(Imu, '/imu_test_b/data', 5000)
    wait_for(lambda: publisher.get_subscription_count() >= 1, 20, 'the bridge subscribed to the IMU')
    publish_at_1khz(publisher, range(300))

    wait_for(lambda: status_level(statuses[-1]) == OK and values_of(statuses[-1])['blocks published'] == '6', 20,
             'status OK with the six blocks of 300 samples')
    values = values_of(statuses[-1])
    assert values['source'] == 'imu' and float(values['sample rate [Hz]']) == pytest.approx(1000.0)
    assert values['lost samples'] == '0' and float(values['block rate [1/s]']) > 0
    publish_at_1khz(publisher, [k for k in range(300, 700) if not 400 <= k < 450])      # 50 lost
    wait_for(lambda: status_level(statuses[-1]) == WARN, 20, 'WARN after the gap')
    values = values_of(statuses[-1])
    assert values['lost samples'] == '50' and 'gap' in values['last error']
    wait_for(lambda: status_level(statuses[-1]) == STALE, 20, 'STALE once samples stop')
    assert statuses[-1].message == 'no block for stale_timeout'
    assert bridge.health.blocks == bridge.messages_published


def test_a_failing_card_is_an_error_status(graph, fake_daq):
    name = 'bridge_daq_c'
    statuses = graph.statuses(f'{name}: /card sensor source')
    bridge = graph.bridge(name, source='hardware', namespace='/card', daq_channel='Dev7/ai1', block_length=0.05,
                          diagnostics_period=0.2)
    wait_for(lambda: statuses and status_level(statuses[-1]) == OK, 20, 'status OK while the card reads')
    assert statuses[-1].hardware_id == 'Dev7/ai1'
    fake_daq.fail_on = 'read'
    wait_for(lambda: status_level(statuses[-1]) == ERROR, 20, 'ERROR after the read failed')
    assert 'keep up with the hardware acquisition' in statuses[-1].message
    assert bridge.finished.is_set() and bridge.exit_status == 1


def test_hardware_id_parameter_and_bad_imu_settings(graph):
    statuses = graph.statuses('bridge_imu_d: /prsm sensor source')
    graph.bridge('bridge_imu_d', source='imu', hardware_id='nut IMU 7', diagnostics_period=0.2)
    wait_for(lambda: statuses, 20, 'a source status')
    assert statuses[-1].hardware_id == 'nut IMU 7'
    with pytest.raises(InputError, match="imu_axis: 'q' is not one of x, y, z"):
        graph.bridge('bridge_imu_e', source='imu', imu_axis='q')
    with pytest.raises(InputError, match='imu_topic: empty'):
        graph.bridge('bridge_imu_f', source='imu', imu_topic=' ')


def test_in_a_namespace_the_imu_topic_blocks_and_status_move_with_it(graph):
    bridge = graph.add(SensorBridge('bridge_imu_g', context=graph.context,
                                    cli_args=['--ros-args', '-r', '__ns:=/ema_x', '-p', 'source:=imu']))
    assert bridge._imu_topic == '/ema_x/imu/data' and bridge.topics == {'vibration': '/ema_x/vibration'}
    assert bridge.status_name == 'bridge_imu_g: /ema_x sensor source' and bridge.hardware_id == '/ema_x/imu/data'
    wait_for(lambda: graph.probe.count_subscribers('/ema_x/imu/data') == 1, 20, 'the IMU subscription')


def test_messages_without_linear_acceleration_are_dropped_counted_and_logged_once(graph):
    """REP 145: linear_acceleration_covariance[0] = -1 means the IMU does not measure it."""
    name = 'bridge_imu_h'
    logs = graph.log_lines(name)
    blocks = graph.collect(VibrationBlock, '/no_accel/vibration')
    bridge = graph.bridge(name, source='imu', namespace='/no_accel', imu_topic='/imu_test_h/data',
                          sample_rate=1000.0, block_length=0.01)
    publisher = graph.probe.create_publisher(Imu, '/imu_test_h/data', 1000)
    wait_for(lambda: publisher.get_subscription_count() >= 1, 20, 'the bridge subscribed to the IMU')
    for k in range(30):
        msg = imu_message(k)
        msg.linear_acceleration_covariance[0] = -1.0
        publisher.publish(msg)
    wait_for(lambda: bridge.health.lost_samples == 30, 20, 'thirty samples counted lost')
    wait_for(lambda: any('not measured' in m.msg for m in logs), 10, 'the log line')
    assert len([m for m in logs if 'not measured' in m.msg]) == 1 and blocks == []


def test_gravity_leaves_the_imu_blocks_and_the_vibration_stays(graph):
    """z = 9.81 m/s^2 + 0.5 m/s^2 at 50 Hz, with a gap: the blocks carry the 50 Hz tone without the gravity."""
    blocks = graph.collect(VibrationBlock, '/gravity_rig/vibration')
    bridge = graph.bridge('bridge_imu_g', source='imu', namespace='/gravity_rig', imu_topic='/imu_test_g/data',
                          imu_axis='z', sample_rate=1000.0, block_length=0.1, qos_depth=5000)
    publisher = graph.probe.create_publisher(Imu, '/imu_test_g/data', 5000)
    wait_for(lambda: publisher.get_subscription_count() >= 1, 20, 'the bridge subscribed to the IMU')
    wait_for(lambda: graph.probe.count_publishers('/gravity_rig/vibration') >= 1 and bridge._outputs[
        'vibration'].get_subscription_count() >= 1, 20, 'the probe subscribed to the blocks')
    tone = 0.5 * np.sqrt(2.0)            # amplitude of a 0.5 m/s^2 RMS sine

    def message(k):
        msg = imu_message(k)
        msg.linear_acceleration.z = 9.81 + tone * np.sin(2 * np.pi * 50.0 * k / 1000.0)
        return msg

    indices = [k for k in range(2000) if not 1200 <= k < 1250]     # a gap: the filter starts afresh after it
    start = time.monotonic()
    for n, k in enumerate(indices):
        publisher.publish(message(k))
        if n % 10 == 9:
            delay = start + (n + 1) * 1e-3 - time.monotonic()
            if delay > 0:
                time.sleep(delay)
    wait_for(lambda: sum(len(b.samples) for b in blocks) >= 1900, 30, 'the samples as blocks')
    received = np.concatenate([np.asarray(b.samples, float) for b in blocks])
    assert abs(float(np.mean(received))) < 0.02                      # gravity gone (raw mean: 9.81)
    assert np.sqrt(np.mean(received ** 2)) == pytest.approx(0.5, rel=0.02)   # the 50 Hz vibration kept
    after_gap = np.concatenate([np.asarray(b.samples, float) for b in blocks
                                if block_stamp(b) >= T0 + 1250 * MS])
    assert abs(float(np.mean(after_gap[:100]))) < 0.05               # no gravity step after the gap
    assert not graph.errors
