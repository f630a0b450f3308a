# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Oil viscosity falling with temperature, thinning the film of Eq. 9.

Physics: Eq. 9 holds the viscosity at its reference value; in service the nut
and oil warm and the viscosity falls.  The Hamrock-Dowson film grows with
``(eta u)^0.68`` (Eq. 8, U is proportional to eta), so the film ratio in the
exponent of Eq. 22 scales by

    f(T) = (eta(T) / eta_ref)^0.68.

Three viscosity-temperature laws of lubricating oils are known here
(:data:`LAWS`), each written with the slope ``beta = -d ln eta / dT`` at
T_ref (1/K) and, for the curved ones, one shape parameter:

* ``exponential`` (Reynolds): ``eta / eta_ref = exp(-beta (T - T_ref))``; a
  straight line in ln eta, good over a few tens of kelvin;
* ``vogel`` (Vogel-Fulcher-Tammann): ``eta = a exp(b / (T - T_V))`` with the
  Vogel temperature T_V (degC) below which the oil would stop flowing; with
  ``D = T_ref - T_V`` (K) and ``b = beta D^2`` (so the slope at T_ref is
  beta): ``eta / eta_ref = exp(beta D^2 (1 / (T - T_V) - 1 / D))``; ln eta is
  convex in T, the more so the smaller D (mineral oils: D about 100-150 K);
* ``walther`` (ASTM D341): ``log10 log10(nu + 0.7) = A - B log10 T_K`` for
  the kinematic viscosity nu in mm^2/s and the absolute temperature T_K; given
  nu_ref at T_ref, B follows from beta (``B = beta T_K,ref nu_ref / ((nu_ref +
  0.7) ln(nu_ref + 0.7))``) and ``nu(T) = 10^(10^(Z_ref - B log10(T_K / T_K,ref)))
  - 0.7``.  The oil's density changes by well under 0.1 %/K, so
  ``eta / eta_ref = nu / nu_ref``.

The rig's nut and oil relax with time constant tau towards ``T0 + dT`` while
the screw turns and towards the ambient T0 at standstill.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import choose, Extension as EffectExtension, Simulation as EffectSimulation
from ...validation import require, require_all_positive
from ..vibration_model import VELOCITY_EXPONENT

if TYPE_CHECKING:
    from collections.abc import Mapping

    import numpy.typing as npt

    from . import ContactState, SimulationContext

__all__ = ['Extension', 'KELVIN', 'LAWS', 'Law', 'REFERENCE_VISCOSITY_RANGE', 'Simulation', 'TEMPERATURE_RISE_RANGE',
           'THERMAL_TIME_CONSTANT_RANGE', 'ThermalViscosityLaw', 'VOGEL_DISTANCE_RANGE', 'WALTHER_OFFSET', 'draw',
           'film_factor',
           'law_viscosity_ratio', 'viscosity_ratio', 'vogel_viscosity_ratio', 'walther_slope',
           'walther_viscosity_ratio']

#: Viscosity-temperature laws (see module doc).
LAWS = ('exponential', 'vogel', 'walther')
#: degC to K.
KELVIN = 273.15
#: ASTM D341's additive constant, mm^2/s.
WALTHER_OFFSET = 0.7
#: Drawn range of Vogel's T0 - T_V, K (mineral oils).
VOGEL_DISTANCE_RANGE = (90.0, 150.0)
#: Drawn range of the kinematic viscosity at ambient for the Walther law, mm^2/s (ISO VG 32-320).
REFERENCE_VISCOSITY_RANGE = (30.0, 300.0)
#: Drawn range of the steady temperature rise of nut and oil while running, K.
TEMPERATURE_RISE_RANGE = (5.0, 25.0)
#: Drawn range of the thermal time constant of nut and oil, s.
THERMAL_TIME_CONSTANT_RANGE = (120.0, 600.0)


def viscosity_ratio(temperature: npt.ArrayLike, reference_temperature: float,
                    viscosity_temperature_coefficient: npt.ArrayLike) -> np.ndarray | float:
    """``eta(T) / eta_ref = exp(-beta (T - T_ref))`` (Reynolds' exponential law), dimensionless.

    temperature T and reference_temperature T_ref in degC, beta in 1/K.
    """
    return np.exp(-np.asarray(viscosity_temperature_coefficient, dtype=float)
                  * (np.asarray(temperature, dtype=float) - reference_temperature))


