#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""CPU time of the estimator's input path per actuator-second, without DDS: code trees compared on a loaded machine.

``live_latency.py`` measures real-time capacity, which a machine busy with
other work cannot show (its estimator, niced, falls behind at any count when
the core is taken).  This benchmark measures what that capacity is made of,
in process CPU time, which other load inflates far less: a
:class:`LubricationEstimator` with ``--actuators`` actuators (the
calibration of ``live_latency.py``: band and healthy baseline) is fed
``--seconds`` of each actuator's inputs (4 kHz vibration in 0.1 s blocks,
joint states 100 Hz, load 50 Hz, temperature 1 Hz, screw at 20 rad/s and
150 N, as live_latency's generator sends) through its own callback path:
each 0.1 s, the joint states, loads and temperatures of the slice join the
actuator's auxiliary queues (lists standing in for the subscriptions' queues,
serialized for the inputs the node subscribes to raw), then the vibration
subscription's callback gets the block; the node drains the queues when it
flushes (taking blocks and inputs, closing and assessing windows, publishing
states), as it does live.  Only DDS and the executor are left out.

Each ``--code`` tree (a checkout, e.g. ``git worktree add /tmp/base main``; ``.`` is this one) runs in a
child process of its own, alternately, ``--repeat`` times; the result is the median CPU ms per
actuator-second and the actuators one core could feed at that cost (1000 / it).  Results go to
``benchmarks/results/<name>.{json,md}``.

Usage: ``nice -n 10 python benchmarks/estimator_input_cost.py --code /tmp/base --code . [--actuators 8]
[--seconds 30] [--repeat 5] [--name estimator_input_cost]`` (after ``source .env-jazzy.sh``).
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import statistics
import subprocess
import sys
import tempfile

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
SPEED, LOAD, RATE, BLOCK = 20.0, 150.0, 4000.0, 0.1


class ListDrain:
    """Stands in for ``fast_drain.FastDrain``: takes up to ``limit`` messages from a list the feed fills.

    The vibration subscription's own queue (drained by its callback) is empty
    here: the feed hands each block to the callback.
    """

    enabled = True

    @staticmethod
    def drain(queue, limit: int):
        if not isinstance(queue, list):
            return iter(())
        taken = queue[:limit]
        del queue[:limit]
        return iter(taken)


def run_child(count: int, seconds: float) -> dict:
    """In the code tree first on sys.path: feed the estimator and return its process CPU time."""
    import time

    import numpy as np
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from rclpy.parameter import Parameter
    from sensor_msgs.msg import JointState, Temperature

    from prsm_lube_ros.estimation.calibration_file import save_calibration
    from prsm_lube_ros.msg import VibrationBlock
    from rclpy.serialization import serialize_message

    from prsm_lube_ros.nodes.lubrication_estimator import actuator_label, LubricationEstimator
    from prsm_lube_ros.nodes.raw_inputs import RAW_INPUTS
    from prsm_lube_ros.nodes.ros_convert import time_from_ns
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from live_latency import actuator_names, benchmark_calibration   # the live benchmark's actuators

    folder = tempfile.mkdtemp(prefix='input_cost_')
    names = actuator_names(count)
    for name in names:
        save_calibration(benchmark_calibration(), os.path.join(folder, f'calibration_{actuator_label(name)}.yaml'))
    rclpy.init(args=['estimator_input_cost'])
    node = LubricationEstimator(parameter_overrides=[
        Parameter('actuators', value=names),
        Parameter('calibration_file', value=os.path.join(folder, 'calibration_{actuator}.yaml')),
        Parameter('recordings_dir', value=folder), Parameter('stale_timeout', value=600.0)])
    vibration = {s.topic_name.rsplit('/', 1)[0]: s.callback for s in node.subscriptions
                 if s.topic_name.endswith('/vibration')}
    if not node._fast.enabled:
        raise RuntimeError('the fast drain is off in this rclpy: the node takes its inputs one callback at a time, '
                           'which this benchmark does not feed')
    node._fast = ListDrain()                 # the subscriptions' queues, as lists the feed below fills
    queues = {}
    for channel in node.channels:
        queues[channel.name] = {key: [] for key, _, _ in channel.auxiliary}
        channel.auxiliary = [(key, queues[channel.name][key], convert) for key, _, convert in channel.auxiliary]
    rng = np.random.default_rng(0)
    size = int(RATE * BLOCK)
    blocks = [(rng.standard_normal(size) * 2.0).astype(np.float32) for _ in range(10)]
    start_ns = time.time_ns() - int(seconds * 1e9) - 10**9
    slices = int(round(seconds / BLOCK))

    def stamp(t: float):
        return time_from_ns(start_ns + int(round(t * 1e9)))

    def as_taken(key: str, msg):
        """What the node's subscription hands over: the CDR bytes of a raw input, else the message."""
        return serialize_message(msg) if key in RAW_INPUTS else msg

    feed = []                     # built before the clock starts: only the estimator's work is timed
    for k in range(slices):
        t0 = k * BLOCK
        for index, channel in enumerate(node.channels):
            queued: dict[str, list] = {'joint_states': [], 'axial_load': [], 'temperature': []}
            for j in range(10):
                t = t0 + j * 0.01
                msg = JointState(name=['screw'], position=[SPEED * t], velocity=[SPEED])
                msg.header.stamp = stamp(t)
                queued['joint_states'].append(as_taken('joint_states', msg))
                if j % 2 == 0:
                    wrench = WrenchStamped()
                    wrench.header.stamp = stamp(t)
                    wrench.wrench.force.z = -LOAD
                    queued['axial_load'].append(as_taken('axial_load', wrench))
            if k % 10 == 0:
                reading = Temperature(temperature=31.0)
                reading.header.stamp = stamp(t0)
                queued['temperature'].append(as_taken('temperature', reading))
            block = VibrationBlock(sample_rate=RATE, samples=blocks[(k + index) % 10])
            block.header.stamp = stamp(t0)
            feed.append((channel, queued, as_taken('vibration', block)))
    started = time.process_time()
    wall = time.monotonic()
    for channel, queued, block in feed:
        for key, queue in queues[channel.name].items():
            queue.extend(queued[key])
        vibration[channel.name](block)
    cpu = time.process_time() - started
    windows = sum(c.windows for c in node.channels)
    problems = sum(c.problem_count() for c in node.channels)
    if windows == 0 or problems:
        raise RuntimeError(f'the estimator made {windows} windows and left out {problems} inputs: the feed is not '
                           'what the node takes (a benchmark of refusals is no benchmark)')
    node.destroy_node()
    rclpy.try_shutdown()
    return {'cpu_s': cpu, 'wall_s': time.monotonic() - wall, 'windows': windows, 'actuator_seconds': count * seconds}


