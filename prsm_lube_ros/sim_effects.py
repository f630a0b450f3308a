# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Physical effects the paper's model leaves out, as the rig simulator's *truth*.

Each effect is a frozen dataclass of physical parameters (SI) with the
function that says how it changes the recording, and a ``draw_*`` function
that picks its parameters at random inside a documented physical range (for
studies of the diagnosis).  :mod:`prsm_lube_ros.rig_simulator` applies them;
recordings carry no label of them, only ``truth.json`` does.  The diagnosis
side models these effects separately and must not import this module.

All effects are off by default (:class:`Effects` with every field ``None``).
How each one changes the acceleration RMS ``A`` of Eq. 22:

* ``position_dependent_stiffness``: ``A = A_22 (1 + k_c(F) / k_s(x))``;
* ``resonance``: ``A = A_22 |H(r)|``, ``r = n f_S / f_r``;
* ``thermal_viscosity``: theta_Oil C_lambda in the exponent of Eq. 22 is
  multiplied by ``(eta(T) / eta_ref)^0.68``;
* ``lubricant_depletion``: ``theta_eff = theta_Oil exp(-N_rev / N_d)``;
* ``background_vibration``: ``A^2 = A_22^2 + B^2``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields
import math

import numpy as np

from .errors import InputError
from .vibration_model import STIFFNESS_EXPONENT, VELOCITY_EXPONENT, forced_response_amplitude

#: Effect identifiers, as CONTRACT.md names them for ``prsm-lube diagnose``.
EFFECT_IDS = ('position_dependent_stiffness', 'resonance', 'thermal_viscosity',
              'lubricant_depletion', 'background_vibration')

#: Drawn range of the amplitude change over one stroke at the reference load (fraction).
STIFFNESS_CHANGE_RANGE = (0.05, 0.30)
#: Drawn range of the frequency ratio r = n f_S / f_r at the plan's top forward speed.
RESONANCE_RATIO_RANGE = (0.5, 0.9)
#: Drawn range of the damping ratio of the structural mode.
RESONANCE_DAMPING_RANGE = (0.02, 0.10)
#: Drawn range of the steady temperature rise of nut and oil while running, K.
TEMPERATURE_RISE_RANGE = (5.0, 25.0)
#: Drawn range of the thermal time constant of nut and oil, s.
THERMAL_TIME_CONSTANT_RANGE = (120.0, 600.0)
#: Drawn range of the fall of theta_Oil over one session (one bag) by depletion (fraction).
DEPLETION_FALL_RANGE = (0.05, 0.25)
#: Drawn range of the background RMS relative to the thread-contact RMS at the lowest speed.
#: Background RMS as a fraction of the thread-contact amplitude at the lowest speed.  Adding in power, 0.5 raises
#: the low-speed amplitude by 12 % (the least at which "the amplitude stops following the model" at low speed)
#: and 1.5 by 80 % (motor and bearing vibration dominating a slowly turning screw).
BACKGROUND_FRACTION_RANGE = (0.50, 1.50)


def _check_positive(owner: str, **values) -> None:
    """Raise :class:`InputError` unless every value is a finite number > 0."""
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise InputError(f'{owner} {name} must be a positive number, got {value!r}')


def shaft_axial_stiffness(youngs_modulus: float, root_diameter: float, free_length):
    """Axial stiffness of the screw shaft between nut and fixed bearing, ``k_s = E A / L`` in N/m.

    youngs_modulus E in Pa, root_diameter in m (A = pi d^2 / 4), free_length L in m.
    """
    area = math.pi * root_diameter ** 2 / 4.0
    return youngs_modulus * area / np.asarray(free_length, dtype=float)


def series_stiffness_amplification(contact_stiffness, shaft_stiffness):
    """``K_hertz / K_series = 1 + k_c / k_s``: how much a compliant shaft in series raises X0 = F0/K."""
    return 1.0 + np.asarray(contact_stiffness, dtype=float) / np.asarray(shaft_stiffness, dtype=float)


