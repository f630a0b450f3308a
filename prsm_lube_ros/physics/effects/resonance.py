# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Dynamic amplification of a lightly damped structural mode (Eq. 13 without the step to Eq. 14).

Physics: Eq. 14 takes the quasi-static response ``X_0 = F_0 / K_0``, valid far
below every natural frequency.  The thread-contact excitation runs at orders n
of the screw rotation, ``f = n omega_S / (2 pi)``; as it approaches a lightly
damped mode at f_r the full solution of Eq. 13 applies:

    X = (F_0 / K_0) |H(r)|,  |H(r)| = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2),  r = n f_S / f_r

so ``A = A_22 |H(r)|``.

Any rotation order n can excite the mode (roller passing, nut thread starts,
a screw run-out at n = 1); the mode may lie below the speed band (every speed
past resonance, r > 1: the amplitude rises more slowly than omega^2 and
approaches A_22 / r^2), inside it (a peak at ``omega_S = 2 pi f_r / n``) or
above it (r < 1 throughout: the amplitude rises faster than omega^2).  The RMS
amplitude only sees the screw speed at which the excitation meets the mode,
``omega_r = 2 pi f_r / n``; f_r and n separately need the spectrum
(:data:`BAND_POSITIONS`, :func:`band_position`).

Eq. 13 holds for every frequency component of the contact force: the
contacts' broadband part rings the mode at f_r at every speed too, past
resonance as well, with a power rho times the contacts' response
(:func:`broadband_ring_share`): in the samples a band fixed in Hz at every
speed, in the RMS a constant factor ``sqrt(1 + rho)`` (C_sys's).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import (choose, ContactBroadband, Extension as EffectExtension, resonator_energy,
               Simulation as EffectSimulation, Waveform)
from ...validation import require, require_all_positive
from ..vibration_model import forced_response_amplitude

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import numpy.typing as npt

    from . import ContactState, SampleState, SimulationContext, StreamRandom

__all__ = ['BANDS', 'BAND_POSITIONS', 'BELOW_MESH_SHARE', 'BELOW_RATIO_RANGE', 'DAMPING_RANGE', 'Extension',
           'HIGHEST_RINGING', 'INSIDE_RANGE', 'LOW_ORDERS', 'Law', 'MESH_GAP_MARGIN',
           'MODE_STREAM_KEY', 'RATIO_RANGE', 'ResonanceLaw', 'Simulation', 'band_position', 'broadband_ring_share',
           'draw', 'draw_below_mesh', 'exciting_orders',
           'magnification', 'natural_frequency']

#: Drawn range of the frequency ratio r = n f_S / f_r at the plan's top forward speed (mode above the band).
RATIO_RANGE = (0.5, 0.9)
#: Drawn range of r at the lowest speed for a mode below the band.
BELOW_RATIO_RANGE = (1.3, 3.0)
#: Drawn position of a mode inside the band, ln(omega_r / omega_min) / ln(omega_max / omega_min).
INSIDE_RANGE = (0.25, 0.75)
#: Where the mode lies against the speed band.
BANDS = ('above', 'inside', 'below')
#: The low rotation orders (run-out, misalignment): they sweep 1-3 times the screw frequency.
LOW_ORDERS = (1.0, 2.0, 3.0)
#: Share of the drawn modes placed below the band the mesh orders sweep, above the low orders' band.
BELOW_MESH_SHARE = 0.25
#: A mode below the mesh band keeps this ratio from the low orders' top and the mesh order's bottom frequency.
MESH_GAP_MARGIN = 1.1
#: Drawn range of the damping ratio of the structural mode.
DAMPING_RANGE = (0.02, 0.20)
#: Key of the mode's own random stream in a simulated recording (:meth:`.StreamRandom.keyed`).
MODE_STREAM_KEY = 3
#: The mode rings in the recording only below this fraction of the sample rate.
HIGHEST_RINGING = 0.45


def magnification(frequency_ratio: npt.ArrayLike, damping_ratio: npt.ArrayLike) -> np.ndarray | float:
    """``|H(r)| = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2)``: Eq. 13's forced response over Eq. 14's X0 = F0/K.

    frequency_ratio r = excitation / natural frequency, damping_ratio zeta (dimensionless).
    Written with :func:`..vibration_model.forced_response_amplitude` for k = 1, m = 1, c = 2 zeta.
    """
    ratio = np.abs(np.asarray(frequency_ratio, dtype=float))
    return forced_response_amplitude(1.0, 1.0, 1.0, 2.0 * np.asarray(damping_ratio, dtype=float), ratio)


