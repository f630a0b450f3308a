# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Acceleration of the simulated rig: the true amplitude (Eq. 22 and effects), its time signal, streamed or live."""
from __future__ import annotations

from dataclasses import dataclass
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.signal import iirpeak, lfilter

from ..physics.effects import ContactBroadband, ContactState, resonator_energy, SampleState, StreamRandom
from ..physics.vibration_model import acceleration_amplitude
from ..validation import as_number, require
from .drive import DriveProgram
from .effects import Effects
from .rig_config import RigConfig, STANDSTILL_SPEED


__all__ = ['RigBlock', 'RigChunk', 'RigSignalGenerator', 'RigStream', 'WANDER_TERMS', 'effective_load',
           'expected_rms', 'thread_contact_amplitude']


# ---------------------------------------------------------------------------------------------
# Truth: the amplitude the signal is scaled to
# ---------------------------------------------------------------------------------------------
def effective_load(applied_load: npt.ArrayLike, rig: RigConfig) -> np.ndarray:
    """Load the thread contacts carry, N: the applied load, but at least the nut preload."""
    return np.maximum(np.abs(np.asarray(applied_load, dtype=float)), rig.nut_preload)


def thread_contact_amplitude(screw_speed: npt.ArrayLike, applied_load: npt.ArrayLike, theta_oil: npt.ArrayLike,
                             rig: RigConfig, effects: Effects | None = None, *, nut_position: npt.ArrayLike = 0.0,
                             temperature: npt.ArrayLike | None = None,
                             revolutions: npt.ArrayLike = 0.0) -> np.ndarray:
    """True RMS of the thread-contact vibration, m/s^2: Eq. 22 changed by the active effects.

    screw_speed in rad/s, applied_load in N (preload as floor), theta_oil the
    stage's lubrication; nut_position in m from the start of the stroke,
    temperature in degC (None = ambient), revolutions since the last
    lubrication.  Background vibration and sensor noise are not included:
    the recorded RMS is ``sqrt(A^2 + B^2 + sigma_n^2)``.
    """
    effects = effects or Effects()
    load = effective_load(applied_load, rig)
    state = ContactState(speed=screw_speed, load=load, nut_position=nut_position, temperature=temperature,
                         ambient_temperature=rig.ambient_temperature, revolutions=revolutions)
    hooks = list(effects.hooks())
    theta = np.asarray(theta_oil, dtype=float)
    for hook, law in sorted(hooks, key=lambda pair: pair[0].film_rank):   # stable: registry order among equals
        theta = theta * hook.film_factor(law, state)
    amplitude = acceleration_amplitude(np.asarray(screw_speed, dtype=float), load, theta, rig.constants)
    for hook, law in hooks:
        amplitude = amplitude * hook.amplitude_factor(law, state)
    return amplitude


def _added_power(effects: Effects, state: ContactState) -> np.ndarray | float:
    """Mean square (m/s^2)^2 the active effects add beside the thread contacts (background, impacts)."""
    power: np.ndarray | float = 0.0
    for hook, law in effects.hooks():
        power = power + hook.added_power(law, state)
    return power


def expected_rms(screw_speed: npt.ArrayLike, applied_load: npt.ArrayLike, theta_oil: npt.ArrayLike,
                 rig: RigConfig, effects: Effects | None = None, **state: Any) -> np.ndarray:
    """RMS the recording should show in steady running, m/s^2: contact, background and sensor noise in power."""
    effects = effects or Effects()
    contact = thread_contact_amplitude(screw_speed, applied_load, theta_oil, rig, effects, **state)
    where = ContactState(speed=screw_speed, load=effective_load(applied_load, rig),
                         nut_position=state.get('nut_position', 0.0), temperature=state.get('temperature'),
                         ambient_temperature=rig.ambient_temperature, revolutions=state.get('revolutions', 0.0))
    return np.sqrt(contact ** 2 + _added_power(effects, where) + rig.sensor_noise ** 2)


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


