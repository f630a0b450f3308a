# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Step 2 of ``prsm-lube demo``: both nodes on a live graph, watched and called the way the ros2 tools do.

``prsm-lube run`` (the sensor bridge and the lubrication estimator in one
process, as an integrator starts them without ``ros2 launch``) runs as a child
process with a parameter file written here: the bridge plays a recording
(``source: playback``, looping, ``playback_rate`` times real time), the
estimator starts from a given calibration file and may read recordings only
from ``recordings_dir``.  This process is the observer: a plain rclpy node
that subscribes ``/prsm/lubrication_state`` and ``/diagnostics`` (what ``ros2
topic echo`` shows) and calls ``/prsm/calibrate`` with a
``prsm_lube_ros/srv/Calibrate`` request (what ``ros2 service call`` sends).

The graph is private: ``ROS_DOMAIN_ID`` as set, else one drawn in 100..199,
and discovery on localhost only unless ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is
set, so the demo neither hears nor disturbs another graph on the network.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import os
from pathlib import Path
import random
import signal
import subprocess
from typing import Any
import sys
import threading
import time
from collections.abc import Callable

from diagnostic_msgs.msg import DiagnosticArray
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy

from ..msg import LubricationState
from ..srv import Calibrate

__all__ = ['CALIBRATE_SERVICE', 'LiveResult', 'Observer', 'STATE_TOPIC', 'STATUS_PART', 'graph_environment',
           'run_live_graph', 'stop_child', 'write_parameters']

#: The contract's default namespace: topics and the service of the actuator ``prsm``.
STATE_TOPIC = '/prsm/lubrication_state'
CALIBRATE_SERVICE = '/prsm/calibrate'
#: The estimator's lubrication status name on /diagnostics (not its '... /prsm surface condition' beside it).
STATUS_PART = 'lubrication_estimator: /prsm lubrication'


@dataclass
class LiveResult:
    """What the observer saw: windows (wall time s since start, theta_Oil) and the calibrate answer."""

    windows_before: list = field(default_factory=list)
    windows_after: list = field(default_factory=list)
    calibrated_at: float = math.nan          # s since start when the answer came
    response: Any = None                      # Calibrate.Response (generated, untyped)
    statuses: list = field(default_factory=list)   # (wall s, level, message) of the estimator's status
    bridge_statuses: int = 0
    problem: str = ''


def graph_environment() -> dict:
    """The environment of the child: a private domain (100..199 unless set) and localhost discovery."""
    env = dict(os.environ)
    if not env.get('ROS_DOMAIN_ID'):
        env['ROS_DOMAIN_ID'] = str(random.randrange(100, 200))
    env.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    return env


