# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Simulated test rig of the paper: contract recordings with a known truth.

The rig turns the screw of the default actuator through the paper's
experiment (Sec. 3.1): single-direction feed over the 180 mm stroke with
acceleration and deceleration ramps, three speeds x two loads, after each of
three lubrication steps; between runs the nut returns to the start at a fixed
rewind speed with the load actuator off.  It records what a real rig would:
4 kHz nut acceleration (``VibrationBlock``), screw joint states, axial load
and temperature, as rosbag2 bags (:mod:`prsm_lube_ros.bag_writer`), and writes
the truth (theta per stage, constants, schedule, effects) to ``truth.json``.

The acceleration is a time signal whose RMS follows Eq. 22
(:func:`prsm_lube_ros.vibration_model.acceleration_amplitude`) with the
simulator's true constants, built from unit-RMS components mixed by power
shares and scaled sample by sample by the target amplitude A(t) of the
instantaneous speed and load:

* thread-contact excitation: white noise through a lightly damped structural
  mode (second-order resonator, gain normalised by its impulse-response energy);
* rotation-order harmonics (1x and the roller-pass order of Eq. 1), their
  phase the order times the screw angle, hence continuous through speed changes;
* sensor noise, white, small against the signal.

Optional physical effects (:mod:`prsm_lube_ros.sim_effects`) change the truth.
Everything streams in chunks of about one second, so memory stays flat.
Same seed, same configuration => identical samples.  No ROS import.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields, replace
from datetime import datetime, timezone
import json
import math
from pathlib import Path
from typing import Callable, Iterator, Sequence

import numpy as np
from scipy.signal import iirpeak, lfilter

from .actuator import Actuator, load_actuator
from .bag_writer import ContractBagWriter, bag_path, check_storage
from .errors import InputError
from .kinematics import roller_revolution_speed
from .sim_effects import (EFFECT_IDS, Effects, draw_background_vibration, draw_lubricant_depletion,
                          draw_position_dependent_stiffness, draw_resonance, draw_thermal_viscosity)
from .vibration_model import ModelConstants, acceleration_amplitude
from .yaml_file import read_yaml

RPM = 2.0 * math.pi / 60.0
#: Harmonic order placeholder for the roller-pass order ``roller_count omega_P / omega_S`` (Eq. 1).
ROLLER_PASS = 'roller_pass'
#: Screw speeds below this (rad/s) count as standstill (thermal effect).
STANDSTILL_SPEED = 1e-6
#: Chunk of generation, s (rounded to whole vibration blocks).
CHUNK_DURATION = 1.0
ProgressCallback = Callable[[float, float], None]


# ---------------------------------------------------------------------------------------------
# Configuration
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RigConfig:
    """The simulated rig: true constants, signal make-up, sensors and recording (SI units).

    The defaults are those of ``config/rig_simulator.yaml``; see there for each field.
    """

    actuator: Actuator = field(default_factory=Actuator)
    c_sys: float = 0.08
    c_f: float = 1.0e-3
    c_lambda: float = 0.30
    nut_preload: float = 20.0
    contact_mode_frequency: float = 1200.0
    contact_mode_damping: float = 0.05
    harmonic_orders: tuple = (1.0, ROLLER_PASS)
    harmonic_shares: tuple = (0.10, 0.15)
    sensor_noise: float = 0.003
    vibration_rate: float = 4000.0
    vibration_block: float = 0.1
    joint_state_rate: float = 100.0
    load_rate: float = 50.0
    load_noise_relative: float = 0.002
    load_noise_absolute: float = 0.2
    load_ramp_time: float = 0.5
    temperature_rate: float = 1.0
    ambient_temperature: float = 30.0
    temperature_noise: float = 0.02
    transport_latency: float = 0.0005
    latency_jitter: float = 0.0003
    live_acceleration: float = 20.0
    epoch: str = '2026-01-01T00:00:00Z'
    namespace: str = '/prsm'
    vibration_frame_id: str = 'nut_accelerometer'
    load_frame_id: str = 'load_cell'
    temperature_frame_id: str = 'nut'

    def __post_init__(self):
        """Check every field; raise :class:`InputError` naming the first bad one."""
        object.__setattr__(self, 'harmonic_orders', tuple(
            order if order == ROLLER_PASS else _number('rig harmonic_orders', order)
            for order in self.harmonic_orders))
        object.__setattr__(self, 'harmonic_shares', tuple(
            _number('rig harmonic_shares', share) for share in self.harmonic_shares))
        for name in ('c_sys', 'nut_preload', 'contact_mode_frequency', 'contact_mode_damping',
                     'vibration_rate', 'vibration_block', 'joint_state_rate', 'load_rate',
                     'temperature_rate', 'live_acceleration'):
            _require(getattr(self, name) > 0, f'rig {name} must be > 0, got {getattr(self, name)!r}')
        for name in ('c_f', 'c_lambda', 'sensor_noise', 'load_noise_relative', 'load_noise_absolute',
                     'load_ramp_time', 'temperature_noise', 'transport_latency', 'latency_jitter'):
            _require(getattr(self, name) >= 0, f'rig {name} must be >= 0, got {getattr(self, name)!r}')
        _require(self.contact_mode_damping < 1, 'rig contact_mode_damping must be below 1')
        _require(len(self.harmonic_orders) == len(self.harmonic_shares),
                 'rig harmonic_orders and harmonic_shares differ in length')
        _require(all(order == ROLLER_PASS or order > 0 for order in self.harmonic_orders),
                 'rig harmonic_orders must be > 0')
        _require(all(share >= 0 for share in self.harmonic_shares) and sum(self.harmonic_shares) < 1,
                 f'rig harmonic_shares must be >= 0 and add up to less than 1, got {self.harmonic_shares}')
        size = self.vibration_rate * self.vibration_block
        _require(abs(size - round(size)) < 1e-6 and round(size) >= 1,
                 f'rig vibration_block x vibration_rate must be a whole number of samples, got {size}')
        _require(self.contact_mode_frequency < 0.45 * self.vibration_rate,
                 f'rig contact_mode_frequency {self.contact_mode_frequency} Hz must lie below '
                 f'0.45 x vibration_rate')
        self.epoch_ns  # noqa: B018 - validates the epoch

    @property
    def constants(self) -> ModelConstants:
        """The true constants of Eq. 22."""
        return ModelConstants(c_sys=self.c_sys, c_f=self.c_f, c_lambda=self.c_lambda)

    @property
    def block_size(self) -> int:
        """Samples per ``VibrationBlock``."""
        return int(round(self.vibration_rate * self.vibration_block))

    @property
    def contact_share(self) -> float:
        """Power share of the thread-contact (resonator) component."""
        return 1.0 - sum(self.harmonic_shares)

    @property
    def roller_pass_order(self) -> float:
        """Roller-pass order ``roller_count omega_P / omega_S`` from Eq. 1 (rollers passing a nut point)."""
        return float(self.actuator.roller_count * roller_revolution_speed(
            1.0, self.actuator.screw_mean_diameter, self.actuator.roller_mean_diameter))

    @property
    def resolved_harmonic_orders(self) -> tuple[float, ...]:
        """Harmonic orders with ``roller_pass`` replaced by its value."""
        return tuple(self.roller_pass_order if order == ROLLER_PASS else float(order)
                     for order in self.harmonic_orders)

    @property
    def epoch_ns(self) -> int:
        """Stamp of simulated time zero, ns since the Unix epoch."""
        try:
            moment = datetime.fromisoformat(str(self.epoch).replace('Z', '+00:00'))
        except ValueError:
            raise InputError(f'rig epoch must be an ISO 8601 time, got {self.epoch!r}') from None
        if moment.tzinfo is None:
            moment = moment.replace(tzinfo=timezone.utc)
        delta = moment - datetime(1970, 1, 1, tzinfo=timezone.utc)
        return (delta.days * 86400 + delta.seconds) * 1_000_000_000 + delta.microseconds * 1000

    def as_dict(self) -> dict:
        """Plain mapping (for ``truth.json``)."""
        result = asdict(self)
        result['harmonic_orders'] = list(self.harmonic_orders)
        result['harmonic_shares'] = list(self.harmonic_shares)
        result['roller_pass_order'] = self.roller_pass_order
        return result


