# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A spall or pit on a raceway or roller: impulsive vibration at a defect order, adding in power.

Physics: each contact that passes a local defect strikes it.  The strike is
an impulse whose response rings a structural mode (natural frequency f_n,
damping ratio zeta); the strikes come at a defect order n_d per screw
revolution from the kinematics (Eq. 1-2; :func:`defect_orders`):

* ``screw raceway``: the N rollers pass a point of the screw thread,
  ``n_d = N (1 - K_P)`` (6.25 with the default actuator);
* ``nut raceway``: they pass a point of the nut thread, ``n_d = N K_P`` (3.75);
* ``roller``: a defect on a roller strikes both races once per roller
  revolution, ``n_d = 2 K_R`` (3.75),

with ``K_P = d_S / (2 (d_S + d_R))`` (Eq. 1) and ``K_R = omega_R / omega_S``
(Eq. 2).  Strikes scatter in strength (log-normal, sigma_s) and in time (the
rollers slip: a jitter of 1-2 % of the strike period); the load zone
turning with the carrier (order K_P) may modulate them.  Their strength
grows with the impact speed and the load, and with the revolutions run as
the spall grows:

    P_imp = A_imp^2 (|omega| / omega_ref)^(2a) (F / F_ref)^(2b) g(N)^2

with ``g(N) = exp(N / N_g)`` (``exponential``), ``1 + N / N_g`` (``linear``)
or 1 (``steady``), N the revolutions run.  The impacts do not come from the
film, so their power adds to the contacts' (:data:`~.background_vibration`'s law):

    A = sqrt(A_22^2 + P_imp),  ln A = ln A_22 + 0.5 ln(1 + P_imp / A_22^2).

The window RMS alone cannot tell this from other power added at speed; the
impulsiveness can: the band kurtosis rises above the 3 of Gaussian contact
vibration and the envelope spectrum peaks at n_d.  theta_Oil is no
lubrication measure while it lasts (the film is not what changed).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import choose, Extension as EffectExtension, resonator_energy, Simulation as EffectSimulation, Waveform
from .background_vibration import contact_amplitude, log_gain as added_power_log_gain
from ..defect_orders import prsm_defect_orders
from ..kinematics import roller_revolution_speed
from ...validation import require, require_all_positive

if TYPE_CHECKING:
    from collections.abc import Mapping

    import numpy.typing as npt

    from ..actuator import Actuator
    from . import ContactState, SampleState, SimulationContext, StreamRandom

__all__ = ['COMPONENTS', 'DAMPING_RANGE', 'DEFECT_STREAM_KEY', 'ENVELOPE_GAIN', 'Extension', 'GROWTH_FACTOR_RANGE',
           'GROWTH_FORMS', 'JITTER_RANGE', 'LOAD_EXPONENT_RANGE', 'Law', 'MODULATION_RANGE', 'NATURAL_FREQUENCY_RANGE',
           'SCATTER_RANGE', 'SIZE_RANGE', 'SPEED_EXPONENT_RANGE', 'Simulation', 'SurfaceDefectLaw',
           'cumulative_revolutions', 'defect_orders', 'growth_factor', 'impulsive_power', 'window_kurtosis']

#: Where the defect sits (each with its strike order, :func:`defect_orders`).
COMPONENTS = ('screw raceway', 'nut raceway', 'roller')
#: How the strikes' strength follows the revolutions run (see module doc).
GROWTH_FORMS = ('steady', 'exponential', 'linear')
#: Drawn range of the impulsive RMS over the thread-contact RMS at the reference condition (the lowest
#: speed, highest load, theta_Oil = 1) at the end of one session: detectable (band kurtosis well above 3)
#: but not always dominant.
SIZE_RANGE = (0.3, 1.5)
#: Drawn range of a: impulsive RMS ~ (omega / omega_ref)^a (impact velocity).
SPEED_EXPONENT_RANGE = (1.0, 2.0)
#: Drawn range of b: impulsive RMS ~ (F / F_ref)^b (contact force at the strike).
LOAD_EXPONENT_RANGE = (0.3, 1.0)
#: Drawn range of the rise of the impulsive RMS over one session by a growing spall (factor).
GROWTH_FACTOR_RANGE = (1.5, 4.0)
#: Drawn range of the ringing mode's natural frequency, fraction of the sample rate (kept below 0.9 x the
#: analysis band's upper edge).
NATURAL_FREQUENCY_RANGE = (0.15, 0.40)
#: Drawn range of the ringing mode's damping ratio.
DAMPING_RANGE = (0.02, 0.10)
#: Drawn range of sigma of ln strike strength (strike-to-strike scatter).
SCATTER_RANGE = (0.1, 0.5)
#: Drawn range of the strike-time jitter, fraction of the strike period (roller slip).
JITTER_RANGE = (0.01, 0.02)
#: Drawn range of the load-zone modulation depth at the carrier order (half the draws have none).
MODULATION_RANGE = (0.2, 0.8)
#: Envelope line over floor per unit impulsive-to-contact power ratio at window level
#: (:meth:`Simulation.window_indicators`).
ENVELOPE_GAIN = 30.0
#: Key of the defect's own random stream in a simulated recording (:meth:`.StreamRandom.keyed`).
DEFECT_STREAM_KEY = 6


