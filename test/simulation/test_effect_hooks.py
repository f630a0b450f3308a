# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The simulators reach every effect through its simulation hook; the surface defect through nothing else."""
import hashlib
import json
import math

import numpy as np
import pytest
from scipy.signal import butter, hilbert, sosfiltfilt
from scipy.stats import kurtosis

from prsm_lube_ros.cli import main
from prsm_lube_ros.physics.effects import effect_ids, law_type, SampleState, simulation, StreamRandom
from prsm_lube_ros.physics.effects import surface_defect as defect
from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.simulation.drive import DriveProgram, schedule_session
from prsm_lube_ros.simulation.effects import Effects
from prsm_lube_ros.simulation.recordings import draw_effects, simulation_context
from prsm_lube_ros.simulation.rig_acceleration import expected_rms, RigStream, thread_contact_amplitude
from prsm_lube_ros.simulation.rig_config import ExperimentPlan, RigConfig

RPM = 2 * math.pi / 60
RIG = RigConfig()
#: A short plan: one stage, two speeds, 40 mm strokes.
PLAN = ExperimentPlan(stage_thetas=(0.9,), speeds=(100 * RPM, 200 * RPM), loads=(150.0,), stroke=0.04)
#: sha256 (first 16 hex digits) of the float32 samples of PLAN's stage with each drawn effect, made by the rig
#: simulator before the effects had simulation hooks (commit a99c97d): the hooks must not change one bit.
BEFORE_HOOKS = [
    (('position_dependent_stiffness',), 1, '4e597c4587780a80'),
    (('resonance',), 2, '8ad2238b9348bea2'),
    (('resonance',), 5, 'b20eb3e28c176a99'),
    (('thermal_viscosity',), 3, 'f57905a247052290'),
    (('lubricant_depletion',), 4, 'dd463df4570b586b'),
    (('background_vibration',), 5, '2e6f4d6cb29969be'),
    (('thermal_viscosity', 'lubricant_depletion'), 6, 'fa4a76e773fa8eb2'),
    (('resonance', 'background_vibration'), 7, '8d936c709047baee'),
]


#: One steady condition long enough for several 1 s windows (7 s at 150 r/min).
DEFECT_PLAN = ExperimentPlan(stage_thetas=(1.0,), speeds=(150 * RPM,), loads=(150.0,), stroke=0.09)


def _samples(effects, seed, plan=PLAN, theta=0.9):
    """Samples, speeds per sample and the stream of one stage of ``plan``."""
    program = DriveProgram()
    _, end = schedule_session(program, 0.0, plan.conditions, plan, RIG)
    stream = RigStream(RIG, program, seed=seed, effects=effects)
    chunk = stream.advance(0, int(end / RIG.vibration_block), theta)
    return chunk.samples, np.repeat(chunk.block_speeds, RIG.block_size)


@pytest.mark.parametrize('names, seed, digest', BEFORE_HOOKS)
def test_recordings_of_the_existing_effects_are_bit_identical_to_before_the_hooks(names, seed, digest, monkeypatch):
    # Modes below the mesh band came later, drawn last (a quarter of the resonance draws, seed 7's among them):
    # without them every draw is the one before the hooks.  The mode's ringing by the contacts' broadband came
    # later too (no draw of its own: rho from the rig's contact mode); without it the samples are those before.
    from prsm_lube_ros.physics.effects import resonance
    monkeypatch.setattr(resonance, 'BELOW_MESH_SHARE', 0.0)
    monkeypatch.setattr(resonance, 'broadband_ring_share', lambda *args: 0.0)
    samples, _ = _samples(draw_effects(list(names), seed=seed, rig=RIG, plan=PLAN), seed)
    assert hashlib.sha256(samples.tobytes()).hexdigest()[:16] == digest


def test_draw_effects_loops_over_the_registry():
    for effect_id in effect_ids():
        law = getattr(draw_effects([effect_id], seed=3), effect_id)
        assert isinstance(law, law_type(effect_id))
    # One stream per effect by registry index: drawn alone or beside another, the same law.
    both = draw_effects(['lubricant_depletion', 'surface_defect'], seed=3)
    assert both.surface_defect == draw_effects(['surface_defect'], seed=3).surface_defect
    assert both.lubricant_depletion == draw_effects(['lubricant_depletion'], seed=3).lubricant_depletion


