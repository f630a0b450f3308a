# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The lubrication_estimator node on a real ROS graph (rclpy + Fast DDS on loopback).

Inputs are synthetic runs with a known RMS (a whole number of sine periods per
window), so theta_Oil follows from Eq. 23 by hand; the node's answers are also
checked against the offline WindowBuilder + Assessor on the same messages.
"""
from dataclasses import replace
import math
import os
import signal
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest
from spinning import SpinningContext, torn_down

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import WrenchStamped  # noqa: E402
from action_msgs.msg import GoalStatus  # noqa: E402
from rclpy.action import ActionClient  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import JointState, Temperature  # noqa: E402

from prsm_lube_ros.estimation.assessment import Assessor  # noqa: E402
from prsm_lube_ros.estimation.conditioning import DEFAULT_BAND  # noqa: E402
from prsm_lube_ros.estimation.domain import CalibrationDomain  # noqa: E402
from prsm_lube_ros.estimation.calibration import Calibration  # noqa: E402
from prsm_lube_ros.estimation.calibration_file import load_calibration, save_calibration  # noqa: E402
from prsm_lube_ros.estimation.defect_screen import ConditionBaseline  # noqa: E402
from prsm_lube_ros.estimation.health import ERROR, OK, STALE, WARN  # noqa: E402
from prsm_lube_ros.msg import LubricationState, VibrationBlock  # noqa: E402
from prsm_lube_ros.nodes import ros_convert  # noqa: E402
from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator  # noqa: E402
from prsm_lube_ros.action import Calibrate as CalibrateAction  # noqa: E402
from prsm_lube_ros.srv import Calibrate  # noqa: E402
from prsm_lube_ros.physics.vibration_model import acceleration_amplitude, film_speed_load_term, ModelConstants  # noqa
from prsm_lube_ros.estimation.windowing import WindowBuilder, WindowSettings  # noqa: E402

import synthetic_inputs  # noqa: E402
from bridge_graph import values_of  # noqa: E402
from polling import settle, stop_process, wait_for  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(60)]

#: This module's own DDS domain (100..199), apart from other test modules'.
DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 41) % 100 + 100
T0 = synthetic_inputs.T0
SPEED, LOAD = 10.0, 150.0                  # rad/s, N of the live runs
#: Constants the node starts with: theta 0.9 for a sine of amplitude 2 at SPEED, LOAD.
START = ModelConstants(c_sys=1.0, c_f=1e-3, c_lambda=0.3)
START = ModelConstants(c_sys=math.sqrt(2.0) / float(acceleration_amplitude(SPEED, LOAD, 0.9, START)),
                       c_f=1e-3, c_lambda=0.3)
#: Constants of the reference recordings the calibrate service is asked to fit.
TRUE = ModelConstants(c_sys=0.05, c_f=2e-3, c_lambda=0.5)


def calibration(constants):
    """A calibration with the given constants and small, plain uncertainties."""
    return Calibration(constants=constants, covariance=np.diag([1e-6, 1e-12, 1e-6]), fit_rmse=0.0,
                       residual_std=0.01, windows_used=6, reference_theta=1.0)


def rms_for(theta, constants=START, speed=SPEED, load=LOAD):
    """Window RMS (m/s^2) that Eq. 22 gives for theta at speed and load."""
    return float(acceleration_amplitude(speed, load, theta, constants))


# -- synthetic inputs ------------------------------------------------------------------------------
def segments_stream(segments, t0=T0, rate=2000.0, block=0.05, joint_rate=50.0, load_rate=20.0, freq=100.0,
                    vibration=None):
    """Messages ``(stamp, kind, msg)`` in stamp order for segments ``(seconds, rms, speed, load)``.

    The vibration is a sine of ``freq`` Hz with the segment's RMS; 100 Hz puts
    whole periods in every 0.05 s block, so any window of whole blocks has that RMS.
    ``vibration(times, rms, speed, index)``, given, makes the samples of segment
    ``index`` instead (``times`` in s from the segment's start).
    """
    events = []
    t = 0.0
    angle = 0.0
    n = int(round(block * rate))
    for index, (seconds, rms, speed, load) in enumerate(segments):
        blocks = int(round(seconds / block))
        if vibration is not None:
            samples = vibration(np.arange(blocks * n) / rate, rms, speed, index)
        for b in range(blocks):
            start = t + b * block
            chunk = (samples[b * n:(b + 1) * n] if vibration is not None
                     else math.sqrt(2) * rms * np.sin(2 * math.pi * freq * (np.arange(n) / rate)))
            events.append((t0 + start, 'vibration', ros_convert.vibration_block_msg(t0 + start, rate, chunk)))
        for j in range(int(round(seconds * joint_rate))):
            stamp = t + j / joint_rate
            events.append((t0 + stamp, 'joint_states', ros_convert.joint_state_msg(t0 + stamp, angle, speed)))
            angle += speed / joint_rate
        for k in range(int(round(seconds * load_rate))):
            stamp = t + k / load_rate
            events.append((t0 + stamp, 'axial_load', ros_convert.wrench_msg(t0 + stamp, -load)))
        t += seconds
    events.sort(key=lambda e: e[0])
    return events


# -- the graph -------------------------------------------------------------------------------------
class Graph(SpinningContext):
    """A context on this module's domain, an executor thread, a probe node and the estimators started."""

    TYPES = {'vibration': VibrationBlock, 'joint_states': JointState, 'axial_load': WrenchStamped,
             'temperature': Temperature}

    def __init__(self):
        super().__init__(DOMAIN_ID, 'estimator_test_probe')

    def estimator(self, tmp_path, **params):
        """Start an estimator with test defaults (calibration START in tmp_path) and ``params``."""
        if 'calibration_file' not in params:
            save_calibration(calibration(START), tmp_path / 'calibration_prsm.yaml')
        values = dict(calibration_file=str(tmp_path / 'calibration_{actuator}.yaml'),
                      recordings_dir=str(tmp_path), window_length=0.5, completion_delay=0.25,
                      stale_timeout=1.0, diagnostics_period=0.2, qos_depth=2000)
        values.update(params)
        node = LubricationEstimator(context=self.context, parameter_overrides=[
            Parameter(k, value=v) for k, v in values.items()])
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def collect(self, msg_type, topic):
        """List that fills with the messages arriving on ``topic``."""
        received = []
        self.probe.create_subscription(msg_type, topic, received.append, 100)
        return received

    def publishers(self, namespace='/prsm'):
        """Reliable publishers for the input topics of one actuator (compatible with best effort)."""
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        return {kind: self.probe.create_publisher(t, f'{namespace}/{kind}', qos) for kind, t in self.TYPES.items()}

    def publish(self, publishers, events, speedup=4.0):
        """Publish ``events`` in order, ``speedup`` times faster than their stamps advance.

        Like a live sensor (only faster), so no topic runs seconds ahead of another in the
        node's queues; bad events with odd stamps go out in their place in the list.
        """
        wait_for(lambda: all(p.get_subscription_count() > 0 for p in publishers.values()), 10,
                 'estimator subscriptions discovered')
        # The best-effort readers match the writers a little after the writers match them.
        topics = {p.topic_name for p in publishers.values()}
        readers = [s for node in self.nodes for s in node.subscriptions if s.topic_name in topics]
        if readers:
            wait_for(lambda: all(s.get_publisher_count() > 0 for s in readers), 10, 'writers discovered')
        else:                                       # the estimator runs in another process
            time.sleep(1.0)
        start, first = time.monotonic(), events[0][0]
        latest = first
        for _, kind, msg in events:
            latest = max(latest, _)
            delay = start + (latest - first) / speedup - time.monotonic()
            if delay > 0.002:
                time.sleep(delay)
            publishers[kind].publish(msg)


@pytest.fixture
def graph():
    """A fresh ROS graph for one test, always torn down (a callback that raised fails the test)."""
    yield from torn_down(Graph())


def call(graph, name, bag_paths, theta=1.0, persist=False, timeout=30, recording_namespace=''):
    """Call a Calibrate service from the probe; return the response."""
    client = graph.probe.create_client(Calibrate, name)
    assert client.wait_for_service(timeout_sec=10), f'{name} not offered'
    request = Calibrate.Request(bag_paths=[str(p) for p in bag_paths], reference_theta=theta, persist=persist,
                                recording_namespace=recording_namespace)
    future = client.call_async(request)
    wait_for(future.done, timeout, f'answer of {name}')
    return future.result()


def by_window(states):
    """LubricationState messages keyed by window start (rounded to ms)."""
    return {round(s.window_start - T0, 3): s for s in states}


def status_of(array, name_part):
    """The status whose name contains ``name_part`` in a DiagnosticArray."""
    return next(s for s in array.status if name_part in s.name)


# -- tests -----------------------------------------------------------------------------------------
def test_theta_matches_the_offline_assessor_and_the_hand_value(graph, tmp_path):
    node = graph.estimator(tmp_path, window_length=1.0, completion_delay=0.5)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    streams = synthetic_inputs.run_streams()          # sine of amplitude 2 at 10 rad/s, 150 N
    synthetic_frame = ros_convert.batch_messages(streams['vibration'][0])[0].header.frame_id or 'prsm'
    events = [(float(b.stamps[0]), kind, ros_convert.batch_messages(b)[0])
              for kind, key in (('vibration', 'vibration'), ('joint_states', 'screw'), ('axial_load', 'load'),
                                ('temperature', 'temperature')) for b in streams[key]]
    events.sort(key=lambda e: e[0])
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), events)

    # Offline: the same messages through the same builder and the Assessor.
    builder = WindowBuilder(WindowSettings(window_length=1.0, completion_delay=0.5), lead=0.005)
    offline = []
    for batch in synthetic_inputs.interleave(streams):
        builder.add(batch)
        offline.extend(builder.pop_closed())
    assessor = Assessor(calibration(START))
    expected = {round(w.start - T0, 3): assessor.assess_window(w) for w in offline if w.steady}
    assert len(expected) >= 8
    wait_for(lambda: set(expected) <= set(by_window(states)), 15, 'a state for every steady window')
    live = by_window(states)
    for start, item in expected.items():
        state = live[start]
        assert state.theta_oil == pytest.approx(item.theta_oil, abs=0.01), (
            start, state.message, node.channels[0].builder.problem_summary())
        assert state.theta_oil == pytest.approx(0.9, abs=0.01)        # by construction of START
        assert state.screw_speed == pytest.approx(SPEED, rel=1e-6)
        assert state.axial_load == pytest.approx(LOAD, rel=1e-6)
        assert state.vibration_rms == pytest.approx(math.sqrt(2), rel=1e-3)
        assert state.temperature == pytest.approx(31.0)
        assert state.actuator == '/prsm' and state.level == OK
        assert state.header.frame_id == synthetic_frame
        assert state.header.stamp.sec + state.header.stamp.nanosec * 1e-9 == pytest.approx(T0 + start + 1.0)
    resting = [s for s in states if s.screw_speed < 1.0]
    assert resting and all(math.isnan(s.theta_oil) and 'at rest' in s.message for s in resting)