def vogel_viscosity_ratio(temperature: npt.ArrayLike, reference_temperature: float,
                          viscosity_temperature_coefficient: float, vogel_distance: float) -> np.ndarray | float:
    """Vogel: ``eta / eta_ref = exp(beta D^2 (1 / (T - T_V) - 1 / D))``, ``T_V = T_ref - D``, dimensionless.

    T, T_ref in degC, beta (slope of ln eta at T_ref) in 1/K, vogel_distance D = T_ref - T_V in K.
    Temperatures at or below T_V + D/10 are held there (the law diverges at T_V).
    """
    gap = np.maximum(np.asarray(temperature, dtype=float) - reference_temperature + vogel_distance,
                     0.1 * vogel_distance)
    return np.exp(viscosity_temperature_coefficient * vogel_distance ** 2 * (1.0 / gap - 1.0 / vogel_distance))


def walther_slope(viscosity_temperature_coefficient: float, reference_temperature: float,
                  reference_viscosity: float) -> float:
    """ASTM D341's B (dimensionless) giving the slope beta (1/K) of ln nu at T_ref (degC), nu_ref in mm^2/s."""
    shifted = reference_viscosity + WALTHER_OFFSET
    return (viscosity_temperature_coefficient * (reference_temperature + KELVIN) * reference_viscosity
            / (shifted * math.log(shifted)))


def walther_viscosity_ratio(temperature: npt.ArrayLike, reference_temperature: float,
                            viscosity_temperature_coefficient: float, reference_viscosity: float) -> np.ndarray | float:
    """Walther / ASTM D341: ``nu(T) / nu_ref`` with ``log10 log10(nu + 0.7) = A - B log10 T_K``, dimensionless.

    T, T_ref in degC, beta (slope of ln nu at T_ref) in 1/K, reference_viscosity nu_ref in mm^2/s.
    """
    slope = walther_slope(viscosity_temperature_coefficient, reference_temperature, reference_viscosity)
    z_ref = math.log10(math.log10(reference_viscosity + WALTHER_OFFSET))
    absolute = np.maximum(np.asarray(temperature, dtype=float) + KELVIN, 1.0)
    z = z_ref - slope * np.log10(absolute / (reference_temperature + KELVIN))
    return (10.0 ** (10.0 ** z) - WALTHER_OFFSET) / reference_viscosity


def law_viscosity_ratio(law: str, temperature: npt.ArrayLike, reference_temperature: float,
                        viscosity_temperature_coefficient: float, shape: float = math.nan) -> np.ndarray | float:
    """``eta(T) / eta_ref`` by one of :data:`LAWS`; ``shape`` is D (K) for vogel, nu_ref (mm^2/s) for walther."""
    if law == 'vogel':
        return vogel_viscosity_ratio(temperature, reference_temperature, viscosity_temperature_coefficient, shape)
    if law == 'walther':
        return walther_viscosity_ratio(temperature, reference_temperature, viscosity_temperature_coefficient,
                                       shape)
    if law != 'exponential':
        raise ValueError(f'unknown viscosity law {law!r}; known: {", ".join(LAWS)}')
    return viscosity_ratio(temperature, reference_temperature, viscosity_temperature_coefficient)


def film_factor(temperature: npt.ArrayLike, reference_temperature: float, viscosity_temperature_coefficient: float,
                law: str = 'exponential', shape: float = math.nan) -> np.ndarray | float:
    """``(eta(T) / eta_ref)^0.68``: the factor on theta_Oil C_lambda in the exponent of Eq. 22 (Eq. 8)."""
    return law_viscosity_ratio(law, temperature, reference_temperature, viscosity_temperature_coefficient,
                               shape) ** VELOCITY_EXPONENT


@dataclass(frozen=True)
class ThermalViscosityLaw:
    """Nut and oil warm while running and cool at standstill; the oil thins.

    From cold ``T = T0 + dT (1 - exp(-t_run / tau))``; eta_ref is at the
    ambient T0 of the rig, where the true constants hold.  ``viscosity_law``
    is one of :data:`LAWS`; beta is the slope of ln eta at T0 in every law,
    ``vogel_distance`` (K, T0 - T_V) shapes the Vogel law and
    ``reference_viscosity`` (mm^2/s at T0) the Walther law.
    """

    temperature_rise: float                    # K, dT
    time_constant: float                       # s, tau
    viscosity_temperature_coefficient: float   # 1/K, beta
    viscosity_law: str = 'exponential'
    vogel_distance: float = 120.0              # K, T0 - T_V (vogel)
    reference_viscosity: float = 100.0         # mm^2/s at T0 (walther)

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('thermal_viscosity', temperature_rise=self.temperature_rise,
                             time_constant=self.time_constant,
                             viscosity_temperature_coefficient=self.viscosity_temperature_coefficient,
                             vogel_distance=self.vogel_distance, reference_viscosity=self.reference_viscosity)
        require(self.viscosity_law in LAWS,
                f'thermal_viscosity viscosity_law must be one of {", ".join(LAWS)}, got {self.viscosity_law!r}')

    @property
    def shape(self) -> float:
        """The law's shape parameter: D for vogel, nu_ref for walther, NaN for exponential."""
        return {'vogel': self.vogel_distance, 'walther': self.reference_viscosity}.get(self.viscosity_law, math.nan)

    def film_factor(self, temperature: npt.ArrayLike, ambient_temperature: float) -> np.ndarray | float:
        """``(eta(T) / eta_ref)^0.68``, the factor on theta_Oil C_lambda in Eq. 22."""
        return film_factor(temperature, ambient_temperature, self.viscosity_temperature_coefficient,
                           self.viscosity_law, self.shape)