def test_the_prsm_defect_orders_of_the_default_actuator():
    assert defect.defect_orders(Actuator()) == pytest.approx({'screw raceway': 6.25, 'nut raceway': 3.75,
                                                              'roller': 3.75})


def test_surface_defect_draws_lie_inside_the_documented_ranges():
    context = simulation_context(RIG, ExperimentPlan())
    hook = simulation('surface_defect')
    laws = [hook.draw(np.random.default_rng(seed), context) for seed in range(200)]
    orders = defect.defect_orders(context.actuator)
    fs, top = context.sample_rate, min(defect.NATURAL_FREQUENCY_RANGE[1] * context.sample_rate,
                                       0.9 * context.band_high)
    for law in laws:
        assert law.strike_order == orders[law.component]
        grown = float(law.power(law.reference_speed, law.reference_load, context.session_revolutions))
        growth = 1.0 if law.growth == 'steady' else math.sqrt(grown) / law.impulsive_rms
        size = law.impulsive_rms * growth / context.reference_amplitude
        assert defect.SIZE_RANGE[0] <= size <= defect.SIZE_RANGE[1]
        if law.growth != 'steady':
            assert defect.GROWTH_FACTOR_RANGE[0] <= growth <= defect.GROWTH_FACTOR_RANGE[1]
        assert defect.SPEED_EXPONENT_RANGE[0] <= law.speed_exponent <= defect.SPEED_EXPONENT_RANGE[1]
        assert defect.LOAD_EXPONENT_RANGE[0] <= law.load_exponent <= defect.LOAD_EXPONENT_RANGE[1]
        assert defect.NATURAL_FREQUENCY_RANGE[0] * fs <= law.natural_frequency <= top < context.band_high
        assert defect.DAMPING_RANGE[0] <= law.damping_ratio <= defect.DAMPING_RANGE[1]
        assert defect.SCATTER_RANGE[0] <= law.strike_scatter <= defect.SCATTER_RANGE[1]
        assert defect.JITTER_RANGE[0] <= law.timing_jitter <= defect.JITTER_RANGE[1]
        assert law.modulation_depth == 0 or defect.MODULATION_RANGE[0] <= law.modulation_depth <= \
            defect.MODULATION_RANGE[1]
    assert {law.component for law in laws} == set(defect.COMPONENTS)
    assert {law.growth for law in laws} == set(defect.GROWTH_FORMS)
    assert 0.35 < np.mean([law.growth == 'steady' for law in laws]) < 0.65
    assert 0.35 < np.mean([law.modulation_depth > 0 for law in laws]) < 0.65


def _defect(component='screw raceway', size=1.0, **changes):
    context = simulation_context(RIG, PLAN)
    law = defect.SurfaceDefectLaw(component=component, strike_order=defect.defect_orders(RIG.actuator)[component],
                                  impulsive_rms=size * context.reference_amplitude, reference_speed=min(PLAN.speeds),
                                  reference_load=max(PLAN.loads), speed_exponent=1.5, load_exponent=0.6,
                                  natural_frequency=1100.0, damping_ratio=0.05)
    return defect.SurfaceDefectLaw(**{**law.__dict__, **changes})


def _band_windows(samples, speeds, speed):
    """1 s windows of the band-passed signal (10 Hz .. 0.8 x Nyquist) at steady ``speed``."""
    fs = RIG.vibration_rate
    band = sosfiltfilt(butter(4, [10.0, 0.4 * fs], 'bandpass', fs=fs, output='sos'), samples.reshape(-1))
    n = int(fs)
    return [band[k:k + n] for k in range(0, band.size - n, n) if np.all(np.abs(speeds[k:k + n] - speed) < 1e-6)]