def test_levels_fall_with_theta_recover_with_hysteresis_and_go_stale(graph, tmp_path):
    """Each window judged alone (level_smoothing 1); the smoothing itself is tested in test_health."""
    graph.estimator(tmp_path, level_smoothing=1)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    #          theta, level expected for its windows (warn 0.85, error 0.70, hysteresis 0.03)
    schedule = [(0.90, OK), (0.80, WARN), (0.60, ERROR), (0.72, ERROR), (0.80, WARN), (0.87, WARN),
                (0.95, OK)]
    segments = [(1.0, rms_for(theta), SPEED, LOAD) for theta, _ in schedule] + [(1.0, rms_for(0.95), SPEED, LOAD)]
    wait_for(lambda: len(diagnostics) > 0, 10, 'first diagnostics')
    assert status_of(diagnostics[-1], '/prsm').level == bytes([STALE])     # no vibration yet
    graph.publish(graph.publishers(), segments_stream(segments))
    wait_for(lambda: len(by_window(states)) >= 2 * len(schedule), 15, 'states of the schedule')
    live = by_window(states)
    for i, (theta, level) in enumerate(schedule):
        for half in (0.0, 0.5):
            state = live[round(i + half, 3)]
            assert state.theta_oil == pytest.approx(theta, abs=0.01), (i, half)
            assert state.level == level, (i, half, state.message)
    seen = [ros_convert.status_level(status_of(a, '/prsm')) for a in diagnostics]
    order = [level for k, level in enumerate(seen) if k == 0 or level != seen[k - 1]]
    assert order[:5] == [STALE, OK, WARN, ERROR, WARN]
    status = status_of(diagnostics[-1], '/prsm')
    assert status.name == 'lubrication_estimator: /prsm lubrication' and status.hardware_id == 'prsm'
    values = values_of(status)
    assert {'theta_oil', 'theta_oil_std', 'vibration_rms', 'screw_speed', 'axial_load', 'window',
            'calibration_file', 'problems'} <= set(values)
    # Inputs stop: STALE within stale_timeout (1 s) + a diagnostics period, keeping the last theta.
    wait_for(lambda: status_of(diagnostics[-1], '/prsm').level == bytes([STALE]), 5, 'STALE')
    assert 'no vibration for' in status_of(diagnostics[-1], '/prsm').message


def test_staleness_follows_the_node_clock_under_sim_time(graph, tmp_path):
    """With use_sim_time, STALE comes from /clock time without vibration, not from wall time."""
    from rosgraph_msgs.msg import Clock
    node = graph.estimator(tmp_path, use_sim_time=True)
    clock = graph.probe.create_publisher(Clock, '/clock', 10)
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')

    def tick(seconds):
        clock.publish(Clock(clock=ros_convert.time_msg(seconds)))

    wait_for(lambda: clock.get_subscription_count() > 0, 10, '/clock subscribed')
    tick(1000.0)
    wait_for(lambda: node.now() == pytest.approx(1000.0), 10, 'node clock at 1000 s')
    graph.publish(graph.publishers(), segments_stream([(1.5, rms_for(0.9), SPEED, LOAD)]))
    wait_for(lambda: node.channels[0].windows >= 2, 10, 'windows')
    time.sleep(1.5)                                  # wall time passes, /clock does not
    count = len(diagnostics)
    tick(1000.4)
    wait_for(lambda: len(diagnostics) > count, 10, 'diagnostics after a /clock step')
    assert status_of(diagnostics[-1], '/prsm').level == bytes([OK])
    assert diagnostics[-1].header.stamp.sec == 1000
    tick(1001.6)                                     # 1.6 s of node clock without vibration > 1.0 s
    wait_for(lambda: status_of(diagnostics[-1], '/prsm').level == bytes([STALE]), 10, 'STALE on /clock')
    status = status_of(diagnostics[-1], '/prsm')
    assert 'no vibration for more than stale_timeout' in status.message
    assert values_of(status)['last_vibration_age'] == '1.6'


