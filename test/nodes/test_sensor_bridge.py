# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The sensor_bridge node on a real ROS graph (rclpy + Fast DDS on loopback).

A short simulated stage (two runs) is replayed at 8x to the lubrication
estimator; theta_Oil published live must equal what the offline pipeline
(``prsm-lube assess``: recording_windows + assess_recording) gives on the same
bag, window by window, within 0.01.  The calibration is the simulator's true
constants, so both sides assess with the same numbers.
"""
import math
import os
from pathlib import Path
import subprocess
import sys
import time

import numpy as np
import pytest

rclpy = pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import QoSCompatibility, qos_check_compatible, QoSProfile, ReliabilityPolicy  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402

from prsm_lube_ros.recording import reader as bag_reader  # noqa: E402
from prsm_lube_ros.physics.actuator import Actuator  # noqa: E402
from prsm_lube_ros.estimation.pipeline import assess_recording, recording_windows  # noqa: E402
from prsm_lube_ros.estimation.calibration import Calibration  # noqa: E402
from prsm_lube_ros.estimation.calibration_file import save_calibration  # noqa: E402
from prsm_lube_ros.errors import InputError  # noqa: E402
from prsm_lube_ros.msg import LubricationState, VibrationBlock  # noqa: E402
from prsm_lube_ros.nodes.lubrication_estimator import LubricationEstimator  # noqa: E402
from prsm_lube_ros.nodes.sensor_bridge import NODE_NAME, publisher_qos, SensorBridge  # noqa: E402
from prsm_lube_ros.simulation.recordings import simulate_experiment  # noqa: E402
from prsm_lube_ros.simulation.rig_config import ExperimentPlan, RigConfig  # noqa: E402
from prsm_lube_ros.estimation.windowing import WindowSettings  # noqa: E402
from bridge_graph import BridgeGraph  # noqa: E402
from polling import settle, stop_process, wait_for  # noqa: E402
from spinning import torn_down  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.timeout(120)]

DOMAIN_ID = (int(os.environ.get('ROS_DOMAIN_ID', '0') or 0) + 53) % 100 + 100
ROOT = Path(__file__).resolve().parents[2]
RIG = RigConfig()
#: Two runs (15 and 25 rad/s at 150 N) of 120 mm, theta 0.8: about 30 s of stamps.
PLAN = ExperimentPlan(speeds=(15.0, 25.0), loads=(150.0,), stage_thetas=(0.8,), stroke=0.12,
                      ramp_travel=0.004, standstill=0.6)
RATE = 8.0


def process_env():
    """Environment of node processes: this module's domain, unbuffered, no deprecated ROS_LOCALHOST_ONLY."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID), PYTHONUNBUFFERED='1',
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


@pytest.fixture(scope='module')
def stage(tmp_path_factory):
    """The simulated bag, a calibration file with the rig's true constants, and the offline assessment."""
    folder = tmp_path_factory.mktemp('bridge')
    bag = simulate_experiment(folder / 'sim', plan=PLAN, rig=RIG, seed=5)[0]
    calibration = Calibration(constants=RIG.constants, covariance=np.diag([1e-6, 1e-12, 1e-6]), fit_rmse=0.0,
                              residual_std=0.01, windows_used=6, reference_theta=1.0)
    save_calibration(calibration, folder / 'calibration_prsm.yaml')
    windows = recording_windows(bag, lead=Actuator().lead, settings=WindowSettings())
    offline = assess_recording(windows, calibration, min_axial_load=5.0)
    return {'bag': bag, 'folder': folder, 'offline': offline.windows}


def offline_thetas(stage):
    """theta_Oil of every assessed offline window, by window end stamp (us)."""
    return {round(w.window.end * 1e6): w.theta_oil for w in stage['offline'] if math.isfinite(w.theta_oil)}