@dataclass(frozen=True)
class ExperimentPlan:
    """What the rig runs: the paper's 3 speeds x 2 loads after each of three lubrication steps.

    speeds in rad/s (forward feed), loads in N, stage_thetas the true theta_Oil
    after each lubrication step (one bag each), stroke and ramp_travel (per
    ramp) in m, rewind_speed in rad/s, standstill and stage_pause in s,
    run_order ``'fixed'`` (speed-major, as listed) or ``'random'`` (seeded).
    """

    speeds: tuple[float, ...] = (100 * RPM, 150 * RPM, 200 * RPM)
    loads: tuple[float, ...] = (100.0, 200.0)
    stage_thetas: tuple[float, ...] = (0.72, 0.83, 1.0)
    stroke: float = 0.18
    ramp_travel: float = 0.005
    rewind_speed: float = 300 * RPM
    standstill: float = 1.0
    stage_pause: float = 60.0
    run_order: str = 'fixed'

    def __post_init__(self):
        """Check every field; raise :class:`InputError` naming the first bad one."""
        for name in ('speeds', 'loads', 'stage_thetas'):
            values = tuple(_number(f'plan {name}', value) for value in getattr(self, name))
            _require(values and all(value > 0 for value in values),
                     f'plan {name} must be a non-empty list of numbers > 0, got {getattr(self, name)!r}')
            object.__setattr__(self, name, values)
        for name in ('stroke', 'ramp_travel', 'rewind_speed', 'standstill'):
            _require(getattr(self, name) > 0, f'plan {name} must be > 0, got {getattr(self, name)!r}')
        _require(self.stage_pause >= 0, f'plan stage_pause must be >= 0, got {self.stage_pause!r}')
        _require(2 * self.ramp_travel < self.stroke,
                 f'plan ramp_travel {self.ramp_travel} m leaves no steady travel in the {self.stroke} m stroke')
        _require(self.run_order in ('fixed', 'random'),
                 f'plan run_order must be "fixed" or "random", got {self.run_order!r}')

    @property
    def conditions(self) -> list[tuple[float, float]]:
        """``(speed, load)`` pairs in the fixed order: each speed with each load."""
        return [(speed, load) for speed in self.speeds for load in self.loads]

    def as_dict(self) -> dict:
        """Plain mapping (for ``truth.json``)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


def _require(condition, message: str) -> None:
    if not condition:
        raise InputError(message)


def _number(name: str, value) -> float:
    if isinstance(value, bool):
        raise InputError(f'{name} must be a number, got {value!r}')
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(f'{name} must be a number, got {value!r}') from None
    _require(math.isfinite(value), f'{name} must be finite, got {value!r}')
    return value


def _read_section(path: str | Path, section: str) -> tuple[dict, Path]:
    path = Path(path)
    document = read_yaml(path, 'rig simulator file')
    root = document.get('rig_simulator', document) if isinstance(document, dict) else None
    if not isinstance(root, dict):
        raise InputError(f'{path}: expected a mapping under "rig_simulator:"')
    values = root.get(section) or {}
    if not isinstance(values, dict):
        raise InputError(f'{path}: expected a mapping under "rig_simulator: {section}:"')
    return values, path


def _coerce(path: Path, kind, values: dict, skip=()) -> dict:
    known = {f.name: f for f in fields(kind)}
    unknown = sorted(set(values) - set(known) - set(skip))
    if unknown:
        raise InputError(f'{path}: unknown {kind.__name__} field(s) {", ".join(unknown)}')
    result = {}
    for key, value in values.items():
        if key in skip:
            continue
        default = known[key].default
        if isinstance(default, tuple):
            if not isinstance(value, (list, tuple)):
                raise InputError(f'{path}: {key} must be a list, got {value!r}')
            result[key] = tuple(value)
        elif isinstance(default, str):
            result[key] = str(value)
        else:
            result[key] = _number(f'{path}: {key}', value)
    return result


def load_rig_config(path: str | Path | None = None) -> RigConfig:
    """Rig from the ``rig_simulator: rig:`` mapping of a YAML file; ``None`` gives the defaults.

    ``actuator_file`` (relative to the YAML file) names an actuator YAML; without
    it the contract's default actuator is used.
    """
    if path is None:
        return RigConfig()
    values, path = _read_section(path, 'rig')
    actuator_file = values.get('actuator_file')
    actuator = load_actuator(path.parent / actuator_file) if actuator_file else Actuator()
    try:
        return RigConfig(actuator=actuator, **_coerce(path, RigConfig, values, skip=('actuator_file',)))
    except InputError as exc:
        raise InputError(f'{path}: {exc}') from None


def load_experiment_plan(path: str | Path | None = None) -> ExperimentPlan:
    """Plan from the ``rig_simulator: plan:`` mapping of a YAML file; ``None`` gives the paper's plan."""
    if path is None:
        return ExperimentPlan()
    values, path = _read_section(path, 'plan')
    try:
        return ExperimentPlan(**_coerce(path, ExperimentPlan, values))
    except InputError as exc:
        raise InputError(f'{path}: {exc}') from None