def test_bad_inputs_are_left_out_and_the_node_keeps_publishing(graph, tmp_path):
    node = graph.estimator(tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    rms = rms_for(0.9)
    good = segments_stream([(2.0, rms, SPEED, LOAD)])
    # Zero load for windows [2, 3); a gap of lost blocks in [3, 3.5); good again from 3.5 s on.
    zero = segments_stream([(1.0, rms, SPEED, 0.0)], t0=T0 + 2.0)
    after = [e for e in segments_stream([(3.0, rms, SPEED, LOAD)], t0=T0 + 3.0)
             if not (e[1] == 'vibration' and e[0] < T0 + 3.4)]
    bad = [
        (T0 + 1.0, 'vibration', ros_convert.vibration_block_msg(T0 + 1.0, 2000.0, [np.nan, np.inf, 1.0])),
        (T0 + 1.0, 'vibration', ros_convert.vibration_block_msg(T0 + 1.0, 2000.0, [])),
        (T0 + 1.0, 'vibration', ros_convert.vibration_block_msg(T0 + 1.0, 0.0, [1.0, 2.0])),
        (T0 + 1.0, 'vibration', ros_convert.vibration_block_msg(T0 + 1.0, -5.0, [1.0, 2.0])),
        (T0 + 1.0, 'joint_states', ros_convert.joint_state_msg(T0 + 1.0, 0.0, 1.0, joint='motor')),
        (T0 + 1.0, 'joint_states', JointState(header=ros_convert.joint_state_msg(T0 + 1.0, 0, 0).header,
                                              name=['screw'])),  # screw without position/velocity
        (T0 + 1.0, 'axial_load', WrenchStamped()),                   # header.stamp never set
        (T0 + 1.0, 'axial_load', ros_convert.wrench_msg(T0 + 1.0, math.nan)),
    ]
    backwards = [(T0 + 4.0, 'vibration', ros_convert.vibration_block_msg(T0 + 0.1, 2000.0, np.ones(100))),
                 (T0 + 4.0, 'joint_states', ros_convert.joint_state_msg(T0 + 0.1, 0.0, SPEED)),
                 (T0 + 4.0, 'axial_load', ros_convert.wrench_msg(T0 + 0.1, 0.0))]
    events = sorted(good + bad + zero + after + backwards, key=lambda e: e[0])
    graph.publish(graph.publishers(), events)
    wait_for(lambda: {5.0, 5.5} & set(by_window(states)), 15, 'states after the bad input')
    live = by_window(states)
    for start in (0.0, 0.5, 1.5, 3.5, 4.0, 4.5):
        assert live[start].theta_oil == pytest.approx(0.9, abs=0.01), (start, live[start].message)
    for start in (2.0, 2.5):
        assert math.isnan(live[start].theta_oil) and 'axial load' in live[start].message
    assert math.isnan(live[3.0].theta_oil) and 'blocks lost' in live[3.0].message
    assert live[3.5].level == OK
    channel = node.channels[0]
    assert set(channel.input_errors) == {'joint_states:InputError', 'axial_load:InputError'}
    kinds = channel.builder.problem_summary()
    for kind in ('vibration-nonfinite', 'vibration-empty', 'vibration-rate', 'vibration-late', 'screw-late'):
        assert kinds.get(kind, 0) > 0, kind
    wait_for(lambda: int(values_of(status_of(diagnostics[-1], '/prsm'))['problems']) > 5, 5, 'problem count')


@pytest.mark.parametrize('rate', [1e-3, 1e-6, 5e-324, 1e9])
def test_a_block_with_an_extreme_rate_is_one_counted_reason_and_the_node_keeps_its_period(graph, tmp_path, rate):
    """The trial's case: one block at 1e-3 Hz made 30,710 NaN states and /diagnostics silent for 20 s.

    The block is left out before it sizes anything: no flood of states, no
    memory, /diagnostics keeps its 0.2 s period, the reason is counted.
    """
    import resource
    node = graph.estimator(tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    arrivals = []
    graph.probe.create_subscription(DiagnosticArray, '/diagnostics', lambda msg: arrivals.append(time.monotonic()),
                                    100)
    good = segments_stream([(4.0, rms_for(0.9), SPEED, LOAD)])
    bad = [(T0 + 1.0, 'vibration', ros_convert.vibration_block_msg(T0 + 1.01, rate, np.ones(4000, np.float32)))]
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    graph.publish(graph.publishers(), sorted(good + bad, key=lambda e: e[0]))
    wait_for(lambda: 3.0 in by_window(states), 15, 'the states after the bad block')
    time.sleep(1.0)                                       # and a second more of /diagnostics
    done = time.monotonic()
    live = by_window(states)
    assert len(states) <= 8, sorted(live)                 # the run's 0.5 s windows, not years of NaN windows
    for start in (0.0, 0.5, 1.0, 1.5, 2.0, 2.5):
        assert live[start].theta_oil == pytest.approx(0.9, abs=0.01), (start, live[start].message)
    assert node.channels[0].builder.problem_summary().get('vibration-rate') == 1
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 200_000      # kB
    gaps = np.diff([t for t in arrivals if t <= done])
    assert gaps.size >= 4 and gaps.max() < 2.0, gaps     # period 0.2 s; the old code fell silent for 20 s
    wait_for(lambda: int(values_of(status_of(diagnostics[-1], '/prsm'))['problems']) >= 1, 5, 'problem count')


def test_joint_states_and_load_are_taken_while_vibration_is_silent(graph, tmp_path):
    """Only vibration wakes the executor; when it stops, the other inputs are still taken (drain timer).

    Vibration for 1.5 s, joint states and load for 5.5 s: once they are
    stream_timeout (3 s) past the last block, vibration stops holding the windows
    open and the silent ones close without theta (no vibration samples; the status goes STALE).
    """
    node = graph.estimator(tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    events = [e for e in segments_stream([(5.5, rms_for(0.9), SPEED, LOAD)])
              if not (e[1] == 'vibration' and e[0] >= T0 + 1.5)]
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), events)
    wait_for(lambda: 4.5 in by_window(states), 10, 'the windows after the vibration stopped')
    live = by_window(states)
    for start in (0.0, 0.5, 1.0):
        assert live[start].theta_oil == pytest.approx(0.9, abs=0.01), live[start].message
    for start in (1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5):
        assert math.isnan(live[start].theta_oil) and 'no vibration' in live[start].message, start
        assert live[start].screw_speed == pytest.approx(SPEED, rel=1e-6)


def test_blocks_wait_in_the_node_until_one_may_close_a_window(graph, tmp_path, monkeypatch):
    """Blocks are kept until one passes the earliest open window's end by completion_delay; then that window
    closes, though no flush by time ever comes (FLUSH_PERIOD made longer than the test)."""
    from prsm_lube_ros.nodes import lubrication_estimator
    monkeypatch.setattr(lubrication_estimator, 'FLUSH_PERIOD', 1e3)
    graph.estimator(tmp_path, window_length=1.0, completion_delay=0.25)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    events = segments_stream([(4.0, rms_for(0.9), SPEED, LOAD)])
    publishers = graph.publishers()
    # Up to the block [1.3, 1.4) s: its end passes window 0's end (1 s) by more than 0.25 s; window 1's is 2.25 s.
    graph.publish(publishers, [e for e in events if e[0] < T0 + 1.35])
    wait_for(lambda: 0.0 in by_window(states), 10, 'window 0 once a block passed its end by completion_delay')
    time.sleep(0.5)
    assert sorted(by_window(states)) == [0.0]
    assert by_window(states)[0.0].theta_oil == pytest.approx(0.9, abs=0.01)
    graph.publish(publishers, [e for e in events if T0 + 1.35 <= e[0] < T0 + 3.45])
    wait_for(lambda: 2.0 in by_window(states), 10, 'windows 1 and 2')
    assert sorted(by_window(states)) == [0.0, 1.0, 2.0]


# -- the input path driven by hand --------------------------------------------------------------------
class HandQueue:
    """A subscription's KEEP_LAST queue of serialized messages: beyond ``depth`` the oldest is dropped."""

    def __init__(self, depth):
        self.messages, self.depth, self.dropped, self.put_count = [], depth, 0, 0

    def put(self, data):
        self.messages.append(data)
        self.put_count += 1
        if len(self.messages) > self.depth:
            del self.messages[0]
            self.dropped += 1


class HandDrain:
    """Stands in for fast_drain.FastDrain: takes what a :class:`HandQueue` holds."""

    enabled = True

    def drain(self, queue, limit):
        if queue is None:
            return iter(())
        taken, queue.messages = queue.messages[:limit], queue.messages[limit:]
        return iter(taken)


class HandDriven:
    """An estimator whose inputs the test delivers: no executor, DDS or wall clock decides when anything happens.

    The node is never spun: the test calls its vibration callback, its drain
    timer every ``tick`` s, its diagnostics timer every ``diagnostics_period``
    s and (without the fast drain) its plain auxiliary callbacks, on a clock it
    sets (``time.monotonic`` of the node's module, and the node clock: T0 at
    the start), and the auxiliary messages wait in :class:`HandQueue` s of
    ``qos_depth``.  Published states and diagnostics are kept in lists.
    """

    def __init__(self, graph, tmp_path, monkeypatch, fast=True, tick=0.1, **params):
        from prsm_lube_ros.nodes import lubrication_estimator
        from prsm_lube_ros.nodes.raw_inputs import raw_load_converter, raw_screw_converter, raw_vibration_converter
        self.clock = 1000.0
        monkeypatch.setattr(lubrication_estimator, 'time', SimpleNamespace(monotonic=lambda: self.clock))
        monkeypatch.setattr(LubricationEstimator, 'now', lambda node: T0 + self.clock - 1000.0)
        save_calibration(calibration(START), tmp_path / 'calibration_prsm.yaml')
        values = dict(calibration_file=str(tmp_path / 'calibration_{actuator}.yaml'), recordings_dir=str(tmp_path),
                      window_length=0.5, completion_delay=0.25, stale_timeout=1.0, diagnostics_period=0.2,
                      qos_depth=2000)
        values.update(params)
        self.node = node = LubricationEstimator(context=graph.context, parameter_overrides=[
            Parameter(k, value=v) for k, v in values.items()])
        graph.nodes.append(node)                  # destroyed with the graph; never spun
        self.channel = channel = node.channels[0]
        self.states, self.diagnostics = [], []
        channel.publisher = SimpleNamespace(publish=self.states.append)
        node._diagnostics = SimpleNamespace(publish=self.diagnostics.append)
        converters = {'joint_states': raw_screw_converter('/prsm/joint_states', 'screw'),
                      'axial_load': raw_load_converter('/prsm/axial_load')}
        self.queues = {key: HandQueue(int(values['qos_depth'])) for key in converters}
        if fast:
            node._fast = HandDrain()
            channel.auxiliary = [(key, self.queues[key], convert) for key, convert in converters.items()]
            self.callbacks = {key: self.queues[key].put for key in converters}
        else:
            node._fast.enabled = False
            channel.auxiliary = []
            self.callbacks = {key: node._auxiliary_callback(channel, key, convert)
                              for key, convert in converters.items()}
        self.vibration = node._vibration_callback(
            channel, raw_vibration_converter('/prsm/vibration', lambda frame: None), {})
        period = float(values['diagnostics_period'])
        self.timers = [[self.clock + tick, tick, node._drain_idle],
                       [self.clock + period, period, node._publish_diagnostics]]

    def run(self, events, until=None):
        """Deliver ``events`` (arrival s from the start, kind, serialized message) in arrival order, with the
        drain timer's ticks between them, then tick on up to ``until`` s."""
        start = 1000.0
        for arrival, kind, data in sorted(events, key=lambda e: e[0]):
            self._tick_to(start + arrival)
            self.clock = start + arrival
            if kind == 'vibration':
                self.vibration(data)
            elif kind == 'call':        # something else happening to the node then: data(self)
                with self.node._lock:
                    data(self)
            else:
                self.callbacks[kind](data)
        if until is not None:
            self._tick_to(start + until)

    def deactivate(self):
        """Lifecycle deactivate: the node's subscriptions and queues go."""
        self.converters = [(key, convert) for key, _, convert in self.channel.auxiliary]
        self.node.trigger_deactivate()
        assert not self.channel.pending and not self.channel.auxiliary

    def activate(self):
        """Lifecycle activate: new (empty) queues."""
        self.node.trigger_activate()
        self.queues = {key: HandQueue(self.queues[key].depth) for key, _ in self.converters}
        self.channel.auxiliary = [(key, self.queues[key], convert) for key, convert in self.converters]
        self.callbacks = {key: self.queues[key].put for key, _ in self.converters}

    def _tick_to(self, when):
        while (timer := min(self.timers))[0] <= when:
            self.clock = timer[0]
            timer[2]()
            timer[0] += timer[1]


def arrivals(segments, stamp_origin, wall_origin, **stream):
    """``segments_stream`` as it reaches a node: (arrival s, kind, serialized message); a block arrives when its
    last sample is taken, the other messages at their stamp."""
    from rclpy.serialization import serialize_message
    block = stream.get('block', 0.05)
    return [(wall_origin + stamp - stamp_origin + (block if kind == 'vibration' else 0.0), kind,
             serialize_message(msg)) for stamp, kind, msg in segments_stream(segments, t0=stamp_origin, **stream)]


@pytest.mark.parametrize('fast', [True, False], ids=['fast drain', 'plain callbacks'])
def test_a_clock_reset_with_blocks_pending_gives_each_window_once_and_whole(graph, tmp_path, monkeypatch, fast):
    """Stamps go back 100 s (a clock reset, a bag played again): the windows before it close whole, once.

    The blocks a node keeps pending must reach the builder before the joint
    states or loads that go back restart its time, as when every block went in
    at its arrival: else the last window before the reset is published twice
    (cut short, then with those blocks and no speed) and the first ones after it
    are closed early without vibration.  The messages after the reset come
    0.02 s after the last block before it (with none, the joint states after
    the reset may overtake that block, and a flush between them splits the
    window, as it did when each block went in at its arrival).  Without the
    fast drain (``fast`` False) the joint states and loads go in at their
    arrival, so the blocks must too.
    """
    driven = HandDriven(graph, tmp_path, monkeypatch, fast=fast)
    events = (arrivals([(6.0, rms_for(0.9), SPEED, LOAD)], T0, 0.0)
              + arrivals([(3.0, rms_for(0.9), SPEED, LOAD)], T0 - 100.0, 6.02))
    driven.run(events, until=10.0)
    starts = [round(s.window_start - T0, 3) for s in driven.states]
    assert starts == [0.5 * k for k in range(12)] + [-100.0 + 0.5 * k for k in range(5)]
    for state in driven.states:
        assert state.theta_oil == pytest.approx(0.9, abs=0.01), (state.window_start - T0, state.message)


@pytest.mark.parametrize('stop', [1.6, 1.65, 1.7, 1.75, 1.8, 1.85, 1.9, 1.95])
def test_a_queue_as_deep_as_qos_depth_says_loses_nothing_when_vibration_stops(graph, tmp_path, monkeypatch, stop):
    """Joint states at 1 kHz into a queue of FLUSH_PERIOD + DRAIN_PERIOD s of them (qos_depth's doc): when the
    vibration stops (at ``stop`` s, any phase to the flushes), the drain timer takes the queue before it overflows."""
    from prsm_lube_ros.nodes.lubrication_estimator import DRAIN_PERIOD, FLUSH_PERIOD
    depth = int(1000 * (FLUSH_PERIOD + DRAIN_PERIOD)) + 1
    driven = HandDriven(graph, tmp_path, monkeypatch, qos_depth=depth)
    events = [e for e in arrivals([(4.0, rms_for(0.9), SPEED, LOAD)], T0, 0.0, joint_rate=1000.0)
              if e[1] != 'vibration' or e[0] <= stop + 1e-9]
    driven.run(events, until=5.0)
    queue = driven.queues['joint_states']
    assert queue.put_count == 4000 and queue.dropped == 0


def test_the_input_rates_in_the_diagnostics_count_every_message_arrived(graph, tmp_path, monkeypatch):
    """Joint states at 100 Hz and loads at 50 Hz, their expected rates, judged over 3 diagnostic periods of
    0.3 s: the statuses say OK, within rate_tolerance (10 %) of the rate they came at, though the queues wait
    for flushes up to 0.35 s apart (counted at those, the rate over 0.9 s swung from 83 to 111 Hz: WARN
    'Frequency too low.' at 100 Hz)."""
    driven = HandDriven(graph, tmp_path, monkeypatch, diagnostics_period=0.3, rate_window=3)
    driven.run(arrivals([(6.0, rms_for(0.9), SPEED, LOAD)], T0, 0.0, joint_rate=100.0, load_rate=50.0))
    judged = 0
    for array in driven.diagnostics[4:]:              # from the first full window of 3 periods on
        for key, rate in (('joint_states', 100.0), ('axial_load', 50.0)):
            status = status_of(array, f'{key} input')
            frequency = float(values_of(status)['Actual frequency (Hz)'])
            assert status.level == b'\x00' and frequency == pytest.approx(rate, rel=0.1), (key, status.message)
            judged += 1
    assert judged >= 30


def lagging(events, kind, delay):
    """``events`` with the messages of ``kind`` arriving ``delay`` s later."""
    return [(arrival + delay if k == kind else arrival, k, data) for arrival, k, data in events]


def odd_block(stamp, rate, arrival):
    """An event of one vibration block of 100 samples stamped ``stamp`` s after T0 at ``rate`` Hz."""
    from rclpy.serialization import serialize_message
    return (arrival, 'vibration', serialize_message(ros_convert.vibration_block_msg(
        T0 + stamp, rate, np.ones(100, np.float32))))


def live_cases():
    """(name, events, estimator parameters) of input streams as they reach a node, ordinary and odd."""
    run = arrivals([(6.0, rms_for(0.9), SPEED, LOAD)], T0, 0.0)
    repeated = next(e for e in run if e[1] == 'vibration' and abs(e[0] - 2.5) < 1e-6)
    yield 'steady', run, {}
    yield 'joint states 0.3 s late', lagging(run, 'joint_states', 0.3), {}
    yield 'loads 0.12 s late', lagging(run, 'axial_load', 0.12), {}
    yield 'joint states stop', [e for e in run if not (e[1] == 'joint_states' and e[0] > 2.0)], {}
    yield 'vibration stops', [e for e in run if not (e[1] == 'vibration' and e[0] > 2.03)], {}
    blocks = arrivals([(6.0, rms_for(0.9), SPEED, LOAD)], T0, 0.0, block=0.1)
    yield '0.1 s blocks, 1 s windows', blocks, dict(window_length=1.0, completion_delay=0.5)
    yield 'a block stamped 1000 s ahead', run + [odd_block(1000.0, 2000.0, 3.01)], {}
    yield 'a block of rate 1e-6 Hz', run + [odd_block(3.0, 1e-6, 3.01)], {}
    yield 'a block twice', run + [(2.52, 'vibration', repeated[2])], {}
    yield 'stamps back 3 s', run + arrivals([(3.0, rms_for(0.9), SPEED, LOAD)], T0 + 3.0, 6.02), {}
    yield 'clock reset', run + arrivals([(3.0, rms_for(0.9), SPEED, LOAD)], T0 - 100.0, 6.02), {}
    banded = replace(calibration(START), band=DEFAULT_BAND)
    yield 'calibration swapped: windows rebuilt in its band', run + [
        (3.13, 'call', lambda driven: driven.node._swap_calibration(driven.channel, banded))], {}
    yield 'window settings changed: windows rebuilt', run + [
        (3.13, 'call', lambda driven: driven.node.set_parameters([Parameter('min_coverage', value=0.79)]))], {}
    yield 'deactivated mid-window, activated again', [e for e in run if not 3.13 < e[0] < 3.6] + [
        (3.13, 'call', HandDriven.deactivate), (3.6, 'call', HandDriven.activate)], {}


@pytest.mark.parametrize('case', [c[0] for c in live_cases()])
def test_pending_blocks_give_the_windows_and_times_of_blocks_taken_at_arrival(graph, tmp_path, monkeypatch, case):
    """The claim of the pending blocks: the same windows, published at the same moments, as a node that adds
    every block (and the queues) to the builder at its arrival, over streams late, stopping, odd or going back."""
    from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator as Node
    _, events, params = next(c for c in live_cases() if c[0] == case)
    published = []
    for flush_every_block in (False, True):
        if flush_every_block:
            monkeypatch.setattr(Node, '_flush_due', lambda node, channel: bool(channel.pending))
        driven = HandDriven(graph, tmp_path, monkeypatch, **params)
        driven.channel.publisher = SimpleNamespace(publish=lambda msg, driven=driven: published[-1].append(
            (round(driven.clock, 6), msg.window_start, msg.theta_oil, msg.message)))
        published.append([])
        driven.run(events, until=max(e[0] for e in events) + 2.0)
    kept, each = published
    assert len(kept) >= 5 and [(s[0], s[1], s[3]) for s in kept] == [(s[0], s[1], s[3]) for s in each]
    assert [s[2] for s in kept] == pytest.approx([s[2] for s in each], rel=1e-9, nan_ok=True)


def test_a_qos_depth_too_small_for_an_expected_rate_is_one_warning(graph, tmp_path, capfd):
    """qos_depth 50 with joint states expected at 1 kHz: their queue waits up to 0.35 s (350 messages) between
    flushes, so one WARN says so; the loads at their default 50/s (18 messages) fit."""
    graph.estimator(tmp_path, qos_depth=50, joint_states_rate=1000.0)
    lines = [line for line in capfd.readouterr().err.splitlines() if '[WARN]' in line and 'qos_depth' in line]
    assert len(lines) == 1 and 'joint_states' in lines[0] and '350' in lines[0], lines


def test_parameters_are_validated_and_applied(graph, tmp_path):
    node = graph.estimator(tmp_path)
    broken = tmp_path / 'broken.yaml'
    broken.write_text('format: something else\n')
    refused = {
        'error_below': 0.9,                            # above warn_below
        'window_length': 0.0,                          # out of range
        'hysteresis': 0.5,                             # wider than the WARN band
        'calibration_file': str(broken),
        'recordings_dir': str(tmp_path / 'missing'),
    }
    for name, value in refused.items():
        result = node.set_parameters([Parameter(name, value=value)])[0]
        assert not result.successful and result.reason, name
    result = node.set_parameters([Parameter('actuators', value=['/x'])])[0]
    assert not result.successful                        # read-only
    assert node.set_parameters([Parameter('warn_below', value=0.95)])[0].successful
    assert node.channels[0].monitor.thresholds.warn_below == 0.95
    assert node.set_parameters([Parameter('window_length', value=0.25)])[0].successful
    assert node.channels[0].builder.settings.window_length == 0.25
    assert node.channels[0].assessor is not None       # the calibration survived every refusal


def test_windows_outside_the_calibrated_domain_warn_and_say_how_far(graph, tmp_path):
    """theta 0.9 (OK by level) at 10 rad/s on constants fitted at 20-40 rad/s: WARN, extrapolated, said how far."""
    fitted = replace(calibration(START), band=DEFAULT_BAND.resolved(2000.0),
                     domain=CalibrationDomain(speed=(20.0, 40.0), load=(100.0, 200.0)))
    save_calibration(fitted, tmp_path / 'calibration_prsm.yaml')
    node = graph.estimator(tmp_path, calibration_file=str(tmp_path / 'calibration_{actuator}.yaml'),
                           level_smoothing=1)
    assert node.channels[0].builder.band == fitted.band            # windows in the calibration's band
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(3.0, rms_for(0.9), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 3, 15, 'states')
    flag = 'extrapolated: speed 50 % below the calibrated 20-40 rad/s'
    assert states[1].theta_oil == pytest.approx(0.9, abs=0.01)
    assert states[1].level == WARN and states[1].message == f'theta_oil {flag}', states[1].message
    wait_for(lambda: status_of(diagnostics[-1], '/prsm').level == bytes([WARN]), 5, 'WARN on /diagnostics')
    status = status_of(diagnostics[-1], '/prsm')
    values = values_of(status)
    assert status.message == f'theta_oil {flag}' and values['domain_flag'] == flag
    assert values['calibration_band'].startswith('band 0.5-800 Hz')
    assert values['calibration_domain'] == 'speed 20-40 rad/s, load 100-200 N'


def test_several_actuators_each_have_topics_status_and_service(graph, tmp_path):
    left, right = '/ema_left/prsm', '/ema_right/prsm'
    save_calibration(calibration(START), tmp_path / 'calibration_ema_left_prsm.yaml')
    node = graph.estimator(tmp_path, actuators=[left, right], hardware_ids=['EMA-L 0042'],
                           calibration_file=str(tmp_path / 'calibration_{actuator}.yaml'))
    states = graph.collect(LubricationState, f'{left}/lubrication_state')
    other = graph.collect(LubricationState, f'{right}/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(left), segments_stream([(3.0, rms_for(0.8), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 3, 15, 'left states')
    assert all(s.actuator == left for s in states)
    assert states[0].theta_oil == pytest.approx(0.8, abs=0.01)
    assert not other
    wait_for(lambda: status_of(diagnostics[-1], left).level == bytes([WARN]), 5, 'left WARN')
    last = diagnostics[-1]
    judged = [s for s in last.status if not s.name.endswith(' input')]      # the input statuses: test_ros_stack
    assert [s.name for s in judged] == [f'lubrication_estimator: {a} {task}' for a in (left, right)
                                        for task in ('lubrication', 'surface condition')]
    assert [s.hardware_id for s in judged] == ['EMA-L 0042'] * 2 + ['ema_right/prsm'] * 2
    assert status_of(last, f'{right} surface').level == bytes([STALE])
    assert status_of(last, left).hardware_id == 'EMA-L 0042'
    assert status_of(last, right).hardware_id == 'ema_right/prsm'
    assert status_of(last, right).level == bytes([STALE])
    assert 'no calibration yet' in values_of(status_of(last, right))['calibration']
    for name in ('/prsm/calibrate', f'{left}/calibrate', f'{right}/calibrate'):
        response = call(graph, name, [])
        assert not response.success and 'bag_paths is empty' in response.message


# -- calibration service ---------------------------------------------------------------------------
def write_reference_bag(path, segments, namespace='/prsm', topics=('vibration', 'joint_states', 'axial_load'),
                        stream=None):
    """A rosbag2 (mcap) of ``stream(segments)`` (default ``segments_stream``) written with rosbags."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from prsm_lube_ros.contract import JOINT_STATE, VIBRATION_BLOCK, WRENCH_STAMPED
    from prsm_lube_ros.recording.typestore import contract_typestore
    store = contract_typestore()
    types = {'vibration': VIBRATION_BLOCK, 'joint_states': JOINT_STATE, 'axial_load': WRENCH_STAMPED}
    T = store.types

    def header(msg):
        return T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](
            sec=msg.header.stamp.sec, nanosec=msg.header.stamp.nanosec), frame_id='')

    def convert(kind, msg):
        if kind == 'vibration':
            return T[VIBRATION_BLOCK](header=header(msg), sample_rate=msg.sample_rate,
                                      samples=np.array(msg.samples, np.float32))
        if kind == 'joint_states':
            return T[JOINT_STATE](header=header(msg), name=['screw'], position=np.array(msg.position),
                                  velocity=np.array(msg.velocity), effort=np.zeros(0))
        vector = T['geometry_msgs/msg/Vector3']
        return T[WRENCH_STAMPED](header=header(msg), wrench=T['geometry_msgs/msg/Wrench'](
            force=vector(x=0.0, y=0.0, z=msg.wrench.force.z), torque=vector(x=0.0, y=0.0, z=0.0)))

    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {kind: writer.add_connection(f'{namespace}/{kind}', types[kind], typestore=store)
                       for kind in topics}
        for stamp, kind, msg in (stream or segments_stream)(segments):
            if kind in connections:
                writer.write(connections[kind], int(round(stamp * 1e9)),
                             store.serialize_cdr(convert(kind, msg), types[kind]))
    return path


def reference_segments(theta=1.0, speeds=(8.0, 12.0, 16.0), loads=(100.0, 200.0)):
    """3 speeds x 2 loads: rest 1 s, then 3 s steady, with the RMS of TRUE at ``theta``."""
    segments = []
    for load in loads:
        for speed in speeds:
            segments += [(1.0, 0.01, 0.0, load),
                         (3.0, float(acceleration_amplitude(speed, load, theta, TRUE)), speed, load)]
    return segments + [(1.0, 0.01, 0.0, loads[-1])]


def test_bad_calibration_requests_answer_false_and_the_node_keeps_serving(graph, tmp_path):
    node = graph.estimator(tmp_path)
    before = node.channels[0].assessor
    write_reference_bag(tmp_path / 'other_ns', reference_segments(), namespace='/other')
    write_reference_bag(tmp_path / 'one_level', [(4.0, rms_for(1.0), SPEED, LOAD)])
    write_reference_bag(tmp_path / 'no_load', reference_segments(), topics=('vibration', 'joint_states'))
    outside = tmp_path.parent / 'outside_bag'
    outside.mkdir(exist_ok=True)
    cases = [
        ([], 1.0, 'bag_paths is empty'),
        ([tmp_path / 'nope'], 1.0, 'not found'),
        ([outside], 1.0, 'outside the recordings folder'),
        (['../outside_bag'], 1.0, 'outside the recordings folder'),
        ([tmp_path / 'other_ns'], 1.0, '/prsm'),
        ([tmp_path / 'no_load'], 1.0, 'no usable window: no message could be read on axial_load'),
        ([tmp_path / 'one_level'], 1.0, 'cannot identify'),
        ([tmp_path / 'one_level'], -1.0, 'reference_theta'),
        ([tmp_path / 'one_level', 'one_level'], 1.0, 'named twice'),     # absolute and relative: one bag
    ]
    for paths, theta, words in cases:
        response = call(graph, '/prsm/calibrate', paths, theta)
        assert not response.success, paths
        assert words in response.message, (paths, response.message)
    assert node.channels[0].assessor is before                 # nothing calibrated was lost
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(0.9), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 2, 10, 'states after the refusals')
    assert states[0].theta_oil == pytest.approx(0.9, abs=0.01)


def test_calibrate_fits_swaps_and_persists(graph, tmp_path):
    node = graph.estimator(tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    write_reference_bag(tmp_path / 'reference', reference_segments(theta=0.95))
    file = tmp_path / 'calibration_prsm.yaml'
    old_text = file.read_text()
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95, persist=False)
    assert response.success, response.message
    assert response.c_sys == pytest.approx(TRUE.c_sys, rel=0.01)
    assert response.c_f == pytest.approx(TRUE.c_f, rel=0.01)
    assert response.c_lambda == pytest.approx(TRUE.c_lambda, rel=0.01)
    assert response.fit_rmse < 0.01 and response.windows_used >= 24
    assert file.read_text() == old_text                                  # not persisted
    # The live windows are now judged with TRUE: an RMS of TRUE at theta 0.75 reads 0.75.
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(0.75, TRUE), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 2, 10, 'states after the swap')
    assert states[0].theta_oil == pytest.approx(0.75, abs=0.01)
    assert states[0].level == WARN
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95, persist=True)
    assert response.success and response.calibration_file == str(file)
    saved = load_calibration(file)
    assert saved.constants.c_lambda == pytest.approx(TRUE.c_lambda, rel=0.01)
    assert not list(tmp_path.glob('.calibration_prsm.yaml.*'))          # no temporary file left


def test_calibrate_reads_the_namespace_the_request_names(graph, tmp_path):
    """A reference recorded as /rig/left (another rig's naming) calibrates the live /prsm actuator."""
    graph.estimator(tmp_path)
    write_reference_bag(tmp_path / 'left', reference_segments(), namespace='/rig/left')
    refused = call(graph, '/prsm/calibrate', ['left'])
    assert not refused.success and '/prsm' in refused.message
    bad = call(graph, '/prsm/calibrate', ['left'], recording_namespace='rig left!')
    assert not bad.success and 'recording_namespace' in bad.message
    response = call(graph, '/prsm/calibrate', ['left'], recording_namespace='/rig/left')
    assert response.success, response.message
    assert 'under /rig/left' in response.message
    assert response.c_lambda == pytest.approx(TRUE.c_lambda, rel=0.01)


def test_calibrate_on_three_conditions_fits_but_says_the_form_is_untested(graph, tmp_path):
    graph.estimator(tmp_path)
    segments = []
    for speed, load in ((8.0, 100.0), (12.0, 200.0), (16.0, 200.0)):      # three conditions for three constants
        segments += [(1.0, 0.01, 0.0, load), (3.0, float(acceleration_amplitude(speed, load, 1.0, TRUE)), speed, load)]
    write_reference_bag(tmp_path / 'three', segments + [(1.0, 0.01, 0.0, 200.0)])
    response = call(graph, '/prsm/calibrate', ['three'], theta=1.0, persist=False)
    assert response.success, response.message
    assert 'form untested: record 2 more conditions' in response.message
    assert '3 speeds x 2 loads, 3 conditions' in response.message


def test_a_slow_fit_does_not_hold_up_the_inputs(graph, tmp_path, monkeypatch):
    """While a calibration is being fitted (here: made to take 3 s) windows keep being assessed."""
    from prsm_lube_ros.nodes import lubrication_estimator as module
    release = threading.Event()

    def slow_fit(*args, **kwargs):
        release.wait(3.0)
        raise module.InputError('calibrate: stopped on purpose')

    monkeypatch.setattr(module, 'calibrate_from_request', slow_fit)
    node = graph.estimator(tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    client = graph.probe.create_client(Calibrate, '/prsm/calibrate')
    assert client.wait_for_service(timeout_sec=10)
    future = client.call_async(Calibrate.Request(bag_paths=['x']))
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(0.9), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 2, 10, 'states while the fit runs')
    assert not future.done()
    release.set()
    wait_for(future.done, 10, 'the answer')
    assert not future.result().success and 'stopped on purpose' in future.result().message


# -- calibrate action ------------------------------------------------------------------------------
def send_goal(graph, name, bag_paths, theta=1.0, persist=False, feedback=None):
    """Send a Calibrate action goal from the probe (as ros2 action send_goal); the accepted goal handle.

    One client per action name and graph, kept for the test's later goals: a
    second client of the same name must be matched by discovery again (once
    it was not within 10 s on a CI run, after the first goal had run).
    """
    clients = graph.__dict__.setdefault('action_clients', {})
    if name not in clients:
        clients[name] = ActionClient(graph.probe, CalibrateAction, name)
    client = clients[name]
    assert client.wait_for_server(timeout_sec=10), f'action {name} not offered'
    goal = CalibrateAction.Goal(bag_paths=[str(p) for p in bag_paths], reference_theta=theta, persist=persist)
    sent = client.send_goal_async(goal, feedback_callback=None if feedback is None else (
        lambda message: feedback.append(message.feedback)))
    wait_for(sent.done, 10, f'goal of {name} answered')
    assert sent.result().accepted
    return sent.result()


def outcome_of(handle, timeout=30):
    """(status, result) of an action goal."""
    future = handle.get_result_async()
    wait_for(future.done, timeout, 'the action result')
    return future.result().status, future.result().result


def test_the_calibrate_action_reports_its_progress_and_fits_as_the_service_does(graph, tmp_path):
    node = graph.estimator(tmp_path)
    for name in ('a', 'b'):
        write_reference_bag(tmp_path / name, reference_segments(theta=0.95))
    feedback = []
    status, result = outcome_of(send_goal(graph, '/prsm/calibrate', ['a', 'b'], theta=0.95, persist=True,
                                          feedback=feedback))
    assert status == GoalStatus.STATUS_SUCCEEDED and result.success, result.message
    assert result.c_lambda == pytest.approx(TRUE.c_lambda, rel=0.01)
    assert result.calibration_file == str(tmp_path / 'calibration_prsm.yaml')
    assert node.channels[0].assessor.calibration.constants.c_lambda == result.c_lambda      # swapped in
    wait_for(lambda: any(f.stage == 'writing' for f in feedback), 10, 'the last feedback')
    assert [(f.stage, f.bags_read, f.bag_count) for f in feedback] == [
        ('queued', 0, 2), ('reading', 0, 2), ('reading', 1, 2), ('fitting', 2, 2), ('writing', 2, 2)]
    assert 0 < feedback[2].windows_read < feedback[3].windows_read
    service = call(graph, '/prsm/calibrate', ['a', 'b'], theta=0.95)
    assert (service.c_sys, service.c_f, service.c_lambda) == (result.c_sys, result.c_f, result.c_lambda)
    status, result = outcome_of(send_goal(graph, '/prsm/calibrate', []))
    assert status == GoalStatus.STATUS_ABORTED and not result.success and 'bag_paths is empty' in result.message


def test_cancel_withdraws_a_waiting_calibration_and_stops_a_running_one(graph, tmp_path, monkeypatch):
    """Issue 36: a calibration is cancellable while it reads; it stops at its next check and changes nothing."""
    from prsm_lube_ros.nodes import lubrication_estimator as module
    real, entered, release = module.calibrate_from_request, threading.Event(), threading.Event()

    def held(*args, **kwargs):
        entered.set()
        release.wait(20)
        return real(*args, **kwargs)

    monkeypatch.setattr(module, 'calibrate_from_request', held)
    node = graph.estimator(tmp_path)
    before = node.channels[0].assessor
    write_reference_bag(tmp_path / 'reference', reference_segments(theta=0.95))
    running = send_goal(graph, '/prsm/calibrate', ['reference'], theta=0.95)
    wait_for(entered.is_set, 10, 'the first calibration running')
    waiting = send_goal(graph, '/prsm/calibrate', ['reference'], theta=0.5)
    accepted = waiting.cancel_goal_async()
    wait_for(accepted.done, 10, 'the answer to the cancel of the waiting one')
    assert [bytes(g.goal_id.uuid) for g in accepted.result().goals_canceling] == [bytes(waiting.goal_id.uuid)]
    status, result = outcome_of(waiting)
    assert status == GoalStatus.STATUS_CANCELED and not result.success and 'nothing was read' in result.message
    stopping = running.cancel_goal_async()
    wait_for(stopping.done, 10, 'the answer to the cancel of the running one')
    assert [bytes(g.goal_id.uuid) for g in stopping.result().goals_canceling] == [bytes(running.goal_id.uuid)]
    release.set()
    status, result = outcome_of(running)
    assert status == GoalStatus.STATUS_CANCELED and not result.success, result.message
    assert 'cancelled while reading' in result.message
    assert node.channels[0].assessor is before                       # nothing swapped in
    answer = call(graph, '/prsm/calibrate', ['reference'], theta=0.95)   # and the next request is served
    assert answer.success, answer.message


def test_a_fifo_in_a_bag_is_refused_and_the_next_request_answered(graph, tmp_path):
    """Issue 36: a FIFO as a bag's storage file used to wedge the service for good."""
    node = graph.estimator(tmp_path)
    before = node.channels[0].assessor
    write_reference_bag(tmp_path / 'reference', reference_segments(theta=0.95))
    write_reference_bag(tmp_path / 'piped', reference_segments(theta=0.95))
    storage = next((tmp_path / 'piped').glob('*.mcap'))
    storage.unlink()
    os.mkfifo(storage)
    response = call(graph, '/prsm/calibrate', ['piped'], timeout=20)
    assert not response.success and 'FIFO' in response.message and '\n' not in response.message
    assert node.channels[0].assessor is before
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95, timeout=30)
    assert response.success, response.message


def test_a_bag_file_linked_from_outside_the_recordings_folder_is_not_read(graph, tmp_path):
    """Issue 36: the service fitted a bag whose storage file linked to a recording outside recordings_dir."""
    recordings = tmp_path / 'recordings'
    recordings.mkdir()
    graph.estimator(tmp_path, recordings_dir=str(recordings))
    write_reference_bag(tmp_path / 'outside', reference_segments(theta=0.95))
    write_reference_bag(recordings / 'linked', reference_segments(theta=0.95))
    storage = next((recordings / 'linked').glob('*.mcap'))
    storage.unlink()
    storage.symlink_to(next((tmp_path / 'outside').glob('*.mcap')))
    response = call(graph, '/prsm/calibrate', ['linked'])
    assert not response.success and 'leads outside' in response.message, response.message
    assert response.windows_used == 0


@pytest.mark.parametrize('special', ['/dev/zero', 'fifo'])
def test_a_special_file_as_calibration_file_is_one_line_and_persist_never_blocks(graph, tmp_path, special):
    """Issue 36: calibration_file:=/dev/zero died at 2.4 GB; a FIFO nobody reads must not wedge persist."""
    if special == 'fifo':
        special = str(tmp_path / 'calibration.fifo')
        os.mkfifo(special)
    node = graph.estimator(tmp_path, calibration_file=special)
    note = node.channels[0].calibration_note
    assert node.channels[0].assessor is None and special in note and 'not a regular file' in note, note
    write_reference_bag(tmp_path / 'reference', reference_segments(theta=0.95))
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95, persist=True)
    if special == '/dev/zero':      # a stream takes what is written to it
        assert response.success, response.message
    else:
        assert not response.success and special in response.message, response.message


def test_a_calibration_past_its_deadline_stops_and_the_service_answers_on(graph, tmp_path, monkeypatch):
    from prsm_lube_ros.nodes import lubrication_estimator as module
    real, slow = module.calibrate_from_request, threading.Event()
    slow.set()

    def delayed(*args, **kwargs):
        if slow.is_set():
            time.sleep(1.5)
        return real(*args, **kwargs)

    monkeypatch.setattr(module, 'calibrate_from_request', delayed)
    node = graph.estimator(tmp_path, calibration_timeout=1.0)
    before = node.channels[0].assessor
    write_reference_bag(tmp_path / 'reference', reference_segments(theta=0.95))
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95)
    assert not response.success and 'calibration_timeout (1 s)' in response.message, response.message
    assert node.channels[0].assessor is before
    slow.clear()
    response = call(graph, '/prsm/calibrate', ['reference'], theta=0.95)
    assert response.success, response.message