def assert_live_equals_offline(states, stage):
    """Every assessed offline window arrived live with its theta within 0.01, and no live theta is extra."""
    expected = offline_thetas(stage)
    assert len(expected) >= 8, 'the stage should give several steady windows'

    def live_thetas():
        return {round((msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9) * 1e6): msg.theta_oil
                for msg in list(states) if math.isfinite(msg.theta_oil)}
    # The last windows close on the estimator's timer once the inputs fall silent: on a loaded machine
    # that can come later than the caller's quiet period, so wait for them (bounded) before judging.
    deadline = time.monotonic() + 15.0
    while not set(expected) <= set(live := live_thetas()) and time.monotonic() < deadline:
        time.sleep(0.1)
    missing = sorted(set(expected) - set(live))
    assert not missing, f'{len(missing)} assessed offline windows not published live: {missing[:3]}'
    extra = sorted(set(live) - set(expected))
    assert not extra, f'live windows with theta that offline did not assess: {extra[:3]}'
    worst = max(abs(live[k] - expected[k]) for k in expected)
    assert worst <= 0.01, f'largest live - offline theta difference {worst:.4f}'
    thetas = np.array(list(expected.values()))
    assert abs(np.median(thetas) - 0.8) < 0.1      # and it is the stage's theta, not some constant


class Graph(BridgeGraph):
    """A context on this module's domain, an executor thread, a probe node, and the nodes started in it."""

    def __init__(self):
        super().__init__(DOMAIN_ID, 'bridge_test_probe')

    def bridge(self, **params):
        """A SensorBridge in this process."""
        return super().bridge(SensorBridge, NODE_NAME, **params)

    def estimator(self, folder):
        """A LubricationEstimator with the estimator's default windows and the stage's calibration."""
        return self.add(LubricationEstimator(context=self.context, parameter_overrides=[
            Parameter('calibration_file', value=str(folder / 'calibration_{actuator}.yaml')),
            Parameter('recordings_dir', value=str(folder)), Parameter('qos_depth', value=2000)]))


@pytest.fixture
def graph():
    """A fresh ROS graph for one test, always torn down (a callback that raised fails the test)."""
    yield from torn_down(Graph())


def bridge_command(bag, *params):
    """``ros2 run prsm_lube_ros sensor_bridge`` as the installed script runs it."""
    command = [sys.executable, str(ROOT / 'scripts' / 'sensor_bridge'), '--ros-args', '-p', 'source:=playback',
               '-p', f'bag:={bag}']
    for param in params:
        command += ['-p', param]
    return command


# -- replay to the estimator ---------------------------------------------------------------------------
def test_replay_assessed_live_equals_prsm_lube_assess_window_by_window(graph, stage):
    """In one process; also: every recorded stamp arrives unchanged and in order per topic."""
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    blocks = graph.collect(VibrationBlock, '/prsm/vibration', QoSProfile(depth=5000,
                                                                         reliability=ReliabilityPolicy.RELIABLE))
    joints = graph.collect(JointState, '/prsm/joint_states', QoSProfile(depth=5000,
                                                                        reliability=ReliabilityPolicy.RELIABLE))
    graph.estimator(stage['folder'])
    wait_for(lambda: graph.probe.count_subscribers('/prsm/vibration') >= 2, 10, 'estimator subscribed')
    bridge = graph.bridge(source='playback', bag=str(stage['bag']), playback_rate=RATE, wait_for_subscribers=10.0)
    wait_for(bridge.finished.is_set, 40, 'the replay to end')
    settle(states)
    assert bridge.exit_status == 0
    assert_live_equals_offline(states, stage)

    recorded = {kind: [] for kind in ('vibration', 'joint_states')}
    for batches in bag_reader.open_recording(stage['bag']).slices():
        for batch in batches:
            kind = {'VibrationBatch': 'vibration', 'ScrewStateBatch': 'joint_states'}.get(type(batch).__name__)
            if kind:
                recorded[kind].extend(batch.stamps)
    # The probe takes 8 kHz of joint states in Python: on a loaded machine it may still be catching up.
    wait_for(lambda: len(blocks) >= len(recorded['vibration']) and len(joints) >= len(recorded['joint_states']),
             30, 'the probe to receive every recorded message')
    for kind, received in (('vibration', blocks), ('joint_states', joints)):
        got = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in received]
        assert got == recorded[kind], f'{kind}: stamps differ from the bag'   # exact floats, same order
    assert all(m.sample_rate == 4000.0 and len(m.samples) == 400 for m in blocks)