@pytest.mark.parametrize('component', defect.COMPONENTS)
def test_a_simulated_surface_defect_is_impulsive_and_strikes_at_its_component_order(component):
    law = _defect(component, size=0.8)
    speed = DEFECT_PLAN.speeds[0]
    samples, speeds = _samples(Effects(surface_defect=law), seed=11, plan=DEFECT_PLAN)
    windows = _band_windows(samples, speeds, speed)
    healthy = _band_windows(*_samples(Effects(), seed=11, plan=DEFECT_PLAN), speed)
    assert len(windows) >= 4 and len(healthy) == len(windows)
    assert np.median([kurtosis(w, fisher=False) for w in healthy]) < 3.3
    assert np.median([kurtosis(w, fisher=False) for w in windows]) > 4.5
    # Envelope spectrum of the band around the ringing mode, in orders of the screw speed: its peak is the strike order.
    fs = RIG.vibration_rate
    around = butter(4, [0.7 * law.natural_frequency, 1.3 * law.natural_frequency], 'bandpass', fs=fs, output='sos')
    envelope = np.abs(hilbert(sosfiltfilt(around, np.concatenate(windows))))
    spectrum = np.abs(np.fft.rfft(envelope - envelope.mean()))
    orders = np.fft.rfftfreq(envelope.size, 1.0 / fs) / (speed / (2 * math.pi))
    inside = (orders > 1.0) & (orders < 10.0)
    assert orders[inside][np.argmax(spectrum[inside])] == pytest.approx(law.strike_order, abs=0.05)


def _strike_rms(law, seconds=40.0, speed=20.0):
    """RMS of the strike train per second at constant speed and load, from the hook's own waveform."""
    fs = RIG.vibration_rate
    sequence = np.random.SeedSequence(5)
    random = StreamRandom(sequence=sequence, phases=np.random.default_rng(1), added=np.random.default_rng(2))
    waveform = simulation('surface_defect').waveform(law, fs, random)
    rms = []
    for second in range(int(seconds)):
        times = second + np.arange(int(fs)) / fs
        state = SampleState(times=times, angles=speed * times, speeds=np.full(times.size, speed),
                            loads=np.full(times.size, 150.0), revolutions=speed * times / (2 * math.pi),
                            contact_amplitude=np.ones(times.size))
        rms.append(float(np.sqrt(np.mean(waveform.add(state) ** 2))))
    return np.array(rms)


def test_a_growing_defect_strikes_harder_with_the_revolutions_and_a_steady_one_does_not():
    revolutions = 40.0 * 20.0 / (2 * math.pi)                       # run over the 40 s
    growing = _strike_rms(_defect(growth='exponential', growth_revolutions=revolutions / math.log(3.0)))
    steady = _strike_rms(_defect())
    assert growing[-10:].mean() / growing[:10].mean() == pytest.approx(np.exp(30 / 40 * math.log(3.0)), rel=0.2)
    assert steady[-10:].mean() / steady[:10].mean() == pytest.approx(1.0, abs=0.15)
    # The train's mean square is P_imp: the law's RMS at the speed and load (steady).
    law = _defect()
    assert steady.mean() == pytest.approx(float(np.sqrt(law.power(20.0, 150.0, 0.0))), rel=0.15)


def test_the_defect_adds_in_power_to_the_expected_rms_and_leaves_the_contact_amplitude():
    law = _defect(size=0.5)
    effects = Effects(surface_defect=law)
    contact = thread_contact_amplitude(15.0, 150.0, 1.0, RIG)
    assert thread_contact_amplitude(15.0, 150.0, 1.0, RIG, effects) == contact
    power = float(law.power(15.0, 150.0, 0.0))
    assert expected_rms(15.0, 150.0, 1.0, RIG, effects) == pytest.approx(
        math.sqrt(contact ** 2 + power + RIG.sensor_noise ** 2))


def test_prsm_lube_simulate_conceals_a_surface_defect(tmp_path):
    config = tmp_path / 'short.yaml'
    config.write_text('rig_simulator:\n  plan:\n    speeds: [15.0]\n    loads: [150.0]\n    stroke: 0.03\n'
                      '    stage_thetas: [1.0]\n')
    assert main(['simulate', str(tmp_path / 'sim'), '--effect', 'surface_defect', '--seed', '2',
                 '--config', str(config)]) == 0
    truth = json.loads((tmp_path / 'sim' / 'truth.json').read_text())
    assert truth['effects']['surface_defect']['component'] in defect.COMPONENTS
    assert Effects.from_dict(truth['effects']).surface_defect == draw_effects(
        ['surface_defect'], seed=2, rig=RIG, plan=ExperimentPlan(speeds=(15.0,), loads=(150.0,), stroke=0.03,
                                                                 stage_thetas=(1.0,))).surface_defect