# -- diagnostics -----------------------------------------------------------------------------------
def test_status_messages_stay_the_same_while_the_state_does(graph, tmp_path):
    """Aggregators and loggers de-duplicate on the message: the counts change in the KeyValues only."""
    graph.estimator(tmp_path, max_unassessed_windows=3)
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    wait_for(lambda: diagnostics, 10, 'diagnostics')
    # 4 s at theta 0.95 (OK), then 5 s moving with no load (not assessable, WARN after 3 windows).
    graph.publish(graph.publishers(), segments_stream([(4.0, rms_for(0.95), SPEED, LOAD),
                                                       (5.0, rms_for(0.95), SPEED, 0.0)]), speedup=2.0)
    settle(diagnostics, quiet=0.5)
    statuses = [status_of(a, '/prsm') for a in diagnostics]
    good = [s for s in statuses if s.level == bytes([OK]) and values_of(s)['unassessed_windows'] == '0'
            and values_of(s)['theta_oil'] != 'nan']
    assert {s.message for s in good} == {'lubrication good'}
    assert len({values_of(s)['windows'] for s in good}) >= 2                       # the count moved meanwhile
    warned = [s for s in statuses if s.level == bytes([WARN])]
    assert {s.message for s in warned} == {'not assessable while the screw moves (max_unassessed_windows 3 '
                                           'reached): axial load below min_axial_load; last level OK'}
    assert len({values_of(s)['unassessed_moving_windows'] for s in warned}) >= 2
    assert 'below 5 N' in values_of(warned[-1])['unassessed_reason']              # the full reason is kept