def defect_orders(actuator: Actuator) -> dict[str, float]:
    """Strike orders per screw revolution of each of :data:`COMPONENTS` (Eq. 1-2): N (1 - K_P), N K_P, 2 K_R.

    From :func:`..defect_orders.prsm_defect_orders` (the carrier order K_P modulates, it does not strike).
    """
    return {item.component: item.order for item in prsm_defect_orders(actuator) if item.component in COMPONENTS}


def growth_factor(revolutions: npt.ArrayLike, growth_per_revolution: float, linear: bool = False
                  ) -> np.ndarray | float:
    """``g(N)``: ``exp(N / N_g)`` or ``1 + N / N_g`` for revolutions N at 1/N_g per revolution (0: steady)."""
    grown = growth_per_revolution * np.nan_to_num(np.asarray(revolutions, dtype=float))
    return 1.0 + grown if linear else np.exp(grown)


def impulsive_power(impulsive_rms: float, speed: npt.ArrayLike, load: npt.ArrayLike, reference_speed: float,
                    reference_load: float, speed_exponent: float, load_exponent: float,
                    growth: npt.ArrayLike = 1.0) -> np.ndarray:
    """``P_imp = A_imp^2 (|omega|/omega_ref)^(2a) (|F|/F_ref)^(2b) g^2``, (m/s^2)^2; speed rad/s, load N."""
    ratio = np.abs(np.asarray(speed, dtype=float)) / reference_speed
    loading = np.abs(np.asarray(load, dtype=float)) / reference_load
    return np.asarray(impulsive_rms * ratio ** speed_exponent * loading ** load_exponent
                      * np.asarray(growth, dtype=float)) ** 2


def cumulative_revolutions(revolutions: npt.ArrayLike, recording: npt.ArrayLike | None = None) -> np.ndarray:
    """Revolutions run since the start of the first recording, the recordings taken as consecutive in index order.

    A spall does not heal when the screw is relubricated (when each recording's
    count restarts): each recording adds the most revolutions of those before it.
    """
    counted = np.nan_to_num(np.asarray(revolutions, dtype=float))
    if recording is None:
        return counted
    which = np.asarray(recording)
    out = counted.copy()
    offset = 0.0
    for index in np.unique(which):
        mine = which == index
        out[mine] += offset
        offset += float(np.max(counted[mine]))
    return out


def window_kurtosis(contact_power: npt.ArrayLike, impulsive_power: npt.ArrayLike,
                    strike_rate: npt.ArrayLike, decay_time: float, scatter: float) -> np.ndarray:
    """Kurtosis (3 = Gaussian) of Gaussian contact vibration plus a train of ringing strikes, powers in (m/s^2)^2.

    Shot noise at ``strike_rate`` (1/s) of responses ``exp(-t/tau) sin(omega_d t)``
    (``decay_time`` tau, s) with log-normal strengths (sigma ``scatter``) has the
    kurtosis ``3 + e^(4 sigma^2) 3 / (2 lambda tau)``; independent parts mix as
    ``(3 P_c^2 + 6 P_c P_i + K_i P_i^2) / (P_c + P_i)^2``.
    """
    contact, strikes = np.asarray(contact_power, dtype=float), np.asarray(impulsive_power, dtype=float)
    rate = np.maximum(np.asarray(strike_rate, dtype=float), 1e-12)
    alone = 3.0 + math.exp(4.0 * scatter ** 2) * 1.5 / (rate * decay_time)
    return (3.0 * contact ** 2 + 6.0 * contact * strikes + alone * strikes ** 2) / (contact + strikes) ** 2