Law = ThermalViscosityLaw


def _params_law(params: Mapping[str, float]) -> tuple[str, float]:
    """The law and its shape parameter from fitted parameters (exponential when neither shape is given)."""
    if 'vogel_distance' in params:
        return 'vogel', params['vogel_distance']
    if 'reference_viscosity' in params:
        return 'walther', params['reference_viscosity']
    return 'exponential', math.nan


class Extension(EffectExtension):
    """theta_Oil in Eq. 22 times ``(eta(T)/eta_ref)^0.68`` by the law the parameters name.

    beta and T_ref, plus ``vogel_distance`` (Vogel) or ``reference_viscosity`` (Walther) when the law is curved.
    """

    id = 'thermal_viscosity'

    def film_factor(self, params: Mapping[str, float], covariates: Any) -> np.ndarray | float:
        """``(eta(T)/eta_ref)^0.68``; windows without a temperature count as at T_ref."""
        temperature = np.asarray(covariates.temperature, dtype=float)
        reference = params['reference_temperature']
        law, shape = _params_law(params)
        return film_factor(np.where(np.isfinite(temperature), temperature, reference), reference,
                           params['viscosity_temperature_coefficient'], law, shape)

    def assessment_film_factor(self, params: Mapping[str, float], covariates: Any) -> np.ndarray:
        """As :meth:`film_factor`, but NaN (not assessable) without a temperature."""
        temperature = np.asarray(covariates.temperature, dtype=float)
        return np.where(np.isfinite(temperature), self.film_factor(params, covariates), np.nan)


def draw(rng: np.random.Generator, *, viscosity_temperature_coefficient: float,
         law: str | None = None) -> ThermalViscosityLaw:
    """Random warming: dT and tau uniform in their ranges; beta (1/K) is the oil's slope at ambient.

    ``law`` (default: drawn) is one of :data:`LAWS`; Vogel's distance
    T0 - T_V and Walther's nu_ref are drawn in :data:`VOGEL_DISTANCE_RANGE` and
    :data:`REFERENCE_VISCOSITY_RANGE`.
    """
    law = choose(rng, LAWS, law)
    return ThermalViscosityLaw(temperature_rise=float(rng.uniform(*TEMPERATURE_RISE_RANGE)),
                               time_constant=float(rng.uniform(*THERMAL_TIME_CONSTANT_RANGE)),
                               viscosity_temperature_coefficient=float(viscosity_temperature_coefficient),
                               viscosity_law=law, vogel_distance=float(rng.uniform(*VOGEL_DISTANCE_RANGE)),
                               reference_viscosity=float(rng.uniform(*REFERENCE_VISCOSITY_RANGE)))


class Simulation(EffectSimulation):
    """Nut and oil heat while running (the rig's temperature); theta_Oil times the film factor at that temperature."""

    id = 'thermal_viscosity'

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> ThermalViscosityLaw:
        """:func:`draw` with the actuator oil's viscosity-temperature coefficient."""
        return draw(rng, viscosity_temperature_coefficient=context.actuator.viscosity_temperature_coefficient)

    def film_factor(self, law: ThermalViscosityLaw, state: ContactState) -> np.ndarray | float:
        """``(eta(T) / eta_ref)^0.68`` at the simulated temperature (1 when no temperature is simulated)."""
        if state.temperature is None:
            return 1.0
        return law.film_factor(state.temperature, state.ambient_temperature)

    def heating(self, law: ThermalViscosityLaw) -> tuple[float, float]:
        """The law's temperature rise (K) and time constant (s)."""
        return law.temperature_rise, law.time_constant