#: Where the mode lies relative to the recorded speed band.
BAND_POSITIONS = ('below the speed band', 'inside the speed band', 'above the speed band')


def band_position(resonant_speed: float, lowest_speed: float, highest_speed: float) -> str:
    """Which of :data:`BAND_POSITIONS` the resonant screw speed omega_r (rad/s) takes against the band."""
    if resonant_speed < lowest_speed:
        return BAND_POSITIONS[0]
    if resonant_speed > highest_speed:
        return BAND_POSITIONS[2]
    return BAND_POSITIONS[1]


def natural_frequency(resonant_speed: float, order: float) -> float:
    """``f_r = n omega_r / (2 pi)``, Hz: the mode that order n meets at screw speed omega_r (rad/s)."""
    return order * resonant_speed / (2.0 * math.pi)


@dataclass(frozen=True)
class ResonanceLaw:
    """A rotation-order excitation approaching a lightly damped structural mode.

    The excitation at ``order`` times the screw rotation frequency f_S drives
    the mode at natural_frequency f_r; the thread-contact vibration is
    magnified by ``|H(r)|``, ``r = order f_S / f_r``.
    """

    order: float              # excitation order (per screw revolution)
    natural_frequency: float  # Hz, f_r
    damping_ratio: float      # zeta

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('resonance', **self.__dict__)
        require(self.damping_ratio < 1.0, f'resonance damping_ratio must be below 1, got {self.damping_ratio!r}')

    def frequency_ratio(self, screw_speed: npt.ArrayLike) -> np.ndarray | float:
        """``r = order |omega_S| / (2 pi f_r)`` for screw_speed in rad/s."""
        return self.order * np.abs(np.asarray(screw_speed, dtype=float)) / (2.0 * math.pi * self.natural_frequency)

    def amplitude_factor(self, screw_speed: npt.ArrayLike) -> np.ndarray | float:
        """``|H(r)|`` at screw_speed in rad/s."""
        return magnification(self.frequency_ratio(screw_speed), self.damping_ratio)


Law = ResonanceLaw


class Extension(EffectExtension):
    """Eq. 22 times ``|H(omega_S / omega_r)|`` with ``resonant_speed`` omega_r (rad/s) and ``damping_ratio``."""

    id = 'resonance'

    def log_gain(self, params: Mapping[str, float], covariates: Any, ln_a22: np.ndarray | float) -> np.ndarray | float:
        """``ln |H(omega_S / omega_r)|``."""
        ratio = np.abs(np.asarray(covariates.speed, dtype=float)) / params['resonant_speed']
        return np.log(magnification(ratio, params['damping_ratio']))


def exciting_orders(roller_pass: float) -> tuple[float, ...]:
    """The rotation orders that may excite a mode: :data:`LOW_ORDERS`, the roller pass n_p (Eq. 1), 6, 3 n_p, 6 n_p.

    ``roller_pass`` = n_p, rollers passing a point of the nut per screw revolution.
    """
    return (*LOW_ORDERS, roller_pass, 6.0, 3.0 * roller_pass, 6.0 * roller_pass)


def draw(rng: np.random.Generator, *, order: float, top_speed: float, bottom_speed: float | None = None,
         orders: Sequence[float] | None = None, band: str | None = None) -> ResonanceLaw:
    """Random resonance excited by rotation ``order`` (or one of ``orders`` at random), zeta in its range.

    ``band`` (default: drawn when bottom_speed is given, else ``above``): the
    mode above the speed band (r at top_speed in :data:`RATIO_RANGE`),
    inside it (resonant speed log-uniform in the middle of the band) or below it
    (r at bottom_speed in :data:`BELOW_RATIO_RANGE`); speeds in rad/s.
    """
    order = float(choose(rng, tuple(orders))) if orders else float(order)
    bands = BANDS if bottom_speed is not None else BANDS[:1]
    band = choose(rng, bands, band)
    damping = rng.uniform(*DAMPING_RANGE)
    top = abs(top_speed)
    if band == 'above':
        resonant = top / rng.uniform(*RATIO_RANGE)
    elif band == 'inside':
        assert bottom_speed is not None  # the band is below or inside only with a bottom speed
        low = abs(bottom_speed)
        resonant = low * (top / low) ** rng.uniform(*INSIDE_RANGE)
    else:
        assert bottom_speed is not None  # the band is below or inside only with a bottom speed
        resonant = abs(bottom_speed) / rng.uniform(*BELOW_RATIO_RANGE)
    natural = order * resonant / (2.0 * math.pi)
    return ResonanceLaw(order=order, natural_frequency=float(natural), damping_ratio=float(damping))


