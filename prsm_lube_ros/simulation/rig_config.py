# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Configuration of the simulated rig and of the experiment it runs (``config/rig_simulator.yaml``)."""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from datetime import datetime, timezone
import math
from pathlib import Path
from collections.abc import Callable


from ..config_file import build, coerce_fields, read_section
from ..errors import InputError
from ..physics.actuator import Actuator, load_actuator
from ..physics.kinematics import roller_revolution_speed
from ..physics.vibration_model import ModelConstants
from ..validation import as_number, require


__all__ = ['CHUNK_DURATION', 'ExperimentPlan', 'ProgressCallback', 'ROLLER_PASS', 'RPM', 'RigConfig',
           'STANDSTILL_SPEED', 'load_experiment_plan', 'load_rig_config']

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
    run_scatter: float = 0.0
    run_wander: float = 0.0
    wander_period: tuple[float, float] = (20.0, 120.0)
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
    # Physics outside the diagnosis catalogue and temperature histories (off by default):
    mount_step: float = 0.0
    mount_step_at: float = 0.5
    return_factor: float = 1.0
    initial_temperature_offset: float = 0.0

    def __post_init__(self) -> None:
        """Check every field; raise :class:`InputError` naming the first bad one."""
        object.__setattr__(self, 'harmonic_orders', tuple(
            order if order == ROLLER_PASS else as_number('rig harmonic_orders', order)
            for order in self.harmonic_orders))
        object.__setattr__(self, 'harmonic_shares', tuple(
            as_number('rig harmonic_shares', share) for share in self.harmonic_shares))
        for name in ('c_sys', 'nut_preload', 'contact_mode_frequency', 'contact_mode_damping',
                     'vibration_rate', 'vibration_block', 'joint_state_rate', 'load_rate',
                     'temperature_rate', 'live_acceleration'):
            require(getattr(self, name) > 0, f'rig {name} must be > 0, got {getattr(self, name)!r}')
        for name in ('c_f', 'c_lambda', 'sensor_noise', 'load_noise_relative', 'load_noise_absolute',
                     'load_ramp_time', 'temperature_noise', 'transport_latency', 'latency_jitter'):
            require(getattr(self, name) >= 0, f'rig {name} must be >= 0, got {getattr(self, name)!r}')
        require(self.contact_mode_damping < 1, 'rig contact_mode_damping must be below 1')
        for name in ('run_scatter', 'run_wander'):
            require(0 <= getattr(self, name) < 0.5, f'rig {name} must lie in [0, 0.5), got {getattr(self, name)!r}')
        require(-0.5 < self.mount_step < 1.0, f'rig mount_step must lie in (-0.5, 1), got {self.mount_step!r}')
        require(0.0 < self.mount_step_at < 1.0, f'rig mount_step_at must lie in (0, 1), got {self.mount_step_at!r}')
        require(0.2 <= self.return_factor <= 5.0, f'rig return_factor must lie in [0.2, 5], got {self.return_factor!r}')
        require(abs(self.initial_temperature_offset) <= 100.0,
                f'rig initial_temperature_offset must lie within 100 K, got {self.initial_temperature_offset!r}')
        object.__setattr__(self, 'wander_period', tuple(as_number('rig wander_period', v)
                                                        for v in self.wander_period))
        require(len(self.wander_period) == 2 and 0 < self.wander_period[0] <= self.wander_period[1],
                f'rig wander_period must be [shortest, longest] s > 0, got {self.wander_period!r}')
        require(len(self.harmonic_orders) == len(self.harmonic_shares),
                'rig harmonic_orders and harmonic_shares differ in length')
        require(all(order == ROLLER_PASS or order > 0 for order in self.harmonic_orders),
                'rig harmonic_orders must be > 0')
        require(all(share >= 0 for share in self.harmonic_shares) and sum(self.harmonic_shares) < 1,
                f'rig harmonic_shares must be >= 0 and add up to less than 1, got {self.harmonic_shares}')
        size = self.vibration_rate * self.vibration_block
        require(abs(size - round(size)) < 1e-6 and round(size) >= 1,
                f'rig vibration_block x vibration_rate must be a whole number of samples, got {size}')
        require(self.contact_mode_frequency < 0.45 * self.vibration_rate,
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
        result['wander_period'] = list(self.wander_period)
        result['roller_pass_order'] = self.roller_pass_order
        return result


@dataclass(frozen=True)
class ExperimentPlan:
    """What the rig runs: the paper's 3 speeds x 2 loads after each of three lubrication steps.

    speeds in rad/s (forward feed), loads in N, stage_thetas the true theta_Oil
    after each lubrication step (one bag each), stroke and ramp_travel (per
    ramp) in m, rewind_speed in rad/s, standstill and stage_pause in s,
    run_order ``'fixed'`` (speed-major, as listed) or ``'random'`` (seeded);
    return_under_load: the return stroke runs back at the run's speed and load
    (out and back, both measured) instead of an unloaded rewind;
    cool_down_pause s of standstill after every cool_down_every runs (0: none),
    so the nut cools while the revolutions stand still.
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
    return_under_load: bool = False
    cool_down_pause: float = 0.0
    cool_down_every: int = 0

    def __post_init__(self) -> None:
        """Check every field; raise :class:`InputError` naming the first bad one."""
        for name in ('speeds', 'loads', 'stage_thetas'):
            values = tuple(as_number(f'plan {name}', value) for value in getattr(self, name))
            require(values and all(value > 0 for value in values),
                    f'plan {name} must be a non-empty list of numbers > 0, got {getattr(self, name)!r}')
            object.__setattr__(self, name, values)
        for name in ('stroke', 'ramp_travel', 'rewind_speed', 'standstill'):
            require(getattr(self, name) > 0, f'plan {name} must be > 0, got {getattr(self, name)!r}')
        require(self.stage_pause >= 0, f'plan stage_pause must be >= 0, got {self.stage_pause!r}')
        require(self.cool_down_pause >= 0, f'plan cool_down_pause must be >= 0 s, got {self.cool_down_pause!r}')
        require(int(self.cool_down_every) == self.cool_down_every and self.cool_down_every >= 0,
                f'plan cool_down_every must be a whole number of runs >= 0, got {self.cool_down_every!r}')
        require(2 * self.ramp_travel < self.stroke,
                f'plan ramp_travel {self.ramp_travel} m leaves no steady travel in the {self.stroke} m stroke')
        require(self.run_order in ('fixed', 'random'),
                f'plan run_order must be "fixed" or "random", got {self.run_order!r}')

    @property
    def conditions(self) -> list[tuple[float, float]]:
        """``(speed, load)`` pairs in the fixed order: each speed with each load."""
        return [(speed, load) for speed in self.speeds for load in self.loads]

    def as_dict(self) -> dict:
        """Plain mapping (for ``truth.json``)."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


def load_rig_config(path: str | Path | None = None) -> RigConfig:
    """Rig from the ``rig_simulator: rig:`` mapping of a YAML file; ``None`` gives the defaults.

    ``actuator_file`` (relative to the YAML file) names an actuator YAML; without
    it the contract's default actuator is used.
    """
    if path is None:
        return RigConfig()
    path = Path(path)
    values = read_section(path, ['rig_simulator', 'rig'], 'rig simulator file')
    actuator_file = values.get('actuator_file')
    actuator = load_actuator(path.parent / actuator_file) if actuator_file else Actuator()
    return build(path, RigConfig, coerce_fields(path, RigConfig, values, skip=('actuator_file', 'actuator')),
                 actuator=actuator)


def load_experiment_plan(path: str | Path | None = None) -> ExperimentPlan:
    """Plan from the ``rig_simulator: plan:`` mapping of a YAML file; ``None`` gives the paper's plan."""
    if path is None:
        return ExperimentPlan()
    values = read_section(path, ['rig_simulator', 'plan'], 'rig simulator file')
    return build(path, ExperimentPlan, coerce_fields(path, ExperimentPlan, values))
