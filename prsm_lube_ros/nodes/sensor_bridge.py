# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``sensor_bridge``: puts the contract's input topics on the graph from a bag, the rig simulator or the card.

Parameter ``source`` (read-only) chooses where the data come from:

- ``playback``: the ``bag``'s contract topics (actuator ``bag_namespace``,
  default ``namespace``), paced on their header stamps ``playback_rate`` times
  faster than real time (a vibration block goes out when its last sample was
  taken, other messages at their stamp).  Header stamps are published
  unchanged, bit for bit as ``prsm-lube assess`` reads them.  ``loop`` starts
  over at the end (logged; stamps go back, which the estimator takes as a clock
  reset); ``publish_clock`` puts the replay's time on ``/clock`` for nodes on
  sim time.  Without ``loop`` the ``ros2 run`` process ends with status 0 after
  the last message (``exit_at_end``).  A bag that cannot be opened, or holds no
  ``<ns>/vibration``, ends the node at start with one line and status 2.
- ``simulator``: :class:`~prsm_lube_ros.simulation.rig_acceleration.RigSignalGenerator` in
  real time; ``speed``, ``load`` and ``theta_oil`` may be changed while it runs.
- ``hardware``: the nut accelerometer through NI-DAQmx (:mod:`.daq`) published
  as VibrationBlocks; speed and load come from the EMA stack's own topics,
  optionally relayed from ``relay_joint_states`` / ``relay_axial_load`` onto the
  contract names.  Without the nidaqmx package, the driver or the card: one
  line and status 2.
- ``imu``: one axis (``imu_axis``) of ``linear_acceleration`` of the
  ``sensor_msgs/Imu`` messages on ``imu_topic`` (any IMU or accelerometer
  driver; a relative name, sensor-data QoS), grouped into VibrationBlocks of
  ``block_length`` s by :class:`~.imu_blocks.ImuBlockAssembler`: each block
  is stamped with its first sample and carries ``sample_rate`` (0: the rate
  measured from the stamps).  A gap, jitter beyond ``jitter_tolerance``,
  stamps going back, or stamps whose rate differs from ``sample_rate`` by
  more than ``rate_tolerance`` close the block early; each kind is logged
  once in one line and counted on ``/diagnostics``.  Gravity (in every
  ``sensor_msgs/Imu``) is taken out by a high-pass at ``imu_highpass`` Hz,
  the lower edge of the windows' band
  (:mod:`prsm_lube_ros.estimation.conditioning`).  header.frame_id is the
  IMU's (``frame_id`` when the IMU leaves it empty).  Only vibration is
  published: speed and load come from the control stack's own topics (or
  the relays below).

The bridge reports its own health on ``/diagnostics`` (absolute, as
diagnostic aggregators expect) every ``diagnostic_period`` s: one status
named ``<node name>: <namespace> sensor source`` with ``hardware_id`` (the
DAQ channel, bag, IMU topic or ``rig simulator`` unless set), the blocks
published, block and sample rate, lost samples, and the last error; OK,
WARN (block rate below the expected one, data lost in the last 10 s),
ERROR (the source failed) or STALE (no block for ``stale_timeout`` s)
(:mod:`.bridge_health`).  ``sensor_bridge_managed`` is the lifecycle
variant (:class:`ManagedSensorBridge`).

