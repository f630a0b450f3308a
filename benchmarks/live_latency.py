#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Live estimator: block-arrival-to-publish latency, and how many 4 kHz actuators one core serves.

Two processes per measurement, on a ROS graph of their own (random domain, loopback):

* the **estimator** (:class:`LubricationEstimator`, unchanged, subclassed and its
  callbacks wrapped only to read clocks) pinned with ``os.sched_setaffinity`` to CPU 0 before rclpy starts,
  so its executor and Fast DDS threads all share that one core;
* a **generator** pinned to CPU 1 publishing, for each of N actuators
  (``/aNN/prsm``), 4 kHz vibration in 0.1 s blocks (10 per s), joint states at
  100 Hz, axial load at 50 Hz and temperature at 1 Hz (161 messages per s),
  stamped with the wall clock, screw at a steady 20 rad/s and 150 N, so every
  1 s window is steady and gets a theta_Oil.

Each actuator's calibration is what ``prsm-lube calibrate`` writes today: the
analysis band (0.5 Hz to the 4 kHz rate's upper edge) and a healthy condition
baseline, so every steady window gets its condition indicators (kurtosis,
crest factor, spectral-kurtosis band, envelope order spectrum) and the
estimator its surface defect screen.  ``--raw-band`` writes calibrations of the
raw RMS instead (files from before analysis bands: no indicators), the load
this benchmark measured before issue 34.

Inside the estimator, ``arrival`` is the entry of an executor callback (after
rclpy has taken its message: raw bytes for the estimator's raw subscriptions); ``latency`` is from the arrival
of the callback that closes a window to the return of that window's
``LubricationState`` ``publish()`` (whatever the callback drains from other
queues first is inside it).  ``close delay`` is wall time at that return minus
the window's end plus ``completion_delay``: end to end, with transport and the
wait for the closing callback.  ``processing`` is the time of each ``_add``
(one block, or the joint states or loads drained at once, into the window
builder) and of each ``_close_windows`` (closing, assessment, publishing).  ``lag`` is wall time at a block's
arrival minus its last sample time: it grows without bound once the estimator
falls behind.

N rises until the estimator falls behind: CPU > 90 % of its core, the lag's
p99 above 0.5 s or growing, over 2 % of the blocks lost (under 95 % taken), or over
10 % of the windows lost (under 80 % published).  Results go to
``benchmarks/results/live_latency.{json,md}``.

Usage: ``python benchmarks/live_latency.py [--duration 8] [--levels 1,4,8,16,24,32,40,48,56,64] [--raw-band]
[--name live_latency]`` (run after ``source .env-jazzy.sh``; results to
``benchmarks/results/<name>.{json,md}``).  A last run at ``--profile-at`` actuators (default 32) under cProfile
shows where the estimator's time goes (cProfile slows it; the shares are what counts); with
``LIVE_LATENCY_PSTATS=FILE`` in the environment its whole profile is also written to FILE for ``pstats``.
``LIVE_LATENCY_QOS_DEPTH`` sets the estimator's ``qos_depth`` (default 2000; the node's own default is 500);
``LIVE_LATENCY_STACKS=FILE`` has the estimator write its main thread's stack to FILE every 2 s;
``LIVE_LATENCY_UNREAD_PIPE=1`` puts back the unread pipe described next.
The estimator's output goes to files, never to a pipe nobody reads while the generator runs: a full pipe
blocks its next log call (at 80 actuators its start-up logs pass the 64 KiB a pipe holds; the "collapse"
of ``benchmarks/results/live_latency_collapse_80.md``), and a warm-up that overruns is reported as falling behind.
"""
from __future__ import annotations

import argparse
import array
import json
import math
import os
from pathlib import Path
import platform
import random
import resource
import subprocess
import sys
import tempfile
import time

from results_files import write_results     # beside this file

ROOT = Path(__file__).resolve().parents[1]
SPEED, LOAD, THETA = 20.0, 150.0, 0.8
RATE, BLOCK = 4000.0, 0.1
WARM_UP = 3.0          # s of wall time after the first message before measuring
#: The estimator's CPU (``LIVE_LATENCY_ESTIMATOR_CPU``, 0 or 1: on a shared machine, the one less busy); the
#: generator gets the other.
ESTIMATOR_CPU = int(os.environ.get('LIVE_LATENCY_ESTIMATOR_CPU', '0'))
GENERATOR_CPU = 1 - ESTIMATOR_CPU
#: The estimator's qos_depth (``LIVE_LATENCY_QOS_DEPTH``; the node's default is 500).
QOS_DEPTH = int(os.environ.get('LIVE_LATENCY_QOS_DEPTH', '2000'))
#: ``LIVE_LATENCY_UNREAD_PIPE=1``: the estimator's log into a pipe read only after the generator has finished,
#: as this benchmark did before (to reproduce the collapse it caused, live_latency_collapse_80.md).
UNREAD_PIPE = os.environ.get('LIVE_LATENCY_UNREAD_PIPE') == '1'


def actuator_names(count: int) -> list[str]:
    """Namespaces of the simulated actuators."""
    return [f'/a{k:02d}/prsm' for k in range(count)]


def _percentiles(values, *qs):
    import numpy as np
    if not values:
        return [math.nan] * len(qs)
    return [float(np.percentile(values, q)) for q in qs]


# -- the estimator process --------------------------------------------------------------------------------
def run_estimator(count: int, duration: float, folder: str, profile: bool = False, condition_every: int = 1,
                  code: str = '', executor_kind: str = 'single') -> dict:
    """Spin a timed LubricationEstimator (of checkout ``code``, default this one) for ``count`` actuators.

    ``executor_kind``: ``single`` (rclpy's SingleThreadedExecutor) or ``events``
    (``rclpy.experimental.EventsExecutor``).  Returns what was measured.
    """
    os.sched_setaffinity(0, {ESTIMATOR_CPU})
    if os.environ.get('LIVE_LATENCY_STACKS'):      # where the estimator's main thread is, every 2 s, into FILE
        import faulthandler
        stacks = open(os.environ['LIVE_LATENCY_STACKS'], 'w')   # left open: dumps go on until exit
        faulthandler.dump_traceback_later(2.0, repeat=True, file=stacks)
    sys.path.insert(0, code or str(ROOT))
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator

    clock = time.perf_counter
    record = {'latency': [], 'close_delay': [], 'callback': [], 'processing': {}, 'fed': {}, 'lag': [],
              'lag_at': [], 'blocks': 0, 'blocks_lost': 0, 'windows': 0,
              'windows_lost': 0}
    last_block: dict = {}
    state = {'measuring': False, 'arrival': 0.0, 'seen': 0, 'callbacks': 0}

    class Publisher:
        """Wraps a state publisher: latency from the arrival of the message being taken to publish's return."""

        def __init__(self, inner):
            self.inner = inner
            self.last_stamp = None

        def publish(self, msg):
            self.inner.publish(msg)
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            if state['measuring']:
                record['latency'].append(clock() - state['arrival'])
                record['close_delay'].append(time.time() - (stamp + delay))
                record['windows'] += 1
                if self.last_stamp is not None:      # windows missing: gaps in the actuator's window stamps
                    record['windows_lost'] += max(0, round((stamp - self.last_stamp) / window_length) - 1)
            self.last_stamp = stamp

    def timed_callback(inner):
        def callback(msg):
            start = clock()
            state['arrival'] = start
            state['callbacks'] += 1
            inner(msg)
            if state['measuring']:
                record['callback'].append(clock() - start)
        return callback

    class TimedEstimator(LubricationEstimator):
        def _add(self, channel, key, batch):
            start = clock()
            state['seen'] += 1
            super()._add(channel, key, batch)
            if state['measuring']:
                record['processing'].setdefault(key, []).append(clock() - start)
                record['fed'][key] = record['fed'].get(key, 0) + len(batch)
                if key == 'vibration':
                    samples = int(batch.offsets[-1] - batch.offsets[-2])
                    end = float(batch.stamps[-1]) + samples / float(batch.sample_rates[-1])
                    record['lag'].append(time.time() - end)
                    record['lag_at'].append(time.monotonic())
                    record['blocks'] += len(batch)
                    # Blocks lost on the way: gaps in the actuator's 0.1 s grid of block stamps.
                    stamps = [float(t) for t in batch.stamps]
                    previous = last_block.get(channel.name)
                    steps = [round((b - a) / BLOCK) for a, b in zip([previous] + stamps, stamps) if a is not None]
                    record['blocks_lost'] += sum(step - 1 for step in steps if step > 1)
                    last_block[channel.name] = stamps[-1]

        def _close_windows(self, channel):
            start = clock()
            super()._close_windows(channel)
            if state['measuring']:
                record['processing'].setdefault('closing', []).append(clock() - start)

    if executor_kind == 'events':
        # The EventsExecutor runs every subscription's callback as its messages arrive, whatever the callback
        # group says: the fast drain's queues would be emptied into its no-op callback.  Plain callbacks then.
        import prsm_lube_ros.nodes.fast_drain as fast_drain
        fast_drain.missing_api = lambda: 'a drain the EventsExecutor honours (benchmark: plain callbacks)'
    rclpy.init(args=['estimator'])
    node = TimedEstimator(parameter_overrides=[
        Parameter('actuators', value=actuator_names(count)),
        Parameter('calibration_file', value=os.path.join(folder, 'calibration_{actuator}.yaml')),
        Parameter('recordings_dir', value=folder), Parameter('qos_depth', value=QOS_DEPTH),
        Parameter('stale_timeout', value=60.0), Parameter('condition_every', value=condition_every)])
    for channel in node.channels:
        channel.publisher = Publisher(channel.publisher)
    for subscription in node.subscriptions:        # every callback the executor runs marks an arrival
        subscription.callback = timed_callback(subscription.callback)
    delay, window_length = node._settings.completion_delay, node._settings.window_length
    _freeze_as_run_node_does()
    if executor_kind == 'events':
        from rclpy.experimental import EventsExecutor
        executor = EventsExecutor()    # its node was built with plain callbacks (see below)
    else:
        executor = SingleThreadedExecutor()
    executor.add_node(node)
    print('ready', flush=True)
    timeline = record['timeline'] = {'ready': time.time()}
    deadline = time.monotonic() + 60.0
    while state['seen'] == 0 and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.05)
    timeline['first_input'] = time.time()
    callbacks_before = state['callbacks']
    begin = time.monotonic() + WARM_UP
    while time.monotonic() < begin:
        executor.spin_once(timeout_sec=0.05)
    _time_full_collections(record, state, clock)
    state['measuring'] = True
    timeline['measure_start'] = time.time()
    record['warm_up_callbacks'] = state['callbacks'] - callbacks_before
    usage0, wall0 = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
    end = wall0 + duration
    profiler = None
    if profile:
        import cProfile
        profiler = cProfile.Profile()
        profiler.enable()
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)
    if profiler is not None:
        profiler.disable()
        record['profile'] = _profile_table(profiler)
        if os.environ.get('LIVE_LATENCY_PSTATS'):       # the whole profile, for pstats
            profiler.dump_stats(os.environ['LIVE_LATENCY_PSTATS'])
    usage1, wall1 = resource.getrusage(resource.RUSAGE_SELF), time.monotonic()
    timeline['measure_end'] = time.time()
    state['measuring'] = False
    cpu = (usage1.ru_utime + usage1.ru_stime - usage0.ru_utime - usage0.ru_stime)
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    record['cpu_seconds'], record['wall_seconds'] = cpu, wall1 - wall0
    record['lag_at'] = [t - wall0 for t in record['lag_at']]
    return record