def draw_below_mesh(rng: np.random.Generator, *, mesh_orders: Sequence[float], top_speed: float,
                    bottom_speed: float) -> ResonanceLaw | None:
    """A mode between the low orders' band and the band a mesh order sweeps, or None where they overlap.

    The low orders (:data:`LOW_ORDERS`) reach ``3 f_S`` at the top speed, a
    mesh order m (roller pass n_p and its multiples) starts at ``m f_S`` at the
    lowest speed; the mode's natural frequency f_r is drawn log-uniform between
    them (each :data:`MESH_GAP_MARGIN` away), excited by that mesh order from
    above: every recorded speed is past resonance for it (r > 1 throughout, up
    to ``m f_min / (3 f_max)`` at the lowest speed), while the low orders stay
    below f_r.  Speeds in rad/s.
    """
    top, bottom = abs(top_speed), abs(bottom_speed)
    low_top = max(LOW_ORDERS) * top / (2.0 * math.pi) * MESH_GAP_MARGIN
    gaps = [float(m) for m in mesh_orders if m * bottom / (2.0 * math.pi) / MESH_GAP_MARGIN > low_top]
    if not gaps:
        return None
    order = float(choose(rng, tuple(gaps)))
    high = order * bottom / (2.0 * math.pi) / MESH_GAP_MARGIN
    natural = math.exp(rng.uniform(math.log(low_top), math.log(high)))
    return ResonanceLaw(order=order, natural_frequency=float(natural), damping_ratio=float(rng.uniform(*DAMPING_RANGE)))


def broadband_ring_share(law: ResonanceLaw, contact: ContactBroadband, sample_rate: float) -> float:
    """rho: the mode's ringing by the contacts' broadband force over the contacts' response, dimensionless.

    Eq. 13 holds for every frequency component of the contact force, not only
    for the rotation order that sweeps towards f_r.  The contacts' random part
    is a white force (density S_F, N^2/Hz, flat over the sample band) that
    rings the contacts' own mode (f_c, zeta_c) into ``contact.share`` of the
    unit contact signal's mean square.  The same force rings the structural
    mode (f_r, zeta_r).  A mode of modal mass m driven by white force has the
    acceleration mean square ``S_F / m^2 * integral r^4 |H(r)|^2 df`` =
    ``S_F / m^2 * pi f / (4 zeta)`` ((m/s^2)^2: its noise bandwidth
    ``pi f / (4 zeta)`` Hz, the peak gain ``1 / (2 zeta)`` squared times the
    band ``pi zeta f``), so with equal modal masses (the nut's, an assumption)

        rho = share * (f_r / zeta_r) / (f_c / zeta_c),

    evaluated on the discrete resonators the simulator uses (``iirpeak`` of unit
    peak gain, energy E ~ pi zeta f / (f_s / 2)): ``share (zeta_c / zeta_r)^2
    E_r / E_c``.  Whatever law the contacts' broadband follows (Eq. 22's A_22
    and the order's |H(r)|, the simulator's contact amplitude), the ring follows
    too: both modes are driven by one force, so rho is one number per mode.
    """
    from scipy.signal import iirpeak
    energies = [resonator_energy(*iirpeak(f, 1.0 / (2.0 * z), sample_rate))
                for f, z in ((law.natural_frequency, law.damping_ratio), (contact.frequency, contact.damping))]
    return float(contact.share * (contact.damping / law.damping_ratio) ** 2 * energies[0] / energies[1])