Topics are ``<namespace>/vibration``, ``/joint_states``, ``/axial_load`` and
``/temperature`` (CONTRACT.md).  Names are relative, as in ROS packages: the
default ``namespace`` '' is the node's own, ``/prsm`` unless remapped (``-r
__ns:=/ema_left`` gives ``/ema_left/vibration``), and the bag's actuator
(``bag_namespace`` left empty) is looked up under it; ``namespace`` and
``imu_topic`` report the resolved names.  Parameters fixed after start-up
refuse a change with the reason and accept their current value (``ros2 param
load`` of the node's own dump; :class:`~.parameters.ReadOnlyAfterStartUp`); so
do the settings of another source.  Each lifecycle transition of
``sensor_bridge_managed`` is logged once.  Publishers are RELIABLE / KEEP_LAST by
default: a reliable writer serves best-effort readers (the estimator's
sensor-data subscriptions) and reliable ones (``ros2 bag record``) alike,
whereas a best-effort writer would be silently ignored by a reliable reader;
``reliability: best_effort`` is there for links where retransmission hurts.
"""
from __future__ import annotations

import math
import sys
import threading
import time
import traceback
from typing import Any, TYPE_CHECKING
from collections.abc import Callable

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import ParameterType, SetParametersResult
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, qos_profile_sensor_data, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState, Temperature

from ..contract import DEFAULT_NAMESPACE, DIAGNOSTICS_TOPIC, SOURCE_TASK, status_name, topic_name
from ..errors import InputError
from ..estimation.conditioning import HIGHPASS_CORNER
from ..msg import VibrationBlock
from ..recording.reader import open_recording
from ..simulation.rig_config import load_rig_config
from ..simulation.rig_acceleration import RigSignalGenerator
from .bridge_health import SourceHealth, SourceStatus
from .bridge_sources import Pacer, recording_events, rig_block_events
from .daq import DaqSettings, NiDaqAccelerometer
from .fast_drain import FastDrain, missing_api
from .imu_blocks import AssembledBlock, check_axis, ImuBlockAssembler
from .parameters import declare_parameter_table, DEFAULT_DIAGNOSTIC_PERIOD, diagnostic_period, \
    FORMER_DIAGNOSTIC_PERIOD, OVERRIDABLE, own_qos, ParameterSpec, ReadOnlyAfterStartUp, resolved_names, same_value
from .ros_convert import (diagnostic_status, joint_state_msg, temperature_msg, time_from_ns, vibration_block_msg,
                          wrench_msg)
from .startup import autostart, run_node

if TYPE_CHECKING:
    from rclpy.parameter import Parameter
    from rclpy.publisher import Publisher
    from rclpy.subscription import Subscription
    from rclpy.timer import Timer

    from ..recording.reader import Recording
    from ..simulation.rig_config import RigConfig

__all__ = ['BridgeCore', 'MAX_IMU_DRAIN', 'ManagedSensorBridge', 'NODE_NAME', 'PARAMETERS', 'SIMULATOR_PARAMETERS',
           'SOURCES', 'SensorBridge', 'create_node', 'main', 'main_managed', 'publisher_qos']

NODE_NAME = 'sensor_bridge'
SOURCES = ('playback', 'simulator', 'hardware', 'imu')

_BOOL = ParameterType.PARAMETER_BOOL
_DOUBLE = ParameterType.PARAMETER_DOUBLE
_INTEGER = ParameterType.PARAMETER_INTEGER
_STRING = ParameterType.PARAMETER_STRING

#: name: how the parameter is declared (default, type, description, range, read-only)
PARAMETERS = {
    'source': ParameterSpec(
        'simulator', _STRING,
        'where the data come from: playback (a recorded bag), simulator (the rig simulator in real time), '
        'hardware (NI-DAQmx accelerometer) or imu (a sensor_msgs/Imu topic)', read_only=True),
    'namespace': ParameterSpec(
        '', _STRING,
        'topics are <namespace>/vibration, /joint_states, /axial_load, /temperature (a namespace ending in _ '
        "is a plain prefix); '': the node's namespace; reported resolved", read_only=True),
    'reliability': ParameterSpec(
        'reliable', _STRING,
        'QoS of the publishers: reliable (serves best-effort and reliable readers) or best_effort', read_only=True),
    'qos_depth': ParameterSpec(100, _INTEGER, 'KEEP_LAST depth of the publishers', bounds=(1, 100000), read_only=True),
    'frame_id': ParameterSpec(
        'nut_accelerometer', _STRING,
        "header.frame_id of the VibrationBlocks (playback, hardware; the simulator uses its rig file's, imu "
        "the IMU's when it sets one)", read_only=True),
    'hardware_id': ParameterSpec(
        '', _STRING,
        'diagnostic hardware_id of the source status: the serial or device id of the sensor, unique in the fleet '
        '(empty: the DAQ channel, bag, IMU topic or rig simulator, with one WARN at start-up)', read_only=True),
    'autostart': ParameterSpec(
        False, _BOOL,
        'sensor_bridge_managed: configure and activate at start-up (false: wait unconfigured for a lifecycle '
        'manager or ros2 lifecycle set); the plain sensor_bridge always starts at once', read_only=True),
    'stale_timeout': ParameterSpec(
        2.0, _DOUBLE,
        's without a published vibration block before the source status is STALE',
        bounds=(0.01, 3600.0), read_only=True),
    'diagnostic_period': ParameterSpec(
        DEFAULT_DIAGNOSTIC_PERIOD, _DOUBLE,
        's between the source status messages on /diagnostics', bounds=(0.05, 60.0), read_only=True),
    'diagnostics_period': FORMER_DIAGNOSTIC_PERIOD,
    'bag': ParameterSpec('', _STRING, 'playback: rosbag2 directory or .mcap file to replay', read_only=True),
    'bag_namespace': ParameterSpec(
        '', _STRING,
        'playback: actuator namespace inside the bag (empty: namespace)', read_only=True),
    'playback_rate': ParameterSpec(
        1.0, _DOUBLE,
        'playback: 1.0 replays in real time, larger is faster (header-stamp time over wall time)',
        bounds=(0.01, 10000.0)),
    'loop': ParameterSpec(False, _BOOL, 'playback: start over at the end (header stamps then go back)', read_only=True),
    'publish_clock': ParameterSpec(
        False, _BOOL,
        'playback: publish the replay time on /clock for nodes with use_sim_time', read_only=True),
    'clock_period': ParameterSpec(
        0.01, _DOUBLE,
        'playback: s of replay time between /clock messages', bounds=(0.0001, 10.0), read_only=True),
    'wait_for_subscribers': ParameterSpec(
        2.0, _DOUBLE,
        'playback: s of wall time to wait for a vibration subscriber before the first message (best-effort '
        'readers miss what is sent before they match)', bounds=(0.0, 3600.0), read_only=True),
    'exit_at_end': ParameterSpec(
        True, _BOOL,
        'playback without loop: end the process (ros2 run) after the last message', read_only=True),
    'speed': ParameterSpec(
        10.471975511965976, _DOUBLE,
        "simulator: commanded screw speed in rad/s (ramps at the rig's live_acceleration)", bounds=(-1000.0, 1000.0)),
    'load': ParameterSpec(100.0, _DOUBLE, 'simulator: commanded axial load in N', bounds=(0.0, 1.0e6)),
    'theta_oil': ParameterSpec(
        1.0, _DOUBLE,
        'simulator: true lubrication supply factor (1 = fully lubricated)', bounds=(0.0, 2.0)),
    'seed': ParameterSpec(0, _INTEGER, 'simulator: random seed', bounds=(0, 2 ** 31 - 1), read_only=True),
    'rig_config': ParameterSpec(
        '', _STRING,
        'simulator: rig YAML (config/rig_simulator.yaml layout); empty: defaults', read_only=True),
    'daq_channel': ParameterSpec(
        'Dev1/ai0', _STRING,
        'hardware: NI-DAQmx physical channel of the nut accelerometer', read_only=True),
    'sample_rate': ParameterSpec(
        4000.0, _DOUBLE,
        "hardware: samples per second (paper: 4 kHz); imu: the IMU's expected rate, 0 = the rate measured from "
        'the stamps', bounds=(0.0, 1.0e6), read_only=True),
    'block_length': ParameterSpec(
        0.1, _DOUBLE,
        'hardware, imu: s per VibrationBlock (rounded to whole samples)', bounds=(0.001, 10.0), read_only=True),
    'sensitivity': ParameterSpec(
        100.0, _DOUBLE,
        'hardware: accelerometer sensitivity in mV/g (paper: 100 mV/g)', bounds=(0.001, 1.0e5), read_only=True),
    'iepe_current': ParameterSpec(
        0.004, _DOUBLE,
        'hardware: IEPE excitation current in A (0: no excitation)', bounds=(0.0, 0.1), read_only=True),
    'range_g': ParameterSpec(50.0, _DOUBLE, 'hardware: measurement range +/- g', bounds=(0.001, 1.0e5), read_only=True),
    'buffer_seconds': ParameterSpec(
        10.0, _DOUBLE,
        'hardware: ring buffer of the continuous acquisition in s', bounds=(0.1, 3600.0), read_only=True),
    'imu_topic': ParameterSpec(
        'imu/data', _STRING,
        "imu: sensor_msgs/Imu topic (relative: in the node's namespace); reported resolved", read_only=True),
    'imu_axis': ParameterSpec(
        'z', _STRING,
        'imu: axis of linear_acceleration along the screw: x, y or z', read_only=True),
    'rate_tolerance': ParameterSpec(
        0.05, _DOUBLE,
        'imu: largest relative difference between the rate of the stamps and sample_rate before the measured '
        'rate is used (reported once)', bounds=(0.001, 0.5), read_only=True),
    'jitter_tolerance': ParameterSpec(
        0.25, _DOUBLE,
        'imu: largest deviation of one stamp interval from the sample period, as a fraction of it, before the '
        'block is closed early', bounds=(0.01, 0.49), read_only=True),
    'imu_highpass': ParameterSpec(
        HIGHPASS_CORNER, _DOUBLE,
        'imu: corner in Hz of the high-pass that takes gravity (DC) out of the samples, the lower edge of the '
        "windows' band (0: samples passed on unchanged)", bounds=(0.0, 100.0), read_only=True),
    'relay_joint_states': ParameterSpec(
        '', _STRING,
        'hardware, imu: JointState topic of the EMA stack to republish on <namespace>/joint_states (empty: the '
        'stack publishes there itself)', read_only=True),
    'relay_joint': ParameterSpec(
        '', _STRING,
        'hardware, imu: name of the screw joint in the relayed JointState, renamed to screw (empty: already '
        'named screw)', read_only=True),
    'relay_axial_load': ParameterSpec(
        '', _STRING,
        'hardware, imu: WrenchStamped topic of the EMA stack to republish on <namespace>/axial_load (empty: '
        'none)', read_only=True),
}
SIMULATOR_PARAMETERS = ('speed', 'load', 'theta_oil')
#: Most IMU messages taken from the queue per callback (the rest wait for the next one).
MAX_IMU_DRAIN = 10000


def publisher_qos(reliability: str, depth: int) -> QoSProfile:
    """The publishers' QoS: KEEP_LAST ``depth``, volatile, ``reliable`` or ``best_effort``."""
    policies = {'reliable': ReliabilityPolicy.RELIABLE, 'best_effort': ReliabilityPolicy.BEST_EFFORT}
    if reliability not in policies:
        raise InputError(f'parameter reliability: {reliability!r} is neither reliable nor best_effort')
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth), reliability=policies[reliability],
                      durability=DurabilityPolicy.VOLATILE)