@dataclass(frozen=True)
class SurfaceDefectLaw:
    """A local defect struck ``strike_order`` times per screw revolution, each strike ringing a mode.

    ``impulsive_rms`` A_imp (m/s^2) at ``reference_speed`` (rad/s) and
    ``reference_load`` (N) before any growth; ``growth`` one of
    :data:`GROWTH_FORMS` with ``growth_revolutions`` N_g (None when steady);
    the strike rings ``natural_frequency`` (Hz) at ``damping_ratio``;
    ``strike_scatter`` sigma of ln strength, ``timing_jitter`` standard deviation
    of the strike time over the strike period; ``modulation_depth`` m of the
    load zone turning at ``modulation_order`` (per screw revolution, 0: none).
    """

    component: str
    strike_order: float          # strikes per screw revolution
    impulsive_rms: float         # m/s^2, A_imp
    reference_speed: float       # rad/s
    reference_load: float        # N
    speed_exponent: float        # a
    load_exponent: float         # b
    natural_frequency: float     # Hz, f_n
    damping_ratio: float         # zeta
    growth: str = 'steady'
    growth_revolutions: float | None = None   # N_g, revolutions
    strike_scatter: float = 0.3
    timing_jitter: float = 0.015
    modulation_depth: float = 0.0
    modulation_order: float = 0.0

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('surface_defect', strike_order=self.strike_order, impulsive_rms=self.impulsive_rms,
                             reference_speed=self.reference_speed, reference_load=self.reference_load,
                             natural_frequency=self.natural_frequency, damping_ratio=self.damping_ratio)
        require(self.component in COMPONENTS,
                f'surface_defect component must be one of {", ".join(COMPONENTS)}, got {self.component!r}')
        require(self.growth in GROWTH_FORMS,
                f'surface_defect growth must be one of {", ".join(GROWTH_FORMS)}, got {self.growth!r}')
        require((self.growth == 'steady') == (self.growth_revolutions is None),
                'surface_defect growth_revolutions is given exactly when the defect grows')
        if self.growth_revolutions is not None:
            require_all_positive('surface_defect', growth_revolutions=self.growth_revolutions)
        require(self.damping_ratio < 1.0 and 0.0 <= self.modulation_depth < 1.0 and self.strike_scatter >= 0
                and 0.0 <= self.timing_jitter < 0.5 and self.speed_exponent >= 0 and self.load_exponent >= 0,
                'surface_defect: damping_ratio < 1, modulation_depth in [0, 1), timing_jitter in [0, 0.5), '
                'strike_scatter and the exponents >= 0')

    @property
    def growth_per_revolution(self) -> float:
        """1 / N_g (0 when steady)."""
        return 0.0 if self.growth_revolutions is None else 1.0 / self.growth_revolutions

    def power(self, speed: npt.ArrayLike, load: npt.ArrayLike, revolutions: npt.ArrayLike) -> np.ndarray:
        """Impulsive mean square P_imp, (m/s^2)^2, at screw speed (rad/s), load (N) and revolutions run."""
        growth = growth_factor(revolutions, self.growth_per_revolution, self.growth == 'linear')
        return impulsive_power(self.impulsive_rms, speed, load, self.reference_speed, self.reference_load,
                               self.speed_exponent, self.load_exponent, growth)


Law = SurfaceDefectLaw


class Extension(EffectExtension):
    """``A = sqrt(A_22^2 + P_imp)``: impulsive power adding to the contacts' at speed, load and revolutions.

    Parameters: ``impulsive_rms`` (m/s^2), ``reference_speed`` (rad/s),
    ``reference_load`` (N), ``speed_exponent``, ``load_exponent``,
    ``growth_per_revolution`` (1/N_g, 0 steady) and ``linear`` (1 for linear
    growth).  Revolutions count over the recordings in index order
    (:func:`cumulative_revolutions`).  It is not lubrication: the assessment
    film factor stays 1 and Eq. 22's amplitude is the RMS with P_imp removed.
    """

    id = 'surface_defect'

    @staticmethod
    def power(params: Mapping[str, float], covariates: Any) -> np.ndarray:
        """P_imp of each window, (m/s^2)^2."""
        revolutions = cumulative_revolutions(covariates.revolutions, getattr(covariates, 'recording', None))
        growth = growth_factor(revolutions, params.get('growth_per_revolution', 0.0), bool(params.get('linear')))
        return impulsive_power(params['impulsive_rms'], covariates.speed, covariates.load, params['reference_speed'],
                               params['reference_load'], params['speed_exponent'], params['load_exponent'], growth)

    def log_gain(self, params: Mapping[str, float], covariates: Any, ln_a22: np.ndarray | float) -> np.ndarray | float:
        """``0.5 ln(1 + P_imp / A_22^2)``."""
        return added_power_log_gain(ln_a22, np.sqrt(self.power(params, covariates)))

    def eq22_amplitude(self, params: Mapping[str, float], covariates: Any, rms: npt.ArrayLike) -> np.ndarray:
        """``sqrt(A^2 - P_imp)``; NaN where the RMS does not exceed the impulsive part."""
        return contact_amplitude(rms, np.sqrt(self.power(params, covariates)))