# ---------------------------------------------------------------------------------------------
# Drive program: screw motion and applied load as piecewise polynomials of time
# ---------------------------------------------------------------------------------------------
class DriveProgram:
    """Screw angle/speed (constant-acceleration phases) and applied load (linear phases) over time.

    Times are s since simulated time zero.  Each phase holds until the next
    begins; the last holds for ever.  Angle and speed are continuous, so the
    angle is the exact integral of the speed.
    """

    def __init__(self, angle: float = 0.0):
        """Standstill at ``angle`` (rad) and no load from time zero."""
        self._motion = [[0.0], [float(angle)], [0.0], [0.0]]   # start, angle, speed, acceleration
        self._load = [[0.0], [0.0], [0.0]]                      # start, load, rate
        self._arrays = None

    def _tables(self):
        if self._arrays is None:
            self._arrays = (tuple(np.array(column) for column in self._motion),
                            tuple(np.array(column) for column in self._load))
        return self._arrays

    def motion(self, times) -> tuple[np.ndarray, np.ndarray]:
        """Screw angle in rad and speed in rad/s at ``times`` (s)."""
        (start, angle, speed, accel), _ = self._tables()
        times = np.asarray(times, dtype=float)
        index = np.clip(np.searchsorted(start, times, side='right') - 1, 0, None)
        dt = times - start[index]
        return (angle[index] + speed[index] * dt + 0.5 * accel[index] * dt * dt,
                speed[index] + accel[index] * dt)

    def load(self, times) -> np.ndarray:
        """Applied axial load in N at ``times`` (s)."""
        _, (start, load, rate) = self._tables()
        times = np.asarray(times, dtype=float)
        index = np.clip(np.searchsorted(start, times, side='right') - 1, 0, None)
        return load[index] + rate[index] * (times - start[index])

    def append_motion(self, start: float, acceleration: float, speed: float | None = None) -> None:
        """New phase from ``start``; angle continuous, speed continuous unless given (exact end of a ramp)."""
        self._truncate(self._motion, start)
        angle, current = (float(v) for v in self.motion(start))
        self._arrays = None
        for column, value in zip(self._motion, (start, angle, current if speed is None else speed,
                                                acceleration)):
            column.append(float(value))

    def append_load(self, start: float, rate: float, load: float | None = None) -> None:
        """New load phase from ``start`` with ``rate`` in N/s; load continuous unless given."""
        self._truncate(self._load, start)
        current = float(self.load(start))
        self._arrays = None
        for column, value in zip(self._load, (start, current if load is None else load, rate)):
            column.append(float(value))

    def _truncate(self, table, start: float) -> None:
        """Drop phases that begin at or after ``start`` (later commands replace planned ones)."""
        keep = sum(1 for begin in table[0] if begin < start) or 1
        if keep < len(table[0]):
            for column in table:
                del column[keep:]
            self._arrays = None

    def forget_before(self, time: float) -> None:
        """Drop phases that ended before ``time`` (keeps a long-running live program small)."""
        for table in (self._motion, self._load):
            active = max(sum(1 for begin in table[0] if begin <= time) - 1, 0)
            if active:
                for column in table:
                    del column[:active]
                self._arrays = None

    def command_speed(self, now: float, target: float, acceleration: float) -> None:
        """Ramp the screw speed from ``now`` to ``target`` (rad/s) at ``acceleration`` (rad/s^2)."""
        _, current = (float(v) for v in self.motion(now))
        if current == target:
            self.append_motion(now, 0.0, target)
            return
        duration = abs(target - current) / acceleration
        self.append_motion(now, math.copysign(acceleration, target - current))
        self.append_motion(now + duration, 0.0, target)

    def command_load(self, now: float, target: float, rate: float) -> None:
        """Ramp the applied load from ``now`` to ``target`` (N) at ``rate`` (N/s)."""
        current = float(self.load(now))
        if current == target or rate <= 0:
            self.append_load(now, 0.0, target)
            return
        self.append_load(now, math.copysign(rate, target - current))
        self.append_load(now + abs(target - current) / rate, 0.0, target)


