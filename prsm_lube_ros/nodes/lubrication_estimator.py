# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``lubrication_estimator``: theta_Oil per steady window, live, for one or several actuators.

For each actuator (a namespace or topic prefix in the ``actuators`` parameter)
the node subscribes ``<ns>/vibration``, ``<ns>/joint_states``,
``<ns>/axial_load`` and ``<ns>/temperature`` with sensor-data QoS, feeds each
message to that actuator's :class:`~prsm_lube_ros.estimation.windowing.WindowBuilder`
(which pairs the streams by header stamp), assesses every closed window with
:class:`~prsm_lube_ros.estimation.assessment.Assessor` and publishes a
``LubricationState`` on ``<ns>/lubrication_state``.  ``/diagnostics`` carries
two statuses per actuator: ``<node>: <actuator> lubrication``, judged by
:mod:`prsm_lube_ros.estimation.health`, and ``<node>: <actuator> surface
condition``, the surface defect screen of :mod:`prsm_lube_ros.estimation.surface_health`
(the last ``defect_windows`` steady windows' kurtosis, crest factor and
envelope lines at the actuator's defect orders, from ``actuator_file``,
against the calibration's healthy baseline).  While a defect is suspected
the surface status is ERROR with the component, and theta_Oil is withheld:
``LubricationState.theta_oil`` is NaN (the contract's "not assessable"; the
value Eq. 23 gave is the lubrication status's KeyValue ``theta_oil_withheld``),
and the lubrication status and the message say "theta_oil withheld", never
"lubrication insufficient": the vibration is the defect's, not the oil's.
A window's theta_Oil is published as soon as its band RMS is known; its
condition indicators are computed after that (the window builder's
``defer_conditions``) and go to the screen then, so each window is judged by
the screen of the windows before it: withholding starts with the window after
the one that made the screen suspect a defect.  The analysis (about 1 ms a
window at 4 kHz) runs in a one-shot timer's callback, ready at the executor's
next wait: with rclpy's executors, where many actuators close windows in the
callbacks of one wait, they all publish before any analysis runs
(``benchmarks/live_latency.py``).  An actuator's next close, a calibration
swap or a deactivation screens what is still waiting first.

Windows are made in the band of the actuator's calibration
(:mod:`prsm_lube_ros.estimation.conditioning`: DC and gravity out, nothing
above the band's upper edge); a window outside the calibration's domain (speeds, loads,
temperatures fitted) makes the status at least WARN with how far outside
(KeyValue ``domain_flag``), beside ``calibration_band`` and
``calibration_domain``.

Only the vibration subscriptions (with the timers and services) wake the
executor, which rebuilds its wait set from every entity on every wake.  The
joint state, load and temperature subscriptions, which bring 151 of the 161
messages per second of a typical actuator, sit in a callback group executors
never wait on.  The vibration callback decodes its blocks and keeps them
pending; when a window may close (a pending block passes the end of the
earliest open window by ``completion_delay``) or ``FLUSH_PERIOD`` s after
the last time, it drains
those queues and adds everything to the window builder at once (a few large
batches instead of thirty small ones a second: the same windows, a third of
the builder's calls).  A steady-clock timer, every ``DRAIN_PERIOD`` s, does
the same for an actuator not flushed for ``FLUSH_PERIOD`` s (its vibration
stopped or lags), so queues stay bounded and silent windows still close.
That drain leans on rclpy internals, all of it in :mod:`.fast_drain`, which
checks them at start-up; without them the node logs one warning and takes the
auxiliary inputs through plain subscription callbacks, and each block at its
arrival, with no pending (same windows, more CPU).

Each actuator has the service ``<ns>/calibrate`` and, beside it, the action
``<ns>/calibrate`` (``prsm_lube_ros/action/Calibrate``: the same request, feedback
with the stage and the recordings and windows read, and a cancel that only
withdraws a calibration still waiting for another to finish: one that runs is
left untouched and delivers its result).  Parameter ``calibrate_service``
names one more service for the first actuator.

Names: relative, resolved in the node's namespace, as ROS packages do.  The
node's default namespace is ``/prsm`` (``DEFAULT_NAMESPACE``), so ``ros2 run``
gives the contract's ``/prsm/vibration`` ... ``/prsm/calibrate``; ``-r
__ns:=/ema_left`` (or ``Node(namespace=...)``, the launch file's
``namespace``) moves them all to ``/ema_left/...``, and the actuator is called
after the namespace (calibration file ``calibration_ema_left.yaml``).  An
``actuators`` entry '' is the node's namespace; others are resolved in it
(absolute ones stay as they are).  ``actuators`` and ``calibrate_service``
report the resolved names (``ros2 param get``).  ``/diagnostics`` stays
absolute, as diagnostic aggregators expect.

Parameters that decide what may be read or written (``recordings_dir``,
``calibration_file``, ``history_dir``, ``actuator_file``), and those that
shape the graph, are read-only after start-up: a change is refused with its
reason, a set to the current value (``ros2 param load`` of the node's own
dump) passes (:class:`~.parameters.ReadOnlyAfterStartUp`).  Fitting runs on a
worker thread: the service and action callbacks are coroutines that await
it, so subscriptions keep flowing with any executor; the new constants
replace the old in one reference swap.  Bad input never stops the node: it is
left out and reported once per kind.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
import math
import os
from pathlib import Path
import sys
import threading
import time
import traceback
from typing import Any, TYPE_CHECKING
from collections.abc import Awaitable, Callable

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
import numpy as np
from rcl_interfaces.msg import ParameterType, SetParametersResult
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.clock import Clock, ClockType
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from sensor_msgs.msg import JointState, Temperature

from . import ros_convert
from ..action import Calibrate as CalibrateAction
from ..contract import DEFAULT_NAMESPACE, LUBRICATION_TASK, status_name, SURFACE_TASK, topic_name
from ..errors import InputError
from ..estimation.assessment import Assessor
from ..estimation.calibration import Calibration
from ..estimation.calibration_file import band_note, baseline_note, load_calibration, save_calibration
from ..estimation.conditioning import band_text
from ..estimation.health import HealthMonitor, HealthThresholds, LEVEL_NAMES, out_of_range, outside_domain, \
    uncalibrated
from ..estimation.surface_health import DEFAULT_DEFECT_WINDOWS, defect_orders_text, SurfaceMonitor, withheld
from ..estimation.windowing import DEFAULT_DEFECT_ORDERS, MIN_AXIAL_LOAD, WindowBuilder, WindowSettings
from ..fleet.forecast_summary import forecast_summaries
from ..msg import LubricationState, VibrationBlock
from ..physics.actuator import load_actuator
from ..physics.defect_orders import defect_orders as actuator_defect_orders
from ..recording.batches import VibrationBatch
from ..srv import Calibrate
from .calibration_request import calibrate_from_request, recording_namespace
from .fast_drain import FastDrain
from .raw_inputs import join_blocks, raw_load_converter, raw_screw_converter, raw_vibration_converter, RAW_INPUTS
from .parameters import declare_parameter_table, DEFAULT_DIAGNOSTIC_PERIOD, diagnostic_period, \
    FORMER_DIAGNOSTIC_PERIOD, OVERRIDABLE, own_qos, ParameterSpec, ReadOnlyAfterStartUp, resolved_names, same_value
from .startup import autostart, run_node
from .topic_status import RateSettings, StampSettings, TopicStatus

if TYPE_CHECKING:
    from collections.abc import Sequence

    from diagnostic_msgs.msg import DiagnosticStatus
    from rclpy.parameter import Parameter
    from rclpy.publisher import Publisher
    from rclpy.service import Service

    from ..estimation.health import HealthStatus
    from ..estimation.surface_health import SurfaceStatus
    from ..estimation.windowing import Window
    from ..recording.batches import InputBatch

    from ..physics.defect_orders import DefectOrder

__all__ = ['ActuatorChannel', 'CalibrationJob', 'CalibrationWithdrawn', 'DRAIN_PERIOD', 'FIXED_REASONS',
           'FLUSH_PERIOD', 'HEALTH_PARAMETERS', 'INPUT_KEYS', 'INPUT_TASK', 'LubricationEstimator', 'MAX_DRAIN',
           'NODE_NAME', 'PARAMETERS', 'STATE_QOS', 'STATUS_PREFIX', 'WINDOW_PARAMETERS', 'actuator_label',
           'calibration_arguments', 'calibration_path', 'configured_hardware_id', 'hardware_ids', 'health_thresholds',
           'join_batches', 'main', 'rising_runs', 'window_settings']

NODE_NAME = 'lubrication_estimator'
STATUS_PREFIX = 'prsm_lube_ros'

_DOUBLE = ParameterType.PARAMETER_DOUBLE
_INTEGER = ParameterType.PARAMETER_INTEGER
_STRING = ParameterType.PARAMETER_STRING
_STRINGS = ParameterType.PARAMETER_STRING_ARRAY
_BOOL = ParameterType.PARAMETER_BOOL

#: Defaults of the window and health parameters: the dataclasses' own.
_WINDOW, _HEALTH = WindowSettings(), HealthThresholds()
#: name: how the parameter is declared (default, type, description, range, read-only)
PARAMETERS = {
    'actuators': ParameterSpec(
        [''], _STRINGS,
        'namespace or topic prefix of each actuator watched; inputs are <ns>/vibration, <ns>/joint_states, '
        "<ns>/axial_load, <ns>/temperature; '' is the node's namespace, relative entries are resolved in it "
        '(reported resolved)', read_only=True),
    'hardware_ids': ParameterSpec(
        [''], _STRINGS,
        'diagnostic hardware_id of each actuator, in the order of actuators: its serial or device id, unique in '
        'the fleet (missing or empty: the actuator name, with one WARN at start-up)', read_only=True),
    'autostart': ParameterSpec(
        True, _BOOL,
        'configure and activate at start-up (the node works at once); false: it waits unconfigured for a '
        'lifecycle manager (ros2 lifecycle set, nav2_lifecycle_manager)', read_only=True),
    'calibrate_enabled': ParameterSpec(
        True, _BOOL,
        'offer the calibrate service and action; false: neither exists on the graph (where swapping the live '
        'calibration must not be reachable)', read_only=True),
    'calibration_file': ParameterSpec(
        '~/.ros/prsm_lube_ros/calibration_{actuator}.yaml', _STRING,
        'calibration YAML (prsm-lube calibrate); {actuator} is replaced by the actuator name with / as _ (e.g. '
        'prsm); empty: none. Loaded at start; the calibrate service writes it when persist is set (read-only: '
        'it decides where the node writes)', read_only=True),
    'history_dir': ParameterSpec(
        '', _STRING,
        "Parquet assessment history of the fleet (prsm-lube assess --history); when set, each actuator's "
        'depletion forecast (prsm-lube trend) is added to its diagnostics', read_only=True),
    'forecast_period': ParameterSpec(
        600.0, _DOUBLE,
        's between re-reads of history_dir for the forecast', bounds=(1.0, 86400.0), read_only=True),
    'recordings_dir': ParameterSpec(
        '~/prsm_recordings', _STRING,
        'folder the calibrate service may read bags from; relative bag paths are taken from it, paths outside '
        'it are refused (read-only: it decides what the node reads)', read_only=True),
    'calibration_timeout': ParameterSpec(
        600.0, _DOUBLE,
        's a calibration may spend reading its recordings before it stops, changing nothing (the service then '
        'answers the next request)', bounds=(1.0, 86400.0), read_only=True),
    'actuator_file': ParameterSpec(
        '', _STRING,
        "actuator geometry YAML (config/actuator.yaml layout) for the screw lead and the defect orders (roller "
        "screw, support bearing); empty: the contract's default actuator", read_only=True),
    'window_length': ParameterSpec(
        _WINDOW.window_length, _DOUBLE,
        'window length in s of header-stamp time for the vibration RMS', bounds=(0.05, 60.0)),
    'min_speed': ParameterSpec(
        _WINDOW.min_speed, _DOUBLE,
        'screw speed in rad/s above which the screw counts as moving', bounds=(0.001, 1000.0)),
    'max_speed_spread': ParameterSpec(
        _WINDOW.max_speed_spread, _DOUBLE,
        'largest relative speed variation inside a steady window', bounds=(0.001, 1.0)),
    'min_coverage': ParameterSpec(
        _WINDOW.min_coverage, _DOUBLE,
        'smallest fraction of a window the vibration samples must cover (less: blocks lost, window not '
        'assessed)', bounds=(0.05, 1.0)),
    'completion_delay': ParameterSpec(
        _WINDOW.completion_delay, _DOUBLE,
        "s of header-stamp time every input must pass a window's end before the window is closed (covers "
        'jitter between topics)', bounds=(0.0, 30.0)),
    'stream_timeout': ParameterSpec(
        _WINDOW.stream_timeout, _DOUBLE,
        's of header-stamp time after which a silent input stops holding windows open (its windows then close '
        'with a reason)', bounds=(0.1, 3600.0)),
    'min_axial_load': ParameterSpec(
        MIN_AXIAL_LOAD, _DOUBLE,
        'smallest axial load in N at which theta_oil is evaluated', bounds=(0.0, 1.0e7)),
    'warn_below': ParameterSpec(_HEALTH.warn_below, _DOUBLE, 'theta_oil below this is WARN', bounds=(0.0, 2.0)),
    'error_below': ParameterSpec(_HEALTH.error_below, _DOUBLE, 'theta_oil below this is ERROR', bounds=(0.0, 2.0)),
    'hysteresis': ParameterSpec(
        _HEALTH.hysteresis, _DOUBLE,
        'a level clears only when theta_oil rises above its threshold plus this', bounds=(0.0, 1.0)),
    'stale_timeout': ParameterSpec(
        _HEALTH.stale_timeout, _DOUBLE,
        's of node clock without vibration after which the status is STALE', bounds=(0.1, 3600.0)),
    'max_unassessed_windows': ParameterSpec(
        _HEALTH.max_unassessed_windows, _INTEGER,
        'consecutive windows without theta_oil while the screw moves after which the status is at least WARN '
        '(0: never)', bounds=(0, 1000000)),
    'level_smoothing': ParameterSpec(
        _HEALTH.level_smoothing, _INTEGER,
        'assessed windows whose mean theta_oil sets the diagnostic level (1: each window alone; the per-window '
        'theta_oil is published unsmoothed)', bounds=(1, 1000)),
    'condition_every': ParameterSpec(
        _WINDOW.condition_every, _INTEGER,
        'compute the condition indicators (kurtosis, crest factor, envelope spectrum) on every k-th window only: '
        'about 1.5 ms of CPU per window of a 4 kHz actuator saved on the others; the surface screen then pools '
        'defect_windows screened windows, k times as long (1: every window)', bounds=(1, 100)),
    'defect_windows': ParameterSpec(
        DEFAULT_DEFECT_WINDOWS, _INTEGER,
        'last steady windows pooled for the surface defect screen (kurtosis, crest factor, envelope lines at the '
        "defect orders) against the calibration's healthy baseline; judged once that many are in, and a suspected "
        'defect clears only after that many clean judgements in a row', bounds=(1, 1000)),
    'diagnostic_period': ParameterSpec(
        DEFAULT_DIAGNOSTIC_PERIOD, _DOUBLE,
        's of node clock between /diagnostics messages (also the period the input rates are counted in)',
        bounds=(0.05, 60.0), read_only=True),
    'diagnostics_period': FORMER_DIAGNOSTIC_PERIOD,
    'vibration_rate': ParameterSpec(
        10.0, _DOUBLE,
        'expected VibrationBlocks per s on <ns>/vibration (input status: WARN below it by more than '
        'rate_tolerance; 0: only silence is judged)', bounds=(0.0, 1.0e6), read_only=True),
    'joint_states_rate': ParameterSpec(
        100.0, _DOUBLE, 'expected JointStates per s on <ns>/joint_states (as vibration_rate)', bounds=(0.0, 1.0e6),
        read_only=True),
    'axial_load_rate': ParameterSpec(
        50.0, _DOUBLE, 'expected WrenchStampeds per s on <ns>/axial_load (as vibration_rate)', bounds=(0.0, 1.0e6),
        read_only=True),
    'temperature_rate': ParameterSpec(
        0.0, _DOUBLE, 'expected Temperatures per s on <ns>/temperature (as vibration_rate; 0: optional input, '
        'only its silence is reported)', bounds=(0.0, 1.0e6), read_only=True),
    'rate_tolerance': ParameterSpec(
        0.1, _DOUBLE, 'relative shortfall of an input rate that is still OK (diagnostic_updater tolerance)',
        bounds=(0.0, 1.0), read_only=True),
    'rate_window': ParameterSpec(
        5, _INTEGER, 'diagnostic periods an input rate is measured over (diagnostic_updater window_size)',
        bounds=(1, 1000), read_only=True),
    'max_stamp_age': ParameterSpec(
        5.0, _DOUBLE, 's a header stamp may trail the node clock at arrival before the input status is ERROR',
        bounds=(0.001, 86400.0), read_only=True),
    'max_future_stamp': ParameterSpec(
        1.0, _DOUBLE, 's a header stamp may lie ahead of the node clock before the input status is ERROR',
        bounds=(0.0, 86400.0), read_only=True),
    'vibration_topic': ParameterSpec(
        'vibration', _STRING,
        'vibration topic below each actuator namespace', read_only=True),
    'joint_states_topic': ParameterSpec(
        'joint_states', _STRING,
        'joint states topic below each actuator namespace', read_only=True),
    'axial_load_topic': ParameterSpec(
        'axial_load', _STRING,
        'axial load topic below each actuator namespace', read_only=True),
    'temperature_topic': ParameterSpec(
        'temperature', _STRING,
        'temperature topic below each actuator namespace (optional input)', read_only=True),
    'state_topic': ParameterSpec(
        'lubrication_state', _STRING,
        'output topic below each actuator namespace', read_only=True),
    'diagnostics_topic': ParameterSpec('/diagnostics', _STRING, 'diagnostics topic', read_only=True),
    'calibrate_service': ParameterSpec(
        'calibrate', _STRING,
        'calibration service of the first actuator (each actuator also has <ns>/calibrate); reported resolved',
        read_only=True),
    'screw_joint': ParameterSpec('screw', _STRING, 'name of the screw entry in JointState', read_only=True),
    'qos_depth': ParameterSpec(
        500, _INTEGER,
        'queue depth of the input subscriptions (best effort, sensor data); joint states, load and temperature '
        'are taken when a window may close and at least every 0.35 s (FLUSH_PERIOD + DRAIN_PERIOD), so it must '
        'hold what a topic brings meanwhile', bounds=(1, 100000), read_only=True),
}

#: LubricationState: reliable, and transient local so that a dashboard or logger started late gets the last
#: states at once (volatile subscribers, e.g. ``ros2 topic echo``, match it as before).
STATE_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)

#: Most messages one input callback takes from its queue (the rest wait for the next wait cycle).
MAX_DRAIN = 5000
#: Period in s of the drain timer, which takes the pending blocks and auxiliary queues of an actuator not
#: flushed for FLUSH_PERIOD (its vibration stopped, or its blocks come further apart).
DRAIN_PERIOD = 0.1
#: Longest time in s vibration blocks stay pending (and the auxiliary queues undrained) while no window can
#: close: the next block or the drain timer flushes them, so a queue holds at most FLUSH_PERIOD + DRAIN_PERIOD
#: of messages (0.35 s: 350 of a 1 kHz topic; qos_depth is 500).
FLUSH_PERIOD = 0.25

WINDOW_PARAMETERS = ('window_length', 'min_speed', 'max_speed_spread', 'min_coverage', 'completion_delay',
                     'stream_timeout', 'condition_every')
HEALTH_PARAMETERS = ('warn_below', 'error_below', 'hysteresis', 'stale_timeout', 'max_unassessed_windows',
                     'level_smoothing')
#: Why the parameters that decide what the node reads or writes are fixed after start-up (refusal reasons).
FIXED_REASONS = {
    'recordings_dir': 'it confines what the calibrate service may read',
    'calibration_timeout': 'it bounds what one calibrate request may cost',
    'calibration_file': 'it decides where calibrate writes when persist is set',
    'history_dir': 'it decides what the node reads',
    'actuator_file': 'it decides what the node reads',
}


#: The input streams of an actuator, as the ``<key>_topic`` and ``<key>_rate`` parameters name them.
INPUT_KEYS = ('vibration', 'joint_states', 'axial_load', 'temperature')
#: What an input status is called: '<node>: <actuator> <key> input'.
INPUT_TASK = '{key} input'


def hardware_ids(actuators: Sequence[str], configured: Sequence[str]) -> dict:
    """actuator: its hardware_id, the ``hardware_ids`` entry at its index or (missing or empty) its name."""
    return {name: configured_hardware_id(actuators, configured, name) or name.strip('/') or name
            for name in actuators}


def configured_hardware_id(actuators: Sequence[str], configured: Sequence[str], name: str) -> str:
    """The ``hardware_ids`` entry of actuator ``name`` ('' when none is given)."""
    i = list(actuators).index(name)
    return str(configured[i]).strip() if i < len(configured) else ''


def actuator_label(actuator: str) -> str:
    """Actuator name for files and ids: ``/ema_left/prsm`` -> ``ema_left_prsm``."""
    return actuator.strip('/').replace('/', '_') or 'root'


def calibration_path(template: str, actuator: str) -> str:
    """The calibration file of one actuator ('' when none is configured)."""
    if not template.strip():
        return ''
    return os.path.expanduser(template.replace('{actuator}', actuator_label(actuator)))


def window_settings(values: dict, defect_orders: Sequence[DefectOrder] = DEFAULT_DEFECT_ORDERS) -> WindowSettings:
    """WindowSettings from parameter values and the actuator's defect orders (InputError when out of range)."""
    return WindowSettings(**{name: values[name] for name in WINDOW_PARAMETERS}, defect_orders=tuple(defect_orders))


def health_thresholds(values: dict) -> HealthThresholds:
    """HealthThresholds from parameter values (InputError when inconsistent)."""
    return HealthThresholds(**{name: values[name] for name in HEALTH_PARAMETERS})


@dataclass
class ActuatorChannel:
    """Everything the node keeps for one actuator."""

    name: str
    hardware_id: str
    prefix: str                  # what goes before the topic leaves ('' for relative names: see contract)
    builder: WindowBuilder
    monitor: HealthMonitor
    calibration_file: str
    surface: SurfaceMonitor                          # the surface defect screen of the last steady windows
    assessor: Assessor | None = None
    calibration_note: str = 'no calibration loaded'
    publisher: Any = None                            # rclpy Publisher of LubricationState, once configured
    last_window: Window | None = None
    last_theta: float = math.nan
    last_theta_std: float = math.nan
    last_flag: str = ''                              # theta_range_flag of the last assessed theta
    last_domain_flag: str = ''                       # domain_flag of the last assessed window ('' inside)
    last_level: int | None = None
    windows: int = 0
    input_errors: dict = field(default_factory=dict)
    auxiliary: list = field(default_factory=list)    # (key, subscription, convert) drained by the node
    pending: list = field(default_factory=list)      # VibrationBatch decoded, not yet in the builder
    last_block: float = -math.inf                    # stamp of the last block taken (pending or in the builder)
    last_flush: float = -math.inf                    # time.monotonic() of the last flush into the builder
    node_name: str = STATUS_PREFIX
    frame_id: str = ''                               # header.frame_id of the last vibration block
    forecast: list = field(default_factory=list)     # (key, value) of the depletion forecast from history_dir
    withheld_theta: float = math.nan                 # theta_Oil of the last window withheld for a surface defect
    withholding: bool = False                        # the last assessed window's theta was withheld
    last_surface_level: int | None = None
    unscreened: list = field(default_factory=list)   # windows published, their indicators not yet screened
    inputs: dict = field(default_factory=dict)       # input key: TopicStatus (rate and stamps), while active
    subscriptions: dict = field(default_factory=dict)  # input key: its subscription, while active

    @property
    def status_name(self) -> str:
        """diagnostic_updater style status name: '<node name>: <actuator> lubrication'."""
        return status_name(self.node_name, self.name, LUBRICATION_TASK)

    @property
    def surface_status_name(self) -> str:
        """Name of the surface condition status: '<node name>: <actuator> surface condition'."""
        return status_name(self.node_name, self.name, SURFACE_TASK)

    def problem_count(self) -> int:
        """Bad messages and samples left out so far."""
        return sum(self.builder.problem_summary().values()) + sum(self.input_errors.values())


class CalibrationWithdrawn(Exception):
    """A calibration action cancelled before it changed anything (waiting, or while reading the recordings)."""


class CalibrationJob:
    """Whether one calibration action has started and whether it was withdrawn (cancelled).

    A cancel is always taken: a waiting calibration never starts, a running
    one stops at its next check while it reads the recordings (nothing is
    written or swapped); one already fitting finishes.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self.started = False
        self.withdrawn = False

    def withdraw(self) -> bool:
        """Cancel: mark it withdrawn; True."""
        with self._lock:
            self.withdrawn = True
            return True

    def start(self) -> bool:
        """Mark it started; False when it was withdrawn first."""
        with self._lock:
            self.started = not self.withdrawn
            return self.started


class LubricationEstimator(ReadOnlyAfterStartUp, LifecycleNode):
    """The estimator node, a lifecycle node; see the module docstring.  ``kwargs`` go to :class:`rclpy.node.Node`.

    Constructed with its parameters declared and checked; configure makes the
    channels (calibrations loaded) and the publishers, activate the
    subscriptions, calibrate services and actions and the timers; deactivate
    takes those away again, cleanup the rest.  With ``autostart`` (the
    default) the constructor configures and activates it: the node works at once.
    """

    fixed_reasons = FIXED_REASONS

    def __init__(self, node_name: str = NODE_NAME, namespace: str = DEFAULT_NAMESPACE, **kwargs: Any) -> None:
        super().__init__(node_name, namespace=namespace, **kwargs)
        self._lock = threading.RLock()
        self._fit_lock = threading.Lock()
        self._jobs: dict = {}
        declare_parameter_table(self, PARAMETERS, resolve={
            'actuators': lambda entries: [self._resolve_namespace(e) for e in entries],
            'calibrate_service': resolved_names(self)})
        values = self._values()
        actuator = load_actuator(values['actuator_file'] or None)
        self._lead = actuator.lead
        self._defect_orders = actuator_defect_orders(actuator)
        self._defect_windows = int(values['defect_windows'])
        self._settings = window_settings(values, self._defect_orders)
        self._thresholds = health_thresholds(values)
        self._min_axial_load = float(values['min_axial_load'])
        self._recordings_dir = str(values['recordings_dir'])
        self._calibration_timeout = float(values['calibration_timeout'])
        actuators = [a.strip() for a in values['actuators'] if a.strip()]
        if not actuators:
            raise InputError('parameter actuators: empty; name at least one namespace, e.g. [/prsm]')
        if len(set(actuators)) != len(actuators):
            raise InputError(f'parameter actuators: {actuators} names an actuator twice')
        self._actuator_names = actuators
        self._hardware_ids = self._checked_hardware_ids(actuators, list(values['hardware_ids']))
        self._diagnostic_period = diagnostic_period(values)
        self._rates = {key: RateSettings(expected=float(values[f'{key}_rate']),
                                         tolerance=float(values['rate_tolerance']),
                                         window=int(values['rate_window'])) for key in INPUT_KEYS}
        self._check_qos_depth(int(values['qos_depth']))
        self._stamp_settings = StampSettings(max_age=float(values['max_stamp_age']),
                                             max_future=float(values['max_future_stamp']))
        self._input_group = MutuallyExclusiveCallbackGroup()
        self._service_group = ReentrantCallbackGroup()
        self._fast = FastDrain(self.log)
        self._arrival = 0.0                   # node-clock time of the input callback running (stamp ages)
        self.channels: list[ActuatorChannel] = []
        # Not self._services: that is rclpy's own list (it holds the parameter services).
        self._calibrate_services: list[Service] = []
        self._calibrate_actions: list[ActionServer] = []
        self._input_subscriptions: list = []
        self._timers_started: list = []
        self._screen_timer: Any = None     # one-shot timer of the surface screens waiting (while active)
        self._diagnostics: Publisher | None = None
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._stop_forecast = threading.Event()
        self._forecast_wake = threading.Event()     # set on configure: the new channels' forecasts at once
        self._history_dir = str(values['history_dir']).strip()
        if self._history_dir:
            threading.Thread(target=self._forecast_loop, args=(float(values['forecast_period']),),
                             name='forecast', daemon=True).start()
        if values['autostart']:
            autostart(self)
        else:
            self.log.info('autostart is false: unconfigured, waiting for a lifecycle manager '
                          '(ros2 lifecycle set ... configure, then activate)')

    def _check_qos_depth(self, depth: int) -> None:
        """One WARN per queued input whose expected rate brings more than ``depth`` messages while its queue waits."""
        wait = FLUSH_PERIOD + DRAIN_PERIOD
        for key in ('joint_states', 'axial_load', 'temperature'):
            rate = self._rates[key].expected
            needed = math.ceil(rate * wait - 1e-9)
            if needed > depth:
                self.log.warning(
                    f'qos_depth {depth} is less than the {needed} {key} messages that {rate:g} per s ({key}_rate) '
                    f'bring in the {wait:g} s its queue may wait for a flush (FLUSH_PERIOD + DRAIN_PERIOD): the '
                    f'oldest will be lost; set qos_depth to at least {needed}')

    def _checked_hardware_ids(self, actuators: list[str], configured: list[str]) -> dict:
        """:func:`hardware_ids`, with one WARN naming the actuators left at their default."""
        defaulted = [name for name in actuators if not configured_hardware_id(actuators, configured, name)]
        if defaulted:
            self.log.warning(
                f'hardware_ids not set for {", ".join(defaulted)}: /diagnostics names them by actuator name, which '
                "collides across a fleet; set hardware_ids to each actuator's serial or device id")
        return hardware_ids(actuators, configured)

    # -- lifecycle ---------------------------------------------------------------------------------
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """The actuators' channels (calibrations loaded) and the publishers: state and /diagnostics."""
        try:
            with self._lock:
                self._open()
        except InputError as exc:
            self.log.error(f'configure failed: {exc}')
            self._close()
            return TransitionCallbackReturn.FAILURE
        self.log.info(f'configure: {state.label} -> inactive')
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Subscriptions, calibrate services and actions, diagnostics and drain timers."""
        with self._lock:
            self._start()
        self.log.info(
            f'activate: {state.label} -> active; watching {", ".join(c.name for c in self.channels)}; window '
            f'{self._settings.window_length:g} s; WARN below {self._thresholds.warn_below:g}, ERROR below '
            f'{self._thresholds.error_below:g}')
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """No more input, calibration or diagnostics; channels and publishers stay."""
        with self._lock:
            self._halt()
        self.log.info(f'deactivate: {state.label} -> inactive')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Channels and publishers go."""
        with self._lock:
            self._close()
        self.log.info(f'cleanup: {state.label} -> unconfigured')
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Everything goes, from any state."""
        with self._lock:
            self._halt()
            self._close()
        return TransitionCallbackReturn.SUCCESS

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """A transition raised: everything goes, back to unconfigured."""
        return self.on_shutdown(state)

    # -- set-up ------------------------------------------------------------------------------------
    def _open(self) -> None:
        """configure: one channel and state publisher per actuator, and the /diagnostics publisher."""
        values = self._values()
        for name in self._actuator_names:
            self.channels.append(self._open_actuator(name, self._hardware_ids[name], values))
        self._forecast_wake.set()
        self._diagnostics = self.create_publisher(DiagnosticArray, values['diagnostics_topic'], QoSProfile(depth=10),
                                                  qos_overriding_options=OVERRIDABLE)

    def _start(self) -> None:
        """activate: inputs, calibration interfaces, timers; the input statuses start counting now."""
        values = self._values()
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(values['qos_depth']),
                         reliability=ReliabilityPolicy.BEST_EFFORT)
        now = self.now()
        for i, channel in enumerate(self.channels):
            self._subscribe(channel, values, qos, now)
            if values['calibrate_enabled']:
                self._serve_calibration(channel, values, first=i == 0)
        self._timers_started.append(self.create_timer(self._diagnostic_period, self._publish_diagnostics,
                                                      callback_group=self._input_group))
        # Steady clock: the auxiliary queues must be drained even when a simulated clock stands still.
        self._drain_period = min(DRAIN_PERIOD, self._diagnostic_period)
        self._timers_started.append(self.create_timer(self._drain_period, self._drain_idle,
                                                      callback_group=self._input_group,
                                                      clock=Clock(clock_type=ClockType.STEADY_TIME)))
        # Reset when windows wait for their screen, ready at the executor's next wait: the windows every actuator
        # closed at this one are all published before any of their envelope analyses runs (module doc).  A timer,
        # not a guard condition: rclpy's EventsExecutor refuses nodes with guard conditions.
        self._screen_timer = self.create_timer(0.0, self._screen_waiting, callback_group=self._input_group,
                                               clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._screen_timer.cancel()
        self._timers_started.append(self._screen_timer)

    def _halt(self) -> None:
        """deactivate: subscriptions, calibration interfaces and timers go (a running calibration finishes)."""
        for channel in self.channels:       # what arrived goes into the windows first
            self._flush_before_change(channel)
        for timer in self._timers_started:
            self.destroy_timer(timer)
        self._screen_timer = None
        for subscription in self._input_subscriptions:
            self.destroy_subscription(subscription)
        for service in self._calibrate_services:
            self.destroy_service(service)
        for action in self._calibrate_actions:
            action.destroy()
        self._timers_started, self._input_subscriptions = [], []
        self._calibrate_services, self._calibrate_actions = [], []
        for channel in self.channels:
            channel.auxiliary = []
            channel.inputs = {}

    def _close(self) -> None:
        """cleanup: the channels and publishers go."""
        for channel in self.channels:
            if channel.publisher is not None:
                self.destroy_publisher(channel.publisher)
        if self._diagnostics is not None:
            self.destroy_publisher(self._diagnostics)
        self.channels, self._diagnostics = [], None

    def _open_actuator(self, name: str, hardware_id: str, values: dict) -> ActuatorChannel:
        """One actuator's channel: calibration loaded, state publisher."""
        prefix = '' if name == self.get_namespace() else name      # the node's own: relative names
        channel = ActuatorChannel(name=name, hardware_id=hardware_id, prefix=prefix,
                                  builder=self._new_builder(self._settings),
                                  monitor=HealthMonitor(self._thresholds),
                                  calibration_file=calibration_path(values['calibration_file'], name),
                                  surface=SurfaceMonitor(self._defect_orders, self._defect_windows),
                                  node_name=self.get_name())
        self._load_initial_calibration(channel)
        channel.publisher = self.create_publisher(
            LubricationState, topic_name(prefix, values['state_topic']), own_qos(STATE_QOS),
            qos_overriding_options=OVERRIDABLE)
        return channel

    def _serve_calibration(self, channel: ActuatorChannel, values: dict, *, first: bool) -> None:
        """The actuator's calibrate service and action; the first actuator also on ``calibrate_service``."""
        service_names = [topic_name(channel.prefix, 'calibrate')]
        extra = values['calibrate_service']
        if first and extra and extra != self.resolve_service_name(service_names[0]):
            service_names.insert(0, extra)
        for service_name in service_names:
            self._calibrate_services.append(self.create_service(
                Calibrate, service_name, self._calibrate_handler(channel),
                callback_group=self._service_group))
            self._calibrate_actions.append(ActionServer(
                self, CalibrateAction, service_name, execute_callback=self._calibrate_action(channel),
                cancel_callback=self._cancel_calibration, callback_group=self._service_group))

    def _values(self) -> dict:
        return {name: self.get_parameter(name).value for name in PARAMETERS}

    def _resolve_namespace(self, entry: str) -> str:
        """An ``actuators`` entry resolved in the node's namespace: '' is the namespace itself.

        A trailing ``_`` (topic prefix) is kept; a trailing ``/`` dropped.
        """
        entry = str(entry).strip()
        if not entry:
            return self.get_namespace()
        suffix = '_' if entry.endswith('_') else ''
        core = entry[:-1] if suffix else entry.rstrip('/') or '/'
        try:
            return self.resolve_topic_name(core) + suffix
        except Exception as exc:       # rclpy's InvalidTopicNameException and kin
            raise InputError(f'parameter actuators: {entry!r} is not a ROS namespace or topic prefix ({exc})') \
                from None

    def _subscribe(self, channel: ActuatorChannel, values: dict, qos: QoSProfile, now: float) -> None:
        """Subscribe the actuator's inputs: vibration through the executor, the others drained (module doc).

        Each subscription gets its own copy of ``qos`` (the QoS override parameters change the copy), and each
        input its :class:`~.topic_status.TopicStatus`, counting from ``now``.
        """
        joint = values['screw_joint']
        topics = {key: topic_name(channel.prefix, values[f'{key}_topic']) for key in INPUT_KEYS}
        channel.inputs = {key: TopicStatus(self.resolve_topic_name(topic), self._rates[key], self._stamp_settings,
                                           now) for key, topic in topics.items()}
        converters = {
            # Raw CDR bytes, decoded straight into numpy (raw_inputs.py): no Python message is built.
            'vibration': (VibrationBlock, raw_vibration_converter(topics['vibration'],
                                                                  lambda frame: self._note_frame(channel, frame))),
            'joint_states': (JointState, raw_screw_converter(topics['joint_states'], joint)),
            'axial_load': (WrenchStamped, raw_load_converter(topics['axial_load'])),
            'temperature': (Temperature, lambda m: ros_convert.temperature_batch(m, topics['temperature'])),
        }
        msg_type, convert = converters.pop('vibration')
        holder = channel.subscriptions
        holder['vibration'] = self.create_subscription(
            msg_type, topics['vibration'], self._vibration_callback(channel, convert, holder), own_qos(qos),
            callback_group=self._input_group, qos_overriding_options=OVERRIDABLE, raw=True)
        for key, (msg_type, convert) in converters.items():
            raw = key in RAW_INPUTS
            if not self._fast.enabled:          # fallback (fast_drain.py): one callback per message
                holder[key] = self.create_subscription(
                    msg_type, topics[key], self._auxiliary_callback(channel, key, convert), own_qos(qos),
                    callback_group=self._input_group, qos_overriding_options=OVERRIDABLE, raw=raw)
                continue
            # No event handlers: rmw_fastrtps wakes a wait set holding a subscription's events on every
            # message of that subscription, which would undo the point (measured: one core full at 4 actuators).
            holder[key] = self.create_subscription(
                msg_type, topics[key], self._fast.never_called, own_qos(qos), callback_group=self._fast.group,
                event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False),
                qos_overriding_options=OVERRIDABLE, raw=raw)
            channel.auxiliary.append((key, holder[key], convert))
        self._input_subscriptions.extend(holder.values())

    def _load_initial_calibration(self, channel: ActuatorChannel) -> None:
        path = channel.calibration_file
        if not path:
            channel.calibration_note = 'no calibration: parameter calibration_file is empty; call the ' \
                                       'calibrate service'
        elif not Path(path).exists():
            channel.calibration_note = f'no calibration yet: {path} does not exist; call the calibrate service'
        else:
            try:
                self._swap_calibration(channel, load_calibration(path))
            except InputError as exc:
                channel.calibration_note = f'no calibration: {exc}'
        if channel.assessor is None:
            self.log.warning(f'{channel.name}: {channel.calibration_note}')
        else:
            self.log.info(f'{channel.name}: calibration {path} loaded')

    def _swap_calibration(self, channel: ActuatorChannel, calibration: Calibration) -> None:
        self._flush_before_change(channel)
        band_changed = channel.assessor is None or channel.assessor.calibration.band != calibration.band
        channel.assessor = Assessor(calibration, min_axial_load=self._min_axial_load,
                                    defect_orders=self._defect_orders)
        channel.calibration_note = ''
        channel.last_domain_flag = ''
        rebuilt = band_changed and channel.builder.band != self._channel_settings(channel).band
        if rebuilt:
            # Windows in the calibration's band (conditioning): open windows in another band are dropped.
            channel.builder = self._new_builder(self._channel_settings(channel))
            self.log.info(f'{channel.name}: windows now in the calibration\'s {band_note(calibration)}')
        channel.monitor.restart_smoothing()      # thetas of the old constants must not be averaged with the new
        # The new baseline judges afresh; the pooled indicators go with the band they were computed in.
        channel.surface.set_baseline(calibration.condition_baseline, keep_windows=not rebuilt)

    # -- inputs ------------------------------------------------------------------------------------
    def _new_builder(self, settings: WindowSettings) -> WindowBuilder:
        """An actuator's window builder: its indicators deferred until theta_Oil is out (module doc)."""
        return WindowBuilder(settings, lead=self._lead, defer_conditions=True)

    def _channel_settings(self, channel: ActuatorChannel) -> WindowSettings:
        """The window settings with the band of the actuator's calibration (the default band without one)."""
        if channel.assessor is None:
            return self._settings
        return replace(self._settings, band=channel.assessor.calibration.band)

    def now(self) -> float:
        """Node-clock time in s (sim time when use_sim_time is set)."""
        return self.get_clock().now().nanoseconds * 1e-9

    def _vibration_callback(self, channel: ActuatorChannel, convert: Callable,
                            subscriptions: dict) -> Callable[[Any], None]:
        """Callback of one actuator's vibration topic: everything queued for the actuator, then closing.

        The auxiliary queues are drained with the block, and the vibration queue
        behind it too (an executor serves each ready subscription only once per
        wait, so a lagging node would otherwise fall ever further behind).  All
        of it is one time slice: the builder closes windows once, after the
        slice, so no stream is judged silent halfway through it.
        """
        def callback(data: Any) -> None:
            with self._lock:
                self._arrival = self.now()
                channel.monitor.note_input(self._arrival)
                going_back = False      # a clock reset closes the windows at once, as at each block's arrival
                for msg in (data, *self._fast.drain(subscriptions.get('vibration'), MAX_DRAIN)):
                    batch = self._convert(channel, 'vibration', convert, msg)
                    if batch is not None:
                        going_back |= not batch.stamps[0] > channel.last_block
                        channel.last_block = float(batch.stamps[0])
                        channel.pending.append(batch)
                if going_back or self._flush_due(channel):
                    self._flush(channel)
        return callback

    def _flush_due(self, channel: ActuatorChannel) -> bool:
        """Whether the pending blocks may close a window, or have waited ``FLUSH_PERIOD`` s (module doc).

        A window may close once a block passes its end by ``completion_delay``:
        the builder's earliest open window, so a window the other inputs still
        hold open is tried again at every block, as when each block went in alone.
        """
        if not channel.pending:
            return False
        if not self._fast.enabled:      # joint states and loads go in at their arrival: blocks too (a reset)
            return True
        if time.monotonic() - channel.last_flush >= FLUSH_PERIOD:
            return True
        last = channel.pending[-1]
        rate = float(last.sample_rates[-1])
        end = float(last.stamps[-1]) + (float(last.offsets[-1] - last.offsets[-2]) / rate if rate > 0 else 0.0)
        builder = channel.builder
        # not (a < b) rather than a >= b: a block whose end is not finite is flushed at once (the builder says why)
        return not end - builder.settings.completion_delay < builder.earliest_open_end()

    def _flush(self, channel: ActuatorChannel) -> None:
        """The pending blocks and the queued auxiliary inputs into the builder, in rounds; close.

        Each stream is cut where its stamps go back (:meth:`_queued_runs`), and
        the pieces go in round by round: every stream's first piece, then every
        second one...  So a clock reset restarts the builder's time only once
        what every stream brought before it is in, as when each block went in at
        its arrival with the queues drained beside it; otherwise the last
        windows before a reset would be closed short and opened again.
        """
        streams = []
        if channel.pending:
            pending, channel.pending = channel.pending, []
            streams.append(('vibration', rising_runs(pending)))
        for key, subscription, convert in channel.auxiliary:
            messages = list(self._fast.drain(subscription, MAX_DRAIN))
            if messages:
                streams.append((key, self._queued_runs(channel, key, convert, messages)))
        for index in range(max((len(runs) for _, runs in streams), default=0)):
            for key, runs in streams:
                if index < len(runs):
                    self._add(channel, key, runs[index])
        channel.last_flush = time.monotonic()
        self._close_windows(channel)

    def _flush_before_change(self, channel: ActuatorChannel) -> None:
        """Flush pending blocks before the builder or calibration they arrived under is replaced.

        As when each block went in at its arrival: they belong to the old
        builder's windows (dropped with it), not to a half window the new
        builder would publish as blocks lost.
        """
        if channel.pending:
            self._flush(channel)
        self._screen_now(channel)      # their indicators too, in the band and under the baseline they met

    @staticmethod
    def _note_frame(channel: ActuatorChannel, frame_id: str) -> None:
        """Keep the sensor frame of the actuator's last vibration block (its outputs' frame)."""
        channel.frame_id = frame_id or channel.frame_id

    def _auxiliary_callback(self, channel: ActuatorChannel, key: str, convert: Callable) -> Callable[[Any], None]:
        """Plain callback of one auxiliary input, used only when the fast drain is off."""
        def callback(msg: Any) -> None:
            with self._lock:
                self._arrival = self.now()
                self._take(channel, key, convert, msg)
        return callback

    def _drain_idle(self) -> None:
        """Drain timer: pending blocks and auxiliary inputs not flushed for ``FLUSH_PERIOD`` s (module doc).

        Whatever the vibration did: waiting besides for FLUSH_PERIOD after the
        last block (a stopped vibration) let a queue fill for up to 0.55 s, not
        the 0.35 s ``qos_depth`` is sized for.
        """
        with self._lock:
            self._arrival = self.now()
            limit = time.monotonic() - FLUSH_PERIOD
            for channel in self.channels:
                if channel.last_flush <= limit:
                    self._flush(channel)

    def _take(self, channel: ActuatorChannel, key: str, convert: Callable, msg: Any) -> None:
        """Add one message to the actuator's builder (closing is left to :meth:`_close_windows`)."""
        batch = self._convert(channel, key, convert, msg)
        if batch is not None:
            self._add(channel, key, batch)

    def _queued_runs(self, channel: ActuatorChannel, key: str, convert: Callable, messages: list) -> list[InputBatch]:
        """Messages drained from one auxiliary queue, as batches joined while their stamps rise (:func:`rising_runs`).

        A message that cannot be read is left out and counted on its own.  A
        stamp going back starts a new batch, so back-steps and clock resets reach
        the builder where they happened, as with one message at a time.  A
        converter with ``many`` (raw inputs of a learnt layout, :mod:`.raw_inputs`)
        reads the whole queue at once when every message fits it.
        """
        many = getattr(convert, 'many', None)
        if many is not None and len(messages) > 1:
            batch = self._convert(channel, key, many, messages)
            if batch is not None:
                return [batch]
        converted = (self._convert(channel, key, convert, msg) for msg in messages)
        return rising_runs([batch for batch in converted if batch is not None])

    def _convert(self, channel: ActuatorChannel, key: str, convert: Callable, msg: Any) -> InputBatch | None:
        """The message as a one-entry batch, or None (counted, logged once per kind) when it cannot be read."""
        try:
            return convert(msg)
        except (InputError, ValueError, TypeError, IndexError) as exc:
            self._input_problem(channel, key, exc)
        except Exception as exc:     # a bug, not bad input: say so once, with the traceback, and go on
            self._internal_error(channel, key, exc)
        return None

    def _add(self, channel: ActuatorChannel, key: str, batch: InputBatch) -> None:
        """Count one batch in the input's status, add it to the actuator's builder; a refused one is left out."""
        status = channel.inputs.get(key)
        if status is not None:
            stamps = batch.stamps
            status.tick(len(stamps), float(stamps[0]), float(stamps[-1]), self._arrival)
        try:
            channel.builder.add(batch)
        except (InputError, ValueError, TypeError, IndexError) as exc:
            self._input_problem(channel, key, exc)
        except Exception as exc:     # a bug, not bad input: say so once, with the traceback, and go on
            self._internal_error(channel, key, exc)

    def _close_windows(self, channel: ActuatorChannel) -> None:
        """Close the windows every live input has passed, assess and publish them; log new input problems."""
        try:
            windows = channel.builder.pop_closed()
        except (InputError, ValueError, TypeError, IndexError) as exc:
            self._input_problem(channel, 'windows', exc)
            windows = []
        except Exception as exc:     # a bug, not bad input: say so once, with the traceback, and go on
            self._internal_error(channel, 'windows', exc)
            windows = []
        for line in channel.builder.take_problems():
            self.log.warning(f'{channel.name}: {line}')
        self._screen_now(channel)     # windows of an earlier close first: the screen takes them in order
        for window in windows:
            self._evaluate(channel, window)      # theta_Oil out first; the surface screen after (module doc)
        if windows:
            channel.unscreened.extend(windows)
            if self._screen_timer is not None:
                self._screen_timer.reset()       # after the other callbacks ready now (module doc)
            else:
                self._screen_now(channel)

    def _screen_now(self, channel: ActuatorChannel) -> None:
        """:meth:`_screen_closed` of one actuator, and ``/diagnostics`` at once where a level changed."""
        if self._screen_closed(channel):
            self._publish_diagnostics(inputs=False)

    def _screen_waiting(self) -> None:
        """One-shot timer: the surface screens of the windows published since, every actuator's; then /diagnostics."""
        with self._lock:
            if self._screen_timer is not None:
                self._screen_timer.cancel()
            changed = [self._screen_closed(channel) for channel in self.channels]
            if any(changed):
                self._publish_diagnostics(inputs=False)     # every actuator screened first: none judged half-way

    def _screen_closed(self, channel: ActuatorChannel) -> bool:
        """The windows published and not yet screened into the surface screen, their condition indicators now.

        Returns whether the actuator's lubrication or surface level changed
        (the caller publishes ``/diagnostics`` then; the input rates are
        counted on the timer's beat only).
        """
        windows, channel.unscreened = channel.unscreened, []
        if not windows:
            return False
        completed: dict[int, Window] = {}     # by the closed window's identity (two may share a start: a reset)
        try:
            completed = {id(closed): window for closed, window in channel.builder.complete_conditions(windows)}
        except Exception as exc:     # a bug, not bad input: say so once, with the traceback, and go on
            self._internal_error(channel, 'condition indicators', exc)
        for window in windows:
            self._screen(channel, completed.get(id(window), window))
        now = self.now()
        return (self._health(channel, now).level != channel.last_level
                or self._surface(channel, now).level != channel.last_surface_level)

    def _internal_error(self, channel: ActuatorChannel, key: str, exc: Exception) -> None:
        """Count an unexpected exception; log the first with its traceback."""
        if channel.input_errors.get('internal', 0) == 0:
            self.log.error(f'{channel.name}: internal error on {key} (please report): '
                           f'{"".join(traceback.format_exception(exc)).strip()}')
        channel.input_errors['internal'] = channel.input_errors.get('internal', 0) + 1

    def _input_problem(self, channel: ActuatorChannel, key: str, exc: Exception) -> None:
        """Count a message that could not be taken; log the first of each kind."""
        kind = f'{key}:{type(exc).__name__}'
        seen = channel.input_errors.get(kind, 0)
        channel.input_errors[kind] = seen + 1
        if seen == 0:
            text = str(exc) if isinstance(exc, InputError) else f'{key}: message left out ({exc})'
            self.log.warning(f'{channel.name}: {text} (further ones counted, not logged)')

    def _screen(self, channel: ActuatorChannel, window: Window) -> None:
        """Add a steady window's condition indicators to the actuator's surface screen (never raises)."""
        if not window.steady or (window.condition is None and channel.builder.band is not None):
            return   # not steady, or no indicators on this window by design (condition_every)
        try:
            channel.surface.observe(window.condition, window.end)
        except Exception as exc:     # a bug, not bad input: say so once, with the traceback, and go on
            self._internal_error(channel, 'surface screen', exc)

    def _evaluate(self, channel: ActuatorChannel, window: Window) -> None:
        assessor = channel.assessor      # one read: a calibration swapped meanwhile applies to the next window
        flag = ''
        if assessor is None:
            theta, std, reason = math.nan, math.nan, channel.calibration_note
        else:
            assessed = assessor.assess_window(window)
            theta, std, reason, flag = assessed.theta_oil, assessed.theta_oil_std, assessed.reason, assessed.flag
            if math.isfinite(theta):
                channel.last_domain_flag = assessed.domain_flag
        speed = window.screw_speed
        moving = not (math.isfinite(speed) and speed < self._settings.min_speed)
        kind = window.reason_kind or ('low_load' if assessor is not None and not math.isfinite(theta)
                                      and not window.axial_load >= self._min_axial_load else '')
        if math.isfinite(theta) and channel.surface.suspected:
            # A surface defect raises the RMS as oil loss does: no lubrication measure, and not averaged
            # into the lubrication level (published NaN; the value is kept as a KeyValue for the record).
            channel.withheld_theta, channel.withholding = theta, True
            theta, std, reason, flag = math.nan, math.nan, '', ''
            channel.last_theta, channel.last_theta_std, channel.last_flag = math.nan, math.nan, ''
        else:
            if math.isfinite(theta) and channel.withholding:
                channel.withholding, channel.withheld_theta = False, math.nan
                channel.monitor.restart_smoothing()   # judge the level on windows after the defect cleared
            channel.monitor.observe(theta, std, reason, moving=moving, kind=kind)
        channel.last_window = window
        channel.windows += 1
        if math.isfinite(theta):
            channel.last_theta, channel.last_theta_std, channel.last_flag = theta, std, flag
        now = self.now()
        status = self._health(channel, now, incoming=channel.builder.conditions_deferred(window))
        message = status.message if math.isfinite(theta) or not reason else f'{status.message} ({reason})'
        channel.publisher.publish(ros_convert.lubrication_state_msg(
            channel.name, window, theta, std, status.level, message,
            frame_id=channel.frame_id or actuator_label(channel.name), theta_oil_flag=flag))

    # -- diagnostics -------------------------------------------------------------------------------
    def _health(self, channel: ActuatorChannel, now: float, incoming: bool = False) -> HealthStatus:
        """The monitor's status; without calibration at best WARN 'not calibrated'.

        ``incoming``: the window being published has indicators on their way to the screen (module doc).
        """
        status = channel.monitor.status(now)
        if channel.assessor is None:
            return uncalibrated(status, channel.calibration_note)
        status = outside_domain(out_of_range(status, channel.last_flag), channel.last_domain_flag)
        return withheld(status, self._surface(channel, now), channel.surface.pending_with(incoming))

    def _surface(self, channel: ActuatorChannel, now: float) -> SurfaceStatus:
        """The surface monitor's status; STALE when the lubrication status is (no vibration for stale_timeout)."""
        silent = channel.monitor.stale_for(now)
        stale = ''
        if silent > self._thresholds.stale_timeout:
            stale = ('no vibration received yet' if math.isinf(silent) else
                     f'inputs stopped: no vibration for more than stale_timeout ({self._thresholds.stale_timeout:g} s)')
        return channel.surface.status(stale)

    def _status(self, channel: ActuatorChannel, now: float) -> DiagnosticStatus:
        # A window published and not yet screened counts as on its way to the screen, as when it was published.
        status = self._health(channel, now, incoming=any(channel.builder.conditions_deferred(window)
                                                         for window in channel.unscreened))
        w = channel.last_window
        values = [
            ('theta_oil', channel.last_theta),
            ('theta_oil_std', channel.last_theta_std),
            ('theta_oil_flag', channel.last_flag),
            ('theta_oil_withheld', channel.withheld_theta if channel.surface.suspected else math.nan),
            ('domain_flag', channel.last_domain_flag),
            ('vibration_rms', w.vibration_rms if w else math.nan),
            ('screw_speed', w.screw_speed if w else math.nan),
            ('axial_load', w.axial_load if w else math.nan),
            ('window', f'{w.start:.3f} .. {w.end:.3f}' if w else 'none yet'),
            ('theta_oil_mean', status.theta_mean),
            ('windows', channel.windows),
            ('unassessed_windows', status.unassessed_windows),
            ('unassessed_moving_windows', status.unassessed_moving),
            ('unassessed_reason', status.reason or 'none'),
            ('calibration_file', channel.calibration_file or 'none'),
            ('calibration', 'loaded' if channel.assessor else channel.calibration_note),
            ('calibration_band', band_note(channel.assessor.calibration) if channel.assessor
             else band_text(self._settings.band)),
            ('calibration_domain', channel.assessor.calibration.domain.text
             if channel.assessor and channel.assessor.calibration.domain else 'none'),
            ('problems', channel.problem_count()),
            ('last_vibration_age', channel.monitor.stale_for(now)),
        ] + channel.forecast
        if status.level != channel.last_level:
            self._log_level(f'{channel.name}: {LEVEL_NAMES[status.level]}: {status.message}', status.level)
            channel.last_level = status.level
        return ros_convert.diagnostic_status(channel.status_name, channel.hardware_id, status.level,
                                             status.message, values)

    def _log_level(self, line: str, level: int) -> None:
        """Log a status's change of level: info for OK, warning otherwise."""
        if level == 0:      # two call sites: rclpy refuses a second severity at one line
            self.log.info(line)
        else:
            self.log.warning(line)

    def _surface_status(self, channel: ActuatorChannel, now: float) -> DiagnosticStatus:
        """The actuator's surface condition ``DiagnosticStatus``: the defect screen, its numbers in KeyValues."""
        surface = self._surface(channel, now)
        condition, finding = surface.condition, surface.finding
        peaks = condition.envelope_peaks if condition is not None else ()
        assessor = channel.assessor
        if assessor is None:
            baseline = 'none: no calibration loaded, absolute limits only'
        elif assessor.calibration.condition_baseline is None:
            baseline = f'none: {baseline_note(assessor.calibration)}'
        else:
            b = assessor.calibration.condition_baseline
            baseline = (f'{b.runs} calibration run(s): kurtosis median {b.kurtosis_median:.3g}, max '
                        f'{b.kurtosis_max:.3g}; crest factor max {b.crest_max:.3g}')
        values = [
            ('defect_suspected', surface.suspected),
            ('evidence', finding.evidence or 'none'),
            ('component', finding.component or 'none'),
            ('defect_order', finding.order),
            ('suspected_since', surface.since),
            ('kurtosis', condition.kurtosis if condition is not None else math.nan),
            ('crest_factor', condition.crest_factor if condition is not None else math.nan),
            ('kurtosis_limit', surface.kurtosis_limit),
            ('envelope_peaks', '; '.join(f'{p.order:.3f}x {p.db:.1f} dB {p.component or "no defect order"}'
                                         for p in peaks) or 'none'),
            ('order_resolution', condition.order_resolution if condition is not None else math.nan),
            ('windows_pooled', surface.windows),
            ('defect_windows', channel.surface.windows),
            ('clean_judgements', surface.clean),
            ('baseline', baseline),
            ('defect_orders', defect_orders_text(self._defect_orders)),
        ]
        if surface.level != channel.last_surface_level:
            self._log_level(f'{channel.name}: surface condition {LEVEL_NAMES[surface.level]}: {surface.message}',
                            surface.level)
            channel.last_surface_level = surface.level
        return ros_convert.diagnostic_status(channel.surface_status_name, channel.hardware_id, surface.level,
                                             surface.message, values)

    def _input_statuses(self, channel: ActuatorChannel, now: float) -> list:
        """One ``DiagnosticStatus`` per input stream: rate and stamps (:mod:`.topic_status`), while active."""
        statuses = []
        for key, topic in channel.inputs.items():
            judged = topic.status(now)
            statuses.append(ros_convert.diagnostic_status(
                status_name(channel.node_name, channel.name, INPUT_TASK.format(key=key)), channel.hardware_id,
                judged.level, judged.message, judged.values))
        return statuses

    def _publish_diagnostics(self, inputs: bool = True) -> None:
        """The statuses of every actuator on /diagnostics; the input statuses only on the timer's beat.

        On the beat each actuator is flushed first, so its input statuses count
        every message arrived, not those the last flush took (up to 0.35 s
        earlier: rates over a few periods would swing past rate_tolerance).
        """
        with self._lock:
            if self._diagnostics is None:
                return
            if inputs:
                self._arrival = self.now()
                for channel in self.channels:
                    if channel.inputs:      # active
                        self._flush(channel)
            now = self.now()
            array = DiagnosticArray()
            array.header.stamp = self.get_clock().now().to_msg()
            array.status = [status for channel in self.channels
                            for status in (self._status(channel, now), self._surface_status(channel, now))
                            + (tuple(self._input_statuses(channel, now)) if inputs else ())]
            publisher = self._diagnostics
        publisher.publish(array)

    # -- forecast from the fleet history -----------------------------------------------------------
    def _forecast_loop(self, period: float) -> None:
        """Worker thread: the actuators' depletion forecasts from ``history_dir``, every ``period`` s.

        An actuator is looked up in the history by its hardware id (what
        ``prsm-lube assess --actuator-id`` names it), else by its namespace
        (the default of ``assess``).  One read of the history serves all.
        """
        told: set[str] = set()

        def tell(line: str, error: bool = False) -> None:
            if line not in told:
                told.add(line)
                if error:
                    self.log.error(line)
                else:
                    self.log.warning(line)

        while not self._stop_forecast.is_set():
            with self._lock:
                thresholds = self._thresholds
            wanted = [(channel, (channel.hardware_id, channel.name)) for channel in self.channels]
            ids = list(dict.fromkeys(key for _, keys in wanted for key in keys))
            try:
                found = forecast_summaries(self._history_dir, ids, warn_below=thresholds.warn_below,
                                           error_below=thresholds.error_below)
            except InputError as exc:
                found = {key: {'forecast': f'none: {exc}'} for key in ids}
                tell(f'no forecast: {exc}')
            except Exception as exc:   # a broken history must not stop the node; say it once
                found = {key: {'forecast': f'none: internal error {type(exc).__name__}'} for key in ids}
                tell(f'forecast failed (please report): {type(exc).__name__}: {exc}', error=True)
            for channel, keys in wanted:
                summary = next((found[key] for key in keys if found[key].get('forecast') == 'ok'), found[keys[0]])
                summary = dict(summary)
                values = [('forecast', summary.pop('forecast'))]
                values += [(f'forecast_{key}', value) for key, value in summary.items()]
                with self._lock:
                    channel.forecast = values
            self._forecast_wake.wait(period)
            self._forecast_wake.clear()

    def destroy_node(self) -> None:
        """Stop the forecast worker before the node goes."""
        stop = getattr(self, '_stop_forecast', None)
        if stop is not None:
            stop.set()
            self._forecast_wake.set()
        super().destroy_node()  # type: ignore[no-untyped-call, unused-ignore]  # untyped in Jazzy

    # -- calibration service -----------------------------------------------------------------------
    def _calibrate_handler(self, channel: ActuatorChannel) -> Callable[[Any, Any], Awaitable[Any]]:
        async def handler(request: Any, response: Any) -> Any:
            return await self._calibrate(channel, request, response)
        return handler

    def _off_thread(self, channel: ActuatorChannel, work: Callable) -> Future:
        """Run ``work()`` on a worker thread; a future (woken on this node's executor) of its result or exception."""
        done: Any = Future(executor=self.executor)
        done.add_done_callback(lambda _: None)    # wakes the executor when the worker sets the result

        def run() -> None:
            try:
                done.set_result(work())
            except BaseException as exc:   # never lose the answer: the request gets success=false
                done.set_result(exc)

        threading.Thread(target=run, name=f'calibrate {channel.name}', daemon=True).start()
        return done

    async def _calibrate(self, channel: ActuatorChannel, request: Any, response: Any) -> Any:
        """Fit on a worker thread and await it, so the executor keeps serving the subscriptions."""
        arguments = calibration_arguments(request)
        outcome: Any = await self._off_thread(channel, lambda: self._run_calibration(channel, *arguments))
        return self._answer(channel, response, outcome, persist=arguments[2])

    def _calibrate_action(self, channel: ActuatorChannel) -> Callable[[Any], Awaitable[Any]]:
        """Execute callback of the Calibrate action: as the service, with feedback; see :class:`CalibrationJob`."""
        async def execute(goal_handle: Any) -> Any:
            key = bytes(goal_handle.goal_id.uuid)
            job = self._jobs.setdefault(key, CalibrationJob())
            arguments = calibration_arguments(goal_handle.request)

            def progress(stage: str, read: int, count: int, windows: int) -> None:
                try:
                    goal_handle.publish_feedback(CalibrateAction.Feedback(
                        stage=stage, bags_read=read, bag_count=count, windows_read=windows))
                except Exception as exc:   # feedback is a courtesy: the calibration goes on without it
                    self.log.debug(f'calibrate: feedback not sent ({exc})')

            progress('queued', 0, len(arguments[0]), 0)
            try:
                outcome: Any = await self._off_thread(channel, lambda: self._run_calibration(
                    channel, *arguments, progress=progress, job=job))
            finally:
                self._jobs.pop(key, None)
            result = self._answer(channel, CalibrateAction.Result(), outcome, persist=arguments[2])
            if isinstance(outcome, CalibrationWithdrawn):
                goal_handle.canceled()
            elif result.success:
                goal_handle.succeed()
            else:
                goal_handle.abort()
            return result
        return execute

    def _cancel_calibration(self, goal_handle: Any) -> CancelResponse:
        """Accept a cancel: the calibration stops before it starts or at its next check while reading."""
        self._jobs.setdefault(bytes(goal_handle.goal_id.uuid), CalibrationJob()).withdraw()
        return CancelResponse.ACCEPT

    def _answer(self, channel: ActuatorChannel, response: Any, outcome: tuple[Calibration, str] | BaseException,
                persist: bool) -> Any:
        """Fill a service response or action result (same fields) from a calibration's outcome."""
        if isinstance(outcome, BaseException):
            response.success = False
            if isinstance(outcome, (InputError, ValueError, OSError, CalibrationWithdrawn)):
                response.message = str(outcome)
            else:
                response.message = f'calibrate: internal error {type(outcome).__name__}: {outcome}'
            for name in ('c_sys', 'c_f', 'c_lambda', 'fit_rmse', 'c_sys_std', 'c_f_std', 'c_lambda_std'):
                setattr(response, name, math.nan)
            self.log.warning(f'{channel.name}: calibration refused: {response.message}')
            return response
        calibration, message = outcome
        c = calibration.constants
        response.success = True
        response.message = message
        response.c_sys, response.c_f, response.c_lambda = c.c_sys, c.c_f, c.c_lambda
        response.c_sys_std = calibration.c_sys_std
        response.c_f_std = calibration.c_f_std
        response.c_lambda_std = calibration.c_lambda_std
        response.fit_rmse = calibration.fit_rmse
        response.windows_used = int(calibration.windows_used)
        response.calibration_file = channel.calibration_file if persist else ''
        self.log.info(f'{channel.name}: {message}')
        return response

    def _run_calibration(self, channel: ActuatorChannel, paths: list[str], theta: float, persist: bool,
                         requested_namespace: str = '', progress: Callable | None = None,
                         job: CalibrationJob | None = None) -> tuple[Calibration, str]:
        """Worker thread: check, fit, persist if asked, swap.  Returns (calibration, message).

        One calibration at a time: the others wait; a ``job`` withdrawn while
        it waits raises :class:`CalibrationWithdrawn` without doing anything.
        """
        namespace = recording_namespace(requested_namespace, channel.name)
        while not self._fit_lock.acquire(timeout=0.05):
            if job is not None and job.withdrawn:
                break
        else:
            try:
                if job is not None and not job.start():
                    raise CalibrationWithdrawn('calibrate: cancelled before it started; nothing was read or '
                                               'changed')
                return self._calibrate_now(channel, paths, theta, persist, namespace, progress, job)
            finally:
                self._fit_lock.release()
        raise CalibrationWithdrawn('calibrate: cancelled while waiting for another calibration; nothing was read '
                                   'or changed')

    def _stop_check(self, job: CalibrationJob | None, started: float) -> Callable[[], None]:
        """What a running calibration calls as it reads: raises once cancelled or past ``calibration_timeout``."""
        timeout = self._calibration_timeout

        def check() -> None:
            if job is not None and job.withdrawn:
                raise CalibrationWithdrawn('calibrate: cancelled while reading the recordings; nothing was '
                                           'written or changed')
            if time.monotonic() - started > timeout:
                raise InputError(f'calibrate: stopped after calibration_timeout ({timeout:g} s) while reading the '
                                 'recordings; nothing was written or changed (fewer or shorter recordings?)')
        return check

    def _calibrate_now(self, channel: ActuatorChannel, paths: list[str], theta: float, persist: bool,
                       namespace: str, progress: Callable | None,
                       job: CalibrationJob | None = None) -> tuple[Calibration, str]:
        """:meth:`_run_calibration` holding the fit lock."""
        with self._lock:
            settings, folder = self._settings, self._recordings_dir
            min_load = self._min_axial_load
        logged: set[str] = set()

        def on_problem(line: str) -> None:
            if line not in logged and len(logged) < 20:
                logged.add(line)
                self.log.warning(f'{channel.name}: calibrate: {line}')

        started = time.monotonic()
        outcome = calibrate_from_request(paths, theta, folder=folder, lead=self._lead, settings=settings,
                                         namespace=namespace, min_axial_load=min_load,
                                         on_problem=on_problem, on_progress=progress,
                                         check=self._stop_check(job, started))
        calibration = outcome.calibration
        written = ''
        if persist:
            if not channel.calibration_file:
                raise InputError('calibrate: persist is set but parameter calibration_file is empty; '
                                 'constants not swapped in')
            if progress:
                progress('writing', len(outcome.recordings), len(outcome.recordings), calibration.windows_used)
            save_calibration(calibration, channel.calibration_file)
            written = f'; written to {channel.calibration_file}'
        with self._lock:
            self._swap_calibration(channel, calibration)
        return calibration, (
            f'{calibration.summary}; {len(outcome.recordings)} recording(s)'
            + (f' under {namespace}' if namespace != channel.name else '')
            + f' in {time.monotonic() - started:.1f} s; swapped in{written}'
            + (f'; {len(outcome.problems)} problem(s) in the recordings' if outcome.problems else ''))

    # -- parameters --------------------------------------------------------------------------------
    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Validate and apply changed parameters; refuse with a reason and change nothing otherwise.

        A parameter set to its current value changes nothing (``ros2 param load`` of the node's own dump
        must not drop the open windows).
        """
        values = self._values()
        # Only the node's own table: rclpy declares the read-only qos_overrides.* through here as well.
        parameters = [p for p in parameters if p.name in PARAMETERS and not same_value(p, self.get_parameter(p.name))]
        for parameter in parameters:
            values[parameter.name] = parameter.value
        names = {p.name for p in parameters}
        try:
            settings = window_settings(values, self._defect_orders) if names & set(WINDOW_PARAMETERS) else None
            thresholds = health_thresholds(values) if names & set(HEALTH_PARAMETERS) else None
            defect_windows = int(values['defect_windows'])
            if defect_windows < 1:
                raise InputError(f'parameter defect_windows: {defect_windows} must be >= 1')
        except (InputError, TypeError, ValueError) as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        with self._lock:
            if settings is not None:
                self._settings = settings
                for channel in self.channels:
                    self._flush_before_change(channel)
                    channel.builder = self._new_builder(self._channel_settings(channel))
                self.log.info(f'window settings changed ({", ".join(sorted(names))}); open windows '
                              'dropped, starting over')
            if thresholds is not None:
                self._thresholds = thresholds
                for channel in self.channels:
                    channel.monitor.set_thresholds(thresholds)
            if 'defect_windows' in names:
                self._defect_windows = defect_windows
                changed = False
                for channel in self.channels:
                    changed |= self._screen_closed(channel)     # windows waiting are pooled as they were closed
                    channel.surface.set_windows(defect_windows)
                if changed:
                    self._publish_diagnostics(inputs=False)
            if 'min_axial_load' in names:
                self._min_axial_load = float(values['min_axial_load'])
                for channel in self.channels:
                    if channel.assessor is not None:
                        self._swap_calibration(channel, channel.assessor.calibration)
        return SetParametersResult(successful=True)


def calibration_arguments(request: Any) -> tuple[list[str], float, bool, str]:
    """(bag paths, reference theta, persist, recording namespace) of a Calibrate request or action goal."""
    return (list(request.bag_paths), float(request.reference_theta), bool(request.persist),
            str(getattr(request, 'recording_namespace', '')))


def rising_runs(batches: list[InputBatch]) -> list[InputBatch]:
    """One-entry batches (or one-block vibration batches), in order, joined into one batch while their stamps rise."""
    runs: list[InputBatch] = []
    run: list[InputBatch] = []
    last = -math.inf
    for batch in batches:
        stamp = float(batch.stamps[0]) if len(batch) == 1 else math.nan
        if run and not stamp > last:
            runs.append(join_batches(run))
            run = []
        run.append(batch)
        last = stamp
    if run:
        runs.append(join_batches(run))
    return runs


def join_batches(batches: list) -> InputBatch:
    """One input batch holding the entries of ``batches`` (all of one kind, one value per entry), in order."""
    if len(batches) == 1:
        return batches[0]
    first = batches[0]
    if isinstance(first, VibrationBatch):       # blocks of many samples each: offsets shift
        return join_blocks(batches)
    return type(first)(*(np.concatenate([getattr(b, f.name) for b in batches]) for f in fields(first)))


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run prsm_lube_ros lubrication_estimator``; returns the exit status."""
    return run_node(LubricationEstimator, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
