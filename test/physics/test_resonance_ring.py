# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A structural mode rings at f_r at every speed, driven by the contacts' broadband (Eq. 13 per component)."""
import math

import numpy as np
import pytest
from scipy.signal import welch

from prsm_lube_ros.physics.effects import ContactBroadband
from prsm_lube_ros.physics.effects import resonance
from prsm_lube_ros.physics.effects.resonance import broadband_ring_share, ResonanceLaw
from prsm_lube_ros.simulation.drive import DriveProgram, schedule_session
from prsm_lube_ros.simulation.effects import Effects
from prsm_lube_ros.simulation.rig_acceleration import RigStream
from prsm_lube_ros.simulation.rig_config import ExperimentPlan, RigConfig

RPM = 2 * math.pi / 60
RIG = RigConfig(vibration_rate=1000.0, contact_mode_frequency=400.0)
#: A mode at 16 Hz met by order 22.5 at 43 r/min: every speed of the plan is past resonance (r = 1.6-4.7), and no
#: line of the rig (orders 1 and n_p) falls within 10 % of it.
BELOW = ResonanceLaw(order=22.5, natural_frequency=16.0, damping_ratio=0.1)
SPEEDS = (67 * RPM, 100 * RPM, 150 * RPM)


@pytest.mark.parametrize('natural, zeta', [(12.0, 0.1), (40.0, 0.03), (150.0, 0.2)])
def test_the_ring_share_is_the_ratio_of_the_two_modes_noise_bandwidths(natural, zeta):
    # rho = share (f_r / zeta_r) / (f_c / zeta_c) for equal modal masses (white force, noise bandwidth pi f / (4 zeta));
    # the simulator's discrete resonators warp a mode near Nyquist (400 Hz at 1 kHz) by about a tenth.
    contact = ContactBroadband(share=0.75, frequency=400.0, damping=0.05)
    rho = broadband_ring_share(ResonanceLaw(order=3.0, natural_frequency=natural, damping_ratio=zeta), contact, 1000.0)
    assert rho == pytest.approx(0.75 * (natural / zeta) / (400.0 / 0.05), rel=0.15)


def _stage(speed, ring=True, monkeypatch=None):
    """Samples of one stage at ``speed`` (rad/s) with the mode BELOW; without the broadband ring if not ``ring``."""
    if not ring:
        monkeypatch.setattr(resonance, 'broadband_ring_share', lambda *args: 0.0)
    plan = ExperimentPlan(stage_thetas=(1.0,), speeds=(speed,), loads=(150.0,), stroke=0.1)
    program = DriveProgram()
    _, end = schedule_session(program, 0.0, plan.conditions, plan, RIG)
    stream = RigStream(RIG, program, seed=3, effects=Effects(resonance=BELOW))
    chunk = stream.advance(0, int(end / RIG.vibration_block), 1.0)
    moving = np.repeat(np.abs(chunk.block_speeds) > 0.9 * speed, RIG.block_size)
    freqs, psd = welch(chunk.samples.ravel()[moving], fs=RIG.vibration_rate, nperseg=2048)
    return freqs, psd


def _band_share(freqs, psd):
    """Share of the recorded power within 10 % of the mode's natural frequency."""
    band = np.abs(freqs - BELOW.natural_frequency) <= 0.1 * BELOW.natural_frequency
    return float(psd[band].sum() / psd.sum())


@pytest.mark.parametrize('speed', SPEEDS)
def test_a_mode_below_the_band_rings_at_its_natural_frequency_at_every_speed(speed, monkeypatch):
    # Past resonance at every speed, yet the mode carries rho / (1 + rho) of the response at f_r (about half of
    # it within zeta f_r of f_r, zeta = 0.1); without the broadband ring the band holds almost nothing.
    assert BELOW.frequency_ratio(speed) > 1.5
    rho = broadband_ring_share(BELOW, ContactBroadband(RIG.contact_share, RIG.contact_mode_frequency,
                                                       RIG.contact_mode_damping), RIG.vibration_rate)
    ringing = _band_share(*_stage(speed))
    without = _band_share(*_stage(speed, ring=False, monkeypatch=monkeypatch))
    assert ringing - without > 0.4 * rho / (1.0 + rho)
    assert without < 0.2 * rho / (1.0 + rho)


def test_the_ring_keeps_the_rms_law_the_candidate_fits(monkeypatch):
    # The ring is rho of the contacts' response at every speed; the sum is scaled back by sqrt(1 + rho), so the
    # recorded RMS is A_22 |H(r)| with or without it (the factor is C_sys's).
    with_ring = [np.sqrt(np.mean(_stage(speed)[1])) for speed in SPEEDS]
    without = [np.sqrt(np.mean(_stage(speed, ring=False, monkeypatch=monkeypatch)[1])) for speed in SPEEDS]
    assert np.allclose(with_ring, without, rtol=0.1)
