# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit the viscosity-temperature effect (the law: :mod:`prsm_lube_ros.physics.effects.thermal_viscosity`).

``theta_Oil C_lambda omega^0.68 F^-0.073`` times ``exp(-0.68 beta (T - T_ref))``.
Parameter: beta (1/K); T_ref is the coldest recorded temperature (C_lambda
refers to it).  Needs the contract's optional temperature topic.
"""
from __future__ import annotations

import numpy as np

from ...physics.effects import thermal_viscosity as law
from ...physics.vibration_model import VELOCITY_EXPONENT
from .base import Effect, register

#: Bounds of the viscosity-temperature coefficient beta, 1/K (mineral oils: about 0.02-0.05).
BETA_RANGE = (0.0, 0.15)
#: Smallest temperature spread, K, that can show the effect.
MIN_SPREAD = 0.5


@register
class ThermalViscosity(Effect, law.Extension):
    """The oil warms in service and thins; amplitude follows temperature."""

    id = 'thermal_viscosity'
    title = 'temperature-dependent oil viscosity'
    physics = ('The oil warms in service and its viscosity falls, exp(-beta (T - T_ref)); the film thins with '
               'viscosity to the power 0.68, more asperities touch and the amplitude follows temperature.')
    equations = ('theta_Oil C_lambda omega^0.68 F^-0.073  ->  theta_Oil C_lambda omega^0.68 F^-0.073 '
                 'exp(-0.68 beta (T - T_ref))')
    parameter_names = ('viscosity_temperature_coefficient',)
    covariate = 'temperature'
    to_separate = ('temperature that does not rise with revolutions: cool down between runs, or run a warm '
                   'actuator after a rest, or record the oil temperature with runs in random order')

    def applicable(self, table) -> str:
        """Needs a temperature in most windows that varies by :data:`MIN_SPREAD` K or more."""
        if not table.has_temperature:
            return 'no temperature recorded (/prsm/temperature is optional): cannot test'
        spread = float(np.nanmax(table.temperature) - np.nanmin(table.temperature))
        if spread < MIN_SPREAD:
            return f'temperature varies by {spread:.2f} K only: cannot show a viscosity effect'
        return ''

    def scales(self, table) -> dict:
        """Reference temperature: the coldest recorded, degC."""
        return {'reference_temperature': float(np.nanmin(table.temperature))}

    def bounds(self):
        """beta in :data:`BETA_RANGE`."""
        return np.array([BETA_RANGE[0]]), np.array([BETA_RANGE[1]])

    def starts(self):
        """Typical oils."""
        return [np.array([0.01]), np.array([0.03]), np.array([0.07])]

    def to_params(self, p, scales):
        """viscosity_temperature_coefficient (1/K) and reference_temperature (degC)."""
        return {'viscosity_temperature_coefficient': float(p[0]), **scales}

    def describe(self, params):
        """Viscosity coefficient and the film factor at the warmest point."""
        beta = params['viscosity_temperature_coefficient']
        return (f'Viscosity-temperature coefficient beta = {beta:.4f} 1/K (T_ref = '
                f'{params["reference_temperature"]:.1f} degC): 10 K warmer thins the film to '
                f'{100 * np.exp(-VELOCITY_EXPONENT * beta * 10):.0f} %. ' + self.physics)