def test_bridge_and_estimator_as_separate_processes(graph, stage):
    folder = stage['folder']
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    estimator = subprocess.Popen(
        [sys.executable, '-m', 'prsm_lube_ros.nodes.lubrication_estimator', '--ros-args',
         '-p', f'calibration_file:={folder}/calibration_{{actuator}}.yaml', '-p', f'recordings_dir:={folder}',
         '-p', 'qos_depth:=2000'], env=process_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    bridge = None
    try:
        wait_for(lambda: graph.probe.count_subscribers('/prsm/vibration') >= 1 or estimator.poll() is not None, 30,
                 'the estimator process subscribing')
        # And this test's collector matched to the estimator's state publisher (a loaded machine discovers slowly).
        wait_for(lambda: graph.probe.count_publishers('/prsm/lubrication_state') >= 1 or estimator.poll() is not None,
                 30, 'the estimator publishing states')
        bridge = subprocess.Popen(bridge_command(stage['bag'], f'playback_rate:={RATE}', 'wait_for_subscribers:=10.0'),
                                  env=process_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        bridge_out, bridge_err = bridge.communicate(timeout=60)    # ends by itself after the last message
        settle(states)
    finally:
        estimator_err = stop_process(estimator)
        if bridge is not None and bridge.poll() is None:
            stop_process(bridge)
    assert bridge.returncode == 0, bridge_err
    assert 'playback of' in bridge_err and 'finished' in bridge_err and 'Traceback' not in bridge_err
    assert estimator.returncode == 0 and 'Traceback' not in estimator_err
    assert_live_equals_offline(states, stage)


def test_the_estimator_keeps_publishing_through_a_bridge_restart(graph, stage):
    """Bridge killed (SIGKILL) 8 s of stamps into the replay, started again: the estimator resets and goes on."""
    states = graph.collect(LubricationState, '/prsm/lubrication_state')
    graph.estimator(stage['folder'])
    wait_for(lambda: graph.probe.count_subscribers('/prsm/vibration') >= 1, 10, 'estimator subscribed')
    start = bag_reader.open_recording(stage['bag']).start_time
    first = subprocess.Popen(bridge_command(stage['bag'], 'playback_rate:=4.0', 'wait_for_subscribers:=10.0'),
                             env=process_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        def past(seconds):
            return any(s.header.stamp.sec + s.header.stamp.nanosec * 1e-9 > start + seconds for s in states)
        wait_for(lambda: past(8.0) or first.poll() is not None, 40, 'windows 8 s into the first replay')
        first.kill()
        first.communicate(timeout=10)
        before = len(states)
        second = subprocess.Popen(bridge_command(stage['bag'], f'playback_rate:={RATE}', 'wait_for_subscribers:=10.0'),
                                  env=process_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        _, second_err = second.communicate(timeout=60)
        settle(states)
    finally:
        for process in (first, locals().get('second')):
            if process is not None and process.poll() is None:
                stop_process(process)
    assert second.returncode == 0, second_err
    after = states[before:]
    stamps = [s.header.stamp.sec + s.header.stamp.nanosec * 1e-9 for s in after]
    assert any(t < start + 4.0 for t in stamps), 'windows of the restarted replay (stamps back at the start)'
    again = next(k for k, t in enumerate(stamps) if t < start + 4.0)
    assert_live_equals_offline(after[again:], stage)     # the second replay in full (after the reset's flush)


# -- simulator ------------------------------------------------------------------------------------------
def block_rms(blocks):
    """RMS of the samples of ``blocks`` (m/s^2)."""
    samples = np.concatenate([np.asarray(b.samples, float) for b in blocks])
    return float(np.sqrt(np.mean(samples ** 2)))


def test_simulator_theta_parameter_changes_the_vibration_as_eq_22_says(graph):
    """theta 1.0 -> 0.5 at 20 rad/s, 150 N: the RMS grows by exp(C_lambda w^0.68 F^-0.073 x 0.5), closed form."""
    blocks = graph.collect(VibrationBlock, '/sim/prsm/vibration')
    bridge = graph.bridge(source='simulator', namespace='/sim/prsm', speed=20.0, load=150.0, theta_oil=1.0, seed=4)
    ramp_end = time.time_ns() + int(1.5e9)         # 20 rad/s at 20 rad/s^2 takes 1 s
    wait_for(lambda: len([b for b in blocks if b.header.stamp.sec * 10**9 + b.header.stamp.nanosec > ramp_end]) >= 6,
             15, 'six blocks at speed')
    result = bridge.set_parameters([Parameter('theta_oil', value=0.5)])
    assert result[0].successful
    changed = time.time_ns() + int(0.3e9)
    wait_for(lambda: len([b for b in blocks if b.header.stamp.sec * 10**9 + b.header.stamp.nanosec > changed]) >= 6,
             15, 'six blocks after the change')
    stamp = [b.header.stamp.sec * 10**9 + b.header.stamp.nanosec for b in blocks]
    dry = block_rms([b for b, t in zip(blocks, stamp) if t > changed][:6])
    wet = block_rms([b for b, t in zip(blocks, stamp) if ramp_end < t < changed - int(0.3e9)][-6:])
    c = RIG.constants
    expected = math.exp(c.c_lambda * 20.0 ** 0.68 * 150.0 ** -0.073 * 0.5)      # Eq. 22 ratio, about 2.2
    assert dry / wet == pytest.approx(expected, rel=0.15)
    assert bridge.set_parameters([Parameter('playback_rate', value=2.0)])[0].successful is False


# -- clock, loop, QoS -------------------------------------------------------------------------------------
def test_clock_is_published_on_request_and_a_loop_goes_back_to_the_start(graph, stage):
    clock = graph.collect(Clock, '/clock')
    blocks = graph.collect(VibrationBlock, '/prsm/vibration')
    bridge = graph.bridge(source='playback', bag=str(stage['bag']), playback_rate=20.0, loop=True,
                          publish_clock=True, clock_period=0.05, wait_for_subscribers=10.0)

    def went_back(stamps):
        return any(b < a for a, b in zip(stamps, stamps[1:]))
    wait_for(lambda: went_back([c.clock.sec + c.clock.nanosec * 1e-9 for c in clock])
             and went_back([b.header.stamp.sec + b.header.stamp.nanosec * 1e-9 for b in blocks]), 30,
             'clock and blocks of the second pass')
    assert bridge.loops >= 1
    times = [c.clock.sec + c.clock.nanosec * 1e-9 for c in clock]
    start = bag_reader.open_recording(stage['bag']).start_time
    backs = [k for k in range(1, len(times)) if times[k] < times[k - 1]]
    assert len(backs) >= 1                                # the loop: replay time goes back once per pass
    first_pass = times[:backs[0]]
    assert first_pass == sorted(first_pass) and first_pass[0] == pytest.approx(start, abs=0.2)
    assert first_pass[-1] - first_pass[0] > 10.0          # covers the bag (about 14 s)
    steps = np.diff(first_pass)
    assert np.median(steps) == pytest.approx(0.05, abs=0.01)
    block_stamps = [b.header.stamp.sec + b.header.stamp.nanosec * 1e-9 for b in blocks]
    goes_back = [k for k in range(1, len(block_stamps)) if block_stamps[k] < block_stamps[k - 1]]
    assert goes_back and block_stamps[goes_back[0]] == pytest.approx(start, abs=0.2)


def test_without_publish_clock_there_is_no_clock_publisher(graph, stage):
    graph.bridge(source='playback', bag=str(stage['bag']), playback_rate=50.0, wait_for_subscribers=0.0)
    assert graph.probe.count_publishers('/clock') == 0


@pytest.mark.parametrize('reliability', ['reliable', 'best_effort'])
def test_bridge_publishers_match_the_estimators_subscriptions(graph, stage, reliability):
    estimator = graph.estimator(stage['folder'])
    bridge = graph.bridge(source='simulator', reliability=reliability, speed=0.0)
    for kind, publisher in bridge._outputs.items():
        subscription = next(s for s in estimator.subscriptions if s.topic_name == publisher.topic_name)
        compatibility, reason = qos_check_compatible(publisher.qos_profile, subscription.qos_profile)
        assert compatibility != QoSCompatibility.ERROR, f'{kind}: {reason}'   # WARNING: system defaults only
        wait_for(lambda: publisher.get_subscription_count() >= 1, 10, f'{kind} matched')
    # Why reliable is the default: a reliable reader (ros2 bag record) ignores a best-effort writer.
    recorder = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    assert qos_check_compatible(publisher_qos('best_effort', 10), recorder)[0] == QoSCompatibility.ERROR
    assert qos_check_compatible(publisher_qos('reliable', 10), recorder)[0] != QoSCompatibility.ERROR


# -- bad input ------------------------------------------------------------------------------------------
def test_bad_sources_refuse_at_start(graph, stage, tmp_path):
    with pytest.raises(InputError, match='no such file'):
        graph.bridge(source='playback', bag=str(tmp_path / 'missing'))
    with pytest.raises(InputError, match='no /other/vibration topic'):
        graph.bridge(source='playback', bag=str(stage['bag']), namespace='/other')
    with pytest.raises(InputError, match='bag: empty'):
        graph.bridge(source='playback')
    with pytest.raises(InputError, match='source'):
        graph.bridge(source='camera')


def test_processes_end_with_one_line_for_a_missing_bag_and_a_missing_nidaqmx(tmp_path):
    try:
        import nidaqmx  # noqa: F401
        pytest.skip('nidaqmx is installed here')
    except ImportError:
        pass
    script = str(ROOT / 'scripts' / 'sensor_bridge')
    runs = [subprocess.Popen([sys.executable, script, '--ros-args', '-p', 'source:=hardware'], env=process_env(),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True),
            subprocess.Popen(bridge_command(tmp_path / 'missing.mcap'), env=process_env(),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)]
    (_, hardware), (_, missing) = (run.communicate(timeout=60) for run in runs)
    assert [run.returncode for run in runs] == [2, 2]
    assert hardware.strip().splitlines() == [
        'sensor_bridge: error: source hardware: the Python package nidaqmx is not installed (pip install nidaqmx; '
        'it also needs the NI-DAQmx driver from ni.com)']
    assert missing.strip().splitlines() == [f'sensor_bridge: error: {tmp_path / "missing.mcap"}: no such file or '
                                            'directory']


def test_hardware_publishes_the_cards_blocks(graph, fake_daq):
    """With a fake nidaqmx module: blocks in m/s^2, stamped by sample count, speed and load relayed."""
    blocks = graph.collect(VibrationBlock, '/rig/vibration')
    joints = graph.collect(JointState, '/rig/joint_states')
    bridge = graph.bridge(source='hardware', namespace='/rig', daq_channel='cDAQ1Mod1/ai2', block_length=0.05,
                          relay_joint_states='/ema/joint_states', relay_joint='spindle', frame_id='nut')
    assert set(bridge._outputs) == {'vibration'}
    ema = graph.probe.create_publisher(JointState, '/ema/joint_states', 10)
    wait_for(lambda: len(blocks) >= 5, 10, 'five blocks')
    wait_for(lambda: ema.get_subscription_count() >= 1, 10, 'relay subscribed')
    msg = JointState(name=['motor', 'spindle'], position=[0.0, 3.0], velocity=[0.0, 12.0])
    msg.header.stamp.sec = 5
    ema.publish(msg)
    wait_for(lambda: joints, 10, 'relayed joint state')
    assert list(joints[0].name) == ['motor', 'screw'] and joints[0].velocity[1] == 12.0
    task = fake_daq.instances[0]
    assert task.channel_args['physical_channel'] == 'cDAQ1Mod1/ai2' and task.read_sizes[0] == 200
    stamps = [b.header.stamp.sec * 10**9 + b.header.stamp.nanosec for b in blocks[:5]]
    assert np.diff(stamps).tolist() == [50_000_000] * 4           # 200 samples at 4 kHz
    assert abs(stamps[0] - time.time_ns()) < 30e9
    for k, block in enumerate(blocks[:5]):
        assert block.sample_rate == 4000.0 and block.header.frame_id == 'nut'
        assert block.samples[0] == pytest.approx(k * 9.80665, abs=1e-4)
        assert block.samples[199] == pytest.approx((k + 0.199) * 9.80665, abs=1e-4)
    fake_daq.fail_on = 'read'
    wait_for(bridge.finished.is_set, 10, 'the bridge to stop on a failing read')
    assert bridge.exit_status == 1 and task.closed


def test_the_shipped_parameter_file_lists_every_parameter_with_its_default():
    import yaml
    from prsm_lube_ros.cli import run as run_cli
    from prsm_lube_ros.nodes.sensor_bridge import create_node, PARAMETERS
    shipped = yaml.safe_load((ROOT / 'config' / 'sensor_bridge.yaml').read_text())
    values = shipped['/**/sensor_bridge']['ros__parameters']     # any namespace (-r __ns:=...)
    assert set(values) == set(PARAMETERS)
    assert {name: value for name, value in values.items() if value != PARAMETERS[name][0]} == {}
    assert run_cli._bridge_factory() is create_node          # prsm-lube run starts this bridge