class _Strikes(Waveform):
    """The strike train ringing the mode, carrying the screw's turns, the strike count and the filter state."""

    def __init__(self, law: SurfaceDefectLaw, sample_rate: float, random: StreamRandom) -> None:
        """The mode as a two-pole resonator ``h[n] = r^n sin(n omega_d T)``; the first strike's phase at random."""
        self.law, self.fs, self.rng = law, sample_rate, random.keyed(DEFECT_STREAM_KEY)
        omega = 2.0 * math.pi * law.natural_frequency / sample_rate
        radius = math.exp(-law.damping_ratio * omega)
        damped = omega * math.sqrt(1.0 - law.damping_ratio ** 2)
        self.b = np.array([0.0, math.sin(damped)])
        self.a = np.array([1.0, -2.0 * radius * math.cos(damped), radius ** 2])
        self.energy = resonator_energy(self.b, self.a)
        self.state = np.zeros(2)
        self.phase = float(self.rng.uniform())                 # strike phase at the start, strike periods
        self.carrier_phase = float(self.rng.uniform(0.0, 2.0 * math.pi))
        self.turns, self.last_angle = 0.0, math.nan            # revolutions run (either direction), never reset

    def add(self, state: SampleState) -> np.ndarray:
        """The ringing strikes of this chunk, m/s^2 (none at standstill).

        A strike falls where ``n_d N + phase`` passes a whole number (N the
        turns run), moved by the timing jitter; its strength makes the train's
        mean square P_imp at the strike's speed, load and revolutions:
        ``z sqrt(P_imp f_s / (lambda E_h))`` (N all turns run: a spall does not
        heal when the screw is relubricated) with lambda = n_d |omega| / (2 pi)
        strikes per second, E_h the mode's impulse-response energy and z the
        log-normal scatter (unit mean square) times the load-zone modulation.
        """
        from scipy.signal import lfilter
        law, count = self.law, state.times.size
        last = state.angles[0] if math.isnan(self.last_angle) else self.last_angle
        before = self.turns
        turns = before + np.cumsum(np.abs(np.diff(state.angles, prepend=last))) / (2.0 * math.pi)
        self.turns, self.last_angle = float(turns[-1]), float(state.angles[-1])
        strikes = np.floor(law.strike_order * turns + self.phase)
        index = np.flatnonzero(np.diff(strikes, prepend=math.floor(law.strike_order * before + self.phase)) > 0)
        train = np.zeros(count)
        if index.size:
            speed = np.abs(state.speeds[index])
            rate = law.strike_order * speed / (2.0 * math.pi)
            period = self.fs / np.maximum(rate, 1e-9)
            moved = index + np.rint(law.timing_jitter * period * self.rng.standard_normal(index.size))
            moved = np.clip(moved, 0, count - 1).astype(np.int64)
            scatter = np.exp(law.strike_scatter * self.rng.standard_normal(index.size) - law.strike_scatter ** 2)
            depth = law.modulation_depth
            zone = (1.0 + depth * np.cos(2.0 * math.pi * law.modulation_order * turns[index] + self.carrier_phase)
                    ) / math.sqrt(1.0 + 0.5 * depth ** 2)
            power = law.power(speed, state.loads[index], turns[index])
            strength = np.sqrt(power * self.fs / (np.maximum(rate, 1e-9) * self.energy)) * scatter * zone
            np.add.at(train, moved, strength)
        ringing, self.state = lfilter(self.b, self.a, train, zi=self.state)
        return np.asarray(ringing)