def test_the_estimator_runs_as_its_own_process(tmp_path):
    """python -m ...lubrication_estimator: publishes, refuses a bad request, exits cleanly on SIGINT."""
    save_calibration(calibration(START), tmp_path / 'calibration_prsm.yaml')
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID), PYTHONUNBUFFERED='1')
    command = [sys.executable, '-m', 'prsm_lube_ros.nodes.lubrication_estimator', '--ros-args',
               '-p', f'calibration_file:={tmp_path}/calibration_{{actuator}}.yaml',
               '-p', f'recordings_dir:={tmp_path}', '-p', 'window_length:=0.5', '-p', 'completion_delay:=0.25',
               '-p', 'diagnostics_period:=0.2']
    process = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    graph = Graph()
    try:
        states = graph.collect(LubricationState, '/prsm/lubrication_state')
        diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
        wait_for(lambda: diagnostics or process.poll() is not None, 20, 'diagnostics from the process')
        assert process.poll() is None
        response = call(graph, '/prsm/calibrate', ['/etc'])
        assert not response.success and 'outside the recordings folder' in response.message
        wait_for(lambda: graph.probe.count_publishers('/prsm/lubrication_state') > 0, 10, 'state publisher')
        graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(0.9), SPEED, LOAD)]))
        wait_for(lambda: len(states) >= 2, 15, 'states from the process')
        assert states[0].theta_oil == pytest.approx(0.9, abs=0.01)
    finally:
        graph.close()
        stderr = stop_process(process)
    assert process.returncode == 0, stderr
    assert 'Traceback' not in stderr