def write_parameters(path: Path, *, bag: Path, playback_rate: float, calibration_pattern: Path,
                     recordings_dir: Path, window_length: float) -> Path:
    """The ROS parameter file of both nodes (the keys of config/*.yaml, playback source)."""
    import yaml
    document = {
        '/**/sensor_bridge': {'ros__parameters': {
            'source': 'playback', 'bag': str(bag), 'playback_rate': float(playback_rate), 'loop': True,
            'exit_at_end': False, 'wait_for_subscribers': 10.0, 'diagnostics_period': 0.5,
            'stale_timeout': 5.0}},
        '/**/lubrication_estimator': {'ros__parameters': {
            'calibration_file': str(calibration_pattern), 'recordings_dir': str(recordings_dir),
            'window_length': float(window_length), 'diagnostics_period': 0.5}},
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    return path


class Observer:
    """A plain rclpy node in its own context, spun on a thread: subscriptions and the service client."""

    def __init__(self, domain_id: int):
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = rclpy.create_node('prsm_demo_observer', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.start = time.monotonic()
        self.windows: list[tuple[float, float, float, float]] = []      # (s since start, theta, speed, load)
        self.statuses: list[tuple[float, int, str]] = []
        self.bridge_statuses = 0
        self.lock = threading.Lock()
        self.node.create_subscription(LubricationState, STATE_TOPIC, self._state,
                                      QoSProfile(depth=200, reliability=ReliabilityPolicy.RELIABLE))
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._diagnostics, 50)
        self.client: Any = self.node.create_client(Calibrate, CALIBRATE_SERVICE)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()

    def now(self) -> float:
        """Wall seconds since the observer started."""
        return time.monotonic() - self.start

    def _state(self, msg: Any) -> None:
        if math.isfinite(msg.theta_oil):
            with self.lock:
                self.windows.append((self.now(), float(msg.theta_oil), float(msg.screw_speed),
                                     float(msg.axial_load)))

    def _diagnostics(self, array: Any) -> None:
        for status in array.status:
            if STATUS_PART in status.name:
                with self.lock:
                    self.statuses.append((self.now(), int.from_bytes(status.level, 'little')
                                          if isinstance(status.level, bytes) else int(status.level),
                                          status.message))
            elif 'sensor source' in status.name:
                self.bridge_statuses += 1

    def windows_since(self, t: float) -> list:
        """Windows that arrived after ``t`` (observer s)."""
        with self.lock:
            return [w for w in self.windows if w[0] > t]

    def wait_for(self, condition: Callable[[], bool], timeout: float, child: subprocess.Popen) -> bool:
        """True once ``condition()`` holds; False at ``timeout`` s or when the child has ended."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if condition():
                return True
            if child.poll() is not None:
                return False
            time.sleep(0.1)
        return condition()

    def calibrate(self, bag_names: list[str], theta: float, timeout: float) -> Any:
        """Call the calibrate service as ``ros2 service call /prsm/calibrate prsm_lube_ros/srv/Calibrate`` does."""
        if not self.client.wait_for_service(timeout_sec=min(timeout, 30.0)):
            return None
        request = Calibrate.Request(bag_paths=list(bag_names), reference_theta=float(theta), persist=True)
        future = self.client.call_async(request)
        end = time.monotonic() + timeout
        while not future.done() and time.monotonic() < end:
            time.sleep(0.05)
        return future.result() if future.done() else None

    def close(self) -> None:
        """Stop spinning and shut the context down."""
        self.executor.shutdown(timeout_sec=5)
        self.thread.join(timeout=5)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def stop_child(child: subprocess.Popen, timeout: float = 15.0) -> int:
    """Ctrl-C to ``prsm-lube run`` (it stops both nodes), then kill if it hangs; returns its status."""
    if child.poll() is None:
        child.send_signal(signal.SIGINT)
        try:
            child.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
    return child.returncode


def run_live_graph(folder: Path, parameters: Path, *, reference_bags: list[str], reference_theta: float,
                   windows_wanted: int, settle: float, timeout: float,
                   say: Callable[[str], None]) -> LiveResult:
    """Start ``prsm-lube run`` with ``parameters``, watch, calibrate on ``reference_bags``, watch again, stop.

    ``windows_wanted`` windows are collected before the call and again after it
    (those arriving within ``settle`` s of the answer are left out: they may
    have been assessed with the old constants).  The child's output goes to
    ``folder/nodes.log``.
    """
    env = graph_environment()
    result = LiveResult()
    log = open(folder / 'nodes.log', 'w')
    command = [sys.executable, '-m', 'prsm_lube_ros.cli', 'run', '--config', str(parameters)]
    say(f'    ROS_DOMAIN_ID={env["ROS_DOMAIN_ID"]}, discovery {env["ROS_AUTOMATIC_DISCOVERY_RANGE"]}; '
        f'started: prsm-lube run --config {parameters}')
    child = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=env)
    try:
        observer = Observer(int(env['ROS_DOMAIN_ID']))
    except BaseException:
        stop_child(child)
        log.close()
        raise
    try:
        if not observer.wait_for(lambda: len(observer.windows_since(0.0)) >= windows_wanted, timeout, child):
            result.problem = (f'only {len(observer.windows_since(0.0))} windows of theta_Oil in {timeout:.0f} s '
                              f'(see {folder / "nodes.log"})')
            return result
        result.windows_before = observer.windows_since(0.0)
        say(f'    {len(result.windows_before)} windows on {STATE_TOPIC} after {observer.now():.1f} s; calling '
            f'{CALIBRATE_SERVICE} (bag_paths {reference_bags}, reference_theta {reference_theta:g}, persist true)')
        response = observer.calibrate(reference_bags, reference_theta, timeout)
        result.calibrated_at = observer.now()
        result.response = response
        if response is None:
            result.problem = f'{CALIBRATE_SERVICE} gave no answer in {timeout:.0f} s'
            return result
        if not response.success:
            result.problem = f'{CALIBRATE_SERVICE} refused: {response.message}'
            return result
        since = result.calibrated_at + settle
        if not observer.wait_for(lambda: len(observer.windows_since(since)) >= windows_wanted, timeout, child):
            result.problem = f'only {len(observer.windows_since(since))} windows after the calibration'
        result.windows_after = observer.windows_since(since)
        return result
    finally:
        with observer.lock:
            result.statuses = list(observer.statuses)
            result.bridge_statuses = observer.bridge_statuses
        observer.close()
        status = stop_child(child)
        log.close()
        if status not in (0, -signal.SIGINT, 130) and not result.problem:
            result.problem = f'prsm-lube run ended with status {status} (see {folder / "nodes.log"})'