def resonance_magnification(frequency_ratio, damping_ratio: float):
    """``|H(r)| = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2)``: Eq. 13's forced response over Eq. 14's X0 = F0/K.

    frequency_ratio r = excitation / natural frequency, damping_ratio zeta (dimensionless).
    Written with :func:`vibration_model.forced_response_amplitude` for k = 1, m = 1, c = 2 zeta.
    """
    ratio = np.abs(np.asarray(frequency_ratio, dtype=float))
    return forced_response_amplitude(1.0, 1.0, 1.0, 2.0 * damping_ratio, ratio)


def viscosity_ratio(temperature, reference_temperature: float, viscosity_temperature_coefficient: float):
    """``eta(T) / eta_ref = exp(-beta (T - T_ref))`` (Reynolds' exponential law), dimensionless.

    temperature T and reference_temperature T_ref in degC, beta in 1/K.
    """
    return np.exp(-viscosity_temperature_coefficient
                  * (np.asarray(temperature, dtype=float) - reference_temperature))


@dataclass(frozen=True)
class PositionDependentStiffness:
    """Screw shaft compliance in series with the thread contacts, changing with nut position.

    The axially fixed bearing sits at the far end of travel, so the free shaft
    length ``L(x) = free_length_at_start - x`` shrinks as the nut travels by x
    (m, from the start of the stroke) and ``k_s = E A / L`` grows: the amplitude
    falls along the stroke, as the paper saw.  The Hertzian contact stiffness
    follows ``k_c = contact_stiffness (F / reference_load)^(1/3)`` (Eq. 17, 20).
    """

    contact_stiffness: float        # N/m, k_c at reference_load
    reference_load: float           # N
    youngs_modulus: float           # Pa, shaft material
    root_diameter: float            # m, shaft root diameter
    free_length_at_start: float     # m, nut to fixed bearing at travel 0

    def __post_init__(self):
        """Reject non-physical parameters."""
        _check_positive('position_dependent_stiffness', **asdict(self))

    @property
    def stiffness_ratio_at_start(self) -> float:
        """``k_c / k_s`` at travel 0 and the reference load, dimensionless."""
        return float(self.contact_stiffness
                     / shaft_axial_stiffness(self.youngs_modulus, self.root_diameter,
                                             self.free_length_at_start))

    def amplitude_factor(self, nut_position, axial_load):
        """``1 + k_c(F) / k_s(x)`` for nut_position x in m and axial_load F in N."""
        length = np.maximum(self.free_length_at_start - np.asarray(nut_position, dtype=float), 1e-3)
        contact = self.contact_stiffness * (np.abs(np.asarray(axial_load, dtype=float))
                                            / self.reference_load) ** STIFFNESS_EXPONENT
        return series_stiffness_amplification(
            contact, shaft_axial_stiffness(self.youngs_modulus, self.root_diameter, length))


@dataclass(frozen=True)
class Resonance:
    """A rotation-order excitation approaching a lightly damped structural mode.

    The excitation at ``order`` times the screw rotation frequency f_S drives
    the mode at natural_frequency f_r; the thread-contact vibration is
    magnified by ``|H(r)|``, ``r = order f_S / f_r``.
    """

    order: float              # excitation order (per screw revolution)
    natural_frequency: float  # Hz, f_r
    damping_ratio: float      # zeta

    def __post_init__(self):
        """Reject non-physical parameters."""
        _check_positive('resonance', **asdict(self))
        if self.damping_ratio >= 1.0:
            raise InputError(f'resonance damping_ratio must be below 1, got {self.damping_ratio!r}')

    def frequency_ratio(self, screw_speed):
        """``r = order |omega_S| / (2 pi f_r)`` for screw_speed in rad/s."""
        return (self.order * np.abs(np.asarray(screw_speed, dtype=float))
                / (2.0 * math.pi * self.natural_frequency))

    def amplitude_factor(self, screw_speed):
        """``|H(r)|`` at screw_speed in rad/s."""
        return resonance_magnification(self.frequency_ratio(screw_speed), self.damping_ratio)