def _freeze_as_run_node_does() -> None:
    """``startup.freeze_startup_objects`` where the code measured has it (run_node calls it once the node is built)."""
    try:
        from prsm_lube_ros.nodes.startup import freeze_startup_objects
    except ImportError:        # a checkout from before it: its process did not freeze
        return
    freeze_startup_objects()


def _time_full_collections(record: dict, state: dict, clock) -> None:
    """Record the duration (s) of each full garbage collection (generation 2) while measuring."""
    import gc
    record['gc_full'] = []
    started = {}

    def callback(phase, info):
        if info.get('generation') != 2:
            return
        if phase == 'start':
            started['at'] = clock()
        elif state['measuring'] and 'at' in started:
            record['gc_full'].append(clock() - started['at'])
    gc.callbacks.append(callback)


def _add_times(row: dict) -> str:
    """``p50 / p99`` ms of adding one vibration batch to the builder, from a level's processing times."""
    block = row.get('processing', {}).get('vibration', {})
    return f'{block.get("p50_ms", math.nan):.2f} / {block.get("p99_ms", math.nan):.2f}'


def _profile_table(profiler, top: int = 14) -> list:
    """The functions with the most own time: ``[{function, own_share, calls}]``."""
    import pstats
    stats = pstats.Stats(profiler).stats
    total = sum(entry[2] for entry in stats.values()) or 1.0
    rows = sorted(stats.items(), key=lambda item: item[1][2], reverse=True)[:top]
    return [{'function': f'{Path(f).name}:{line} {name}', 'own_share': tt / total, 'calls': nc}
            for (f, line, name), (cc, nc, tt, ct, callers) in rows]