class Simulation(EffectSimulation):
    """The strike train added to the samples; its power beside the contacts' in the expected RMS."""

    id = 'surface_defect'

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> SurfaceDefectLaw:
        """A defect on one of :data:`COMPONENTS`, every parameter drawn in the module's ranges.

        Reference condition: the plan's lowest speed and highest load, where the
        contacts' RMS is ``context.reference_amplitude``; the size (:data:`SIZE_RANGE`)
        holds at the end of one session (``context.session_revolutions``), so a
        growing defect starts smaller by its growth factor.  Half the defects
        are steady, the others grow exponentially or linearly; half have a
        load-zone modulation at the carrier order K_P.
        """
        orders = defect_orders(context.actuator)
        component = choose(rng, COMPONENTS)
        growth = choose(rng, GROWTH_FORMS[1:]) if rng.uniform() < 0.5 else GROWTH_FORMS[0]
        factor = rng.uniform(*GROWTH_FACTOR_RANGE)
        session = context.session_revolutions
        growth_revolutions = (None if growth == 'steady' else
                              session / math.log(factor) if growth == 'exponential' else session / (factor - 1.0))
        size = rng.uniform(*SIZE_RANGE) / (1.0 if growth == 'steady' else factor)
        top = min(NATURAL_FREQUENCY_RANGE[1] * context.sample_rate, 0.9 * context.band_high)
        natural = rng.uniform(min(NATURAL_FREQUENCY_RANGE[0] * context.sample_rate, 0.5 * top), top)
        depth = rng.uniform(*MODULATION_RANGE) if rng.uniform() < 0.5 else 0.0
        carrier = float(roller_revolution_speed(1.0, context.actuator.screw_mean_diameter,
                                                context.actuator.roller_mean_diameter))
        return SurfaceDefectLaw(
            component=component, strike_order=float(orders[component]),
            impulsive_rms=float(size * context.reference_amplitude), reference_speed=float(min(context.speeds)),
            reference_load=float(max(context.loads)), speed_exponent=float(rng.uniform(*SPEED_EXPONENT_RANGE)),
            load_exponent=float(rng.uniform(*LOAD_EXPONENT_RANGE)), natural_frequency=float(natural),
            damping_ratio=float(rng.uniform(*DAMPING_RANGE)), growth=growth,
            growth_revolutions=None if growth_revolutions is None else float(growth_revolutions),
            strike_scatter=float(rng.uniform(*SCATTER_RANGE)), timing_jitter=float(rng.uniform(*JITTER_RANGE)),
            modulation_depth=float(depth), modulation_order=carrier if depth > 0 else 0.0)

    def added_power(self, law: SurfaceDefectLaw, state: ContactState) -> np.ndarray:
        """P_imp at the speed, load and revolutions.

        The revolutions are those since the last lubrication; the strikes
        themselves grow with all revolutions run, the same within the first session.
        """
        return law.power(state.speed, state.load, state.revolutions)

    def waveform(self, law: SurfaceDefectLaw, sample_rate: float, random: StreamRandom) -> Waveform:
        """The ringing strikes (:class:`_Strikes`)."""
        return _Strikes(law, sample_rate, random)

    def window_indicators(self, law: SurfaceDefectLaw, state: ContactState, contact_power: np.ndarray
                          ) -> dict[str, np.ndarray]:
        """Kurtosis of contact plus strikes (:func:`window_kurtosis`), an envelope peak at the strike order, P_imp.

        The peak stands in for the envelope spectrum at window level: its level
        over the floor grows with the impulsive share of the power,
        ``10 lg(1 + ENVELOPE_GAIN P_imp / P_c)`` dB (a strike train half the contact power
        peaks about 12 dB over the floor).
        """
        power = law.power(state.speed, state.load, state.revolutions)
        rate = law.strike_order * np.abs(np.asarray(state.speed, dtype=float)) / (2.0 * math.pi)
        decay = 1.0 / (2.0 * math.pi * law.natural_frequency * law.damping_ratio)
        contact = np.asarray(contact_power, dtype=float)
        return {'kurtosis': window_kurtosis(contact, power, rate, decay, law.strike_scatter),
                'defect_db': 10.0 * np.log10(1.0 + ENVELOPE_GAIN * power / contact),
                'defect_order': np.full(contact.shape, law.strike_order), 'impulsive_power': power}

    def extension_params(self, law: SurfaceDefectLaw, context: SimulationContext) -> dict[str, float]:
        """The law as :class:`Extension` parameters."""
        return {'impulsive_rms': law.impulsive_rms, 'reference_speed': law.reference_speed,
                'reference_load': law.reference_load, 'speed_exponent': law.speed_exponent,
                'load_exponent': law.load_exponent, 'growth_per_revolution': law.growth_per_revolution,
                'linear': 1.0 if law.growth == 'linear' else 0.0}
