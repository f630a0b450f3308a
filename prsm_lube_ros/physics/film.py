# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Lubricant film of the screw-roller thread contact (Eq. 8-12) and oil viscosity vs temperature.

Units: viscosity in Pa s, speeds in m/s (sliding) or rad/s (screw), forces in
N, film thickness and roughness in m, moduli in Pa, pressure-viscosity
coefficient in 1/Pa, temperatures in degC.

Choices where the paper is silent:

* The film speed is the paper's sliding speed ``|v_SR| = |k_v| omega_S`` (Eq. 9
  substitutes v_SR into Eq. 8).  With the printed Eq. 3-6 this magnitude is
  about the *sum* of the two surface speeds, i.e. twice the mean entrainment
  speed of Hamrock-Dowson; the resulting factor 2^0.68 = 1.6 is left as
  printed because C_lambda is fitted anyway.
* The H of Eq. 9-11 must be a length for ``lambda = H / sigma`` (Eq. 11) to be
  dimensionless, so C_h here is dimensional: the film is ``h = H_min R_x`` in m.
* The contact geometry (R_x, ellipticity) comes from
  :mod:`prsm_lube_ros.physics.contact`; the per-contact load from its uniform sharing.
"""
from __future__ import annotations

import math
from typing import cast, TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..validation import require_positive
from .actuator import Actuator
from .contact import contact_deformation, contact_normal_force, load_sharing_factor, reduced_compliance, thread_contact
from .kinematics import sliding_velocity_coefficient
from .vibration_model import LOAD_EXPONENT, VELOCITY_EXPONENT

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ['DEFAULT_VISCOSITY_TEMPERATURE_COEFFICIENT', 'ELLIPTICITY_EXPONENT', 'HAMROCK_DOWSON_FACTOR',
           'MATERIALS_EXPONENT', 'dimensionless_minimum_film', 'effective_modulus', 'film_constant', 'film_ratio',
           'film_ratio_coefficient', 'film_thickness_from_dimensionless', 'fully_lubricated_film_thickness',
           'hamrock_dowson_film_thickness', 'load_parameter', 'materials_parameter',
           'oil_excitation_from_film_ratio', 'oil_viscosity', 'speed_parameter', 'starved_film_thickness',
           'viscosity_at_temperature']

#: Hamrock-Dowson point-contact minimum film (Eq. 8): leading factor and exponents.
HAMROCK_DOWSON_FACTOR = 3.63
MATERIALS_EXPONENT = 0.49
ELLIPTICITY_EXPONENT = -0.68
#: Exponential viscosity-temperature coefficient beta in 1/K; mineral oils lie around 0.02-0.04.
DEFAULT_VISCOSITY_TEMPERATURE_COEFFICIENT = 0.03


def _array(name: str, value: npt.ArrayLike, *, positive: bool = False, non_negative: bool = False) -> np.ndarray:
    """Float array of ``value``; InputError naming ``name`` unless finite (and > 0 / >= 0)."""
    array = np.asarray(value, dtype=float)
    ok = np.isfinite(array)
    if positive:
        ok &= array > 0
    if non_negative:
        ok &= array >= 0
    if not np.all(ok):
        need = ' and > 0' if positive else ' and >= 0' if non_negative else ''
        raise InputError(f'{name} must be finite{need}, got {value!r}')
    return array


def _out(values: np.ndarray | np.float64) -> np.ndarray | float:
    """Return a float for 0-d results (numpy gives a 0-d array or a numpy scalar), else the array."""
    return float(values) if np.ndim(values) == 0 else values


def effective_modulus(youngs_modulus_1: float, poisson_ratio_1: float,
                      youngs_modulus_2: float | None = None, poisson_ratio_2: float | None = None) -> float:
    """Hamrock-Dowson effective modulus ``E' = 2 / [(1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2]`` in Pa.

    This is 2 / (the compliance E' of Eq. 16); body 2 defaults to body 1's material.
    """
    return 2.0 / reduced_compliance(youngs_modulus_1, poisson_ratio_1, youngs_modulus_2, poisson_ratio_2)


def speed_parameter(viscosity: npt.ArrayLike, speed: npt.ArrayLike, modulus: float,
                    rolling_radius: float) -> np.ndarray | float:
    """Dimensionless speed parameter of Eq. 8: ``U = eta_0 u / (E' R_x)``.

    viscosity eta_0 in Pa s, speed u in m/s (magnitude used), modulus E' in Pa,
    rolling_radius R_x in m.
    """
    return _out(_array('viscosity', viscosity, positive=True) * np.abs(_array('speed', speed))
                / (modulus * rolling_radius))


def materials_parameter(pressure_viscosity_coefficient: float, modulus: float) -> float:
    """Dimensionless materials parameter of Eq. 8: ``G = alpha E'`` (alpha in 1/Pa, E' in Pa)."""
    return pressure_viscosity_coefficient * modulus


def load_parameter(normal_force: npt.ArrayLike, modulus: float, rolling_radius: float) -> np.ndarray | float:
    """Dimensionless load parameter of Eq. 8: ``W = F / (E' R_x^2)``; F in N, E' in Pa, R_x in m."""
    return _out(_array('normal_force', normal_force, positive=True) / (modulus * rolling_radius ** 2))


def dimensionless_minimum_film(speed_param: npt.ArrayLike, materials_param: float, load_param: npt.ArrayLike,
                               film_ellipticity: float) -> np.ndarray | float:
    """Eq. 8 (Hamrock-Dowson): ``H_min = 3.63 U^0.68 G^0.49 W^-0.073 (1 - exp(-0.68 k))``.

    k = a/b is the ellipticity with a transverse to the rolling direction.
    """
    return _out(HAMROCK_DOWSON_FACTOR * np.asarray(speed_param, dtype=float) ** VELOCITY_EXPONENT
                * materials_param ** MATERIALS_EXPONENT
                * np.asarray(load_param, dtype=float) ** LOAD_EXPONENT
                * (1.0 - math.exp(ELLIPTICITY_EXPONENT * film_ellipticity)))


def film_thickness_from_dimensionless(dimensionless_film: npt.ArrayLike, rolling_radius: float) -> np.ndarray | float:
    """Dimensional film ``h = H R_x`` in m from the dimensionless H of Eq. 8 and R_x in m."""
    return _out(np.asarray(dimensionless_film, dtype=float) * rolling_radius)


def hamrock_dowson_film_thickness(viscosity: npt.ArrayLike, speed: npt.ArrayLike, normal_force: npt.ArrayLike,
                                  pressure_viscosity_coefficient: float, modulus: float, rolling_radius: float,
                                  film_ellipticity: float) -> np.ndarray | float:
    """Eq. 8 in metres: minimum film ``h = R_x H_min(U, G, W, k)`` of a point contact.

    viscosity in Pa s, speed in m/s, normal_force in N, pressure-viscosity
    coefficient in 1/Pa, modulus (Hamrock E') in Pa, rolling_radius R_x in m,
    film_ellipticity k dimensionless.
    """
    dimensionless = dimensionless_minimum_film(
        speed_parameter(viscosity, speed, modulus, rolling_radius),
        materials_parameter(pressure_viscosity_coefficient, modulus),
        load_parameter(normal_force, modulus, rolling_radius), film_ellipticity)
    return film_thickness_from_dimensionless(dimensionless, rolling_radius)


def viscosity_at_temperature(temperature: npt.ArrayLike, reference_viscosity: float, reference_temperature: float,
                             coefficient: float = DEFAULT_VISCOSITY_TEMPERATURE_COEFFICIENT) -> np.ndarray | float:
    """Reynolds (exponential) viscosity law ``eta(T) = eta_ref exp(-beta (T - T_ref))`` in Pa s.

    temperature and reference_temperature in degC (or K, consistently),
    reference_viscosity in Pa s, coefficient beta in 1/K (default 0.03, typical
    of mineral oils, 0.02-0.04).  Adequate over a few tens of kelvin.
    """
    temperature = _array('temperature', temperature)
    return _out(reference_viscosity * np.exp(-coefficient * (temperature - reference_temperature)))


def oil_viscosity(actuator: Actuator, temperature: npt.ArrayLike | None = None,
                  coefficient: float = DEFAULT_VISCOSITY_TEMPERATURE_COEFFICIENT) -> np.ndarray | float:
    """Dynamic viscosity of the actuator's oil in Pa s at ``temperature`` degC (None: reference)."""
    if temperature is None:
        return actuator.oil_viscosity
    return viscosity_at_temperature(temperature, actuator.oil_viscosity,
                                    actuator.oil_reference_temperature, coefficient)


def film_constant(actuator: Actuator, viscosity: float | None = None) -> float:
    """C_h of Eq. 9 in m (m/s)^-0.68 N^0.073: ``h = C_h |v_SR|^0.68 F_SR^-0.073``.

    ``C_h = 3.63 R_x (eta/(E' R_x))^0.68 (alpha E')^0.49 (E' R_x^2)^0.073 (1 - exp(-0.68 k))``
    for the actuator's steel, oil (viscosity in Pa s; default the reference
    viscosity) and contact geometry.
    """
    viscosity = actuator.oil_viscosity if viscosity is None else viscosity
    contact = thread_contact(actuator)
    modulus = effective_modulus(actuator.youngs_modulus, actuator.poisson_ratio)
    # Eq. 8 at unit speed (1 m/s) and unit load (1 N) is exactly C_h (a float: every input is a scalar).
    return cast(float, hamrock_dowson_film_thickness(viscosity, 1.0, 1.0, actuator.pressure_viscosity_coefficient,
                                                     modulus, contact.rolling_radius, contact.film_ellipticity))


def fully_lubricated_film_thickness(actuator: Actuator, screw_speed: npt.ArrayLike, axial_load: npt.ArrayLike,
                                    viscosity: npt.ArrayLike | None = None) -> np.ndarray | float:
    """Eq. 9: minimum film of one screw-roller contact under full lubrication, m.

    ``h = C_h |v_SR|^0.68 F_n^-0.073`` with ``|v_SR| = |k_v(delta)| |omega_S|``
    (Eq. 7, delta from Eq. 16) and the per-contact normal force F_n of the
    uniform load sharing.  screw_speed omega_S in rad/s, axial_load F_a in N
    (non-zero), viscosity in Pa s (default: the actuator's reference viscosity;
    see :func:`oil_viscosity` for a temperature).  Arrays broadcast.
    """
    viscosity = actuator.oil_viscosity if viscosity is None else viscosity
    viscosity = _array('viscosity', viscosity, positive=True)
    screw_speed = _array('screw_speed', screw_speed)
    load = _array('axial_load', axial_load)
    if not np.all(load != 0):
        raise InputError('axial_load must be non-zero for the film model (Eq. 9)')
    normal_force = np.asarray(contact_normal_force(actuator, load))
    speed = np.abs(sliding_velocity_coefficient(actuator, contact_deformation(actuator, load)) * screw_speed)
    return _out(film_constant(actuator, 1.0) * viscosity ** VELOCITY_EXPONENT
                * speed ** VELOCITY_EXPONENT * normal_force ** LOAD_EXPONENT)


def starved_film_thickness(full_film: npt.ArrayLike, theta_oil: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 10: ``H_actual = theta_Oil H_min``; film in m, theta_Oil dimensionless (1: fully lubricated)."""
    return _out(_array('theta_oil', theta_oil, non_negative=True) * np.asarray(full_film, dtype=float))


def film_ratio(film: npt.ArrayLike, composite_roughness: float) -> np.ndarray | float:
    """Eq. 11: film thickness ratio ``lambda = H_actual / sigma``; film and sigma in m."""
    composite_roughness = require_positive('composite_roughness (m)', composite_roughness)
    return _out(np.asarray(film, dtype=float) / composite_roughness)


def oil_excitation_from_film_ratio(film_ratio_value: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 12: oil excitation factor ``Phi_Oil = exp(-lambda)``, dimensionless."""
    return _out(np.exp(-np.asarray(film_ratio_value, dtype=float)))


def film_ratio_coefficient(actuator: Actuator, reference_axial_load: float = 100.0,
                           viscosity: float | None = None) -> float:
    """C_lambda that Eq. 9-12 predict for Eq. 19, in (rad/s)^-0.68 N^0.073.

    With ``lambda = theta_Oil h / sigma``, ``h = C_h (|k_v| omega_S)^0.68 (F_a / N)^-0.073``
    and N from :func:`prsm_lube_ros.physics.contact.load_sharing_factor`:
    ``C_lambda = C_h |k_v|^0.68 N^0.073 / sigma`` for omega_S in rad/s and F_a in N.

    k_v depends on the contact deformation only at the 1e-4 level; it is taken
    at ``reference_axial_load`` (N).  This is an order-of-magnitude physical
    expectation, not a substitute for the fitted C_lambda: a fitted value that
    is negative or several decades away from it is not physical.
    """
    load = _array('reference_axial_load', reference_axial_load, positive=True)
    k_v = sliding_velocity_coefficient(actuator, contact_deformation(actuator, float(load)))
    sharing = load_sharing_factor(actuator)
    return (film_constant(actuator, viscosity) * abs(float(k_v)) ** VELOCITY_EXPONENT
            * sharing ** (-LOAD_EXPONENT) / actuator.composite_roughness)