@dataclass(frozen=True)
class ThermalViscosity:
    """Nut and oil warm while running and cool at standstill; the oil thins.

    Temperature relaxes with time_constant tau towards ``T0 + temperature_rise``
    while the screw turns and towards the ambient T0 at standstill, so from cold
    ``T = T0 + dT (1 - exp(-t_run / tau))``.  Viscosity follows
    ``eta(T) = eta_ref exp(-beta (T - T0))`` (eta_ref at the ambient T0 of the
    rig, where the true constants hold); the film and with it the exponent
    ``theta C_lambda omega^0.68 F^-0.073`` of Eq. 22 scale with ``(eta/eta_ref)^0.68``.
    """

    temperature_rise: float                    # K, dT
    time_constant: float                       # s, tau
    viscosity_temperature_coefficient: float   # 1/K, beta

    def __post_init__(self):
        """Reject non-physical parameters."""
        _check_positive('thermal_viscosity', **asdict(self))

    def film_factor(self, temperature, ambient_temperature: float):
        """``(eta(T) / eta_ref)^0.68``, the factor on theta_Oil C_lambda in Eq. 22."""
        return viscosity_ratio(temperature, ambient_temperature,
                               self.viscosity_temperature_coefficient) ** VELOCITY_EXPONENT


@dataclass(frozen=True)
class LubricantDepletion:
    """Oil flung out of the contacts: ``theta_eff = theta_Oil exp(-N_rev / N_d)``.

    N_rev is the screw revolutions (either direction) run since the last
    lubrication, i.e. since the start of the bag.
    """

    depletion_revolutions: float   # N_d, revolutions

    def __post_init__(self):
        """Reject non-physical parameters."""
        _check_positive('lubricant_depletion', **asdict(self))

    def theta_factor(self, revolutions):
        """``exp(-N_rev / N_d)`` for revolutions N_rev since the last lubrication."""
        return np.exp(-np.asarray(revolutions, dtype=float) / self.depletion_revolutions)


@dataclass(frozen=True)
class BackgroundVibration:
    """Vibration not from the thread contacts (drive, bearings, frame), adding in power.

    ``rms`` B in m/s^2 is split by power shares between fixed-frequency tones
    (Hz, not following the rotation) and white broadband noise; present
    whenever the rig is powered, including standstill.
    """

    rms: float                                  # m/s^2, B
    tone_frequencies: tuple[float, ...] = (100.0, 287.0)   # Hz: drive (2x mains), frame/bearing
    tone_shares: tuple[float, ...] = (0.4, 0.3)            # power shares of the tones
    broadband_share: float = 0.3                           # power share of the white part

    def __post_init__(self):
        """Reject non-physical parameters; the shares must add up to 1."""
        _check_positive('background_vibration', rms=self.rms)
        object.__setattr__(self, 'tone_frequencies', tuple(float(f) for f in self.tone_frequencies))
        object.__setattr__(self, 'tone_shares', tuple(float(s) for s in self.tone_shares))
        if len(self.tone_frequencies) != len(self.tone_shares):
            raise InputError('background_vibration tone_frequencies and tone_shares differ in length')
        for frequency in self.tone_frequencies:
            _check_positive('background_vibration', tone_frequency=frequency)
        shares = (*self.tone_shares, self.broadband_share)
        if min(shares) < 0 or abs(sum(shares) - 1.0) > 1e-9:
            raise InputError(f'background_vibration shares must be >= 0 and add up to 1, got {shares}')


_EFFECT_TYPES = {'position_dependent_stiffness': PositionDependentStiffness, 'resonance': Resonance,
                 'thermal_viscosity': ThermalViscosity, 'lubricant_depletion': LubricantDepletion,
                 'background_vibration': BackgroundVibration}


