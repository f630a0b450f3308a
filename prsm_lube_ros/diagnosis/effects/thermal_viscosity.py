# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit the viscosity-temperature effect (the law: :mod:`prsm_lube_ros.physics.effects.thermal_viscosity`).

``theta_Oil C_lambda omega^0.68 F^-0.073`` times ``(eta(T) / eta_ref)^0.68``
(Eq. 8), with eta(T) by one of three laws, each a form fitted in turn:
exponential (Reynolds, parameter beta in 1/K), Vogel (beta and the distance
D = T_ref - T_V to the Vogel temperature, K) and Walther / ASTM D341 (beta and
the kinematic viscosity nu_ref at T_ref, mm^2/s, which sets B).  T_ref is the
coldest recorded temperature (C_lambda refers to it).  The curved laws need
a wide temperature range to differ from the exponential one; the fit keeps
the exponential law unless a curved one lowers the BIC by the engine's form
margin.  Needs the contract's optional temperature topic.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...physics.effects import thermal_viscosity as law
from .base import Effect, register

if TYPE_CHECKING:
    from ..table import WindowTable

__all__ = ['BETA_RANGE', 'LOG_VISCOSITY_RANGE', 'MIN_SPREAD', 'ThermalViscosityCandidate', 'VOGEL_DISTANCE_RANGE',
           'VogelViscosity', 'WaltherViscosity']

#: Bounds of the viscosity-temperature coefficient beta, 1/K (mineral oils: about 0.02-0.05).
BETA_RANGE = (0.0, 0.15)
#: Bounds of the Vogel distance D = T_ref - T_V, K (oils: about 80-200 K).
VOGEL_DISTANCE_RANGE = (30.0, 400.0)
#: Bounds of log10 nu_ref (mm^2/s at T_ref) for the Walther law: 3 to 3000 mm^2/s.
LOG_VISCOSITY_RANGE = (0.5, 3.5)
#: Smallest temperature spread, K, that can show the effect.
MIN_SPREAD = 0.5


@register
class ThermalViscosityCandidate(Effect, law.Extension):
    """The oil warms in service and thins; amplitude follows temperature (exponential law)."""

    id = 'thermal_viscosity'
    title = 'temperature-dependent oil viscosity'
    form = 'exponential (Reynolds)'
    physics = ('The oil warms in service and its viscosity falls; the film thins with viscosity to the power '
               '0.68 (Eq. 8), more asperities touch and the amplitude follows temperature.')
    equations = ('theta_Oil C_lambda omega^0.68 F^-0.073  ->  theta_Oil C_lambda omega^0.68 F^-0.073 '
                 'exp(-0.68 beta (T - T_ref))')
    parameter_names: tuple[str, ...] = ('viscosity_temperature_coefficient',)
    covariate = 'temperature'
    to_separate = ('temperature that does not rise with revolutions: cool down between runs, or run a warm '
                   'actuator after a rest, or record the oil temperature with runs in random order')

    def applicable(self, table: WindowTable) -> str:
        """Needs a temperature in most windows that varies by :data:`MIN_SPREAD` K or more."""
        if not table.has_temperature:
            return 'no temperature recorded (/prsm/temperature is optional): cannot test'
        spread = table.temperature_span
        if spread < MIN_SPREAD:
            return f'temperature varies by {spread:.2f} K only: cannot show a viscosity effect'
        return ''

    def scales(self, table: WindowTable) -> dict[str, float]:
        """Reference temperature: the coldest recorded, degC."""
        return {'reference_temperature': float(np.nanmin(table.temperature))}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """beta in :data:`BETA_RANGE`."""
        return np.array([BETA_RANGE[0]]), np.array([BETA_RANGE[1]])

    def starts(self) -> list[np.ndarray]:
        """Typical oils."""
        return [np.array([0.01]), np.array([0.03]), np.array([0.07])]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """viscosity_temperature_coefficient (1/K) and reference_temperature (degC)."""
        return {'viscosity_temperature_coefficient': float(p[0]), **scales}

    def variants(self) -> list[Effect]:
        """The exponential, Vogel and Walther laws."""
        return [self, VogelViscosity(), WaltherViscosity()]

    def _law_words(self, params: dict[str, float]) -> str:
        return 'exponential law (Reynolds)'

    def describe(self, params: dict[str, float]) -> str:
        """Viscosity law, its slope and the film factor 10 K above T_ref."""
        beta = params['viscosity_temperature_coefficient']
        reference = params['reference_temperature']
        warm = float(self.film_factor(params, _Temperature(reference + 10.0)))
        return (f'Viscosity by the {self._law_words(params)}, slope beta = {beta:.4f} 1/K at T_ref = '
                f'{reference:.1f} degC: 10 K warmer thins the film to {100 * warm:.0f} %. ' + self.physics)