class _Mode(Waveform):
    """The mode ringing at f_r in the contact signal: a resonator driven by its own white noise."""

    def __init__(self, law: ResonanceLaw, sample_rate: float, random: StreamRandom) -> None:
        """The resonator at f_r, warmed up over ten decay times from its own stream; rho from the contacts."""
        from scipy.signal import iirpeak, lfilter
        self.law = law
        self.b, self.a = iirpeak(law.natural_frequency, 1.0 / (2.0 * law.damping_ratio), sample_rate)
        self.rng = random.keyed(MODE_STREAM_KEY)
        decay = 1.0 / (2.0 * math.pi * law.natural_frequency * law.damping_ratio)
        _, self.state = lfilter(self.b, self.a, self.rng.standard_normal(int(math.ceil(10.0 * decay * sample_rate))
                                                                         + 8), zi=np.zeros(2))
        self.energy = math.sqrt(resonator_energy(self.b, self.a))
        #: The broadband-driven ring's power over the contacts' response (:func:`broadband_ring_share`).
        self.ring_share = (broadband_ring_share(law, random.contact, sample_rate)
                           if random.contact is not None and random.contact.frequency < HIGHEST_RINGING * sample_rate
                           else 0.0)

    def shape(self, mix: np.ndarray, state: SampleState) -> np.ndarray:
        """The contact signal with the mode's response in it, same RMS as ``|H(r)|`` times ``mix``.

        The contact amplitude already carries the magnification ``g = |H(r)|``
        of the order that meets the mode.  Where g > 1 the extra power
        ``g^2 - 1`` is the mode ringing at its natural frequency f_r (a band
        fixed in Hz, width 2 zeta f_r, whose power follows the order's approach
        to f_r and the contact excitation); where g < 1 (mass-controlled, past
        resonance) the order's response is attenuated.  At every speed the
        contacts' broadband force rings the mode too, with the power rho times
        the contacts' response (:func:`broadband_ring_share`): a band fixed in
        Hz at every speed whose power follows the contact excitation (Eq. 22's
        A_22 law of speed, load and theta_Oil, times g).  The sum is divided by
        ``sqrt(1 + rho)``: the recorded RMS is ``A_22 |H(r)| sqrt(1 + rho)``
        physically, a constant factor that C_sys absorbs, so the law the
        candidate fits stays ``A_22 |H(r)|``.  Returns the signal to be
        multiplied by that amplitude (unit mean square where mix has it).
        """
        from scipy.signal import lfilter
        gain = self.law.amplitude_factor(state.speeds)
        ring, self.state = lfilter(self.b, self.a, self.rng.standard_normal(mix.size), zi=self.state)
        quasi_static = np.minimum(gain, 1.0) / gain
        ringing = np.sqrt(np.maximum(gain ** 2 - 1.0, 0.0) / gain ** 2 + self.ring_share)
        return (quasi_static * mix + ringing * ring / self.energy) / math.sqrt(1.0 + self.ring_share)


class Simulation(EffectSimulation):
    """The contact amplitude times ``|H(r)|``; below 0.45 x the sample rate the mode rings in the samples."""

    id = 'resonance'

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> ResonanceLaw:
        """:func:`draw` against the plan's speed band.

        The exciting order is one of 1, 2, 3, the roller pass order n_p (Eq. 1), 6, 3 n_p and 6 n_p.
        Then, in :data:`BELOW_MESH_SHARE` of the draws, the mode is placed
        below the band the mesh orders n_p, 3 n_p, 6 n_p sweep and above the
        low orders' (:func:`draw_below_mesh`) where the plan leaves such a gap.
        That choice is drawn last, so the other draws stay those of the studies
        recorded before it.
        """
        from ..kinematics import roller_revolution_speed
        actuator = context.actuator
        roller_pass = float(actuator.roller_count * roller_revolution_speed(
            1.0, actuator.screw_mean_diameter, actuator.roller_mean_diameter))
        top, bottom = max(context.speeds), min(context.speeds)
        law = draw(rng, order=roller_pass, top_speed=top, bottom_speed=bottom,
                   orders=exciting_orders(roller_pass))
        if rng.uniform() < BELOW_MESH_SHARE:
            return draw_below_mesh(rng, mesh_orders=(roller_pass, 3 * roller_pass, 6 * roller_pass),
                                   top_speed=top, bottom_speed=bottom) or law
        return law

    def amplitude_factor(self, law: ResonanceLaw, state: ContactState) -> np.ndarray | float:
        """``|H(r)|`` at the screw speed."""
        return law.amplitude_factor(state.speed)

    def form_words(self, params: Mapping[str, Any], speeds: Sequence[float]) -> list[str]:
        """Where the mode lies against the plan's ``speeds`` (rad/s), and its order."""
        if not (params.get('natural_frequency') and params.get('order')):
            return []
        resonant = 2.0 * math.pi * params['natural_frequency'] / params['order']
        band = band_position(resonant, min(speeds), max(speeds)).replace('speed band', 'band')
        if band.startswith('below') and (params['natural_frequency'] > max(LOW_ORDERS) * max(speeds) / (2.0 * math.pi)):
            band = 'below the mesh band, above the low orders'
        return [f'mode {band}, order {params["order"]:.3g}']

    def waveform(self, law: ResonanceLaw, sample_rate: float, random: StreamRandom) -> Waveform | None:
        """The mode ringing in the contact signal (:class:`_Mode`), or None.

        None when f_r is not below :data:`HIGHEST_RINGING` times the sample
        rate (its gain then scales the whole contact signal).
        """
        if law.natural_frequency >= HIGHEST_RINGING * sample_rate:
            return None
        return _Mode(law, sample_rate, random)