@dataclass(frozen=True)
class Effects:
    """Which effects act on the simulated rig (``None`` = off) and with which parameters."""

    position_dependent_stiffness: PositionDependentStiffness | None = None
    resonance: Resonance | None = None
    thermal_viscosity: ThermalViscosity | None = None
    lubricant_depletion: LubricantDepletion | None = None
    background_vibration: BackgroundVibration | None = None

    @property
    def active(self) -> tuple[str, ...]:
        """IDs of the effects that are on."""
        return tuple(name for name in EFFECT_IDS if getattr(self, name) is not None)

    def as_dict(self) -> dict:
        """``{effect_id: parameters or None}`` for ``truth.json``."""
        result = {}
        for name in EFFECT_IDS:
            effect = getattr(self, name)
            if effect is None:
                result[name] = None
                continue
            result[name] = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(effect).items()}
            if isinstance(effect, PositionDependentStiffness):
                result[name]['stiffness_ratio_at_start'] = effect.stiffness_ratio_at_start
        return result

    @classmethod
    def from_dict(cls, mapping: dict | None) -> 'Effects':
        """Inverse of :meth:`as_dict` (derived entries are ignored)."""
        values = {}
        for name, params in (mapping or {}).items():
            if name not in _EFFECT_TYPES:
                raise InputError(f'effects: unknown effect {name!r}; known: {", ".join(EFFECT_IDS)}')
            if params is None:
                continue
            kind = _EFFECT_TYPES[name]
            known = {f.name for f in fields(kind)}
            try:
                values[name] = kind(**{k: (tuple(v) if isinstance(v, list) else v)
                                       for k, v in params.items() if k in known})
            except TypeError as exc:
                raise InputError(f'effects: {name} parameters incomplete ({exc})') from None
        return cls(**values)


def draw_position_dependent_stiffness(rng: np.random.Generator, *, youngs_modulus: float,
                                      root_diameter: float, stroke: float, fixed_end_offset: float,
                                      reference_load: float) -> PositionDependentStiffness:
    """Random shaft-compliance effect: 5-30 % amplitude fall over the stroke at reference_load.

    The fixed bearing lies fixed_end_offset (m) beyond the end of the stroke,
    so ``L(0) = stroke + fixed_end_offset`` and ``L(stroke) = fixed_end_offset``.
    With rho0 = k_c / k_s(0) the relative fall is
    ``c = rho0 (1 - L(stroke)/L(0)) / (1 + rho0)``; c is drawn uniformly from
    :data:`STIFFNESS_CHANGE_RANGE` and rho0 solved from it.
    """
    length_start = stroke + fixed_end_offset
    shrink = 1.0 - fixed_end_offset / length_start
    change = rng.uniform(*STIFFNESS_CHANGE_RANGE)
    if change >= shrink:
        raise InputError(f'position_dependent_stiffness: a {change:.0%} change is impossible with '
                         f'fixed_end_offset {fixed_end_offset} m')
    ratio = change / (shrink - change)
    contact = ratio * float(shaft_axial_stiffness(youngs_modulus, root_diameter, length_start))
    return PositionDependentStiffness(contact_stiffness=contact, reference_load=reference_load,
                                      youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                      free_length_at_start=length_start)


def draw_resonance(rng: np.random.Generator, *, order: float, top_speed: float) -> Resonance:
    """Random resonance: r at top_speed (rad/s) in :data:`RESONANCE_RATIO_RANGE`, zeta in its range."""
    ratio = rng.uniform(*RESONANCE_RATIO_RANGE)
    damping = rng.uniform(*RESONANCE_DAMPING_RANGE)
    natural = order * abs(top_speed) / (2.0 * math.pi) / ratio
    return Resonance(order=float(order), natural_frequency=float(natural), damping_ratio=float(damping))


def draw_thermal_viscosity(rng: np.random.Generator, *,
                           viscosity_temperature_coefficient: float) -> ThermalViscosity:
    """Random warming: dT and tau uniform in their documented ranges; beta (1/K) is the oil's."""
    return ThermalViscosity(temperature_rise=float(rng.uniform(*TEMPERATURE_RISE_RANGE)),
                            time_constant=float(rng.uniform(*THERMAL_TIME_CONSTANT_RANGE)),
                            viscosity_temperature_coefficient=float(viscosity_temperature_coefficient))


def draw_lubricant_depletion(rng: np.random.Generator, *, session_revolutions: float) -> LubricantDepletion:
    """Random depletion: theta falls by 5-25 % over session_revolutions (one bag)."""
    fall = rng.uniform(*DEPLETION_FALL_RANGE)
    return LubricantDepletion(depletion_revolutions=float(session_revolutions / -math.log1p(-fall)))


def draw_background_vibration(rng: np.random.Generator, *,
                              reference_amplitude: float) -> BackgroundVibration:
    """Random background: B = 50-150 % of reference_amplitude (m/s^2, thread contacts at the lowest speed)."""
    fraction = rng.uniform(*BACKGROUND_FRACTION_RANGE)
    return BackgroundVibration(rms=float(fraction * reference_amplitude))