@dataclass(frozen=True)
class Stroke:
    """One traverse of the nut in the schedule (times in s since simulated time zero)."""

    kind: str            # 'forward' (measured run under load) or 'rewind' (return, load off)
    speed: float         # rad/s, signed (rewind negative)
    load: float          # N, applied (0 for rewind)
    start: float         # s, motion starts
    end: float           # s, motion ends
    steady_start: float  # s, acceleration ramp ends
    steady_end: float    # s, deceleration ramp starts

    def as_dict(self, origin: float) -> dict:
        """Mapping with times in s since the Unix epoch (``origin`` = stamp of time zero)."""
        result = asdict(self)
        for key in ('start', 'end', 'steady_start', 'steady_end'):
            result[key] = origin + result[key]
        return result


def append_stroke(program: DriveProgram, start: float, speed: float, travel: float, ramp_travel: float,
                  lead: float, load: float = 0.0, kind: str = 'forward') -> Stroke:
    """Trapezoidal speed profile moving the nut by ``travel`` (m) at ``speed`` (rad/s, signed).

    Constant acceleration over ``ramp_travel`` (m) at each end, so the ramp
    takes ``t = 2 theta_r / |omega|`` with ``theta_r = 2 pi ramp_travel / lead``.
    """
    total = 2.0 * math.pi * travel / lead
    ramp = 2.0 * math.pi * ramp_travel / lead
    ramp_time = 2.0 * ramp / abs(speed)
    cruise_time = (total - 2.0 * ramp) / abs(speed)
    acceleration = speed / ramp_time
    steady_start, steady_end = start + ramp_time, start + ramp_time + cruise_time
    end = steady_end + ramp_time
    program.append_motion(start, acceleration, 0.0)
    program.append_motion(steady_start, 0.0, speed)
    program.append_motion(steady_end, -acceleration, speed)
    program.append_motion(end, 0.0, 0.0)
    return Stroke(kind, float(speed), float(load), start, end, steady_start, steady_end)


def schedule_session(program: DriveProgram, start: float, conditions: Sequence[tuple[float, float]],
                     plan: ExperimentPlan, rig: RigConfig) -> tuple[list[Stroke], float]:
    """One session from ``start`` (s): standstill, then per condition a forward run and a rewind.

    The load actuator ramps the load up in the ``load_ramp_time`` before each
    forward run and down after it; rewinds run unloaded at ``-rewind_speed``.
    Returns the strokes and the end time (after a final standstill).
    """
    _require(rig.load_ramp_time <= plan.standstill,
             f'rig load_ramp_time {rig.load_ramp_time} s must not exceed plan standstill {plan.standstill} s')
    lead = rig.actuator.lead
    strokes = []
    now = start + plan.standstill
    for speed, load in conditions:
        if rig.load_ramp_time > 0:
            program.append_load(now - rig.load_ramp_time, load / rig.load_ramp_time, 0.0)
        program.append_load(now, 0.0, load)
        run = append_stroke(program, now, speed, plan.stroke, plan.ramp_travel, lead, load, 'forward')
        if rig.load_ramp_time > 0:
            program.append_load(run.end, -load / rig.load_ramp_time, load)
        program.append_load(run.end + rig.load_ramp_time, 0.0, 0.0)
        rewind = append_stroke(program, run.end + plan.standstill, -plan.rewind_speed, plan.stroke,
                               plan.ramp_travel, lead, 0.0, 'rewind')
        strokes += [run, rewind]
        now = rewind.end + plan.standstill
    return strokes, now


# ---------------------------------------------------------------------------------------------
# Truth: the amplitude the signal is scaled to
# ---------------------------------------------------------------------------------------------
def effective_load(applied_load, rig: RigConfig):
    """Load the thread contacts carry, N: the applied load, but at least the nut preload."""
    return np.maximum(np.abs(np.asarray(applied_load, dtype=float)), rig.nut_preload)


def thread_contact_amplitude(screw_speed, applied_load, theta_oil, rig: RigConfig,
                             effects: Effects | None = None, *, nut_position=0.0, temperature=None,
                             revolutions=0.0):
    """True RMS of the thread-contact vibration, m/s^2: Eq. 22 changed by the active effects.

    screw_speed in rad/s, applied_load in N (preload as floor), theta_oil the
    stage's lubrication; nut_position in m from the start of the stroke,
    temperature in degC (None = ambient), revolutions since the last
    lubrication.  Background vibration and sensor noise are not included:
    the recorded RMS is ``sqrt(A^2 + B^2 + sigma_n^2)``.
    """
    effects = effects or Effects()
    load = effective_load(applied_load, rig)
    theta = np.asarray(theta_oil, dtype=float)
    if effects.lubricant_depletion is not None:
        theta = theta * effects.lubricant_depletion.theta_factor(revolutions)
    if effects.thermal_viscosity is not None and temperature is not None:
        theta = theta * effects.thermal_viscosity.film_factor(temperature, rig.ambient_temperature)
    amplitude = acceleration_amplitude(screw_speed, load, theta, rig.constants)
    if effects.position_dependent_stiffness is not None:
        amplitude = amplitude * effects.position_dependent_stiffness.amplitude_factor(nut_position, load)
    if effects.resonance is not None:
        amplitude = amplitude * effects.resonance.amplitude_factor(screw_speed)
    return amplitude


def expected_rms(screw_speed, applied_load, theta_oil, rig: RigConfig, effects: Effects | None = None,
                 **state):
    """RMS the recording should show in steady running, m/s^2: contact, background and sensor noise in power."""
    effects = effects or Effects()
    background = effects.background_vibration.rms if effects.background_vibration is not None else 0.0
    contact = thread_contact_amplitude(screw_speed, applied_load, theta_oil, rig, effects, **state)
    return np.sqrt(contact ** 2 + background ** 2 + rig.sensor_noise ** 2)