class BridgeCore(ReadOnlyAfterStartUp):
    """The bridge's source and publishers, opened, started, halted and closed; mixed into a ROS node class.

    :class:`SensorBridge` opens and starts at construction;
    :class:`ManagedSensorBridge` does each step on a lifecycle transition.
    """

    health: SourceHealth | None                      # from configure on
    _recording: Recording | None                     # playback
    _generator: RigSignalGenerator | None            # simulator
    _daq: NiDaqAccelerometer | None                  # hardware
    _assembler: ImuBlockAssembler | None             # imu
    _pacer: Pacer | None                             # playback, simulator
    _thread: threading.Thread | None                 # the worker, while active
    _imu_subscription: Subscription | None
    _timer: Timer | None
    _outputs: dict[str, Publisher]
    _relays: list[Subscription]
    _clock_publisher: Publisher | None
    _diagnostics: Publisher | None

    @property
    def _health(self) -> SourceHealth:
        """The source's health record (made at configure: every caller runs after it)."""
        assert self.health is not None, "the sensor bridge is not configured"
        return self.health

    def destroy_node(self) -> None:
        """Stop the worker (and the acquisition) and close the source before the node goes."""
        # Also called (by rclpy's shutdown on Kilted) for a bridge whose constructor failed half-way.
        self._close()
        super().destroy_node()  # type: ignore[no-untyped-call, unused-ignore]  # untyped in Jazzy

    def _read_parameters(self) -> dict:
        """Declare the parameters; check the source; the values by name."""
        values = declare_parameter_table(self, PARAMETERS, resolve={
            'namespace': self._resolve_namespace, 'imu_topic': resolved_names(self)})
        self.source = str(values['source']).strip()
        if self.source not in SOURCES:
            raise InputError(f'parameter source: {self.source!r} is not one of {", ".join(SOURCES)}')
        self.namespace = values['namespace']
        self._prefix = '' if self.namespace == self.get_namespace() else self.namespace   # own: relative names
        self.finished = threading.Event()
        self.exit_status = 0
        self.messages_published = 0
        self.loops = 0
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._values = values
        self._recording = self._generator = self._daq = self._assembler = self._pacer = None
        self._thread = self._imu_subscription = self._timer = None
        self._outputs, self._relays, self._clock_publisher = {}, [], None
        self.health = None
        self.add_on_set_parameters_callback(self._on_set_parameters)
        return values

    def _resolve_namespace(self, namespace: str) -> str:
        """The ``namespace`` parameter resolved in the node's namespace ('' is that namespace; a trailing _ stays)."""
        namespace = str(namespace).strip()
        if not namespace:
            return self.get_namespace()
        suffix = '_' if namespace.endswith('_') else ''
        try:
            return self.resolve_topic_name(namespace[:-1] if suffix else namespace.rstrip('/') or '/') + suffix
        except Exception as exc:       # rclpy's InvalidTopicNameException and kin
            raise InputError(f'parameter namespace: {namespace!r} is not a ROS namespace or topic prefix ({exc})') \
                from None

    def _open(self) -> None:
        """Open the source (InputError, nothing published, when it cannot be used), then the publishers."""
        values = self._values = {name: self.get_parameter(name).value for name in PARAMETERS}
        self.frame_id = str(values['frame_id'])
        qos = publisher_qos(str(values['reliability']), values['qos_depth'])
        kinds = ['vibration', 'joint_states', 'axial_load', 'temperature']
        expected_rate = None
        if self.source == 'playback':
            kinds = list(self._open_playback(values).selected)
        elif self.source == 'simulator':
            rig = self._open_simulator(values)
            expected_rate = 1.0 / rig.vibration_block
        elif self.source == 'hardware':
            settings = self._open_hardware(values).settings
            expected_rate = settings.sample_rate / settings.block_size
            kinds = ['vibration']
        else:
            self._open_imu(values)
            kinds = ['vibration']
        types = {'vibration': VibrationBlock, 'joint_states': JointState, 'axial_load': WrenchStamped,
                 'temperature': Temperature}
        self._outputs = {kind: self.create_publisher(types[kind], topic_name(self._prefix, kind), own_qos(qos),
                                                     qos_overriding_options=OVERRIDABLE)
                         for kind in kinds}
        self.topics = {kind: publisher.topic_name for kind, publisher in self._outputs.items()}
        wants_clock = self.source == 'playback' and values['publish_clock']
        self._clock_publisher = self.create_publisher(
            Clock, '/clock', QoSProfile(depth=10), qos_overriding_options=OVERRIDABLE) if wants_clock else None
        self._relays = []
        if self.source in ('hardware', 'imu'):
            self._create_relays(values, qos)
        self._open_diagnostics(values, expected_rate)

    def _start(self) -> None:
        """Start publishing: the worker thread, or (imu) the subscription."""
        previous = getattr(self, '_thread', None)
        if previous is not None and previous.is_alive():
            raise InputError('the source worker of the last activation has not stopped yet (a blocked read?); '
                             'deactivate again later or restart the node')
        self._stop = threading.Event()
        self._health.active = True
        if self.source == 'imu':
            self._imu_subscription = self.create_subscription(Imu, self._imu_topic, self._on_imu,
                                                              own_qos(self._imu_qos),
                                                              qos_overriding_options=OVERRIDABLE)
            return
        if self._pacer is not None:
            self._pacer.stop = self._stop
            self._pacer.restart()
        self.finished.clear()
        if self._daq is not None:
            self._daq.start()
        thread = self._thread = threading.Thread(target=self._work, name='sensor_bridge source', daemon=True)
        thread.start()

    def _halt(self) -> None:
        """Stop publishing (the worker ends, the IMU subscription goes); the source stays open."""
        stop, thread = getattr(self, '_stop', None), getattr(self, '_thread', None)
        if stop is not None:
            stop.set()
        if thread is not None and thread.is_alive() and thread is not threading.current_thread():
            thread.join(timeout=5.0)
        if thread is not None and thread.is_alive() and thread is not threading.current_thread():
            self.log.error('the source worker did not stop within 5 s (a blocked read?); '
                           'it is not started again until it has')
        else:
            self._thread = None
        daq = getattr(self, '_daq', None)
        if daq is not None:
            daq.stop()
        subscription, self._imu_subscription = getattr(self, '_imu_subscription', None), None
        if subscription is not None:
            self.destroy_subscription(subscription)
            assembler = getattr(self, '_assembler', None)
            if assembler is not None:    # the partial block goes out now; the pause is no gap
                self._publish_imu_blocks(assembler.pause(), getattr(self, '_imu_frame_id', self.frame_id),
                                         time.monotonic())
        health = getattr(self, 'health', None)
        if health is not None:
            health.active = False

    def _close(self) -> None:
        """Halt, close the source, and remove the publishers, relays and diagnostics."""
        self._halt()
        daq, self._daq = getattr(self, '_daq', None), None
        if daq is not None:
            daq.close()
        self._recording = self._generator = self._assembler = self._pacer = None
        extras = [getattr(self, name, None) for name in ('_clock_publisher', '_diagnostics')]
        for publisher in list(getattr(self, '_outputs', {}).values()) + extras:
            if publisher is not None:
                self.destroy_publisher(publisher)
        for relay in getattr(self, '_relays', []):
            self.destroy_subscription(relay)
        timer, self._timer = getattr(self, '_timer', None), None
        if timer is not None:
            self.destroy_timer(timer)
        self._outputs, self._relays, self._clock_publisher, self._diagnostics = {}, [], None, None

    # -- sources -----------------------------------------------------------------------------------
    def _open_playback(self, values: dict) -> Recording:
        bag = str(values['bag']).strip()
        if not bag:
            raise InputError('parameter bag: empty; name the rosbag2 directory or .mcap file to replay')
        recording = self._recording = open_recording(bag, namespace=str(values['bag_namespace']).strip()
                                                     or self.namespace)
        self._pacer = Pacer(values['playback_rate'], self._stop)
        return recording

    def _open_simulator(self, values: dict) -> RigConfig:
        rig = load_rig_config(values['rig_config'] or None)
        start_ns = time.time_ns()
        generator = self._generator = RigSignalGenerator(rig, seed=int(values['seed']),
                                                         theta_oil=float(values['theta_oil']), start_stamp_ns=start_ns)
        generator.set_load(float(values['load']))
        generator.set_speed(float(values['speed']))
        self.frame_id = rig.vibration_frame_id
        self._load_frame, self._temperature_frame = rig.load_frame_id, rig.temperature_frame_id
        self._pacer = Pacer(1.0, self._stop)
        return rig

    def _open_hardware(self, values: dict) -> NiDaqAccelerometer:
        size = int(round(values['block_length'] * values['sample_rate']))
        settings = DaqSettings(channel=str(values['daq_channel']), sample_rate=float(values['sample_rate']),
                               block_size=max(size, 1), sensitivity=float(values['sensitivity']),
                               iepe_current=float(values['iepe_current']), range_g=float(values['range_g']),
                               buffer_seconds=float(values['buffer_seconds']))
        daq = self._daq = NiDaqAccelerometer(settings, start=False)      # started by _start
        return daq

    def _open_imu(self, values: dict) -> None:
        self._imu_axis = check_axis(values['imu_axis'])
        topic = str(values['imu_topic']).strip()
        if not topic:
            raise InputError('parameter imu_topic: empty; name the sensor_msgs/Imu topic of the accelerometer')
        self._imu_topic = self.resolve_topic_name(topic)
        self._imu_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(values['qos_depth']),
                                   reliability=qos_profile_sensor_data.reliability,
                                   durability=qos_profile_sensor_data.durability)
        self._assembler = ImuBlockAssembler(float(values['block_length']), float(values['sample_rate']),
                                            float(values['rate_tolerance']), float(values['jitter_tolerance']),
                                            on_problem=self._imu_problem, highpass=float(values['imu_highpass']))
        self._imu_unusable = 0
        # Each IMU callback also takes the messages queued behind it (fast_drain.py): one executor wake-up per
        # burst instead of per sample.  Without that rclpy API: one callback per message.
        self._imu_drain = FastDrain(self.log) if not missing_api() else None

    def _create_relays(self, values: dict, qos: QoSProfile) -> None:
        sensor_qos = QoSProfile(depth=int(values['qos_depth']), reliability=ReliabilityPolicy.BEST_EFFORT)
        joint = str(values['relay_joint']).strip()
        if values['relay_joint_states']:
            out = self.create_publisher(JointState, topic_name(self._prefix, 'joint_states'), own_qos(qos),
                                        qos_overriding_options=OVERRIDABLE)

            def relay_joints(msg: JointState) -> None:
                if joint and joint in msg.name:
                    names = list(msg.name)
                    names[names.index(joint)] = 'screw'
                    msg.name = names
                out.publish(msg)
            self._relays.append(self.create_subscription(JointState, values['relay_joint_states'], relay_joints,
                                                         own_qos(sensor_qos), qos_overriding_options=OVERRIDABLE))
        if values['relay_axial_load']:
            out_load = self.create_publisher(WrenchStamped, topic_name(self._prefix, 'axial_load'), own_qos(qos),
                                             qos_overriding_options=OVERRIDABLE)
            self._relays.append(self.create_subscription(WrenchStamped, values['relay_axial_load'],
                                                         out_load.publish, own_qos(sensor_qos),
                                                         qos_overriding_options=OVERRIDABLE))

    # -- imu ----------------------------------------------------------------------------------------
    def _on_imu(self, msg: Imu) -> None:
        """IMU callback: this sample and those queued behind it."""
        self._take_imu(msg)
        if self._imu_drain is not None:
            for queued in self._imu_drain.drain(self._imu_subscription, MAX_IMU_DRAIN):
                self._take_imu(queued)

    def _take_imu(self, msg: Imu) -> None:
        """One IMU sample: into the current block; publish the blocks it completes."""
        assembler = self._assembler
        if assembler is None:
            return
        now = time.monotonic()
        if msg.linear_acceleration_covariance[0] == -1.0:       # REP 145: no linear acceleration in this message
            self._imu_unusable += 1
            if self._imu_unusable == 1:
                self._imu_problem('no data', 'the IMU marks linear_acceleration as not measured '
                                  '(linear_acceleration_covariance[0] = -1); its samples are dropped')
            self._health.loss(now, samples=1, why='linear_acceleration not measured')
            return
        lost_before = assembler.lost_samples + assembler.dropped_samples
        blocks = assembler.push(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec,
                                getattr(msg.linear_acceleration, self._imu_axis))
        lost = assembler.lost_samples + assembler.dropped_samples - lost_before
        if lost:
            self._health.loss(now, samples=lost, why=assembler.last_problem)
        self._imu_frame_id = msg.header.frame_id or self.frame_id
        self._publish_imu_blocks(blocks, self._imu_frame_id, now)

    def _publish_imu_blocks(self, blocks: list[AssembledBlock], frame_id: str, now: float) -> None:
        """Publish assembled IMU blocks as VibrationBlocks and count them for the bridge's status."""
        vibration = getattr(self, '_outputs', {}).get('vibration')
        if vibration is None:
            return
        assembler = self._assembler
        for block in blocks:
            vibration.publish(vibration_block_msg(time_from_ns(block.stamp_ns), block.sample_rate, block.samples,
                                                  frame_id))
            self.messages_published += 1
            self._health.block(now, block.sample_rate)
            if assembler is not None and assembler.sample_rate and assembler.block_size:
                self._health.expected_block_rate = assembler.sample_rate / assembler.block_size

    def _imu_problem(self, kind: str, line: str) -> None:
        """First problem of a kind: one log line (later ones are counted on /diagnostics)."""
        self.log.warning(f'{self._imu_topic}: {kind}: {line} (logged once; counted on /diagnostics)')
        self._health.note(f'{kind}: {line}')

    # -- diagnostics --------------------------------------------------------------------------------
    def _open_diagnostics(self, values: dict, expected_block_rate: float | None) -> None:
        defaults = {'playback': str(values['bag']).strip(), 'simulator': 'rig simulator',
                    'hardware': str(values['daq_channel']), 'imu': getattr(self, '_imu_topic', '')}
        self.hardware_id = str(values['hardware_id']).strip() or defaults[self.source]
        if not str(values['hardware_id']).strip() and not getattr(self, '_hardware_id_told', False):
            self._hardware_id_told = True      # once per process, not on every configure
            self.log.warning(
                f'hardware_id not set: /diagnostics names the source {self.hardware_id!r}, which collides across a '
                "fleet; set hardware_id to the sensor's serial or device id")
        self.status_name = status_name(self.get_name(), self.namespace, SOURCE_TASK)
        health = self.health = SourceHealth(self.source, float(values['stale_timeout']), expected_block_rate)
        health.active = False                               # until _start
        self._diagnostics = self.create_publisher(DiagnosticArray, DIAGNOSTICS_TOPIC, QoSProfile(depth=10),
                                                  qos_overriding_options=OVERRIDABLE)
        self._timer = self.create_timer(diagnostic_period(values), self.publish_diagnostics)

    def source_status(self) -> SourceStatus:
        """The source's :class:`~.bridge_health.SourceStatus` now."""
        return self._health.status(time.monotonic())

    def publish_diagnostics(self) -> None:
        """One DiagnosticArray with the source status on /diagnostics."""
        status = self.source_status()
        array = DiagnosticArray()
        array.header.stamp = self.get_clock().now().to_msg()
        array.status = [diagnostic_status(self.status_name, self.hardware_id, status.level, status.message,
                                          status.values)]
        if self._diagnostics is not None:
            self._diagnostics.publish(array)

    # -- the worker thread -------------------------------------------------------------------------
    def _work(self) -> None:
        try:
            if self.source == 'playback':
                self._play()
            elif self.source == 'simulator':
                self._simulate()
            else:
                self._acquire()
        except InputError as exc:
            self.log.error(str(exc))
            self._health.fail(str(exc))
            self.exit_status = 1
        except Exception as exc:      # a bug, not bad input: say so with the traceback
            self.log.error(f'internal error (please report): '
                           f'{"".join(traceback.format_exception(exc)).strip()}')
            self._health.fail(f'internal error: {exc}')
            self.exit_status = 1
        finally:
            self.finished.set()

    def _play(self) -> None:
        values = self._values
        recording, pacer = self._recording, self._pacer
        assert recording is not None and pacer is not None, "playback is open"
        rate, bag = values['playback_rate'], values['bag']
        deadline = time.monotonic() + values['wait_for_subscribers']
        vibration = self._outputs['vibration']
        while vibration.get_subscription_count() == 0 and time.monotonic() < deadline:
            if self._stop.wait(0.02):
                return
        if vibration.get_subscription_count():
            self._stop.wait(0.3)      # best-effort readers match the writer a little after it matches them
        self.log.info(f'playback of {bag} ({", ".join(self.topics.values())}) at {rate:g} x real time'
                      + (', looping' if values['loop'] else ''))
        first_stamp = None
        while not self._stop.is_set():
            count = 0
            clock_at = -math.inf
            for events in recording_events(recording, on_problem=self._problem):
                for due, kind, stamp_ns, payload in events:
                    if not pacer.wait(due):
                        return
                    clock_due = due >= clock_at + values["clock_period"] or due < clock_at
                    if self._clock_publisher is not None and clock_due:
                        clock_at = due
                        self._clock_publisher.publish(Clock(clock=time_from_ns(int(round(due * 1e9)))))
                    if first_stamp is None:
                        first_stamp = stamp_ns
                    self._publish(kind, stamp_ns, payload)
                    count += 1
            if count == 0:
                raise InputError(f'{bag}: no messages to replay on {", ".join(self.topics.values())}')
            if not values['loop']:
                self.log.info(f'playback of {bag} finished: {count} messages')
                return
            self.loops += 1
            self.log.info(f'loop {self.loops}: replaying {bag} from the start; header stamps go back '
                          f'to {(first_stamp or 0) * 1e-9:.3f} (subscribers see a clock reset)')
            pacer.restart()

    def _simulate(self) -> None:
        generator, pacer = self._generator, self._pacer
        assert generator is not None and pacer is not None, "the simulator is open"
        while not self._stop.is_set():
            with self._lock:
                block = generator.next_block()
            for due, kind, stamp_ns, payload in rig_block_events(block):
                if not pacer.wait(due):
                    return
                self._publish(kind, stamp_ns, payload)

    def _acquire(self) -> None:
        daq = self._daq
        assert daq is not None, "the acquisition is open"
        settings = daq.settings
        self.log.info(f'acquiring {settings.channel} at {settings.sample_rate:g} Hz, '
                      f'{settings.block_size} samples per block, {settings.sensitivity:g} mV/g')
        try:
            while not self._stop.is_set():
                stamp_ns, samples = daq.read_block()
                self._publish('vibration', stamp_ns, (settings.sample_rate, samples))
        finally:
            if not self._stop.is_set():      # a failed read: the acquisition is over (halted: it stays open)
                daq.close()

    def _publish(self, kind: str, stamp_ns: int, payload: tuple) -> None:
        if kind == 'vibration':
            msg = vibration_block_msg(time_from_ns(stamp_ns), payload[0], payload[1], self.frame_id)
        elif kind == 'joint_states':
            msg = joint_state_msg(time_from_ns(stamp_ns), *payload)
        elif kind == 'axial_load':
            msg = wrench_msg(time_from_ns(stamp_ns), payload[0], getattr(self, '_load_frame', ''))
        else:
            msg = temperature_msg(time_from_ns(stamp_ns), payload[0], getattr(self, '_temperature_frame', ''))
        publisher = self._outputs.get(kind)
        if publisher is not None:
            publisher.publish(msg)
            self.messages_published += 1
            if kind == 'vibration':
                self._health.block(time.monotonic(), payload[0])

    def _problem(self, line: str) -> None:
        self.log.warning(f'{self._values["bag"]}: {line}')
        self._health.note(line)

    # -- parameters --------------------------------------------------------------------------------
    def _on_set_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        """Simulator: speed, load and theta_oil act from the next block; playback: playback_rate at once.

        A value equal to the current one changes nothing and passes, also for another source's setting.
        """
        # Only the node's own table: rclpy declares the read-only qos_overrides.* through here as well.
        parameters = [p for p in parameters if p.name in PARAMETERS and not same_value(p, self.get_parameter(p.name))]
        for parameter in parameters:
            if parameter.name in SIMULATOR_PARAMETERS and self.source != 'simulator':
                return SetParametersResult(successful=False,
                                           reason=f'{parameter.name} applies to source simulator only')
            if parameter.name == 'playback_rate' and self.source != 'playback':
                return SetParametersResult(successful=False, reason='playback_rate applies to source playback only')
        for parameter in parameters:
            value = parameter.value
            if parameter.name in SIMULATOR_PARAMETERS and self._generator is not None:  # else: read at configure
                with self._lock:
                    setter = {'speed': self._generator.set_speed, 'load': self._generator.set_load,
                              'theta_oil': self._generator.set_theta}[parameter.name]
                    setter(float(value))
                self.log.info(f'simulator: {parameter.name} set to {value:g}')
            elif parameter.name == 'playback_rate' and self._pacer is not None:
                self._pacer.rate = float(value)
                self._pacer.restart()
        return SetParametersResult(successful=True)