class _Temperature:
    """Covariates of one temperature (for :meth:`ThermalViscosityCandidate.describe`)."""

    def __init__(self, temperature: float) -> None:
        self.temperature = float(temperature)


class VogelViscosity(ThermalViscosityCandidate):
    """Vogel's law ``eta = a exp(b / (T - T_V))``: ln eta convex in T."""

    form = 'Vogel'
    equations = ('theta_Oil C_lambda ... times (eta(T)/eta_ref)^0.68, eta/eta_ref = exp(beta D^2 (1/(T - T_V) - 1/D)), '
                 'D = T_ref - T_V')
    parameter_names = ('viscosity_temperature_coefficient', 'vogel_distance')

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """beta and D in their ranges."""
        return np.array([BETA_RANGE[0], VOGEL_DISTANCE_RANGE[0]]), np.array([BETA_RANGE[1], VOGEL_DISTANCE_RANGE[1]])

    def starts(self) -> list[np.ndarray]:
        """Typical oils, strongly and mildly curved."""
        return [np.array([b, d]) for b in (0.02, 0.05) for d in (60.0, 150.0)]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """beta (1/K), vogel_distance D (K), reference_temperature (degC)."""
        return {'viscosity_temperature_coefficient': float(p[0]), 'vogel_distance': float(p[1]), **scales}

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]

    def _law_words(self, params: dict[str, float]) -> str:
        return (f'Vogel law, Vogel temperature T_V = {params["reference_temperature"] - params["vogel_distance"]:.0f} '
                'degC')


class WaltherViscosity(ThermalViscosityCandidate):
    """Walther / ASTM D341 ``log10 log10(nu + 0.7) = A - B log10 T_K``."""

    form = 'Walther (ASTM D341)'
    equations = ('theta_Oil C_lambda ... times (nu(T)/nu_ref)^0.68, log10 log10(nu + 0.7) = A - B log10 T_K')
    parameter_names = ('viscosity_temperature_coefficient', 'log_reference_viscosity')

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """beta and log10 nu_ref in their ranges."""
        return np.array([BETA_RANGE[0], LOG_VISCOSITY_RANGE[0]]), np.array([BETA_RANGE[1], LOG_VISCOSITY_RANGE[1]])

    def starts(self) -> list[np.ndarray]:
        """Thin and thick oils."""
        return [np.array([b, v]) for b in (0.02, 0.05) for v in (1.0, 2.5)]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """beta (1/K), reference_viscosity nu_ref (mm^2/s), reference_temperature (degC)."""
        return {'viscosity_temperature_coefficient': float(p[0]), 'reference_viscosity': float(10.0 ** p[1]),
                **scales}

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]

    def _law_words(self, params: dict[str, float]) -> str:
        slope = law.walther_slope(params['viscosity_temperature_coefficient'], params['reference_temperature'],
                                  params['reference_viscosity'])
        return (f'Walther / ASTM D341 law, nu_ref = {params["reference_viscosity"]:.3g} mm^2/s at T_ref, '
                f'B = {slope:.2f}')