def test_a_bad_configuration_ends_with_one_line(tmp_path):
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID))
    command = [sys.executable, '-m', 'prsm_lube_ros.nodes.lubrication_estimator', '--ros-args',
               '-p', 'warn_below:=0.5', '-p', 'error_below:=0.6', '-p', f'calibration_file:={tmp_path}/c.yaml']
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
    assert 'error_below' in result.stderr and 'Traceback' not in result.stderr


def test_the_live_inputs_follow_eq_22():
    """Hand check of the inputs used above: RMS falls by exp(-C_lambda w^0.68 F^-0.073 d theta)."""
    g = START.c_lambda * float(film_speed_load_term(SPEED, LOAD))
    assert rms_for(0.6) / rms_for(0.9) == pytest.approx(math.exp(0.3 * g))
    assert rms_for(0.9) == pytest.approx(math.sqrt(2))


def test_prsm_lube_run_starts_the_estimator_with_a_parameter_file(tmp_path):
    """prsm-lube run --no-bridge --config FILE -p NAME:=VALUE: the file and the overrides both apply.

    Stopped with SIGTERM (what ``ros2 launch`` sends after SIGINT): status 0 too.
    """
    config = tmp_path / 'estimator.yaml'
    config.write_text("'/**/lubrication_estimator':\n  ros__parameters:\n    hardware_ids: [from-yaml]\n"
                      '    actuators: [/runtest/prsm]\n    diagnostics_period: 0.2\n')
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID), PYTHONUNBUFFERED='1')
    command = [sys.executable, '-m', 'prsm_lube_ros.cli', 'run', '--no-bridge', '--config', str(config),
               '-p', f'recordings_dir:={tmp_path}', '-p', f'calibration_file:={tmp_path}/c.yaml',
               '-p', 'warn_below:=0.9', '--ros-args', '-r', '__ns:=/runns']    # the file still applies
    process = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    graph = Graph()
    try:
        diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
        wait_for(lambda: any('/runtest/prsm' in s.name for a in diagnostics for s in a.status)
                 or process.poll() is not None, 20, 'diagnostics from prsm-lube run')
        assert process.poll() is None
        status = status_of(diagnostics[-1], '/runtest/prsm')
        assert status.hardware_id == 'from-yaml'
        response = call(graph, '/runtest/prsm/calibrate', ['missing_bag'])
        assert not response.success and 'not found' in response.message
    finally:
        graph.close()
        stderr = stop_process(process, signal.SIGTERM)
    assert process.returncode == 0, stderr
    assert 'Traceback' not in stderr


def test_run_overrides_and_a_missing_parameter_file():
    from prsm_lube_ros.cli import main
    from prsm_lube_ros.cli.run import parse_override
    assert parse_override('actuators:=[/a/prsm, /b/prsm]') == ('actuators', ['/a/prsm', '/b/prsm'])
    assert parse_override('warn_below:=0.9') == ('warn_below', 0.9)
    assert parse_override('calibration_file:=') == ('calibration_file', '')
    assert main(['run', '--no-bridge', '--config', '/nonexistent/estimator.yaml']) == 2


def test_the_launch_file_parses_and_starts_the_installed_executables():
    import ast
    from pathlib import Path
    from prsm_lube_ros.nodes.launch_arguments import bringup_plan, LAUNCH_ARGUMENTS
    root = Path(__file__).resolve().parents[2]
    tree = ast.parse((root / 'launch' / 'prsm_lube.launch.py').read_text())
    functions = {node.name for node in ast.walk(tree) if isinstance(node, ast.FunctionDef)}
    assert 'generate_launch_description' in functions
    plan = bringup_plan({}, str(root / 'config'))
    executables = {plan.estimator.executable, plan.bridge.executable}
    installed = (root / 'CMakeLists.txt').read_text()
    assert executables == {'sensor_bridge_managed', 'lubrication_estimator'}
    assert all(f'scripts/{name}' in installed for name in executables)
    assert {'namespace', 'log_level', 'use_sim_time', 'params_file', 'autostart'} <= {a[0] for a in LAUNCH_ARGUMENTS}


def test_without_the_private_drain_api_windows_still_come_out(graph, tmp_path, monkeypatch, capfd):
    """rclpy without take_message: one loud warning, plain callbacks, the same theta per window."""
    from types import SimpleNamespace
    from prsm_lube_ros.nodes import fast_drain
    monkeypatch.setattr(fast_drain, '_rclpy', SimpleNamespace(Subscription=object))
    node = graph.estimator(tmp_path)
    assert not node._fast.enabled
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    events = segments_stream([(3.0, rms_for(0.9), SPEED, LOAD)])
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), events)
    wait_for(lambda: {0.0, 0.5, 1.0, 1.5} <= set(by_window(states)), 15, 'windows through the fallback')
    live = by_window(states)
    for start in (0.0, 0.5, 1.0, 1.5):
        assert live[start].theta_oil == pytest.approx(0.9, abs=0.01), live[start].message
        assert live[start].screw_speed == pytest.approx(SPEED, rel=1e-6)
    warnings = [line for line in capfd.readouterr().err.splitlines() if 'FAST DRAIN OFF' in line]
    assert len(warnings) == 1 and 'take_message' in warnings[0]


def test_with_the_private_drain_api_the_fast_drain_is_on(graph, tmp_path):
    """The rclpy this package runs on has what fast_drain needs (else the test above is the only path)."""
    from prsm_lube_ros.nodes import fast_drain
    assert fast_drain.missing_api() == ''
    assert graph.estimator(tmp_path)._fast.enabled