class SensorBridge(BridgeCore, Node):
    """The bridge node; see the module docstring.  ``kwargs`` go to :class:`rclpy.node.Node`.

    Raises :class:`InputError` at construction when the source cannot be used
    (nothing is published then).  A worker thread paces and publishes (imu: the
    subscription's callback); it sets :attr:`finished` when the source ends
    (playback done, acquisition failed), with :attr:`exit_status` 0 or 1.
    """

    def __init__(self, node_name: str = NODE_NAME, namespace: str = DEFAULT_NAMESPACE, **kwargs: Any) -> None:
        super().__init__(node_name, namespace=namespace, **kwargs)
        self._read_parameters()
        self._open()
        self._start()


class ManagedSensorBridge(BridgeCore, LifecycleNode):
    """The bridge as a lifecycle (managed) node: each step of :class:`BridgeCore` on a transition.

    Constructed unconfigured (parameters declared and checked), or with
    ``autostart`` configured and activated at once (InputError when a step fails).  configure
    opens the source (the bag, the rig simulator, the DAQ task set up but not
    started, the IMU settings), creates the publishers and the status on
    /diagnostics; activate starts publishing (worker thread, acquisition or
    IMU subscription); deactivate stops it (the source stays open); cleanup
    and shutdown close the source and remove the publishers.  A source that
    cannot be opened fails configure with one log line (the node stays
    unconfigured).  Activate after deactivate replays a bag from its start
    again; the simulator goes on in its own time (its stamps then trail the
    wall clock by the time it was inactive).
    """

    def __init__(self, node_name: str = NODE_NAME, namespace: str = DEFAULT_NAMESPACE, **kwargs: Any) -> None:
        super().__init__(node_name, namespace=namespace, **kwargs)
        values = self._read_parameters()
        if values['autostart']:
            autostart(self)

    def _step(self, what: str, action: Callable[[], None]) -> TransitionCallbackReturn:
        try:
            action()
        except InputError as exc:
            self.log.error(f'{what} failed: {exc}')
            return TransitionCallbackReturn.FAILURE
        return TransitionCallbackReturn.SUCCESS

    def _transition(self, what: str, state: LifecycleState, goal: str,
                    result: TransitionCallbackReturn) -> TransitionCallbackReturn:
        """Log a transition once: ``configure: unconfigured -> inactive`` (or that it failed)."""
        if result == TransitionCallbackReturn.SUCCESS:
            self.log.info(f'{what}: {state.label} -> {goal}')
        else:
            self.log.warning(f'{what}: failed, stays {state.label}')
        return result

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Open the source and create the publishers (FAILURE, all closed again, when it cannot be used)."""
        result = self._step('configure', self._open)
        if result != TransitionCallbackReturn.SUCCESS:
            self._close()
        return self._transition('configure', state, 'inactive', result)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start publishing."""
        result = self._step('activate', self._start)
        if result == TransitionCallbackReturn.SUCCESS:
            result = super().on_activate(state)
        return self._transition('activate', state, 'active', result)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop publishing; the source stays open."""
        self._halt()
        return self._transition('deactivate', state, 'inactive', super().on_deactivate(state))

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the source and remove the publishers."""
        self._close()
        return self._transition('cleanup', state, 'unconfigured', TransitionCallbackReturn.SUCCESS)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """As cleanup, from any state."""
        self._close()
        return self._transition('shutdown', state, 'finalized', TransitionCallbackReturn.SUCCESS)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """A transition raised: close everything and go back to unconfigured."""
        self._close()
        return self._transition('error', state, 'unconfigured', TransitionCallbackReturn.SUCCESS)


def create_node(**kwargs: Any) -> SensorBridge:
    """The bridge node (``prsm-lube run`` starts it beside the estimator)."""
    return SensorBridge(**kwargs)


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run prsm_lube_ros sensor_bridge``; returns the exit status.

    Bad configuration or an unusable source: one line on stderr, status 2.
    Playback without ``loop`` ends with status 0 after the last message
    (``exit_at_end``); an acquisition that fails while running ends with 1.
    """
    def finished(node: SensorBridge) -> bool:
        exit_at_end = node.source == 'playback' and node.get_parameter('exit_at_end').value
        return node.finished.is_set() and bool(exit_at_end or node.exit_status)
    return run_node(SensorBridge, NODE_NAME, args, done=finished, exit_status=lambda node: node.exit_status)


def main_managed(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run prsm_lube_ros sensor_bridge_managed``: the lifecycle bridge, unconfigured.

    Drive it with ``ros2 lifecycle set <node> configure | activate | deactivate
    | cleanup | shutdown``; it runs until Ctrl-C.  Bad parameters: one line,
    status 2.
    """
    return run_node(ManagedSensorBridge, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
