# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A mode below the band rings at f_r at every speed: the band is measured, and it is a resonance's evidence."""
import dataclasses
import math

import numpy as np
import pytest

from prsm_lube_ros.diagnosis.effects.resonance import (exciting_order_values, ResonanceBelowBandCandidate,
                                                       ResonanceCandidate)
from prsm_lube_ros.diagnosis.locate import locate, spectral_lines
from prsm_lube_ros.diagnosis.rules import DEFAULT_SPECTRAL_RULES
from prsm_lube_ros.diagnosis.table import WindowTable
from prsm_lube_ros.physics.defect_orders import DefectOrder

#: Screw speeds (rad/s) of the hand-made table, and the rotation orders whose lines move with them.
LEVELS = (14.0, 19.0, 26.0, 35.0)
ORDERS = (1.0, 3.75)
#: The ring: a band fixed at 40 Hz carrying a constant share of the contacts' response (zeta 0.05).
RING_HZ = 40.0
#: The recording's roller pass order (nut raceway), n_p: the exciting orders are 1, 2, 3, n_p, 6, 3 n_p, 6 n_p.
NUT_RACEWAY = DefectOrder(3.75, 'nut raceway')


def ring_table(ring_share=0.05, seed=0):
    """Window spectra (0.5 Hz bins) at LEVELS: a flat floor and order lines, power rising as omega^4; a ring."""
    rng = np.random.default_rng(seed)
    df, bins, per_level = 0.5, 801, 30
    freqs = np.arange(bins) * df
    speeds = np.repeat(LEVELS, per_level)
    mean_square = (speeds / 10.0) ** 4
    ratio = freqs / RING_HZ
    ring = 1.0 / ((1.0 - ratio ** 2) ** 2 + (0.1 * ratio) ** 2)
    spectra = np.empty((speeds.size, bins))
    for row, (speed, ms) in enumerate(zip(speeds, mean_square)):
        psd = np.full(bins, (0.8 - ring_share) * ms / (bins * df)) + ring_share * ms * ring / (ring.sum() * df)
        for order in ORDERS:
            psd[int(round(order * speed / (2 * np.pi) / df))] += 0.1 * ms / df
        spectra[row] = psd * rng.gamma(20.0, 1 / 20.0, bins)
    n = speeds.size
    return WindowTable(speed=speeds, load=np.full(n, 100.0), rms=np.sqrt(mean_square), position=np.zeros(n),
                       revolutions=np.arange(n) * 1.0, time=np.arange(n) * 1.0, temperature=np.full(n, np.nan),
                       run=np.repeat(np.arange(len(LEVELS)), per_level), recording=np.zeros(n), spectra=spectra,
                       spectrum_resolution=df, defect_orders=(NUT_RACEWAY,))


def below_band(order):
    """Fitted parameters of a mode below the band that ``order`` meets at RING_HZ."""
    return {'resonant_speed': 2.0 * math.pi * RING_HZ / order, 'damping_ratio': 0.05,
            'top_speed': max(LEVELS), 'bottom_speed': min(LEVELS)}


def test_a_band_fixed_in_hz_at_every_speed_with_a_constant_share_is_measured_as_a_ring():
    lines = spectral_lines(ring_table())
    assert len(lines.ring_frequencies) == 1 and abs(lines.ring_frequencies[0] - RING_HZ) <= 1.0
    assert max(lines.ring_shares[0]) < 2.0 * min(lines.ring_shares[0])     # follows the contacts' power
    assert lines.mode_frequencies == [] and lines.frequencies == []        # not a mode band, not a fixed line
    assert 'Hz at every recorded speed' in lines.ring_note(0)
    assert spectral_lines(ring_table(ring_share=0.0)).ring_frequencies == []


def test_the_exciting_orders_come_from_the_recordings_roller_pass():
    assert exciting_order_values(ring_table()) == (1.0, 2.0, 3.0, 3.75, 6.0, 11.25, 22.5)
    assert exciting_order_values(dataclasses.replace(ring_table(), defect_orders=())) == (1.0, 2.0, 3.0)


@pytest.mark.parametrize('order, shown', [(22.5, True), (22.5 * 0.9, True), (22.5 * 1.1, True), (30.0, False)])
def test_a_band_at_every_speed_is_evidence_when_it_implies_an_exciting_order(order, shown):
    assert abs(30.0 / 22.5 - 1.0) > DEFAULT_SPECTRAL_RULES.mode_order_tolerance >= 0.1
    table = ring_table()
    location = locate(table, np.zeros(len(table)))
    evidence = ResonanceBelowBandCandidate().spectral_evidence(table, location, below_band(order))
    assert bool(evidence) == shown
    if shown:
        assert '22.5 excites it' in evidence and 'every recorded speed' in evidence