def test_a_late_subscriber_gets_the_last_states(graph, tmp_path):
    """LubricationState is transient local: a subscriber started after the windows still receives them."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    node = graph.estimator(tmp_path)
    early = graph.collect(LubricationState, '/prsm/lubrication_state')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(0.9), SPEED, LOAD)]))
    wait_for(lambda: len(early) >= 2, 10, 'states')
    settle(early)
    late = []
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    graph.probe.create_subscription(LubricationState, '/prsm/lubrication_state', late.append, qos)
    wait_for(lambda: len(late) >= min(len(early), 10), 10, 'the last states for the late subscriber')
    assert [s.window_start for s in late] == [s.window_start for s in early[-len(late):]]


def test_the_forecast_of_a_fleet_history_is_in_the_diagnostics(graph, tmp_path, small_fleet):
    """history_dir set: each actuator's depletion forecast (prsm-lube trend's) rides on its status.

    Actuators are found in the history by namespace (/A01) or by hardware id (/prsm as A02).
    """
    from prsm_lube_ros.fleet.forecast_summary import forecast_summary
    graph.estimator(tmp_path, actuators=['/A01', '/prsm', '/nowhere'], hardware_ids=['', 'A02', ''],
                    history_dir=str(small_fleet['history']))
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')

    def forecast_of(actuator):
        return values_of(status_of(diagnostics[-1], actuator)).get('forecast', '') if diagnostics else ''
    wait_for(lambda: forecast_of('/A01') and forecast_of('/nowhere'), 30, 'forecasts in the diagnostics')
    values = values_of(status_of(diagnostics[-1], '/A01'))
    expected = forecast_summary(small_fleet['history'], 'A01')
    assert values['forecast'] == expected.pop('forecast') == 'ok'
    assert {f'forecast_{key}': value for key, value in expected.items()}.items() <= values.items()
    assert forecast_of('/nowhere').startswith('none: ') and 'nowhere' in forecast_of('/nowhere')
    # /prsm is A02 in the history (assess --actuator-id): found through its hardware id
    assert values_of(status_of(diagnostics[-1], '/prsm'))['forecast_tau_days'] == \
        forecast_summary(small_fleet['history'], 'A02')['tau_days']


def test_a_theta_outside_its_physical_range_is_flagged_live(graph, tmp_path):
    """theta 2.0 (vibration far below the calibrated reference) is no 'lubrication good': WARN with the reason."""
    node = graph.estimator(tmp_path, level_smoothing=1)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    graph.publish(graph.publishers(), segments_stream([(2.0, rms_for(2.0), SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 2, 10, 'states')
    state = states[0]
    assert state.theta_oil == pytest.approx(2.0, abs=0.02)
    assert 'far above 1' in state.theta_oil_flag and state.level == WARN
    assert state.message.startswith('theta_oil outside its physical range')
    wait_for(lambda: diagnostics and 'far above 1' in values_of(status_of(diagnostics[-1], '/prsm')).get(
        'theta_oil_flag', ''), 10, 'the flag in the diagnostics')


def test_an_uncalibrated_estimator_never_reports_ok(graph, tmp_path):
    node = graph.estimator(tmp_path, calibration_file='')
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    diagnostics = graph.collect(DiagnosticArray, '/diagnostics')
    wait_for(lambda: node.channels[0].publisher.get_subscription_count() > 0, 10, 'probe subscribed')
    events = segments_stream([(2.0, rms_for(0.9), SPEED, LOAD)])
    for _, kind, msg in events:
        if kind == 'vibration':
            msg.header.frame_id = 'nut_accelerometer'
    graph.publish(graph.publishers(), events)
    wait_for(lambda: len(states) >= 2, 10, 'states without calibration')
    assert all(s.level == WARN and 'not calibrated' in s.message for s in states)
    assert all(s.header.frame_id == 'nut_accelerometer' for s in states)      # the vibration's frame
    statuses = [status_of(a, '/prsm') for a in diagnostics]
    assert bytes([OK]) not in [s.level for s in statuses]
    assert any(s.level == bytes([WARN]) and 'not calibrated' in s.message for s in statuses)
    assert statuses[-1].name == 'lubrication_estimator: /prsm lubrication'


def test_estimators_in_two_namespaces_each_serve_their_own_topics_and_calibrate(graph, tmp_path):
    """``__ns`` moves every name: /ema_left/..., /ema_right/..., nothing under /prsm."""
    nodes = {}
    for side in ('ema_left', 'ema_right'):
        node = LubricationEstimator(context=graph.context, cli_args=['--ros-args', '-r', f'__ns:=/{side}'],
                                    parameter_overrides=[
                                        Parameter('calibration_file', value=str(tmp_path / 'cal_{actuator}.yaml')),
                                        Parameter('recordings_dir', value=str(tmp_path))])
        graph.nodes.append(node)
        graph.executor.add_node(node)
        nodes[side] = node
        assert node.channels[0].name == f'/{side}'
        assert node.channels[0].calibration_file == str(tmp_path / f'cal_{side}.yaml')
    for side, node in nodes.items():
        wait_for(lambda: f'/{side}/calibrate' in {n for n, _ in graph.probe.get_service_names_and_types()}, 10,
                 f'/{side}/calibrate')
        response = call(graph, f'/{side}/calibrate', [])
        assert not response.success and 'bag_paths is empty' in response.message
        own = {name for name, _ in node.get_service_names_and_types_by_node(node.get_name(), f'/{side}')}
        assert f'/{side}/calibrate' in own and f'/{side}/{node.get_name()}/get_parameters' in own
        assert not any(name.startswith('/prsm') for name in own), own
        wait_for(lambda: graph.probe.count_subscribers(f'/{side}/vibration') >= 1, 10, f'/{side}/vibration')
        assert node.channels[0].publisher.topic_name == f'/{side}/lubrication_state'
    services = {name for name, _ in graph.probe.get_service_names_and_types()}
    assert '/prsm/calibrate' not in services
    assert graph.probe.count_subscribers('/prsm/vibration') == 0


def test_a_bridge_in_a_namespace_publishes_there():
    from prsm_lube_ros.nodes.sensor_bridge import SensorBridge
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID)
    try:
        bridge = SensorBridge(context=context, cli_args=['--ros-args', '-r', '__ns:=/ema_left'],
                              parameter_overrides=[Parameter('source', value='simulator')])
        try:
            assert set(bridge.topics.values()) == {f'/ema_left/{k}' for k in Graph.TYPES}
        finally:
            bridge.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)


# -- surface defect screen (issue 34) --------------------------------------------------------------
DEFECT_SPEED = 16.0                        # rad/s: 2.5 revolutions in a 1 s window, strikes at 15.9 Hz
#: Healthy indicators of a Gaussian machine (as prsm-lube calibrate keeps them).
HEALTHY_BASELINE = ConditionBaseline(runs=6, kurtosis_median=3.0, kurtosis_max=3.1, crest_median=4.0,
                                     crest_max=4.4, envelope_levels=((6.25, 4.0), (3.75, 4.0)))
SCREENED = dict(window_length=1.0, completion_delay=0.25, stale_timeout=5.0, defect_windows=4)


def screened_estimator(graph, tmp_path, baseline=HEALTHY_BASELINE, **params):
    """An estimator whose calibration is START with the band of 4 kHz recordings and ``baseline``.

    ``baseline`` None: a file written before baselines were kept.
    """
    save_calibration(replace(calibration(START), band=DEFAULT_BAND.resolved(4000.0), condition_baseline=baseline),
                     tmp_path / 'calibration_prsm.yaml')
    return graph.estimator(tmp_path, **{**SCREENED, 'calibration_file': str(tmp_path / 'calibration_{actuator}.yaml'),
                                        **params})


def defect_stream(segments, strike=0.0, seed=1):
    """:func:`segments_stream` at 4 kHz in 0.1 s blocks with Gaussian vibration of the segment's RMS and, when
    ``strike`` > 0, a screw raceway spall: ``strike`` x RMS peak strikes at 6.25 per screw revolution ringing
    a 1 kHz mode (the angle is continuous over segments of one speed, as the strikes assume)."""
    def vibration(times, rms, speed, index):
        return synthetic_inputs.defect_vibration(times, max(speed, 1e-3), rms=rms, strike=strike * rms,
                                                 seed=seed + index)
    return segments_stream(segments, rate=4000.0, block=0.1, vibration=vibration)


def last_status(arrays, name_part):
    """The newest status whose name contains ``name_part``, or None."""
    for array in reversed(list(arrays)):
        found = [s for s in array.status if name_part in s.name]
        if found:
            return found[0]
    return None


def values_by_key(status):
    return {kv.key: kv.value for kv in status.values}


def test_a_spall_is_an_error_with_its_component_and_theta_is_withheld_not_insufficient(graph, tmp_path):
    node = screened_estimator(graph, tmp_path)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    # RMS where Eq. 23 reads theta 0.5: as oil, "lubrication insufficient".
    rms = rms_for(0.5, speed=DEFECT_SPEED)
    graph.publish(graph.publishers(), defect_stream([(9.0, rms, DEFECT_SPEED, LOAD)], strike=8.0))
    wait_for(lambda: len(states) >= 8, 15, 'eight windows')

    def surface():
        status = last_status(arrays, '/prsm surface condition')
        return status if status is not None and ros_convert.status_level(status) == ERROR else None
    wait_for(surface, 10, 'surface condition ERROR')
    status = surface()
    assert status.name == 'lubrication_estimator: /prsm surface condition' and status.hardware_id == 'prsm'
    assert status.message == ('impulsive at 6.25x screw speed: screw raceway defect suspected; theta_Oil is not '
                              'a lubrication measure while it lasts')
    values = values_by_key(status)
    assert values['defect_suspected'] == 'True' and values['component'] == 'screw raceway'
    assert float(values['kurtosis']) > 4.0 and 'screw raceway' in values['envelope_peaks']
    assert values['baseline'].startswith('6 calibration run(s)') and values['windows_pooled'] == '4'
    lubrication = last_status(arrays, '/prsm lubrication')
    assert ros_convert.status_level(lubrication) == WARN
    assert lubrication.message.startswith('theta_oil withheld: screw raceway defect suspected')
    assert 0.4 < float(values_by_key(lubrication)['theta_oil_withheld']) < 0.6
    # Never read as oil: the first four windows, before the first judgement reaches them, 'not yet judged' (a
    # window's theta goes out before its indicators reach the screen: the fourth makes the first judgement and
    # was published before it); from the fifth on, theta withheld (NaN).
    assert all('insufficient' not in s.message and 'degraded' not in s.message and s.level == WARN for s in states)
    assert all(s.message.startswith('lubrication not yet judged') for s in states if s.window_start - T0 < 4.0)
    judged = [s for s in states if s.window_start - T0 >= 4.0]
    assert judged and all(math.isnan(s.theta_oil) and s.message.startswith('theta_oil withheld') for s in judged)
    for array in arrays:
        for s in array.status:
            # the input statuses judge the synthetic 2026-01-01 stamps as too old: not the lubrication's
            if ros_convert.status_level(s) == ERROR and not s.name.endswith((' surface condition', ' input')):
                assert False, f'lubrication ERROR while the spall was being screened: {s.message}'
    assert node.channels[0].surface.suspected


def test_healthy_vibration_keeps_the_surface_ok_and_theta_published(graph, tmp_path):
    node = screened_estimator(graph, tmp_path, defect_windows=10)
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    # defect_windows through the rcl_interfaces service, as ros2 param set does.
    from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    client = graph.probe.create_client(SetParameters, '/prsm/lubrication_estimator/set_parameters')
    assert client.wait_for_service(timeout_sec=10)
    for value, ok in ((0, False), (4, True)):
        future = client.call_async(SetParameters.Request(parameters=[ParameterMsg(
            name='defect_windows', value=ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value))]))
        wait_for(future.done, 10, 'set_parameters answer')
        assert future.result().results[0].successful is ok, future.result().results[0].reason
    assert node.channels[0].surface.windows == 4
    graph.publish(graph.publishers(), defect_stream([(9.0, rms_for(0.9, speed=DEFECT_SPEED), DEFECT_SPEED, LOAD)]))
    wait_for(lambda: len(states) >= 8, 15, 'eight windows')
    wait_for(lambda: (last_status(arrays, 'surface condition') is not None
                      and last_status(arrays, 'surface condition').message.startswith('no surface defect')), 10,
             'surface judged')
    status = last_status(arrays, 'surface condition')
    assert ros_convert.status_level(status) == OK
    assert status.message == 'no surface defect: kurtosis below 4.0, no envelope line at a defect order'
    assert float(values_by_key(status)['kurtosis']) < 3.5
    assert all(math.isfinite(s.theta_oil) and 'withheld' not in s.message for s in states), [
        (s.window_start - T0, s.theta_oil, s.message) for s in states]
    assert 'withheld' not in last_status(arrays, '/prsm lubrication').message


def reference_defect_stream(segments):
    """This machine's healthy vibration: mildly impulsive at the strike order, as some machines are."""
    return defect_stream(segments, strike=MILD_STRIKE, seed=7)


