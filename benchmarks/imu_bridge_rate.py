#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How fast an IMU the bridge's ``source:=imu`` keeps up with: one ``sensor_msgs/Imu`` per sample over DDS.

For each rate the bridge runs as its own process (``scripts/sensor_bridge``,
``source:=imu``, ``sample_rate`` set, 0.1 s blocks); this process publishes
Imu messages with exact stamps ``k / rate`` for ``--seconds`` of wall time
(in 5 ms bursts) and counts the samples that come back in VibrationBlocks.
Reported per rate: the publish rate achieved, the share of samples delivered
in blocks (of those that fill whole blocks: the last, open block is not
published), the bridge's lost-sample count (from its /diagnostics status) and
the CPU the bridge process used (share of one core, from /proc).  Results go
to ``benchmarks/results/imu_bridge_rate.{json,md}``.

Usage: ``python benchmarks/imu_bridge_rate.py [--rates 250 1000 2000 4000] [--seconds 5]``
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
DOMAIN_ID = int(os.environ.get('ROS_DOMAIN_ID', '0') or 0)
T0 = 1_767_225_600 * 10**9


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process, s."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def measure(rate: float, seconds: float) -> dict:
    """One bridge process at ``rate`` Hz: published, delivered, lost, CPU."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import Imu
    from prsm_lube_ros.msg import VibrationBlock

    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    bridge = subprocess.Popen([sys.executable, str(ROOT / 'scripts' / 'sensor_bridge'), '--ros-args',
                               '-r', '__node:=bench_imu_bridge', '-p', 'source:=imu', '-p', 'namespace:=/bench',
                               '-p', 'imu_topic:=/bench_imu/data', '-p', f'sample_rate:={rate}',
                               '-p', 'qos_depth:=20000', '-p', 'diagnostics_period:=0.2'],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sys.path.insert(0, str(ROOT / 'test' / 'support'))
    from spinning import SpinningContext      # the tests' graph side: own context, executor thread
    driver = SpinningContext(DOMAIN_ID, 'bench_imu_driver')
    node = driver.probe
    received, statuses = [0], []
    node.create_subscription(VibrationBlock, '/bench/vibration', lambda m: received.__setitem__(
        0, received[0] + len(m.samples)), QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    node.create_subscription(DiagnosticArray, '/diagnostics', lambda a: statuses.extend(
        s for s in a.status if s.name.startswith('bench_imu_bridge:')), 100)
    publisher = node.create_publisher(Imu, '/bench_imu/data', 20000)
    try:
        deadline = time.monotonic() + 30
        while (publisher.get_subscription_count() < 1 or node.count_publishers('/bench/vibration') < 1
               or not statuses) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.5)
        msg = Imu()
        msg.header.frame_id = 'imu_link'
        burst = max(1, int(round(rate * 0.005)))
        block = max(1, int(round(0.1 * rate)))          # the bridge's default block_length, 0.1 s
        cpu_start, start = cpu_seconds(bridge.pid), time.monotonic()
        sent = 0
        while time.monotonic() - start < seconds:
            for _ in range(burst):
                msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(T0 + int(round(sent * 1e9 / rate)), 10**9)
                msg.linear_acceleration.z = float(sent % 100)
                publisher.publish(msg)
                sent += 1
            delay = start + sent / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        elapsed = time.monotonic() - start
        time.sleep(2.0)                               # blocks in flight, a last status
        cpu = cpu_seconds(bridge.pid) - cpu_start
        values = {kv.key: kv.value for kv in statuses[-1].values} if statuses else {}
    finally:
        bridge.send_signal(signal.SIGINT)
        try:
            bridge.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            bridge.kill()
        driver.close()
    return {'rate_hz': rate, 'published': sent, 'publish_rate_hz': sent / elapsed,
            'delivered_share': received[0] / (sent - sent % block) if sent >= block else 0.0,
            'lost_samples': int(values.get('lost samples', -1)), 'bridge_cpu_share': cpu / (elapsed + 2.0)}


def main() -> int:
    """Run every rate; write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--rates', type=float, nargs='+', default=[250.0, 1000.0, 2000.0, 4000.0])
    parser.add_argument('--seconds', type=float, default=5.0)
    args = parser.parse_args()
    rows = []
    for rate in args.rates:
        row = measure(rate, args.seconds)
        print(json.dumps(row), flush=True)
        rows.append(row)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'imu_bridge_rate.json').write_text(json.dumps({'seconds': args.seconds, 'rows': rows}, indent=2))
    lines = ['| IMU rate Hz | published Hz | samples delivered in blocks | lost (bridge status) '
             '| bridge CPU of a core |', '|---|---|---|---|---|']
    lines += [f'| {r["rate_hz"]:g} | {r["publish_rate_hz"]:.0f} | {100 * r["delivered_share"]:.1f} % | '
              f'{r["lost_samples"]} | {100 * r["bridge_cpu_share"]:.0f} % |' for r in rows]
    (RESULTS / 'imu_bridge_rate.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
