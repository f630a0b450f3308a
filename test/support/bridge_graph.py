# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A ROS graph for sensor-bridge tests (a probe that collects topics, /rosout and /diagnostics) and IMU samples.

Import only after ``pytest.importorskip('rclpy')`` and the generated messages.
"""
import time

from diagnostic_msgs.msg import DiagnosticArray
from rcl_interfaces.msg import Log
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Imu
from spinning import SpinningContext

T0 = 1_767_225_600 * 10**9          # 2026-01-01, ns
MS = 10**6
RELIABLE = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)


class BridgeGraph(SpinningContext):
    """A context on ``domain_id`` with a probe node; bridges started in it are torn down with it (``with``)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def bridge(self, node_class, name, **params):
        """A ``node_class`` (SensorBridge or ManagedSensorBridge) named ``name`` in this process."""
        return self.add(node_class(name, context=self.context, parameter_overrides=[
            Parameter(k, value=v) for k, v in params.items()]))

    def collect(self, msg_type, topic, qos=RELIABLE):
        """List that fills with the messages arriving on ``topic``."""
        received = []
        self.probe.create_subscription(msg_type, topic, received.append, qos)
        return received

    def log_lines(self, node_name):
        """List that fills with the /rosout messages of ``node_name``."""
        lines = []
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.probe.create_subscription(
            Log, '/rosout', lambda m: lines.append(m) if m.name.split('.')[-1] == node_name else None, qos)
        return lines

    def statuses(self, status_name):
        """List that fills with the DiagnosticStatus named ``status_name`` from /diagnostics."""
        found = []
        self.probe.create_subscription(DiagnosticArray, '/diagnostics', lambda a: found.extend(
            s for s in a.status if s.name == status_name), 100)
        return found


def imu_message(k, frame_id='imu_link'):
    """Sample k: stamp T0 + k ms, linear_acceleration y = k / 100 m/s^2 (x and z other values)."""
    msg = Imu()
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(T0 + k * MS, 10**9)
    msg.header.frame_id = frame_id
    msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z = -1.0, k / 100.0, 9.81
    return msg


def publish_at_1khz(publisher, indices):
    """Publish the samples ``indices`` at about 1 kHz of wall time (ten every 10 ms)."""
    start = time.monotonic()
    for n, k in enumerate(indices):
        publisher.publish(imu_message(int(k)))
        if n % 10 == 9:
            delay = start + (n + 1) * 1e-3 - time.monotonic()
            if delay > 0:
                time.sleep(delay)


def values_of(status):
    """KeyValues of a DiagnosticStatus as a dict."""
    return {kv.key: kv.value for kv in status.values}


def block_stamp(block):
    """Header stamp of a block as int ns."""
    return block.header.stamp.sec * 10**9 + block.header.stamp.nanosec