MILD_STRIKE = 5.0


def test_recalibration_keeps_the_baseline_and_the_node_judges_with_it(graph, tmp_path):
    """A calibration without a baseline judges on absolute limits; calibrate keeps one and the node uses it."""
    node = screened_estimator(graph, tmp_path, baseline=None)
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    graph.publish(graph.publishers(), defect_stream([(7.0, rms_for(0.9, speed=DEFECT_SPEED), DEFECT_SPEED, LOAD)],
                                                    strike=0.8 * MILD_STRIKE, seed=30))
    wait_for(lambda: len(states) >= 6, 15, 'six windows')
    wait_for(lambda: node.channels[0].surface.status().level == ERROR, 5, 'absolute limits flag it')
    wait_for(lambda: (last_status(arrays, 'surface condition') is not None
                      and last_status(arrays, 'surface condition').message.startswith('impulsive')), 10,
             'ERROR on /diagnostics')
    assert values_by_key(last_status(arrays, 'surface condition'))['baseline'].startswith('none: the calibration')

    write_reference_bag(tmp_path / 'reference', reference_segments(speeds=(8.0, 12.0, DEFECT_SPEED)),
                        stream=reference_defect_stream)
    response = call(graph, '/prsm/calibrate', ['reference'], persist=True)
    assert response.success, response.message
    saved = load_calibration(tmp_path / 'calibration_prsm.yaml')
    assert saved.condition_baseline is not None and saved.condition_baseline.runs == 6
    assert saved.condition_baseline.kurtosis_median > 4.0           # this machine's own impulsiveness
    live = node.channels[0].assessor.calibration.condition_baseline      # the fitted one (the file rounds)
    assert live.runs == 6 and live.kurtosis_median == pytest.approx(saved.condition_baseline.kurtosis_median)
    assert node.channels[0].surface.baseline is live
    # Judged again at once on the same windows, against the new baseline: within this machine's healthy range.
    status = node.channels[0].surface.status()
    assert status.level == OK and status.message.startswith('no surface defect'), status.message
    wait_for(lambda: last_status(arrays, 'surface condition').message.startswith('no surface defect'), 10,
             'OK on /diagnostics')
    assert values_by_key(last_status(arrays, 'surface condition'))['baseline'].startswith('6 calibration run(s)')


def test_the_actuator_file_gives_the_defect_orders_screened(graph, tmp_path, repo_root):
    """A rig whose actuator file configures a support bearing (and no roller screw): its orders label the lines."""
    from prsm_lube_ros.physics.actuator import load_actuator
    from prsm_lube_ros.physics.defect_orders import defect_orders
    file = repo_root / 'config' / 'femto_pronostia_bearing.yaml'
    node = screened_estimator(graph, tmp_path, actuator_file=str(file))
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    expected = defect_orders(load_actuator(file))
    assert [o.component for o in expected][:2] == ['support bearing outer race', 'support bearing inner race']
    assert node.channels[0].builder.settings.defect_orders == expected
    assert node.channels[0].surface.orders == expected and node.channels[0].assessor.defect_orders == expected
    wait_for(lambda: last_status(arrays, 'surface condition') is not None, 10, 'a surface status')
    orders = values_by_key(last_status(arrays, 'surface condition'))['defect_orders']
    assert orders.startswith('support bearing outer race 5.61') and 'screw raceway' not in orders


def test_indicators_on_every_second_window_still_find_the_spall(graph, tmp_path):
    """condition_every 2: half the indicator CPU; the screen pools 4 screened windows, over 8 s."""
    node = screened_estimator(graph, tmp_path, condition_every=2)
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    graph.publish(graph.publishers(), defect_stream([(11.0, rms_for(0.9, speed=DEFECT_SPEED), DEFECT_SPEED, LOAD)],
                                                    strike=8.0))
    wait_for(lambda: len(states) >= 10, 15, 'ten windows')
    wait_for(lambda: node.channels[0].surface.suspected, 5, 'the spall suspected')
    wait_for(lambda: ros_convert.status_level(last_status(arrays, 'surface condition')) == ERROR, 5, 'ERROR')
    status = last_status(arrays, 'surface condition')
    assert status.message.startswith('impulsive at 6.25x screw speed: screw raceway defect suspected')
    assert values_by_key(status)['windows_pooled'] == '4'
    assert node.channels[0].surface.status().since - T0 >= 7.0      # the fourth screened window ends at 8 s


def recording_events(path, seconds):
    """The first ``seconds`` of a recording's contract topics as ``(stamp, kind, msg)``, in stamp order."""
    from prsm_lube_ros.recording import reader
    kinds = {'VibrationBatch': 'vibration', 'ScrewStateBatch': 'joint_states', 'AxialLoadBatch': 'axial_load',
             'TemperatureBatch': 'temperature'}
    recording = reader.open_recording(path, namespace='/prsm')
    end = recording.start_time + seconds
    events = []
    for batches in recording.slices(slice_seconds=5.0):
        for batch in batches:
            events += [(float(stamp), kinds[type(batch).__name__], msg)
                       for stamp, msg in zip(batch.stamps, ros_convert.batch_messages(batch)) if stamp < end]
        if batches and min(float(b.stamps[0]) for b in batches if len(b)) >= end:
            break
    return sorted(events, key=lambda e: e[0])


def test_the_simulators_spall_replayed_live_after_calibrating_on_healthy_recordings(graph, tmp_path):
    """prsm-lube simulate --effect surface_defect (a steady roller spall, seed 5); calibrate on the same rig
    healthy; the spalled recording's first 14 s replayed live: ERROR naming the shared 3.75 order."""
    from prsm_lube_ros.cli import main
    assert main(['simulate', str(tmp_path / 'healthy'), '--seed', '3']) == 0
    assert main(['simulate', str(tmp_path / 'spall'), '--effect', 'surface_defect', '--seed', '5']) == 0
    node = graph.estimator(tmp_path, **{**SCREENED, 'calibration_file': str(tmp_path / 'none_{actuator}.yaml')})
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    response = call(graph, '/prsm/calibrate', ['healthy/stage_3'], theta=1.0)
    assert response.success, response.message
    assert node.channels[0].assessor.calibration.condition_baseline.runs == 6
    graph.publish(graph.publishers(), recording_events(tmp_path / 'spall' / 'stage_3', 14.0))
    wait_for(lambda: node.channels[0].surface.suspected, 20, 'the spall suspected')
    wait_for(lambda: ros_convert.status_level(last_status(arrays, 'surface condition')) == ERROR, 5, 'ERROR')
    # Impulsive and periodic, or periodic beyond the healthy runs' level alone: the evidence of the group judged.
    assert last_status(arrays, 'surface condition').message.endswith(
        'at 3.75x screw speed: nut raceway or roller defect suspected; theta_Oil is not a lubrication measure while '
        'it lasts')
    assert last_status(arrays, '/prsm lubrication').message.startswith('theta_oil withheld: nut raceway or roller')


def test_the_simulators_healthy_rig_replayed_live_stays_ok(graph, tmp_path):
    """The same rig without a defect (stage 2, theta 0.83): the screen judges and stays OK, theta is published."""
    from prsm_lube_ros.cli import main
    assert main(['simulate', str(tmp_path / 'healthy'), '--seed', '3']) == 0
    node = graph.estimator(tmp_path, **{**SCREENED, 'calibration_file': str(tmp_path / 'none_{actuator}.yaml')})
    arrays = graph.collect(DiagnosticArray, '/diagnostics')
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    assert call(graph, '/prsm/calibrate', ['healthy/stage_3'], theta=1.0).success
    graph.publish(graph.publishers(), recording_events(tmp_path / 'healthy' / 'stage_2', 20.0))
    wait_for(lambda: node.channels[0].surface.judged, 20, 'a judgement')
    settle(states)
    assert not node.channels[0].surface.suspected
    wait_for(lambda: last_status(arrays, 'surface condition').message.startswith('no surface defect'), 5, 'OK')
    assert any(math.isfinite(s.theta_oil) for s in states)
    assert not any('withheld' in s.message for s in states)


def test_windows_closed_twice_before_their_screen_each_reach_it_with_their_own_indicators(graph, tmp_path):
    # An actuator that closes windows again before the one-shot timer screened its last ones (a lagging node, a
    # drain-timer flush): every steady window still reaches the surface screen, in order, with its indicators.
    node = screened_estimator(graph, tmp_path)
    channel = node.channels[0]
    evaluated, screened = [], []
    evaluate, screen = node._evaluate, node._screen
    node._evaluate = lambda ch, window: (evaluated.append(window), evaluate(ch, window))[1]
    node._screen = lambda ch, window: (screened.append(window), screen(ch, window))[1]
    batches = synthetic_inputs.interleave(synthetic_inputs.run_streams(plateau=20.0, hold=8.0))
    with node._lock:      # the timer's callback waits for the lock: no screen runs between these closes
        for index, batch in enumerate(batches):
            channel.builder.add(batch)
            if index % 140 == 139:
                node._close_windows(channel)
        node._close_windows(channel)
    wait_for(lambda: not channel.unscreened, 5, 'the last windows screened by the timer')
    steady = [w.start for w in evaluated if w.steady]
    assert len(steady) >= 5
    assert [w.start for w in screened if w.steady] == steady
    assert all(w.condition is not None for w in screened if w.steady)


def test_the_estimator_spins_under_the_events_executor(tmp_path):
    # rclpy's EventsExecutor refuses nodes with guard conditions: the screen's wake-up is a timer.
    import rclpy
    from rclpy.experimental import EventsExecutor
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(os.environ.get('ROS_DOMAIN_ID', '0')))
    node, executor = None, None
    try:
        save_calibration(calibration(START), tmp_path / 'calibration_prsm.yaml')
        node = LubricationEstimator(context=context, parameter_overrides=[
            Parameter('calibration_file', value=str(tmp_path / 'calibration_{actuator}.yaml'))])
        executor = EventsExecutor(context=context)
        executor.add_node(node)
        for _ in range(5):
            executor.spin_once(timeout_sec=0.05)
    finally:
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=context)