# -- the generator process --------------------------------------------------------------------------------
def run_generator(count: int, duration: float) -> dict:
    """Publish ``count`` actuators' inputs in real time for ``duration`` s; return what was sent."""
    os.sched_setaffinity(0, {GENERATOR_CPU})
    sys.path.insert(0, str(ROOT))
    import numpy as np
    import rclpy
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import JointState, Temperature
    from prsm_lube_ros.msg import VibrationBlock
    from prsm_lube_ros.nodes.ros_convert import time_from_ns
    from prsm_lube_ros.nodes.sensor_bridge import publisher_qos
    from prsm_lube_ros.simulation.rig_config import RigConfig
    from prsm_lube_ros.physics.vibration_model import acceleration_amplitude

    rclpy.init(args=['generator'])
    node = rclpy.create_node('live_latency_generator')
    qos = publisher_qos('reliable', 100)
    names = actuator_names(count)
    pubs = [(node.create_publisher(VibrationBlock, f'{ns}/vibration', qos),
             node.create_publisher(JointState, f'{ns}/joint_states', qos),
             node.create_publisher(WrenchStamped, f'{ns}/axial_load', qos),
             node.create_publisher(Temperature, f'{ns}/temperature', qos)) for ns in names]
    rms = float(acceleration_amplitude(SPEED, LOAD, THETA, RigConfig().constants))
    rng = np.random.default_rng(0)
    size = int(RATE * BLOCK)
    blocks = []
    for _ in range(10):
        values = array.array('f')
        values.frombytes((rng.standard_normal(size) * rms).astype(np.float32).tobytes())
        blocks.append(values)
    deadline = time.monotonic() + 30
    while any(p[0].get_subscription_count() == 0 for p in pubs) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.5)
    sent = {'vibration': 0, 'joint_states': 0, 'axial_load': 0, 'temperature': 0}
    late_ticks, tick, period = 0, 0, 0.01
    busy, worst_late = 0.0, 0.0
    # Blocks on the 0.1 s grid, as the windows are on theirs: the close delay does not depend on when a run starts.
    now_ns = time.time_ns()
    start_wall = -(-now_ns // int(BLOCK * 1e9)) * int(BLOCK * 1e9)
    time.sleep((start_wall - now_ns) * 1e-9)
    start = time.monotonic()
    stop = start + duration
    while True:
        due = start + tick * period
        now = time.monotonic()
        if due > stop:
            break
        if due > now:
            time.sleep(due - now)
        elif now - due > period:
            late_ticks += 1
        worst_late = max(worst_late, now - due)
        tick_start = time.monotonic()
        stamp_ns = start_wall + int(round(tick * period * 1e9))
        angle = SPEED * tick * period
        stamp = time_from_ns(stamp_ns)
        for k, (vibration, joints, load, temperature) in enumerate(pubs):
            msg = JointState(name=['screw'], position=[angle], velocity=[SPEED])
            msg.header.stamp = stamp
            joints.publish(msg)
            sent['joint_states'] += 1
            if tick % 2 == 0:
                wrench = WrenchStamped()
                wrench.header.stamp = stamp
                wrench.wrench.force.z = -LOAD
                load.publish(wrench)
                sent['axial_load'] += 1
            if tick % 100 == 0:
                reading = Temperature(temperature=31.0)
                reading.header.stamp = stamp
                temperature.publish(reading)
                sent['temperature'] += 1
            if tick % 10 == 0 and tick > 0:
                block = VibrationBlock()
                block.header.stamp = time_from_ns(stamp_ns - int(BLOCK * 1e9))
                block.sample_rate = RATE
                block.samples = blocks[(tick // 10 + k) % 10]
                vibration.publish(block)
                sent['vibration'] += 1
        busy += time.monotonic() - tick_start
        tick += 1
    seconds = time.monotonic() - start
    node.destroy_node()
    rclpy.try_shutdown()
    return {'sent': sent, 'ticks': tick, 'late_ticks': late_ticks, 'seconds': seconds, 'busy_fraction': busy / seconds,
            'worst_late_s': worst_late, 'start_wall': start_wall * 1e-9, 'end_wall': time.time()}


# -- the driver --------------------------------------------------------------------------------------------
def benchmark_calibration(raw_band: bool = False):
    """The actuators' calibration: the rig's constants, with the band and a healthy baseline unless ``raw_band``."""
    sys.path.insert(0, str(ROOT))
    import numpy as np
    from prsm_lube_ros.estimation.calibration import Calibration
    from prsm_lube_ros.estimation.conditioning import DEFAULT_BAND
    from prsm_lube_ros.estimation.defect_screen import ConditionBaseline
    from prsm_lube_ros.simulation.rig_config import RigConfig
    calibration = Calibration(constants=RigConfig().constants, covariance=np.diag([1e-6, 1e-12, 1e-6]),
                              fit_rmse=0.0, residual_std=0.01, windows_used=6, reference_theta=1.0)
    if raw_band:
        return calibration
    from dataclasses import replace
    baseline = ConditionBaseline(runs=6, kurtosis_median=3.0, kurtosis_max=3.2, crest_median=4.2, crest_max=4.6,
                                 envelope_levels=((6.25, 5.0), (3.75, 5.0)))
    return replace(calibration, band=DEFAULT_BAND.resolved(RATE), condition_baseline=baseline)


def measure(count: int, duration: float, profile: bool = False, raw_band: bool = False,
            condition_every: int = 1, code: str = '', executor_kind: str = 'single') -> dict:
    """One level: N actuators for ``duration`` s of measurement (estimator of checkout ``code``); a summary dict."""
    sys.path.insert(0, str(ROOT))
    import numpy as np
    from prsm_lube_ros.estimation.calibration_file import save_calibration
    from prsm_lube_ros.nodes.lubrication_estimator import actuator_label

    env = dict(os.environ, ROS_DOMAIN_ID=str(random.randint(100, 199)), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               PYTHONUNBUFFERED='1')
    env.pop('ROS_LOCALHOST_ONLY', None)
    with tempfile.TemporaryDirectory() as folder:
        calibration = benchmark_calibration(raw_band)
        for name in actuator_names(count):
            save_calibration(calibration, os.path.join(folder, f'calibration_{actuator_label(name)}.yaml'))
        out = os.path.join(folder, 'estimator.json')
        # The estimator's output goes to files, not pipes: nobody reads a pipe while the generator runs, and a
        # full pipe (64 KiB: the log lines of some 80 actuators' start-up and first diagnostics) blocks the
        # estimator in its next log call until the generator has finished (live_latency_collapse_80.md).
        printed, logged = Path(folder, 'estimator.out'), Path(folder, 'estimator.log')
        with printed.open('w') as stdout, logged.open('w') as stderr:
            estimator = subprocess.Popen([sys.executable, __file__, '--role', 'estimator', '--count', str(count),
                                          '--duration', str(duration), '--folder', folder, '--out', out,
                                          '--condition-every', str(condition_every), '--executor', executor_kind]
                                         + (['--code', code] if code else []) + (['--profile'] if profile else []),
                                         env=env, stdout=stdout, stderr=subprocess.PIPE if UNREAD_PIPE else stderr,
                                         text=True)
        while not printed.read_text().startswith('ready') and estimator.poll() is None:
            time.sleep(0.05)
        assert printed.read_text().startswith('ready'), logged.read_text()[-2000:]
        generator = subprocess.run([sys.executable, __file__, '--role', 'generator', '--count', str(count),
                                    '--duration', str(duration + WARM_UP + 3.0)], env=env, capture_output=True,
                                   text=True, timeout=duration + 120)
        piped = estimator.communicate(timeout=duration + 120)[1]      # read only now, as before the fix
        err = piped if piped is not None else logged.read_text()
        if estimator.returncode or generator.returncode:
            raise RuntimeError(f'N={count}: estimator {estimator.returncode}: {err[-2000:]}\n'
                               f'generator {generator.returncode}: {generator.stderr[-2000:]}')
        record = json.loads(Path(out).read_text())
        record['log_bytes'] = len(err.encode())
    sent = json.loads(generator.stdout.strip().splitlines()[-1])
    wall = record['wall_seconds']
    lag, lag_at = record['lag'], record['lag_at']
    slope = float(np.polyfit(lag_at, lag, 1)[0]) if len(lag) > 10 else math.nan
    processing = {key: dict(zip(('p50_ms', 'p99_ms'), [v * 1e3 for v in _percentiles(values, 50, 99)]),
                            count=len(values), messages=record['fed'].get(key, 0))
                  for key, values in record['processing'].items()}
    summary = {
        'actuators': count,
        'cpu_utilisation': record['cpu_seconds'] / wall,
        'latency_p50_ms': _percentiles(record['latency'], 50)[0] * 1e3,
        'latency_p99_ms': _percentiles(record['latency'], 99)[0] * 1e3,
        'latency_max_ms': max(record['latency']) * 1e3 if record['latency'] else math.nan,
        'close_delay_p50_ms': _percentiles(record['close_delay'], 50)[0] * 1e3,
        'close_delay_p99_ms': _percentiles(record['close_delay'], 99)[0] * 1e3,
        'callbacks_per_s': len(record['callback']) / wall,
        'callback_p50_ms': _percentiles(record['callback'], 50)[0] * 1e3,
        'callback_p99_ms': _percentiles(record['callback'], 99)[0] * 1e3,
        'processing': processing,
        'callbacks_share_of_cpu': sum(record['callback']) / record['cpu_seconds'] if record['cpu_seconds']
        else math.nan,
        'lag_p50_s': _percentiles(lag, 50)[0], 'lag_p99_s': _percentiles(lag, 99)[0],
        'lag_slope_s_per_s': slope,
        'blocks_received_fraction': record['blocks'] / (count * wall / BLOCK),
        # Of the blocks the estimator should have had between the first and last it took of each actuator.
        'blocks_lost_fraction': record['blocks_lost'] / max(1, record['blocks'] + record['blocks_lost']),
        'windows_published_fraction': record['windows'] / (count * wall),
        # Of the windows between each actuator's first and last published while measuring: gaps in their stamps.
        'windows_lost_fraction': record['windows_lost'] / max(1, record['windows'] + record['windows_lost']),
        'generator': sent,
        # Wall clock (s since the epoch) of the estimator's ready, first input and measurement.
        'timeline': record['timeline'], 'warm_up_callbacks': record['warm_up_callbacks'],
        'estimator_log_bytes': record['log_bytes'],
        # Full garbage collections while measuring (the whole process stops for them): count and longest, ms.
        'gc_full_collections': len(record.get('gc_full', [])),
        'gc_full_max_ms': 1e3 * max(record.get('gc_full') or [0.0]),
    }
    if 'profile' in record:
        summary['profile'] = record['profile']
    # Kept up: at most 2 % of its 10 ms ticks started over a tick late, and none over a block (0.1 s) late.
    summary['generator_kept_up'] = (sent['late_ticks'] <= 0.02 * sent['ticks']
                                    and sent['worst_late_s'] < BLOCK)
    warm_up = summary['timeline']['measure_start'] - summary['timeline']['first_input']
    reasons = []
    if summary['cpu_utilisation'] > 0.9:
        reasons.append('CPU > 90 %')
    if not summary['lag_p99_s'] < 0.5:
        reasons.append('lag p99 > 0.5 s')
    if summary['lag_slope_s_per_s'] > 0.02:
        reasons.append('lag growing')
    # Lost: over 2 % of the blocks missing from the grids.  Taken: under 95 %, as the blocks are counted at flushes,
    # which all actuators have at the same block times, so the blocks pending at the measurement's two edges
    # (up to FLUSH_PERIOD + a block, 4 % of 8 s) move the count a few % either way even with none lost.
    if summary['blocks_lost_fraction'] > 0.02 or summary['blocks_received_fraction'] < 0.95:
        reasons.append('blocks missing')
    # Lost: over 10 % missing from the 1 s grids.  Published: under 80 %, as all actuators' windows close together:
    # an 8 s measurement holds 7, 8 or 9 of their closing moments (12.5 % either way) with none lost.
    if summary['windows_lost_fraction'] > 0.1 or summary['windows_published_fraction'] < 0.8:
        reasons.append('windows missing')
    if warm_up > WARM_UP + 1.0:      # a callback held the executor: the measurement drains a backlog
        reasons.append(f'warm-up took {warm_up:.1f} s')
    summary['behind'] = reasons
    return summary


def _lost(level: dict, what: str = 'blocks') -> str:
    """' (N % lost)': blocks (or windows) missing from the actuators' grids ('' in results from before)."""
    lost = level.get(f'{what}_lost_fraction')
    return '' if lost is None else f' ({100 * lost:.1f} % lost)'


def _busy(level: dict) -> str:
    """' (N % busy)': the share of the generator's run it spent publishing ('' in results from before)."""
    busy = level['generator'].get('busy_fraction')
    return '' if busy is None else f' ({100 * busy:.0f} % busy)'


def markdown(results: dict) -> str:
    """The results as a Markdown report."""
    lines = ['# Live estimator latency and capacity (`python benchmarks/live_latency.py`)', '',
             f'{results["python"]}, {results["cpus"]} CPUs; estimator pinned to CPU {ESTIMATOR_CPU} (executor and '
             f'Fast DDS threads), generator to CPU {GENERATOR_CPU}; {results["duration"]:g} s measured per level '
             f'after {WARM_UP:g} s warm-up. Per actuator: 4 kHz vibration in 0.1 s blocks, joint states 100 Hz, '
             'load 50 Hz, temperature 1 Hz; 1 s windows, each published with a theta_Oil. Calibrations: '
             + ('raw RMS (no analysis band): no condition indicators, no surface defect screen.'
                if results.get('raw_band') else
                'analysis band and healthy baseline: condition indicators on every '
                f'{results.get("condition_every", 1)}. window, surface defect screen on.')
             + f' Commit {results.get("commit", "?")}.', '',
             'Latency: entry of the executor callback that closes a window (after rclpy took its message, raw or '
             'deserialized; any queues the callback drains are inside the latency) to the return of the '
             'LubricationState `publish()`. Close delay: wall time at that return minus (window end + '
             'completion_delay), the earliest moment every input of the window can have been sent; it also '
             'counts transport, waiting for the closing callback, and one block (0.1 s): a stream has passed a '
             'time when its last sample has, and the block ending on end + completion_delay ends a quarter of a ms '
             'short of it (blocks are generated on the 0.1 s grid). Callbacks: input callbacks the executor ran '
             'per s, their duration, and their share of the process\'s CPU time (the rest is rclpy\'s executor, '
             'deserialization and DDS). Block, joint, load: one `_add` to the window builder of one block, or of '
             'the joint states or loads drained at once; closing: one `_close_windows` (closing, assessment, '
             'publishing). Lag: wall time at a block\'s arrival '
             'minus its last sample time. Generator kept up: at most 2 % of its 10 ms ticks over a tick late and '
             'none over 0.1 s late; busy: the share of its run it spent publishing (its own core).', '',
             '| actuators | CPU of its core | latency p50 ms | latency p99 ms | close delay p50 ms | '
             'close delay p99 ms | callbacks /s | callback p50 ms | callback p99 ms | block p50 ms | '
             'joint p50 ms | load p50 ms | closing p50 ms | callbacks share of CPU | lag p99 s | lag slope s/s | '
             'blocks in | windows out | generator kept up | falls behind |',
             '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|']
    for r in results['levels']:
        p = r['processing']
        lines.append(
            f'| {r["actuators"]} | {100 * r["cpu_utilisation"]:.0f} % | {r["latency_p50_ms"]:.2f} | '
            f'{r["latency_p99_ms"]:.2f} | {r["close_delay_p50_ms"]:.1f} | {r["close_delay_p99_ms"]:.1f} | '
            f'{r["callbacks_per_s"]:.0f} | {r["callback_p50_ms"]:.3f} | {r["callback_p99_ms"]:.3f} | '
            f'{p.get("vibration", {}).get("p50_ms", math.nan):.3f} | '
            f'{p.get("joint_states", {}).get("p50_ms", math.nan):.3f} | '
            f'{p.get("axial_load", {}).get("p50_ms", math.nan):.3f} | '
            f'{p.get("closing", {}).get("p50_ms", math.nan):.3f} | {100 * r["callbacks_share_of_cpu"]:.0f} % | '
            f'{r["lag_p99_s"]:.3f} | {r["lag_slope_s_per_s"]:.4f} | {100 * r["blocks_received_fraction"]:.1f} %'
            f'{_lost(r)} | '
            f'{100 * r["windows_published_fraction"]:.1f} %{_lost(r, "windows")} | '
            f'{"yes" if r["generator_kept_up"] else "NO"}'
            f'{_busy(r)} | '
            f'{", ".join(r["behind"]) or "no"} |')
    lines += ['', f'Largest N served in real time on one core: **{results["max_actuators_real_time"]}**.',
              f'Goals: latency p99 < 5 ms ({results["goals"]["latency_p99_under_5ms"]}), '
              f'>= 32 actuators on one core ({results["goals"]["at_least_32_actuators"]}), '
              f'>= 50 (issue 34: {results["goals"]["at_least_50_actuators"]}).', '']
    if 'profile' in results:
        lines += [f'Where the estimator process spends its time at {results["profile"]["actuators"]} actuators '
                  '(cProfile, own time of each function as a share of the profiled wall time; the rclpy `wait` '
                  'includes idle time):', '',
                  '| function | own time share | calls |', '|---|---|---|']
        lines += [f'| `{row["function"]}` | {100 * row["own_share"]:.1f} % | {row["calls"]} |'
                  for row in results['profile']['functions']]
        lines.append('')
    return '\n'.join(lines)


def main(argv=None) -> int:
    """Run the levels (or one role of a measurement, when called by itself) and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--duration', type=float, default=8.0, help='s measured per level')
    parser.add_argument('--levels', default='1,4,8,16,24,32,40,48,56,64', help='actuator counts, in rising order')
    parser.add_argument('--profile-at', type=int, default=32, help='actuators of the profiled run (0: none)')
    parser.add_argument('--raw-band', action='store_true',
                        help='calibrations of the raw RMS: no condition indicators (the load before issue 34)')
    parser.add_argument('--name', default='live_latency', help='results file name in benchmarks/results')
    parser.add_argument('--condition-every', type=int, default=1,
                        help="the estimator's condition_every: indicators on every k-th window only")
    parser.add_argument('--executor', choices=('single', 'events'), default='single',
                        help="the estimator's executor: rclpy's SingleThreadedExecutor (default) or the "
                        'EventsExecutor of rclpy.experimental')
    parser.add_argument('--code', default='', metavar='CHECKOUT',
                        help='run the estimator of this checkout (e.g. a worktree of main: the code before a change)')
    parser.add_argument('--compare', default='', metavar='CHECKOUT:EXECUTOR,...',
                        help='instead of one configuration, alternate these at each level (CHECKOUT "." for this '
                        'one), e.g. "/tmp/main:single,.:single,.:events": before and after measured in one run')
    parser.add_argument('--keep-going', action='store_true',
                        help='with --compare, measure every level even for a configuration already behind')
    parser.add_argument('--profile', action='store_true', help=argparse.SUPPRESS)
    parser.add_argument('--role', choices=('estimator', 'generator'), help=argparse.SUPPRESS)
    parser.add_argument('--count', type=int, help=argparse.SUPPRESS)
    parser.add_argument('--folder', help=argparse.SUPPRESS)
    parser.add_argument('--out', help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.role == 'estimator':
        record = run_estimator(args.count, args.duration, args.folder, args.profile, args.condition_every,
                               args.code, args.executor)
        Path(args.out).write_text(json.dumps(record))
        return 0
    if args.role == 'generator':
        print(json.dumps(run_generator(args.count, args.duration)))
        return 0
    if len(os.sched_getaffinity(0)) < 2:
        print('live_latency: needs two CPUs (estimator and generator on one each)', file=sys.stderr)
        return 2
    if args.compare:
        return compare(args)
    levels = []
    for count in (int(n) for n in args.levels.split(',')):
        summary = measure(count, args.duration, raw_band=args.raw_band, condition_every=args.condition_every,
                          code=args.code, executor_kind=args.executor)
        levels.append(summary)
        print(f'N={count}: CPU {100 * summary["cpu_utilisation"]:.0f} %, latency p99 '
              f'{summary["latency_p99_ms"]:.2f} ms, lag p99 {summary["lag_p99_s"]:.3f} s, '
              f'behind: {", ".join(summary["behind"]) or "no"}', flush=True)
        if set(summary['behind']) - {'CPU > 90 %'}:
            break                   # really behind (lag, lost data); a saturated core alone is noted, not final
    served = [r['actuators'] for r in levels if not r['behind']]
    first = levels[0]
    commit = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=ROOT, capture_output=True, text=True)
    results = {'python': f'Python {platform.python_version()}', 'cpus': os.cpu_count(), 'duration': args.duration,
               'raw_band': args.raw_band, 'condition_every': args.condition_every,
               'commit': commit.stdout.strip() or '?',
               'levels': levels, 'max_actuators_real_time': max(served) if served else 0,
               'latency_single_actuator_ms': {'p50': first['latency_p50_ms'], 'p99': first['latency_p99_ms']}}
    results['goals'] = {
        'latency_p99_under_5ms': 'met' if all(r['latency_p99_ms'] < 5.0 for r in levels if not r['behind'])
        else 'NOT met',
        'at_least_32_actuators': 'met' if results['max_actuators_real_time'] >= 32 else 'NOT met',
        'at_least_50_actuators': 'met' if results['max_actuators_real_time'] >= 50 else 'NOT met'}
    if args.profile_at:
        results['profile'] = {'actuators': args.profile_at,
                              'functions': measure(args.profile_at, args.duration, profile=True,
                                                   raw_band=args.raw_band,
                                                   condition_every=args.condition_every)['profile']}
    write_results(args.name, results, markdown(results).split('\n'))
    return 0


def compare(args: argparse.Namespace) -> int:
    """Configurations (checkout and executor) measured alternately at each level: before and after in one run.

    At each level every configuration still keeping up runs once, in turn, so
    the other sessions' load falls on them alike; a configuration that falls
    behind is dropped from the higher levels.  Writes
    ``benchmarks/results/<name>.{json,md}``: per configuration the largest N
    served and its latency p99, and every level's row.
    """
    configurations = []
    for item in args.compare.split(','):
        code, _, executor = item.rpartition(':')
        code = '' if code in ('', '.') else str(Path(code).resolve())
        configurations.append({'label': f'{Path(code).name if code else "this checkout"}, {executor} executor',
                               'code': code, 'executor': executor, 'levels': [], 'behind': False})
    for count in (int(n) for n in args.levels.split(',')):
        for config in configurations:
            if config['behind']:
                continue
            summary = measure(count, args.duration, raw_band=args.raw_band, condition_every=args.condition_every,
                              code=config['code'], executor_kind=config['executor'])
            config['levels'].append(summary)
            print(f'{config["label"]}: N={count}: CPU {100 * summary["cpu_utilisation"]:.0f} %, latency p99 '
                  f'{summary["latency_p99_ms"]:.2f} ms, lag p99 {summary["lag_p99_s"]:.3f} s, '
                  f'behind: {", ".join(summary["behind"]) or "no"}', flush=True)
            config['behind'] = bool(summary['behind']) and not args.keep_going
    for config in configurations:
        served = [r for r in config['levels'] if not r['behind']]
        config['max_actuators_real_time'] = served[-1]['actuators'] if served else 0
        config['latency_p99_ms_at_max'] = served[-1]['latency_p99_ms'] if served else math.nan
        config['cpu_at_max'] = served[-1]['cpu_utilisation'] if served else math.nan
        # The estimator's own CPU per actuator (rusage: what it did, whatever else ran on its core), and the
        # actuators 90 % of a core would serve at that cost: comparable on a loaded machine where the largest
        # N served is not.
        costs = [r['cpu_utilisation'] / r['actuators'] for r in served]
        config['cpu_ms_per_actuator_s'] = 1e3 * min(costs) if costs else math.nan
        config['actuators_per_core_from_cpu'] = 0.9 / min(costs) if costs else math.nan
    commit = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=ROOT, capture_output=True, text=True)
    results = {'python': f'Python {platform.python_version()}', 'cpus': os.cpu_count(), 'duration': args.duration,
               'raw_band': args.raw_band, 'condition_every': args.condition_every, 'commit': commit.stdout.strip(),
               'load_average_1min_at_end': os.getloadavg()[0], 'configurations': configurations,
               'command': 'python benchmarks/live_latency.py ' + ' '.join(sys.argv[1:])}
    lines = [f'# Live estimator capacity, configurations side by side (`{results["command"]}`)', '',
             f'{results["python"]}, {results["cpus"]} CPUs, 1-min load average '
             f'{results["load_average_1min_at_end"]:.1f}'
             f' at the end (a shared machine: compare the configurations, measured alternately at each level, '
             f'not the absolute figures); estimator pinned to CPU {ESTIMATOR_CPU}, {args.duration:g} s per level. '
             + ('Calibrations of the raw RMS: no condition indicators.' if args.raw_band else
                f'Analysis band and baseline: condition indicators on every {args.condition_every}. window.'),
             ' CPU ms per actuator-s: the estimator process\'s own CPU time (rusage) per actuator and second, the '
             'lowest over the levels it kept up with; actuators per core from it: 90 % of a core over that cost. '
             'Blocks in: blocks taken while measuring over those sent meanwhile (taken at flushes: a few % either '
             'way at the edges), lost: gaps in the actuators\' 0.1 s grids of block stamps. Windows out: published '
             'while measuring over N x seconds (all actuators close theirs together: an 8 s measurement holds 7 to 9 '
             'closing moments), lost: gaps in their 1 s grids of window stamps. Generator kept up: at '
             'most 2 % of its 10 ms ticks over a tick late and none over 0.1 s late; busy: its share of the run '
             'spent publishing.',
             '', '| configuration | largest N served | latency p99 ms there | CPU there | CPU ms per actuator-s | '
             'actuators per core from CPU |', '|---|---|---|---|---|---|']
    lines += [f'| {c["label"]} | {c["max_actuators_real_time"]} | {c["latency_p99_ms_at_max"]:.2f} | '
              f'{100 * c["cpu_at_max"]:.0f} % | {c["cpu_ms_per_actuator_s"]:.2f} | '
              f'{c["actuators_per_core_from_cpu"]:.0f} |' for c in configurations]
    lines += ['', '| configuration | actuators | CPU | CPU ms per actuator-s | latency p50 ms | latency p99 ms | '
              'close delay p99 ms | block add p50 / p99 ms | gc full: count, max ms | '
              'lag p99 s | blocks in | windows out | generator kept up | falls behind |',
              '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|']
    lines += [f'| {c["label"]} | {r["actuators"]} | {100 * r["cpu_utilisation"]:.0f} % | '
              f'{1e3 * r["cpu_utilisation"] / r["actuators"]:.2f} | {r["latency_p50_ms"]:.2f} | '
              f'{r["latency_p99_ms"]:.2f} | {r["close_delay_p99_ms"]:.0f} | {_add_times(r)} | '
              f'{r.get("gc_full_collections", 0)}, {r.get("gc_full_max_ms", math.nan):.1f} | '
              f'{r["lag_p99_s"]:.3f} | '
              f'{100 * r["blocks_received_fraction"]:.1f} %{_lost(r)} | '
              f'{100 * r["windows_published_fraction"]:.0f} %{_lost(r, "windows")} | '
              f'{"yes" if r["generator_kept_up"] else "NO"}{_busy(r)} | '
              f'{", ".join(r["behind"]) or "no"} |' for c in configurations for r in c['levels']]
    write_results(args.name, results, lines)
    return 0


if __name__ == '__main__':
    sys.exit(main())