# ---------------------------------------------------------------------------------------------
# Streaming synthesis
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RigChunk:
    """Everything the rig's sensors produced in consecutive vibration blocks.

    Stamps are int64 ns since the Unix epoch (acquisition times).  ``samples``
    is (blocks, block_size) float32 m/s^2.  Joint states are true values; load
    and temperature carry sensor noise.  ``block_*`` are true values at each
    block's first sample.
    """

    block_stamps: np.ndarray
    sample_rate: float
    samples: np.ndarray
    joint_stamps: np.ndarray
    joint_angles: np.ndarray
    joint_speeds: np.ndarray
    load_stamps: np.ndarray
    loads: np.ndarray
    temperature_stamps: np.ndarray
    temperatures: np.ndarray
    block_speeds: np.ndarray
    block_angles: np.ndarray
    block_loads: np.ndarray
    block_temperatures: np.ndarray


def _stamps_ns(origin_ns: int, indices: np.ndarray, rate: float) -> np.ndarray:
    return origin_ns + np.rint(indices * (1e9 / rate)).astype(np.int64)


def _index_range(start: float, stop: float, rate: float) -> np.ndarray:
    """Indices k with k / rate in [start, stop)."""
    return np.arange(math.ceil(start * rate - 1e-9), math.ceil(stop * rate - 1e-9), dtype=np.int64)


class RigStream:
    """The rig's state machine: turns a :class:`DriveProgram` into sensor data block by block.

    Carries the resonator state, the harmonic phases, the temperature and the
    revolutions since the last lubrication across calls; random numbers come
    from independent streams of ``seed``, so the samples do not depend on how
    the time is cut into chunks.
    """

    def __init__(self, rig: RigConfig, program: DriveProgram, *, seed: int | np.random.SeedSequence = 0,
                 effects: Effects | None = None, origin_ns: int | None = None):
        """Prepare the filters and random streams; simulated time zero is stamped ``origin_ns``."""
        self.rig, self.program, self.effects = rig, program, effects or Effects()
        self.origin_ns = rig.epoch_ns if origin_ns is None else int(origin_ns)
        sequence = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
        (self._contact_rng, self._sensor_rng, self._background_rng, self._load_rng,
         self._temperature_rng, phase_rng) = (np.random.default_rng(s) for s in sequence.spawn(6))
        fs = rig.vibration_rate
        self._b, self._a = iirpeak(rig.contact_mode_frequency, 1.0 / (2.0 * rig.contact_mode_damping), fs)
        self._contact_gain = math.sqrt(resonator_energy(self._b, self._a))
        decay = 1.0 / (2.0 * math.pi * rig.contact_mode_frequency * rig.contact_mode_damping)
        warm_up = self._contact_rng.standard_normal(int(math.ceil(30.0 * decay * fs)) + 8)
        _, self._contact_state = lfilter(self._b, self._a, warm_up, zi=np.zeros(2))
        self._orders = np.array(rig.resolved_harmonic_orders)
        self._harmonic_amplitudes = np.sqrt(2.0 * np.array(rig.harmonic_shares))
        self._harmonic_phases = phase_rng.uniform(0.0, 2.0 * math.pi, self._orders.size)
        background = self.effects.background_vibration
        tones = len(background.tone_frequencies) if background is not None else 0
        self._tone_phases = phase_rng.uniform(0.0, 2.0 * math.pi, tones)
        self._next_index: int | None = None
        self._last_angle = float(program.motion(0.0)[0])
        self.temperature = rig.ambient_temperature
        self.revolutions = 0.0

    def relubricate(self) -> None:
        """Oil injected: the revolutions since the last lubrication restart at zero."""
        self.revolutions = 0.0

    def _relax_temperature(self, duration: float) -> None:
        thermal = self.effects.thermal_viscosity
        if thermal is not None and duration > 0:
            ambient = self.rig.ambient_temperature
            self.temperature = ambient + (self.temperature - ambient) * math.exp(-duration / thermal.time_constant)

    def _temperatures(self, speeds: np.ndarray) -> np.ndarray:
        thermal = self.effects.thermal_viscosity
        if thermal is None:
            return np.full(speeds.size, self.rig.ambient_temperature)
        decay = math.exp(-1.0 / (self.rig.vibration_rate * thermal.time_constant))
        target = self.rig.ambient_temperature + thermal.temperature_rise * (np.abs(speeds) > STANDSTILL_SPEED)
        result, _ = lfilter([1.0 - decay], [1.0, -decay], target, zi=[decay * self.temperature])
        self.temperature = float(result[-1])
        return result

    def advance(self, first_block: int, stop_block: int, theta_oil: float) -> RigChunk:
        """Sensor data for blocks ``[first_block, stop_block)`` at lubrication ``theta_oil``.

        Blocks must come in increasing order; a gap (e.g. between stages) is
        standstill as far as the temperature is concerned.
        """
        rig, fs, size = self.rig, self.rig.vibration_rate, self.rig.block_size
        first, count = first_block * size, (stop_block - first_block) * size
        if self._next_index is not None:
            _require(first >= self._next_index, 'rig stream: blocks must advance in time')
            self._relax_temperature((first - self._next_index) / fs)
        self._next_index = first + count
        indices = np.arange(first, first + count, dtype=np.int64)
        times = indices / fs
        angles, speeds = self.program.motion(times)
        applied = self.program.load(times)

        steps = np.abs(np.diff(angles, prepend=self._last_angle)) / (2.0 * math.pi)
        revolutions = self.revolutions + np.cumsum(steps)
        self.revolutions = float(revolutions[-1])
        self._last_angle = float(angles[-1])
        temperatures = self._temperatures(speeds)
        nut_positions = self.rig.actuator.nut_travel_from_angle(angles, 0.0)
        amplitude = thread_contact_amplitude(speeds, applied, theta_oil, rig, self.effects,
                                             nut_position=nut_positions, temperature=temperatures,
                                             revolutions=revolutions)

        contact, self._contact_state = lfilter(self._b, self._a, self._contact_rng.standard_normal(count),
                                               zi=self._contact_state)
        mix = math.sqrt(rig.contact_share) / self._contact_gain * contact
        for order, scale, phase in zip(self._orders, self._harmonic_amplitudes, self._harmonic_phases):
            mix += scale * np.sin(order * angles + phase)
        signal = amplitude * mix
        background = self.effects.background_vibration
        if background is not None:
            part = np.zeros(count)
            for frequency, share, phase in zip(background.tone_frequencies, background.tone_shares,
                                               self._tone_phases):
                part += math.sqrt(2.0 * share) * np.sin(2.0 * math.pi * frequency * times + phase)
            if background.broadband_share > 0:
                part += math.sqrt(background.broadband_share) * self._background_rng.standard_normal(count)
            signal += background.rms * part
        signal += rig.sensor_noise * self._sensor_rng.standard_normal(count)

        start, stop = first / fs, (first + count) / fs
        joint_index = _index_range(start, stop, rig.joint_state_rate)
        joint_angles, joint_speeds = self.program.motion(joint_index / rig.joint_state_rate)
        load_index = _index_range(start, stop, rig.load_rate)
        true_loads = self.program.load(load_index / rig.load_rate)
        sigma = rig.load_noise_relative * np.abs(true_loads) + rig.load_noise_absolute
        loads = true_loads + sigma * self._load_rng.standard_normal(load_index.size)
        temperature_index = _index_range(start, stop, rig.temperature_rate)
        position = np.clip(np.floor((temperature_index / rig.temperature_rate - start) * fs + 1e-6)
                           .astype(np.int64), 0, count - 1)
        measured_temperatures = (temperatures[position] + rig.temperature_noise
                                 * self._temperature_rng.standard_normal(temperature_index.size))
        heads = np.arange(0, count, size)
        return RigChunk(
            block_stamps=_stamps_ns(self.origin_ns, indices[heads], fs), sample_rate=fs,
            samples=signal.astype(np.float32).reshape(-1, size),
            joint_stamps=_stamps_ns(self.origin_ns, joint_index, rig.joint_state_rate),
            joint_angles=joint_angles, joint_speeds=joint_speeds,
            load_stamps=_stamps_ns(self.origin_ns, load_index, rig.load_rate), loads=loads,
            temperature_stamps=_stamps_ns(self.origin_ns, temperature_index, rig.temperature_rate),
            temperatures=measured_temperatures, block_speeds=speeds[heads], block_angles=angles[heads],
            block_loads=applied[heads], block_temperatures=temperatures[heads])


