# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Oil viscosity falling with temperature, thinning the film of Eq. 9.

Physics: Eq. 9 holds the viscosity at its reference value; in service the nut
and oil warm and the viscosity follows ``eta(T) = eta_ref exp(-beta (T - T_ref))``
(Reynolds).  The Hamrock-Dowson film grows with ``(eta u)^0.68`` (Eq. 8, U is
proportional to eta), so the film ratio in the exponent of Eq. 22 scales by

    f(T) = (eta(T) / eta_ref)^0.68 = exp(-0.68 beta (T - T_ref)).

The rig's nut and oil relax with time constant tau towards ``T0 + dT`` while
the screw turns and towards the ambient T0 at standstill.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import Extension as EffectExtension
from ...validation import require_all_positive
from ..vibration_model import VELOCITY_EXPONENT


def viscosity_ratio(temperature, reference_temperature: float, viscosity_temperature_coefficient):
    """``eta(T) / eta_ref = exp(-beta (T - T_ref))`` (Reynolds' exponential law), dimensionless.

    temperature T and reference_temperature T_ref in degC, beta in 1/K.
    """
    return np.exp(-np.asarray(viscosity_temperature_coefficient, dtype=float)
                  * (np.asarray(temperature, dtype=float) - reference_temperature))


def film_factor(temperature, reference_temperature: float, viscosity_temperature_coefficient):
    """``(eta(T) / eta_ref)^0.68``: the factor on theta_Oil C_lambda in the exponent of Eq. 22."""
    return viscosity_ratio(temperature, reference_temperature, viscosity_temperature_coefficient) ** VELOCITY_EXPONENT


@dataclass(frozen=True)
class ThermalViscosity:
    """Nut and oil warm while running and cool at standstill; the oil thins.

    From cold ``T = T0 + dT (1 - exp(-t_run / tau))``; eta_ref is at the
    ambient T0 of the rig, where the true constants hold.
    """

    temperature_rise: float                    # K, dT
    time_constant: float                       # s, tau
    viscosity_temperature_coefficient: float   # 1/K, beta

    def __post_init__(self):
        """Reject non-physical parameters."""
        require_all_positive('thermal_viscosity', **self.__dict__)

    def film_factor(self, temperature, ambient_temperature: float):
        """``(eta(T) / eta_ref)^0.68``, the factor on theta_Oil C_lambda in Eq. 22."""
        return film_factor(temperature, ambient_temperature, self.viscosity_temperature_coefficient)


Law = ThermalViscosity


class Extension(EffectExtension):
    """theta_Oil in Eq. 22 times ``(eta(T)/eta_ref)^0.68`` (beta and T_ref as parameters)."""

    id = 'thermal_viscosity'

    def film_factor(self, params, covariates):
        """``exp(-0.68 beta (T - T_ref))``; windows without a temperature count as at T_ref."""
        temperature = np.asarray(covariates.temperature, dtype=float)
        reference = params['reference_temperature']
        return film_factor(np.where(np.isfinite(temperature), temperature, reference), reference,
                           params['viscosity_temperature_coefficient'])

    def assessment_film_factor(self, params, covariates):
        """As :meth:`film_factor`, but NaN (not assessable) without a temperature."""
        temperature = np.asarray(covariates.temperature, dtype=float)
        return np.where(np.isfinite(temperature), self.film_factor(params, covariates), np.nan)
