# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The simulated rig: Eq. 22 levels, schedule, sensors, effects, recordings, reproducibility.

Expected values are worked out here from closed forms (Eq. 22 written out by
hand, trapezoidal ramps, first-order heating), not taken from the simulator.
"""
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from prsm_lube_ros.recording import typestore as interfaces
from prsm_lube_ros.errors import InputError
from prsm_lube_ros.physics.effects import resonance
from prsm_lube_ros.simulation.drive import DriveProgram, schedule_session
from prsm_lube_ros.simulation.recordings import draw_effects, simulate_endurance, simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan, load_experiment_plan, load_rig_config, RigConfig
from prsm_lube_ros.simulation.rig_acceleration import RigSignalGenerator, RigStream, thread_contact_amplitude
from prsm_lube_ros.simulation.effects import Effects
from prsm_lube_ros.physics.effects.background_vibration import BackgroundVibrationLaw
from prsm_lube_ros.physics.effects.lubricant_depletion import LubricantDepletionLaw
from prsm_lube_ros.physics.effects.position_dependent_stiffness import PositionDependentStiffnessLaw
from prsm_lube_ros.physics.effects.resonance import ResonanceLaw
from prsm_lube_ros.physics.effects.thermal_viscosity import ThermalViscosityLaw

ROOT = Path(__file__).resolve().parents[2]
RPM = 2 * math.pi / 60
RIG = RigConfig()
#: Small plan for fast tests: one condition, two stages.
TINY = ExperimentPlan(speeds=(200 * RPM,), loads=(100.0,), stage_thetas=(0.72, 1.0), stage_pause=5.0)


def eq22(speed, load, theta, c_sys=0.08, c_f=1e-3, c_lambda=0.30):
    """Eq. 22 written out: A = C_sys w^2 F^-1/3 exp(C_F F - theta C_lambda w^0.68 F^-0.073)."""
    return (c_sys * speed ** 2 * load ** (-1 / 3)
            * np.exp(c_f * load - theta * c_lambda * speed ** 0.68 * load ** -0.073))


def rms(values):
    return float(np.sqrt(np.mean(np.square(np.asarray(values, dtype=float)))))


def steady(speed, load, seconds, theta, *, effects=None, seed=0, rig=RIG):
    """Constant speed and load from time zero; returns the chunk (all samples) and the stream."""
    program = DriveProgram()
    program.append_motion(0.0, 0.0, speed)
    program.append_load(0.0, 0.0, load)
    stream = RigStream(rig, program, seed=seed, effects=effects)
    return stream.advance(0, int(round(seconds / rig.vibration_block)), theta), stream


def rms_tolerance(seconds, rig=RIG, sigmas=4.0):
    """Relative RMS tolerance of ``sigmas`` standard deviations for a steady stretch.

    The resonator output (power share p) is Gaussian with autocorrelation
    ~exp(-a|t|) cos(w t), a = zeta w_n, so the mean-power estimate over N
    samples has relative variance 2 sum(rho^2)/N with sum(rho^2) = fs/(2a);
    the RMS has half the relative error; the deterministic harmonics add ~0.2 %.
    """
    a = rig.contact_mode_damping * 2 * math.pi * rig.contact_mode_frequency
    samples = seconds * rig.vibration_rate
    power_error = math.sqrt(2 * rig.vibration_rate / (2 * a) / samples) * rig.contact_share
    return sigmas * power_error / 2 + 0.002


def read_bag(path):
    """Decoded topics of a bag as numpy arrays (stamps in s since the epoch)."""
    out = {'vibration': ([], []), 'joint_states': ([], [], []), 'axial_load': ([], []), 'temperature': ([], [])}
    logs, stamps_of = [], []
    with AnyReader([Path(path)], default_typestore=interfaces.contract_typestore()) as reader:
        topics = sorted(c.topic for c in reader.connections)
        for connection, log_time, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
            logs.append(log_time)
            stamps_of.append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
            name = connection.topic.rsplit('/', 1)[1]
            if name == 'vibration':
                out[name][0].append(stamp)
                out[name][1].append(np.asarray(msg.samples))
                assert msg.sample_rate == RIG.vibration_rate
            elif name == 'joint_states':
                assert list(msg.name) == ['screw']
                out[name][0].append(stamp)
                out[name][1].append(msg.position[0])
                out[name][2].append(msg.velocity[0])
            elif name == 'axial_load':
                out[name][0].append(stamp)
                out[name][1].append(msg.wrench.force.z)
            else:
                out[name][0].append(stamp)
                out[name][1].append(msg.temperature)
    result = {'topics': topics, 'log': np.array(logs), 'stamp_ns': np.array(stamps_of)}
    vib_stamps, blocks = out['vibration']
    result['vibration'] = (np.array(vib_stamps), np.array(blocks))
    for name in ('joint_states', 'axial_load', 'temperature'):
        result[name] = tuple(np.array(column) for column in out[name])
    return result


def window_rms(bag, start, end):
    """RMS of the vibration samples acquired in [start, end) (s since the epoch)."""
    stamps, blocks = bag['vibration']
    times = stamps[:, None] + np.arange(blocks.shape[1])[None, :] / RIG.vibration_rate
    return rms(blocks[(times >= start) & (times < end)])


# -- configuration ------------------------------------------------------------------------------

def test_shipped_config_file_holds_the_defaults():
    assert load_rig_config(ROOT / 'config' / 'rig_simulator.yaml') == RigConfig()
    plan = load_experiment_plan(ROOT / 'config' / 'rig_simulator.yaml')
    assert plan == ExperimentPlan()
    np.testing.assert_allclose(plan.speeds, [100 * RPM, 150 * RPM, 200 * RPM])
    assert plan.loads == (100.0, 200.0) and plan.stage_thetas == (0.72, 0.83, 1.0)
    assert plan.rewind_speed == pytest.approx(300 * RPM)
    assert plan.stroke - 2 * plan.ramp_travel == pytest.approx(0.170)     # paper: 170 mm effective
    assert RIG.epoch_ns == 1_767_225_600 * 10**9
    assert RIG.roller_pass_order == pytest.approx(10 * 24 / (2 * (24 + 8)))   # Eq. 1, 10 rollers


@pytest.mark.parametrize('text, message', [
    ('rig_simulator:\n  rig:\n    c_sys: 0.1\n    colour: red\n', 'unknown RigConfig field'),
    ('rig_simulator:\n  rig:\n    c_sys: lots\n', 'c_sys must be a number'),
    ('rig_simulator:\n  rig:\n    vibration_block: 0.10001\n', 'whole number of samples'),
    ('rig_simulator:\n  rig:\n    harmonic_shares: [0.6, 0.5]\n', 'harmonic_shares'),
    ('rig_simulator:\n  plan:\n    stage_thetas: []\n', 'stage_thetas'),
    ('rig_simulator:\n  plan:\n    run_order: shuffled\n', 'run_order'),
    ('rig_simulator: [1, 2]\n', 'expected a mapping'),
])
def test_bad_config_is_one_line_naming_the_file(tmp_path, text, message):
    path = tmp_path / 'rig.yaml'
    path.write_text(text)
    with pytest.raises(InputError, match=message) as caught:
        load_rig_config(path)
        load_experiment_plan(path)
    assert str(path) in str(caught.value) and '\n' not in str(caught.value)


def test_default_constants_give_realistic_levels_and_the_papers_trends():
    speeds, loads = np.array([100, 150, 200]) * RPM, np.array([100.0, 200.0])
    for speed in speeds:
        for load in loads:
            level = eq22(speed, load, 1.0)
            assert 0.3 < level < 5.0                                    # m/s^2 RMS, accelerometer range
            assert 1.25 < eq22(speed, load, 0.72) / level < 1.8         # theta 0.72: tens of percent more
        assert eq22(speed, 200.0, 1.0) < eq22(speed, 100.0, 1.0)        # load up, amplitude slightly down
    # F^-1/3 beats exp(C_F F) between 100 and 200 N (paper, Sec. 3.2) with the rig's true C_F.
    assert abs(math.log(2 ** (-1 / 3))) > abs(RIG.c_f * (200.0 - 100.0))


# -- the signal ---------------------------------------------------------------------------------

@pytest.mark.parametrize('speed, load, theta', [(100 * RPM, 200.0, 0.72), (200 * RPM, 100.0, 1.0)])
def test_steady_rms_follows_eq22(speed, load, theta):
    chunk, _ = steady(speed, load, 10.0, theta)
    expected = math.sqrt(eq22(speed, load, theta) ** 2 + RIG.sensor_noise ** 2)
    assert rms(chunk.samples) == pytest.approx(expected, rel=rms_tolerance(10.0))
    assert chunk.samples.dtype == np.float32 and chunk.samples.shape == (100, 400)


def test_signal_has_the_mode_and_the_rotation_orders():
    speed = 200 * RPM
    chunk, _ = steady(speed, 100.0, 10.0, 1.0)
    x = chunk.samples.ravel().astype(float)
    power = np.abs(np.fft.rfft(x)) ** 2
    freqs = np.fft.rfftfreq(x.size, 1 / RIG.vibration_rate)
    band = (freqs > 900) & (freqs < 1500)
    assert freqs[band][np.argmax(power[band])] == pytest.approx(1200, abs=40)    # structural mode
    for order in (1.0, 3.75):                                                   # 1x and roller pass
        line = order * speed / (2 * math.pi)
        at = np.argmin(abs(freqs - line))
        assert power[at] > 100 * np.median(power[(freqs > line + 1) & (freqs < line + 5)])


def test_same_seed_same_samples_however_the_time_is_chunked():
    whole, _ = steady(150 * RPM, 100.0, 2.0, 0.83, seed=11)
    program = DriveProgram()
    program.append_motion(0.0, 0.0, 150 * RPM)
    program.append_load(0.0, 0.0, 100.0)
    stream = RigStream(RIG, program, seed=11)
    parts = [stream.advance(a, b, 0.83).samples for a, b in ((0, 3), (3, 4), (4, 20))]
    np.testing.assert_array_equal(np.concatenate(parts), whole.samples)
    other, _ = steady(150 * RPM, 100.0, 2.0, 0.83, seed=12)
    assert not np.array_equal(other.samples, whole.samples)


# -- the experiment in bags ---------------------------------------------------------------------

@pytest.fixture(scope='module', params=['mcap', 'sqlite3', 'mcap-file'])
def experiment(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(f'exp_{request.param}')
    paths = simulate_experiment(out, plan=TINY, seed=5, storage=request.param)
    truth = json.loads((out / 'truth.json').read_text())
    return request.param, paths, truth, [read_bag(p) for p in paths]


def test_bags_are_named_by_stage_and_truth_sits_beside_them(experiment):
    storage, paths, truth, bags = experiment
    suffix = '.mcap' if storage == 'mcap-file' else ''
    assert [p.name for p in paths] == [f'stage_1{suffix}', f'stage_2{suffix}']
    assert [b['theta_oil'] for b in truth['bags']] == [0.72, 1.0]
    assert truth['constants'] == {'c_sys': 0.08, 'c_f': 1e-3, 'c_lambda': 0.30}
    assert all(v is None for v in truth['effects'].values())
    for bag in bags:
        assert bag['topics'] == ['/prsm/axial_load', '/prsm/joint_states', '/prsm/temperature',
                                 '/prsm/vibration']


def test_message_counts_rates_and_log_times(experiment):
    _, _, truth, bags = experiment
    for meta, bag in zip(truth['bags'], bags):
        duration = meta['end'] - meta['start']
        # 1 s standstill + 11.4 s run + 1 s + 7.6 s rewind + 1 s, rounded up to whole 0.1 s blocks.
        assert duration == pytest.approx(1 + (0.6 + 10.2 + 0.6) + 1 + (0.4 + 6.8 + 0.4) + 1, abs=0.1)
        stamps, blocks = bag['vibration']
        assert blocks.shape == (round(duration * 10), 400)
        np.testing.assert_allclose(np.diff(stamps), 0.1, atol=2e-6)
        assert stamps[0] == pytest.approx(meta['start'], abs=1e-6)
        for name, rate in (('joint_states', 100), ('axial_load', 50), ('temperature', 1)):
            assert bag[name][0].size == pytest.approx(duration * rate, abs=1)
            np.testing.assert_allclose(np.diff(bag[name][0]), 1 / rate, atol=2e-6)
        latency = bag['log'] - bag['stamp_ns']
        assert latency.min() >= 0.0005e9 and np.median(latency) < 0.11e9      # stamp + small latency
        assert np.all(np.diff(bag['log']) >= 0)
    assert truth['bags'][1]['start'] >= truth['bags'][0]['end'] + 5.0        # stage pause


def test_schedule_ramps_travel_and_rewind(experiment):
    _, _, truth, bags = experiment
    lead, speed = 0.005, 200 * RPM
    for meta, bag in zip(truth['bags'], bags):
        t, angle, velocity = bag['joint_states']
        forward, rewind = meta['runs']
        assert forward['kind'] == 'forward' and rewind['kind'] == 'rewind'
        ramp = 2 * (2 * math.pi * 0.005 / lead) / speed                   # 5 mm ramp at constant accel
        assert forward['steady_start'] - forward['start'] == pytest.approx(ramp)
        assert forward['end'] - forward['start'] == pytest.approx(ramp * 2 + 2 * math.pi * 34 / speed)
        during_ramp = (t > forward['start']) & (t < forward['steady_start'])
        assert np.all(np.diff(velocity[during_ramp]) > 0) and velocity[during_ramp].max() < speed
        cruise = (t >= forward['steady_start'] + 0.01) & (t <= forward['steady_end'] - 0.01)
        np.testing.assert_allclose(velocity[cruise], speed)
        assert np.all(velocity[(t > forward['steady_end'] + 0.01) & (t < forward['end'])] < speed)
        # The angle is the integral of the speed; the nut travels 180 mm and comes back.
        integral = np.concatenate([[0], np.cumsum(np.diff(t) * (velocity[1:] + velocity[:-1]) / 2)])
        np.testing.assert_allclose(angle - angle[0], integral, atol=2e-3)
        at = np.searchsorted(t, [forward['start'], forward['end'] + 0.01, rewind['end'] + 0.01])
        travel = lead * (angle[at] - angle[at[0]]) / (2 * math.pi)
        assert travel[1] == pytest.approx(0.180, abs=1e-6) and travel[2] == pytest.approx(0.0, abs=1e-6)
        assert velocity[(t > rewind['steady_start']) & (t < rewind['steady_end'])] == pytest.approx(-300 * RPM)
        assert np.all(velocity[t < forward['start'] - 1e-9] == 0)
        # Load on during the forward run, off (noise only) during the rewind.
        lt, load = bag['axial_load']
        on = (lt >= forward['start']) & (lt < forward['end'])
        assert np.mean(load[on]) == pytest.approx(100.0, abs=0.2)
        assert np.std(load[on]) == pytest.approx(0.002 * 100 + 0.2, rel=0.25)
        assert abs(np.mean(load[(lt >= rewind['start']) & (lt < rewind['end'])])) < 0.15
        tt, temperature = bag['temperature']
        assert np.mean(temperature) == pytest.approx(30.0, abs=0.02)


def test_recorded_rms_follows_theta(experiment):
    _, _, truth, bags = experiment
    measured = []
    for meta, bag in zip(truth['bags'], bags):
        run = meta['runs'][0]
        measured.append(window_rms(bag, run['steady_start'], run['steady_end']))
        expected = math.sqrt(eq22(run['speed'], run['load'], meta['theta_oil']) ** 2 + 0.003 ** 2)
        assert measured[-1] == pytest.approx(expected, rel=rms_tolerance(10.2))
        assert run['eq22_amplitude'] == pytest.approx(eq22(run['speed'], run['load'], meta['theta_oil']))
        standstill = window_rms(bag, meta['start'], meta['start'] + 0.9)
        assert standstill == pytest.approx(0.003, rel=0.1)                    # sensor noise only
    assert measured[0] > 1.3 * measured[1]                                    # theta 0.72 vs 1.0


def test_same_seed_gives_identical_bags(tmp_path):
    plan = ExperimentPlan(speeds=(200 * RPM,), loads=(100.0,), stage_thetas=(0.9,))
    first = simulate_experiment(tmp_path / 'a', plan=plan, seed=3, storage='mcap-file')[0]
    second = simulate_experiment(tmp_path / 'b', plan=plan, seed=3, storage='mcap-file')[0]
    assert first.read_bytes() == second.read_bytes()
    with pytest.raises(InputError, match='exists already'):
        simulate_experiment(tmp_path / 'a', plan=plan, seed=3, storage='mcap-file')


def test_random_run_order_is_seeded_and_complete(tmp_path):
    plan = ExperimentPlan(speeds=(150 * RPM, 200 * RPM), loads=(100.0, 200.0), stage_thetas=(0.8, 0.9),
                          stroke=0.02, ramp_travel=0.002, run_order='random')
    simulate_experiment(tmp_path / 'a', plan=plan, seed=8)
    simulate_experiment(tmp_path / 'b', plan=plan, seed=8)
    runs = [[(r['speed'], r['load']) for r in bag['runs'] if r['kind'] == 'forward']
            for bag in json.loads((tmp_path / 'a' / 'truth.json').read_text())['bags']]
    again = [[(r['speed'], r['load']) for r in bag['runs'] if r['kind'] == 'forward']
             for bag in json.loads((tmp_path / 'b' / 'truth.json').read_text())['bags']]
    assert runs == again
    assert all(sorted(order) == sorted(plan.conditions) for order in runs)
    assert any(order != plan.conditions for order in runs)


def test_endurance_bag_cycles_the_conditions(tmp_path):
    path = simulate_endurance(tmp_path / 'long.mcap', 30.0, seed=2, storage='mcap-file',
                              truth_path=tmp_path / 'long.json')
    bag = read_bag(path)
    assert bag['vibration'][1].shape == (300, 400)
    truth = json.loads((tmp_path / 'long.json').read_text())
    forward = [r for r in truth['bags'][0]['runs'] if r['kind'] == 'forward']
    assert forward[0]['speed'] == pytest.approx(100 * RPM) and forward[0]['load'] == 100.0
    t, _, velocity = bag['joint_states']
    assert velocity.max() == pytest.approx(100 * RPM) and velocity.min() == pytest.approx(-300 * RPM)


# -- effects ------------------------------------------------------------------------------------

def test_past_resonance_the_whole_signal_is_attenuated_by_the_forced_response():
    speed = 200 * RPM
    order, ratio, zeta = 3.75, 2.0, 0.05
    effect = ResonanceLaw(order=order, natural_frequency=order * speed / (2 * math.pi) / ratio, damping_ratio=zeta)
    base, _ = steady(speed, 100.0, 2.0, 1.0)
    shifted, _ = steady(speed, 100.0, 2.0, 1.0, effects=Effects(resonance=effect))
    magnification = 1 / math.sqrt((1 - ratio ** 2) ** 2 + (2 * zeta * ratio) ** 2)    # 0.333
    assert rms(shifted.samples) / rms(base.samples) == pytest.approx(magnification, rel=0.01)


def test_near_resonance_the_mode_rings_at_its_natural_frequency_with_the_extra_power():
    from scipy.signal import welch
    speed = 200 * RPM
    order, ratio, zeta = 20.0, 0.9, 0.1              # the 20th order meets a mode at 74 Hz
    natural = order * speed / (2 * math.pi) / ratio
    effect = ResonanceLaw(order=order, natural_frequency=natural, damping_ratio=zeta)
    base, _ = steady(speed, 100.0, 10.0, 1.0)
    shifted, _ = steady(speed, 100.0, 10.0, 1.0, effects=Effects(resonance=effect))
    ring = (shifted.samples.astype(float) - base.samples).ravel()   # the rest of the signal is unchanged
    magnification = 1 / math.sqrt((1 - ratio ** 2) ** 2 + (2 * zeta * ratio) ** 2)    # 3.8
    contact = float(thread_contact_amplitude(speed, 100.0, 1.0, RIG))
    # Narrowband: the power estimate over T s has a relative SD of 1 / sqrt(zeta omega_n T) = 4.6 %.
    assert rms(ring) / (contact * math.sqrt(magnification ** 2 - 1)) == pytest.approx(1.0, abs=0.1)
    freqs, power = welch(ring, RIG.vibration_rate, nperseg=4096)
    assert abs(freqs[np.argmax(power)] - natural) < 3 * (freqs[1] - freqs[0])


def test_position_dependent_stiffness_lowers_the_amplitude_along_the_stroke():
    area = math.pi * 0.0215 ** 2 / 4
    length0 = 0.21                                           # 180 mm stroke + 30 mm to the fixed bearing
    contact = 0.3 * 2.06e11 * area / length0                 # k_c / k_s = 0.3 at the start
    effect = PositionDependentStiffnessLaw(contact_stiffness=contact, reference_load=100.0,
                                           youngs_modulus=2.06e11, root_diameter=0.0215,
                                           free_length_at_start=length0)
    plan = ExperimentPlan(speeds=(100 * RPM,), loads=(100.0,), stage_thetas=(1.0,))
    speed, lead = 100 * RPM, 0.005
    program = DriveProgram()
    strokes, _ = schedule_session(program, 0.0, plan.conditions, plan, RIG)
    run = strokes[0]
    windows = [(run.steady_start + 0.2, run.steady_start + 3.2), (run.steady_end - 3.2, run.steady_end - 0.2)]
    ratios = []
    for effects in (None, Effects(position_dependent_stiffness=effect)):
        chunk = RigStream(RIG, program, seed=4, effects=effects).advance(0, int(run.end * 10), 1.0)
        times = ((chunk.block_stamps[:, None] - RIG.epoch_ns) * 1e-9
                 + np.arange(400)[None, :] / RIG.vibration_rate)
        ratios.append([rms(chunk.samples[(times >= a) & (times < b)]) for a, b in windows])

    def factor(travel):                                      # 1 + k_c / k_s(x), L = 0.21 - x
        return 1 + contact / (2.06e11 * area / (length0 - travel))

    # Window centres: 1.7 s after the 5 mm ramp, and 1.7 s before the last one.
    centre_a = 0.005 + lead * speed * 1.7 / (2 * math.pi)
    centre_b = 0.175 - lead * speed * 1.7 / (2 * math.pi)
    assert ratios[1][0] / ratios[0][0] == pytest.approx(factor(centre_a), rel=0.01)
    assert ratios[1][1] / ratios[0][1] == pytest.approx(factor(centre_b), rel=0.01)
    assert factor(centre_b) / factor(centre_a) < 0.85           # amplitude falls away from the motor


def test_thermal_viscosity_warms_the_oil_and_raises_the_amplitude():
    effect = ThermalViscosityLaw(temperature_rise=20.0, time_constant=20.0, viscosity_temperature_coefficient=0.03)
    speed, load = 150 * RPM, 100.0
    chunk, stream = steady(speed, load, 40.0, 1.0, effects=Effects(thermal_viscosity=effect))
    base, _ = steady(speed, load, 40.0, 1.0)
    t = (chunk.temperature_stamps - RIG.epoch_ns) * 1e-9
    heating = 30.0 + 20.0 * (1 - np.exp(-t / 20.0))
    np.testing.assert_allclose(chunk.temperatures, heating, atol=0.1)
    assert chunk.temperatures[-1] > 47.0
    late = slice(-10, None)                                   # last second: T ~ 47.2 degC
    temperature = 30.0 + 20.0 * (1 - math.exp(-39.5 / 20.0))
    thinning = math.exp(-0.03 * (temperature - 30.0)) ** 0.68
    expected = eq22(speed, load, thinning) / eq22(speed, load, 1.0)
    assert rms(chunk.samples[late]) / rms(base.samples[late]) == pytest.approx(expected, rel=0.01)
    # Standstill: the oil cools back towards ambient with the same time constant.
    stream.program.append_motion(40.0, 0.0, 0.0)
    cooled = stream.advance(400, 600, 1.0)
    hot = 20.0 * (1 - math.exp(-40.0 / 20.0))                # K above ambient when the screw stops
    assert cooled.temperature_stamps[-1] - RIG.epoch_ns == 59 * 10**9
    assert cooled.temperatures[-1] == pytest.approx(30.0 + hot * math.exp(-19.0 / 20.0), abs=0.1)


def test_lubricant_depletion_lowers_theta_with_revolutions():
    effect = LubricantDepletionLaw(depletion_revolutions=100.0)
    speed, load = 200 * RPM, 100.0                            # 3.33 rev/s: 100 rev after 30 s
    chunk, stream = steady(speed, load, 30.0, 1.0, effects=Effects(lubricant_depletion=effect))
    base, _ = steady(speed, load, 30.0, 1.0)
    revolutions = speed / (2 * math.pi) * 29.5
    expected = eq22(speed, load, math.exp(-revolutions / 100.0)) / eq22(speed, load, 1.0)
    assert rms(chunk.samples[-10:]) / rms(base.samples[-10:]) == pytest.approx(expected, rel=0.01)
    assert stream.revolutions == pytest.approx(100.0, rel=1e-3)
    stream.relubricate()
    assert stream.revolutions == 0.0


def test_background_vibration_adds_a_fixed_line_in_power():
    effect = BackgroundVibrationLaw(rms=0.3)
    still, _ = steady(0.0, 0.0, 4.0, 1.0, effects=Effects(background_vibration=effect))
    quiet, _ = steady(0.0, 0.0, 4.0, 1.0)
    assert rms(still.samples) == pytest.approx(math.hypot(0.3, 0.003), rel=0.02)
    assert rms(quiet.samples) == pytest.approx(0.003, rel=0.05)
    for speed in (100 * RPM, 200 * RPM):                      # the line stays at 100 Hz
        running, _ = steady(speed, 100.0, 4.0, 1.0, effects=Effects(background_vibration=effect))
        x = running.samples.ravel().astype(float)
        power = np.abs(np.fft.rfft(x)) ** 2
        freqs = np.fft.rfftfreq(x.size, 1 / RIG.vibration_rate)
        at = np.argmin(abs(freqs - 100.0))
        assert power[at] > 50 * np.median(power[(freqs > 90) & (freqs < 110)])
        expected = math.sqrt(eq22(speed, 100.0, 1.0) ** 2 + 0.3 ** 2 + 0.003 ** 2)
        assert rms(x) == pytest.approx(expected, rel=rms_tolerance(4.0) + 0.01)


def test_drawn_effects_stay_in_their_physical_ranges():
    plan = ExperimentPlan()
    session = 2 * 6 * 0.18 / 0.005                            # revolutions of one bag
    lowest = eq22(100 * RPM, 200.0, 1.0)
    arrangements, bands, laws, forms = {}, {}, {}, {}
    for seed in range(20):
        effects = draw_effects(list(Effects().as_dict()), seed=seed, plan=plan)
        stiffness = effects.position_dependent_stiffness
        factor = stiffness.amplitude_factor(np.linspace(0.0, plan.stroke, 201), 100.0)
        assert 0.05 - 1e-9 <= np.ptp(factor) / np.max(factor) <= 0.30 + 1e-9
        if stiffness.arrangement == 'fixed-fixed':           # softest mid-travel
            assert 0 < np.argmax(factor) < factor.size - 1
        arrangements[stiffness.arrangement] = True
        # Any order excites the mode; the screw speed where they meet lies above, inside or below the band.
        mode = effects.resonance
        resonant = 2 * math.pi * mode.natural_frequency / mode.order
        top, bottom = 200 * RPM, 100 * RPM
        # ... or, a mode between the low orders' band and the band its mesh order sweeps (draw_below_mesh).
        below_mesh = (max(resonance.LOW_ORDERS) * top / (2 * math.pi) < mode.natural_frequency
                      < mode.order * bottom / (2 * math.pi))
        assert (0.5 <= top / resonant <= 0.9 or bottom < resonant < top or 1.3 <= bottom / resonant <= 3.0
                or below_mesh)
        assert 0.02 <= mode.damping_ratio <= 0.2
        bands[resonance.band_position(resonant, bottom, top)] = True
        assert 5 <= effects.thermal_viscosity.temperature_rise <= 25
        assert effects.thermal_viscosity.viscosity_temperature_coefficient == 0.03   # the actuator's oil
        laws[effects.thermal_viscosity.viscosity_law] = True
        loss = effects.lubricant_depletion
        fall = 1 - loss.theta_factor(session)
        assert 0.05 - 1e-9 <= fall <= 0.25 + 1e-9
        assert 0.5 <= effects.background_vibration.rms / lowest <= 1.5
        forms[effects.background_vibration.form] = True
        assert Effects.from_dict(json.loads(json.dumps(effects.as_dict(), allow_nan=False))) == effects
    # Every physical form is drawn.
    assert len(arrangements) == 3 and len(bands) == 3 and len(laws) == 3 and len(forms) == 3
    assert draw_effects(['resonance'], seed=1) == draw_effects(['resonance'], seed=1)
    with pytest.raises(InputError, match='unknown effect'):
        draw_effects(['gremlins'])


def test_background_tones_are_drawn_inside_the_band_the_recording_holds():
    """At 1 kHz the window RMS holds 0.5-400 Hz: tones drawn above it would be concealed where nothing sees them."""
    slow = dataclasses.replace(RIG, vibration_rate=1000.0, vibration_block=0.2, contact_mode_frequency=300.0)
    tones = [f for seed in range(40)
             for f in draw_effects(['background_vibration'], seed=seed, rig=slow).background_vibration.tone_frequencies]
    assert tones and max(tones) < 400.0
    fast = [f for seed in range(40)
            for f in draw_effects(['background_vibration'], seed=seed, rig=RIG).background_vibration.tone_frequencies]
    assert max(fast) > 600.0            # at the default 4 kHz the whole drawn range lies in the band


def test_effects_leave_no_trace_in_the_bag_but_in_truth(tmp_path):
    effects = draw_effects(['background_vibration', 'lubricant_depletion'], seed=2, plan=TINY)
    paths = simulate_experiment(tmp_path, plan=TINY, seed=1, effects=effects, storage='mcap-file')
    truth = json.loads((tmp_path / 'truth.json').read_text())
    assert truth['effects']['background_vibration']['rms'] == effects.background_vibration.rms
    assert truth['effects']['resonance'] is None
    data = paths[0].read_bytes()
    for word in (b'background', b'depletion', b'theta', b'0.72'):
        assert word not in data


# -- live generator -----------------------------------------------------------------------------

def test_live_generator_ramps_to_commanded_speed_and_load():
    generator = RigSignalGenerator(seed=1, theta_oil=0.83)
    generator.set_speed(200 * RPM)
    generator.set_load(100.0)
    blocks = [generator.next_block() for _ in range(30)]
    stamps = np.array([b.stamp for b in blocks])
    np.testing.assert_allclose(np.diff(stamps), 0.1, atol=1e-6)
    speeds = np.array([b.speed for b in blocks])
    ramp = 200 * RPM / RIG.live_acceleration                  # ~1.05 s at 20 rad/s^2
    assert speeds[5] == pytest.approx(20.0 * 0.5)
    assert np.all(speeds[int(ramp * 10) + 1:] == pytest.approx(200 * RPM))
    assert blocks[10].load == pytest.approx(100.0)           # 100 N in 0.25 s at 400 N/s
    angles = np.array([b.angle for b in blocks])
    assert angles[-1] - angles[20] == pytest.approx(200 * RPM * 0.9)
    steady_samples = np.concatenate([b.samples for b in blocks[15:]])
    assert rms(steady_samples) == pytest.approx(eq22(200 * RPM, 100.0, 0.83), rel=rms_tolerance(1.5))
    joint = blocks[-1].topics
    assert joint.joint_stamps.size == 10 and joint.load_stamps.size == 5
    generator.set_theta(1.0)
    assert rms(np.concatenate([generator.next_block().samples for _ in range(15)])) < 0.8 * rms(steady_samples)


def test_live_generator_stays_continuous_through_many_commands():
    generator = RigSignalGenerator(seed=2)
    blocks = []
    for step in range(40):
        generator.set_speed((-1) ** step * 5.0)               # reverse every 0.2 s: always ramping
        generator.set_load(50.0 + step)
        blocks += [generator.next_block(), generator.next_block()]
    speeds = np.array([b.speed for b in blocks])
    angles = np.array([b.angle for b in blocks])
    assert np.all(np.abs(np.diff(speeds)) <= RIG.live_acceleration * 0.1 + 1e-9)
    # Angle steps are the trapezoidal integral of a speed that is linear within each 0.1 s block.
    joint = np.concatenate([b.topics.joint_speeds for b in blocks])
    joint_angles = np.concatenate([b.topics.joint_angles for b in blocks])
    steps = np.diff(joint_angles)
    np.testing.assert_allclose(steps, 0.01 * (joint[1:] + joint[:-1]) / 2, atol=1e-9)
    assert angles[0] == 0.0 and np.all(np.abs(speeds) <= 5.0)


def test_live_generator_reverses_at_both_stroke_ends():
    """Commanded 40 rad/s for 16 s: the nut runs 0 .. 0.18 m and back, never beyond the stroke (issue 8)."""
    generator = RigSignalGenerator(seed=3)
    generator.set_speed(40.0)
    blocks = [generator.next_block() for _ in range(160)]
    angles = np.concatenate([b.topics.joint_angles for b in blocks])
    speeds = np.concatenate([b.topics.joint_speeds for b in blocks])
    positions = RIG.actuator.nut_travel_from_angle(angles, 0.0)
    stroke = RIG.actuator.nut_travel
    overshoot = 40.0 * RIG.vibration_block / RigSignalGenerator.REVERSAL_STEPS * RIG.actuator.lead / (2 * np.pi)
    assert positions.min() >= -overshoot and positions.max() <= stroke + overshoot
    top = int(np.argmax(positions))
    assert positions[top] > stroke - 0.002                       # it does reach the far end ...
    assert positions[top:].min() < 0.002                         # ... and comes back to the near one
    assert np.sum(np.diff(np.sign(speeds[np.abs(speeds) > 1.0])) != 0) >= 2   # two reversals
    assert np.abs(speeds).max() <= 40.0 + 1e-9
    # Braking at live_acceleration passes zero at the end: standstill there lasts no longer than one ramp.
    assert np.all(np.abs(np.diff(speeds)) <= RIG.live_acceleration * 0.01 + 1e-9)


def test_live_generator_at_the_start_end_turns_a_backward_command_around():
    generator = RigSignalGenerator(seed=3)
    generator.set_speed(-20.0)
    blocks = [generator.next_block() for _ in range(20)]
    angles = np.concatenate([b.topics.joint_angles for b in blocks])
    assert angles.min() >= -1e-9 and blocks[-1].speed == pytest.approx(20.0)