def resonator_energy(b, a, tolerance: float = 1e-14) -> float:
    """Energy sum(h[n]^2) of a stable IIR filter's impulse response: its output variance for unit white input."""
    length = 1024
    while True:
        impulse = np.zeros(length)
        impulse[0] = 1.0
        response = lfilter(b, a, impulse)
        energy = float(np.sum(response ** 2))
        if np.sum(response[-length // 4:] ** 2) <= tolerance * energy:
            return energy
        length *= 2


# ---------------------------------------------------------------------------------------------
# Live generator
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RigBlock:
    """One vibration block from :class:`RigSignalGenerator`.

    stamp in s since the epoch (first sample), samples float32 m/s^2 at
    sample_rate; speed (rad/s), angle (rad), load (N, applied) and temperature
    (degC) are true values at ``stamp``; ``topics`` holds all sensor messages
    of the block's time span (joint states, noisy load and temperature).
    """

    stamp: float
    sample_rate: float
    samples: np.ndarray
    speed: float
    angle: float
    load: float
    temperature: float
    topics: RigChunk


class RigSignalGenerator:
    """The simulated rig in real time: set speed, load and theta while it runs; take block after block.

    Speed changes ramp at ``rig.live_acceleration`` (rad/s^2), load changes over
    ``rig.load_ramp_time`` per 200 N (a step if that time is 0).
    Changes act from the next block on.
    """

    def __init__(self, rig: RigConfig | None = None, *, seed: int = 0, effects: Effects | None = None,
                 theta_oil: float = 1.0, start_stamp_ns: int | None = None):
        """Rig at standstill and unloaded at ``start_stamp_ns`` (default: the rig's epoch)."""
        self.rig = rig or RigConfig()
        self.theta_oil = theta_oil
        self._program = DriveProgram()
        self._stream = RigStream(self.rig, self._program, seed=seed, effects=effects,
                                 origin_ns=start_stamp_ns)
        self._block = 0

    @property
    def now(self) -> float:
        """Simulated time of the next block's first sample, s since start."""
        return self._block * self.rig.vibration_block

    def set_speed(self, speed: float) -> None:
        """Command the screw speed in rad/s (signed)."""
        self._program.forget_before(self.now)
        self._program.command_speed(self.now, _number('speed', speed), self.rig.live_acceleration)

    def set_load(self, load: float) -> None:
        """Command the applied axial load in N."""
        rate = 200.0 / self.rig.load_ramp_time if self.rig.load_ramp_time > 0 else 0.0
        self._program.forget_before(self.now)
        self._program.command_load(self.now, _number('load', load), rate)

    def set_theta(self, theta_oil: float) -> None:
        """Set the true lubrication supply factor from the next block on."""
        self.theta_oil = _number('theta_oil', theta_oil)

    def relubricate(self, theta_oil: float | None = None) -> None:
        """Inject oil: restart the depletion count and optionally set a new theta."""
        if theta_oil is not None:
            self.set_theta(theta_oil)
        self._stream.relubricate()

    def next_block(self) -> RigBlock:
        """The next vibration block and the sensor data of its time span."""
        chunk = self._stream.advance(self._block, self._block + 1, self.theta_oil)
        self._block += 1
        return RigBlock(stamp=int(chunk.block_stamps[0]) * 1e-9, sample_rate=chunk.sample_rate,
                        samples=chunk.samples[0], speed=float(chunk.block_speeds[0]),
                        angle=float(chunk.block_angles[0]), load=float(chunk.block_loads[0]),
                        temperature=float(chunk.block_temperatures[0]), topics=chunk)

    def __iter__(self) -> Iterator[RigBlock]:
        """Blocks for ever."""
        while True:
            yield self.next_block()


# ---------------------------------------------------------------------------------------------
# Recording
# ---------------------------------------------------------------------------------------------
def _latencies(rng: np.random.Generator, rig: RigConfig, count: int) -> np.ndarray:
    seconds = rig.transport_latency + (rng.exponential(rig.latency_jitter, count)
                                       if rig.latency_jitter > 0 else np.zeros(count))
    return np.rint(seconds * 1e9).astype(np.int64)


def _record(path: Path, storage: str, stream: RigStream, first_block: int, stop_block: int,
            theta_oil: float, latency_rng: np.random.Generator,
            progress: Callable[[int], None] | None, compression: str | None = None) -> None:
    """Write blocks ``[first_block, stop_block)`` of the stream to a new bag."""
    rig = stream.rig
    step = max(1, int(round(CHUNK_DURATION / rig.vibration_block)))
    block_ns = int(round(rig.vibration_block * 1e9))
    with ContractBagWriter(path, storage=storage, namespace=rig.namespace, compression=compression) as writer:
        for start in range(first_block, stop_block, step):
            stop = min(start + step, stop_block)
            chunk = stream.advance(start, stop, theta_oil)
            writer.add_vibration(chunk.block_stamps,
                                 chunk.block_stamps + block_ns + _latencies(latency_rng, rig,
                                                                            len(chunk.block_stamps)),
                                 chunk.sample_rate, chunk.samples, rig.vibration_frame_id)
            writer.add_joint_states(chunk.joint_stamps, chunk.joint_stamps
                                    + _latencies(latency_rng, rig, chunk.joint_stamps.size),
                                    chunk.joint_angles, chunk.joint_speeds)
            writer.add_axial_loads(chunk.load_stamps, chunk.load_stamps
                                   + _latencies(latency_rng, rig, chunk.load_stamps.size),
                                   chunk.loads, rig.load_frame_id)
            writer.add_temperatures(chunk.temperature_stamps, chunk.temperature_stamps
                                    + _latencies(latency_rng, rig, chunk.temperature_stamps.size),
                                    chunk.temperatures, rig.temperature_noise ** 2, rig.temperature_frame_id)
            writer.flush(stream.origin_ns + stop * block_ns)
            if progress is not None:
                progress(stop - start)


def _blocks(seconds: float, rig: RigConfig) -> int:
    """Whole vibration blocks covering ``seconds`` (rounded up)."""
    return int(math.ceil(seconds / rig.vibration_block - 1e-9))


def _streams(seed: int) -> tuple[np.random.SeedSequence, np.random.Generator, np.random.Generator]:
    rig_seed, latency_seed, order_seed = np.random.SeedSequence(seed).spawn(3)
    return rig_seed, np.random.default_rng(latency_seed), np.random.default_rng(order_seed)


def session_revolutions(plan: ExperimentPlan, rig: RigConfig) -> float:
    """Screw revolutions of one session (all conditions, forward and rewind)."""
    return 2.0 * len(plan.conditions) * plan.stroke / rig.actuator.lead


def draw_effects(names: Sequence[str], *, seed: int = 0, rig: RigConfig | None = None,
                 plan: ExperimentPlan | None = None) -> Effects:
    """Effects ``names`` (IDs of :data:`sim_effects.EFFECT_IDS`) with parameters drawn in their physical ranges.

    The ranges refer to the plan: stroke, lowest load, top speed, one session's
    revolutions and the thread-contact amplitude at the lowest speed, highest
    load and theta = 1.
    """
    rig, plan = rig or RigConfig(), plan or ExperimentPlan()
    unknown = sorted(set(names) - set(EFFECT_IDS))
    _require(not unknown, f'effects: unknown effect(s) {", ".join(unknown)}; known: {", ".join(EFFECT_IDS)}')
    rngs = dict(zip(EFFECT_IDS, (np.random.default_rng(s) for s in
                                 np.random.SeedSequence(seed).spawn(len(EFFECT_IDS)))))
    actuator = rig.actuator
    makers = {
        'position_dependent_stiffness': lambda rng: draw_position_dependent_stiffness(
            rng, youngs_modulus=actuator.youngs_modulus, root_diameter=actuator.shaft_root_diameter,
            stroke=plan.stroke, fixed_end_offset=actuator.shaft_fixed_end_offset,
            reference_load=min(plan.loads)),
        'resonance': lambda rng: draw_resonance(rng, order=rig.roller_pass_order, top_speed=max(plan.speeds)),
        'thermal_viscosity': lambda rng: draw_thermal_viscosity(
            rng, viscosity_temperature_coefficient=actuator.viscosity_temperature_coefficient),
        'lubricant_depletion': lambda rng: draw_lubricant_depletion(
            rng, session_revolutions=session_revolutions(plan, rig)),
        'background_vibration': lambda rng: draw_background_vibration(
            rng, reference_amplitude=float(thread_contact_amplitude(min(plan.speeds), max(plan.loads),
                                                                    1.0, rig))),
    }
    return Effects(**{name: makers[name](rngs[name]) for name in names})


def _truth(rig: RigConfig, plan: ExperimentPlan | None, seed: int, effects: Effects, storage: str,
           bags: list[dict]) -> dict:
    return {'generator': 'prsm_lube_ros.rig_simulator', 'seed': seed, 'storage': storage,
            'constants': asdict(rig.constants), 'rig': rig.as_dict(),
            'plan': plan.as_dict() if plan is not None else None,
            'effects': effects.as_dict(), 'bags': bags}


def _origin_seconds(stream: RigStream) -> float:
    return stream.origin_ns * 1e-9


def simulate_experiment(out_dir: str | Path, *, plan: ExperimentPlan | None = None,
                        rig: RigConfig | None = None, seed: int = 0, effects: Effects | None = None,
                        storage: str = 'mcap', run_order: str | None = None,
                        stage_thetas: Sequence[float] | None = None,
                        progress: ProgressCallback | None = None, compression: str | None = None) -> list[Path]:
    """Record the paper's experiment: one bag per lubrication stage in ``out_dir``, plus ``truth.json``.

    Bags are named ``stage_1``, ``stage_2``, ... (storage per
    :data:`bag_writer.STORAGE_FORMATS`); each holds the plan's conditions as
    forward runs with rewinds in between.  ``run_order`` (``'fixed'`` or
    ``'random'``, seeded) and ``stage_thetas`` (true theta_Oil per stage)
    override the plan's.  Stages follow each other after
    ``plan.stage_pause``.  ``progress(done_s, total_s)`` is called with simulated
    seconds.  ``compression='zstd'`` compresses the mcap chunks.  Returns the bag paths.
    """
    rig, plan, effects = rig or RigConfig(), plan or ExperimentPlan(), effects or Effects()
    check_storage(storage)
    if run_order is not None:
        plan = replace(plan, run_order=run_order)
    if stage_thetas is not None:
        plan = replace(plan, stage_thetas=tuple(stage_thetas))
    out_dir = Path(out_dir)
    rig_seed, latency_rng, order_rng = _streams(seed)

    program = DriveProgram()
    schedule, now = [], 0.0
    for number, theta in enumerate(plan.stage_thetas, start=1):
        conditions = plan.conditions
        if plan.run_order == 'random':
            conditions = [conditions[k] for k in order_rng.permutation(len(conditions))]
        first_block = _blocks(now, rig)
        strokes, end = schedule_session(program, first_block * rig.vibration_block, conditions, plan, rig)
        stop_block = _blocks(end, rig)
        schedule.append((f'stage_{number}', theta, first_block, stop_block, strokes))
        now = stop_block * rig.vibration_block + plan.stage_pause
    paths = [bag_path(out_dir, name, storage) for name, *_ in schedule]
    for path in paths + [out_dir / 'truth.json']:
        _require(not path.exists(), f'{path}: exists already, not overwriting')

    stream = RigStream(rig, program, seed=rig_seed, effects=effects)
    total = sum(stop - first for _, _, first, stop, _ in schedule)
    done = 0

    def advance(blocks: int) -> None:
        nonlocal done
        done += blocks
        if progress is not None:
            progress(done * rig.vibration_block, total * rig.vibration_block)

    bags = []
    origin = _origin_seconds(stream)
    for (name, theta, first, stop, strokes), path in zip(schedule, paths):
        stream.relubricate()
        _record(path, storage, stream, first, stop, theta, latency_rng, advance, compression)
        bags.append({'name': name, 'path': path.name, 'theta_oil': theta,
                     'start': origin + first * rig.vibration_block,
                     'end': origin + stop * rig.vibration_block,
                     'runs': [_run_truth(stroke, origin, theta, rig) for stroke in strokes]})
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / 'truth.json').write_text(json.dumps(_truth(rig, plan, seed, effects, storage, bags), indent=2))
    return paths


def _run_truth(stroke: Stroke, origin: float, theta: float, rig: RigConfig) -> dict:
    result = stroke.as_dict(origin)
    result['eq22_amplitude'] = float(thread_contact_amplitude(stroke.speed, stroke.load, theta, rig))
    return result


def simulate_endurance(path: str | Path, duration: float, *, plan: ExperimentPlan | None = None,
                       rig: RigConfig | None = None, seed: int = 0, effects: Effects | None = None,
                       storage: str = 'mcap', theta_oil: float = 1.0, truth_path: str | Path | None = None,
                       progress: ProgressCallback | None = None, compression: str | None = None) -> Path:
    """One long bag at ``path``: the plan's conditions cycled (with rewinds) for ``duration`` s.

    For benchmarks and long-term effects; lubricated once at the start with
    ``theta_oil``.  Writes the truth to ``truth_path`` if given; ``compression='zstd'``
    compresses the mcap chunks.  Returns ``path``.
    """
    rig, plan, effects = rig or RigConfig(), plan or ExperimentPlan(), effects or Effects()
    check_storage(storage)
    duration = _number('duration', duration)
    _require(duration > 0, f'duration must be > 0 s, got {duration}')
    path = Path(path)
    rig_seed, latency_rng, _ = _streams(seed)
    program = DriveProgram()
    strokes, now = [], 0.0
    while now < duration:
        more, now = schedule_session(program, now, plan.conditions, plan, rig)
        now -= plan.standstill  # sessions join with a single standstill
        strokes += more
    stop_block = _blocks(duration, rig)
    stream = RigStream(rig, program, seed=rig_seed, effects=effects)
    total = stop_block * rig.vibration_block
    done = 0

    def advance(blocks: int) -> None:
        nonlocal done
        done += blocks
        if progress is not None:
            progress(done * rig.vibration_block, total)

    _record(path, storage, stream, 0, stop_block, theta_oil, latency_rng, advance, compression)
    if truth_path is not None:
        origin = _origin_seconds(stream)
        kept = [stroke for stroke in strokes if stroke.start < total]
        bag = {'name': path.stem, 'path': path.name, 'theta_oil': theta_oil, 'start': origin,
               'end': origin + total, 'runs': [_run_truth(s, origin, theta_oil, rig) for s in kept]}
        Path(truth_path).write_text(json.dumps(_truth(rig, plan, seed, effects, storage, [bag]), indent=2))
    return path