#: Sinusoids summed into the slow wander of the set-up (:attr:`RigConfig.run_wander`).
WANDER_TERMS = 4


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
        # Each effect's own waveform (a ringing mode, added vibration), made in registry order.
        random = StreamRandom(sequence=sequence, phases=phase_rng, added=self._background_rng,
                              contact=ContactBroadband(rig.contact_share, rig.contact_mode_frequency,
                                                       rig.contact_mode_damping))
        self._waveforms = [waveform for hook, law in self.effects.hooks()
                           if (waveform := hook.waveform(law, fs, random)) is not None]
        heating = [h for hook, law in self.effects.hooks() if (h := hook.heating(law)) is not None]
        #: Temperature rise (K) and time constant (s) of nut and oil while running, or None.
        self._heating = heating[0] if heating else None
        # Set-up scatter: keyed off the seed without spawning from it (the caller's sequence is left as it was).
        self._set_up_key = (sequence.entropy, tuple(sequence.spawn_key) + (1000,))
        wander_rng = np.random.default_rng(np.random.SeedSequence(sequence.entropy,
                                                                  spawn_key=self._set_up_key[1] + (1,)))
        self._wander_periods = wander_rng.uniform(*rig.wander_period, WANDER_TERMS)
        self._wander_phases = wander_rng.uniform(0.0, 2.0 * math.pi, WANDER_TERMS)
        self._next_index: int | None = None
        self._last_angle = float(program.motion(0.0)[0])
        # A warm (or cooled) actuator at the start: the nut relaxes from there (thermal effect only).
        self.temperature = rig.ambient_temperature + rig.initial_temperature_offset
        self.revolutions = 0.0

    def relubricate(self) -> None:
        """Oil injected: the revolutions since the last lubrication restart at zero."""
        self.revolutions = 0.0

    def _relax_temperature(self, duration: float) -> None:
        if self._heating is not None and duration > 0:
            ambient, time_constant = self.rig.ambient_temperature, self._heating[1]
            self.temperature = ambient + (self.temperature - ambient) * math.exp(-duration / time_constant)

    def _temperatures(self, speeds: np.ndarray) -> np.ndarray:
        if self._heating is None:
            return np.full(speeds.size, self.rig.ambient_temperature)
        rise, time_constant = self._heating
        decay = math.exp(-1.0 / (self.rig.vibration_rate * time_constant))
        target = self.rig.ambient_temperature + rise * (np.abs(speeds) > STANDSTILL_SPEED)
        result, _ = lfilter([1.0 - decay], [1.0, -decay], target, zi=[decay * self.temperature])
        self.temperature = float(result[-1])
        return result

    def _set_up_factor(self, times: np.ndarray, speeds: np.ndarray) -> np.ndarray:
        """Amplitude factor of the set-up: one log-normal draw per traverse times a slow wander of time.

        Each traverse (stroke of the drive program) has its own factor
        ``exp(run_scatter z_k)`` (sensor coupling, preload, temperature), drawn
        from the seed and the traverse number alone, so chunking changes
        nothing; the wander is ``run_wander sqrt(2 / J) sum_j sin(2 pi t / T_j + phi_j)``.
        Physics the diagnosis catalogue does not have: from the traverse at the
        fraction ``mount_step_at`` of all traverses on, the amplitude is
        ``1 + mount_step`` times higher (the sensor re-seated); traverses with a
        negative screw speed (the loaded return) are ``return_factor`` times
        higher (flank loading, backlash, preload differing by direction).
        """
        rig = self.rig
        log_factor = np.zeros(times.size)
        if rig.mount_step:
            starts = np.asarray(self.program.traverse_starts, dtype=float)
            traverse = np.searchsorted(starts, times, side='right') - 1
            log_factor[traverse >= int(rig.mount_step_at * starts.size)] += math.log1p(rig.mount_step)
        if rig.return_factor != 1.0:
            log_factor[speeds < -STANDSTILL_SPEED] += math.log(rig.return_factor)
        if rig.run_scatter:
            starts = np.asarray(self.program.traverse_starts, dtype=float)
            traverse = np.clip(np.searchsorted(starts, times, side='right') - 1, 0, None)
            entropy, key = self._set_up_key
            for k in np.unique(traverse).tolist():
                z = np.random.default_rng(np.random.SeedSequence(entropy, spawn_key=key + (2, k))).standard_normal()
                log_factor[traverse == k] += rig.run_scatter * z
        if rig.run_wander:
            phases = 2.0 * math.pi * times[:, None] / self._wander_periods[None, :] + self._wander_phases[None, :]
            log_factor += rig.run_wander * math.sqrt(2.0 / WANDER_TERMS) * np.sin(phases).sum(axis=1)
        return np.exp(log_factor)

    def _true_amplitude(self, angles: np.ndarray, speeds: np.ndarray, applied: np.ndarray,
                        theta_oil: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """True nut temperatures, thread-contact amplitude and revolutions since the last lubrication per sample.

        Advances revolutions and angle.
        """
        steps = np.abs(np.diff(angles, prepend=self._last_angle)) / (2.0 * math.pi)
        revolutions = self.revolutions + np.cumsum(steps)
        self.revolutions = float(revolutions[-1])
        self._last_angle = float(angles[-1])
        temperatures = self._temperatures(speeds)
        nut_positions = self.rig.actuator.nut_travel_from_angle(angles, 0.0)
        amplitude = thread_contact_amplitude(speeds, applied, theta_oil, self.rig, self.effects,
                                             nut_position=nut_positions, temperature=temperatures,
                                             revolutions=revolutions)
        return temperatures, amplitude, revolutions

    def _signal(self, state: SampleState) -> np.ndarray:
        """The recorded acceleration per sample: thread contacts, the effects' waveforms, set-up, noise."""
        rig, times, angles, speeds, count = self.rig, state.times, state.angles, state.speeds, state.times.size
        contact, self._contact_state = lfilter(self._b, self._a, self._contact_rng.standard_normal(count),
                                               zi=self._contact_state)
        mix = math.sqrt(rig.contact_share) / self._contact_gain * contact
        for order, scale, phase in zip(self._orders, self._harmonic_amplitudes, self._harmonic_phases):
            mix += scale * np.sin(order * angles + phase)
        for waveform in self._waveforms:
            mix = waveform.shape(mix, state)
        signal = state.contact_amplitude * mix
        for waveform in self._waveforms:
            signal += waveform.add(state)
        if rig.run_scatter or rig.run_wander or rig.mount_step or rig.return_factor != 1.0:
            signal *= self._set_up_factor(times, speeds)
        signal += rig.sensor_noise * self._sensor_rng.standard_normal(count)
        return signal

    def advance(self, first_block: int, stop_block: int, theta_oil: float) -> RigChunk:
        """Sensor data for blocks ``[first_block, stop_block)`` at lubrication ``theta_oil``.

        Blocks must come in increasing order; a gap (e.g. between stages) is
        standstill as far as the temperature is concerned.
        """
        rig, fs, size = self.rig, self.rig.vibration_rate, self.rig.block_size
        first, count = first_block * size, (stop_block - first_block) * size
        if self._next_index is not None:
            require(first >= self._next_index, 'rig stream: blocks must advance in time')
            self._relax_temperature((first - self._next_index) / fs)
        self._next_index = first + count
        indices = np.arange(first, first + count, dtype=np.int64)
        times = indices / fs
        angles, speeds = self.program.motion(times)
        applied = self.program.load(times)

        temperatures, amplitude, revolutions = self._true_amplitude(angles, speeds, applied, theta_oil)
        signal = self._signal(SampleState(times=times, angles=angles, speeds=speeds, loads=applied,
                                          revolutions=revolutions, contact_amplitude=amplitude))

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
    Changes act from the next block on.  The nut starts at one end of its
    stroke (``rig.actuator.nut_travel``) and reverses at both ends, as the
    rig does: the speed ramps from the commanded speed to its opposite so
    that it passes zero where the nut reaches the end (the load stays as
    commanded).
    """

    #: Instants per block at which the stroke ends are looked for.
    REVERSAL_STEPS = 200

    def __init__(self, rig: RigConfig | None = None, *, seed: int = 0, effects: Effects | None = None,
                 theta_oil: float = 1.0, start_stamp_ns: int | None = None):
        """Rig at standstill and unloaded at ``start_stamp_ns`` (default: the rig's epoch)."""
        self.rig = rig or RigConfig()
        self.theta_oil = theta_oil
        self._program = DriveProgram()
        self._stream = RigStream(self.rig, self._program, seed=seed, effects=effects,
                                 origin_ns=start_stamp_ns)
        self._block = 0
        self._target_speed = 0.0
        # Screw angles of the stroke ends (rad): nut travel 0 .. nut_travel (Eq. of CONTRACT.md, inverted).
        self._angle_limits = (0.0, 2.0 * math.pi * self.rig.actuator.nut_travel / self.rig.actuator.lead)

    @property
    def now(self) -> float:
        """Simulated time of the next block's first sample, s since start."""
        return self._block * self.rig.vibration_block

    def set_speed(self, speed: float) -> None:
        """Command the screw speed in rad/s (signed)."""
        self._target_speed = as_number('speed', speed)
        self._program.forget_before(self.now)
        self._program.command_speed(self.now, self._target_speed, self.rig.live_acceleration)

    def set_load(self, load: float) -> None:
        """Command the applied axial load in N."""
        rate = 200.0 / self.rig.load_ramp_time if self.rig.load_ramp_time > 0 else 0.0
        self._program.forget_before(self.now)
        self._program.command_load(self.now, as_number('load', load), rate)

    def set_theta(self, theta_oil: float) -> None:
        """Set the true lubrication supply factor from the next block on."""
        self.theta_oil = as_number('theta_oil', theta_oil)

    def relubricate(self, theta_oil: float | None = None) -> None:
        """Inject oil: restart the depletion count and optionally set a new theta."""
        if theta_oil is not None:
            self.set_theta(theta_oil)
        self._stream.relubricate()

    def _reverse_at_stroke_ends(self) -> None:
        """Command the opposite speed at the first instant of the next block where braking must begin.

        Braking at ``live_acceleration`` a from speed w takes w^2 / (2 a) rad;
        the reversal is commanded when that distance reaches the stroke end
        the screw is heading for, looked for on a grid of
        :attr:`REVERSAL_STEPS` instants (the nut overshoots by at most one
        grid step of travel).
        """
        if self._target_speed == 0.0:
            return
        acceleration = self.rig.live_acceleration
        times = self.now + np.linspace(0.0, self.rig.vibration_block, self.REVERSAL_STEPS + 1)
        angles, speeds = self._program.motion(times)
        stops = angles + np.sign(speeds) * speeds ** 2 / (2.0 * acceleration)
        low, high = self._angle_limits
        heading = np.sign(self._target_speed)
        beyond = stops >= high if heading > 0 else stops <= low
        beyond &= np.sign(speeds) != -heading
        if not beyond.any():
            return
        when = float(times[int(np.argmax(beyond))])
        self._target_speed = -self._target_speed
        self._program.command_speed(when, self._target_speed, acceleration)

    def next_block(self) -> RigBlock:
        """The next vibration block and the sensor data of its time span."""
        self._reverse_at_stroke_ends()
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