def test_without_the_band_or_with_the_mode_above_the_band_the_ring_is_no_evidence():
    plain = ring_table(ring_share=0.0)
    candidate = ResonanceBelowBandCandidate()
    assert candidate.spectral_evidence(plain, locate(plain, np.zeros(len(plain))), below_band(22.5)) == ''
    table = ring_table()
    location = locate(table, np.zeros(len(table)))
    # A mode above the band rings where its order magnifies (a band following the transfer), not this one.
    above = {**below_band(22.5), 'resonant_speed': 2.0 * max(LEVELS)}
    assert ResonanceCandidate().spectral_evidence(table, location, above) == ''
    # Without fitted parameters no order is implied: no evidence.
    assert candidate.spectral_evidence(table, location) == ''


def struck_table(rung_by, seed=0):
    """Window spectra (2 Hz bins) at three speeds, two runs each, a band at 40 Hz over a flat floor, strikes.

    Each window's Gaussian part (the contacts' vibration, 20 % scatter window to window) and its strikes' power
    are drawn apart; the band's power over the floor is a share of the strikes' power where the strikes ring it
    (``rung_by='strikes'``), else of the Gaussian part (``'orders'``: an order holds the mode's response as the
    speed and the contacts' vibration set it).  Each run has its own set-up factor on every power.
    """
    rng = np.random.default_rng(seed)
    df, bins, per_level = 2.0, 201, 40
    freqs = np.arange(bins) * df
    speeds = np.repeat((6.0, 8.0, 10.0), per_level)
    run = np.repeat(np.arange(6), per_level // 2)
    setup = rng.lognormal(0.0, 0.05, 6)[run]
    gaussian = setup * rng.lognormal(0.0, 0.2, speeds.size)
    strikes = setup * rng.uniform(0.05, 0.4, speeds.size)
    band_power = 0.3 * (strikes if rung_by == 'strikes' else 0.1 * gaussian)
    mean_square = gaussian + strikes
    band = np.abs(freqs - 40.0) <= 2.0
    spectra = np.empty((speeds.size, bins))
    for row in range(speeds.size):
        psd = np.full(bins, (mean_square[row] - band_power[row]) / (bins * df))
        psd[band] += band_power[row] / (band.sum() * df)
        spectra[row] = psd * rng.gamma(50.0, 1 / 50.0, bins)
    n = speeds.size
    return WindowTable(speed=speeds, load=np.full(n, 100.0), rms=np.sqrt(mean_square), position=np.zeros(n),
                       revolutions=np.arange(n) * 1.0, time=np.arange(n) * 1.0, temperature=np.full(n, np.nan),
                       run=run, recording=np.zeros(n), spectra=spectra, spectrum_resolution=df,
                       gaussian_rms=np.sqrt(gaussian))


@pytest.mark.parametrize('rung_by, seed', [('strikes', 0), ('strikes', 1), ('orders', 0), ('orders', 1),
                                           ('orders', 2)])
def test_a_band_that_follows_the_strikes_is_no_evidence_for_a_mode(rung_by, seed):
    """A spall's strikes ring a structural mode: its band's power rises and falls with each window's strikes at a
    steady condition, which an order-excited mode's does not, however the contacts' vibration (and so every share
    of the mean square) scatters window to window (surface_defect 1961: a 252 Hz ring named a mode)."""
    from types import SimpleNamespace

    from prsm_lube_ros.diagnosis.locate import impulse_tracking, SpectralLines
    table = struck_table(rung_by, seed)
    z = impulse_tracking(table, 40.0)
    threshold = DEFAULT_SPECTRAL_RULES.struck_band_z
    assert (z > threshold) if rung_by == 'strikes' else abs(z) < threshold
    lines = SpectralLines(testable=True, mode_frequencies=[40.0], mode_speeds=[6.0, 8.0, 10.0],
                          mode_shares=[[0.1, 0.8, 0.2]])
    params = {'resonant_speed': 8.0, 'damping_ratio': 0.05, 'bottom_speed': 6.0, 'top_speed': 10.0}
    evidence = ResonanceCandidate().independent_evidence(table, SimpleNamespace(spectrum=lines), params)
    assert evidence == '' if rung_by == 'strikes' else 'order 31.42' in evidence
    assert math.isnan(impulse_tracking(dataclasses.replace(table, gaussian_rms=None), 40.0))   # no Gaussian part