def measure(code: str, count: int, seconds: float) -> dict:
    """One child process on the code tree ``code``."""
    tree = str(Path(code).resolve())
    env = dict(os.environ, PYTHONPATH=tree + os.pathsep + os.environ.get('PYTHONPATH', ''),
               ROS_DOMAIN_ID=str(150 + os.getpid() % 40), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    out = subprocess.run([sys.executable, __file__, '--role', 'child', '--actuators', str(count), '--seconds',
                          str(seconds)], env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise RuntimeError(f'{code}: child failed:\n{out.stderr[-3000:]}')
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--code', action='append', help='code tree to measure (repeat; default: this one)')
    parser.add_argument('--actuators', type=int, default=8)
    parser.add_argument('--seconds', type=float, default=30.0, help='s of input per actuator')
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--name', default='estimator_input_cost')
    parser.add_argument('--role', choices=('child',), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role == 'child':
        print(json.dumps(run_child(args.actuators, args.seconds)))
        return 0
    codes = args.code or ['.']
    runs: dict[str, list] = {code: [] for code in codes}
    for _ in range(args.repeat):
        for code in codes:
            result = measure(code, args.actuators, args.seconds)
            runs[code].append(result)
            print(f'{code}: {1000 * result["cpu_s"] / result["actuator_seconds"]:.2f} CPU ms per actuator-second, '
                  f'{result["windows"]} windows', flush=True)
    summary = {}
    for code, results in runs.items():
        per = [1000 * r['cpu_s'] / r['actuator_seconds'] for r in results]
        median = statistics.median(per)
        summary[code] = {'cpu_ms_per_actuator_second': per, 'median': median,
                         'actuators_per_core': 1000.0 / median, 'windows': [r['windows'] for r in results]}
    commit = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=ROOT, capture_output=True, text=True)
    record = {'actuators': args.actuators, 'seconds': args.seconds, 'repeat': args.repeat,
              'commit': commit.stdout.strip(), 'runs': summary}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f'{args.name}.json').write_text(json.dumps(record, indent=2) + '\n')
    lines = ['# Estimator input path, CPU per actuator-second (`python benchmarks/estimator_input_cost.py`)', '',
             f'{args.actuators} actuators, {args.seconds:g} s of input each, {args.repeat} alternating runs per code '
             'tree (process CPU time; DDS and the executor left out).', '',
             '| code | CPU ms per actuator-second (median) | runs | actuators per core at that cost |',
             '|---|---|---|---|']
    for code, s in summary.items():
        each = ', '.join(f'{v:.2f}' for v in s['cpu_ms_per_actuator_second'])
        lines.append(f'| `{code}` | {s["median"]:.2f} | {each} | {s["actuators_per_core"]:.0f} |')
    (RESULTS / f'{args.name}.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
