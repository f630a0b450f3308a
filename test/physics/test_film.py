# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Eq. 8-12: Hamrock-Dowson film, starvation, film ratio and viscosity, against hand values."""
import math

import numpy as np
import pytest

from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.errors import InputError
from prsm_lube_ros.physics.film import (
    dimensionless_minimum_film, effective_modulus, film_constant, film_ratio, film_ratio_coefficient,
    film_thickness_from_dimensionless, fully_lubricated_film_thickness, hamrock_dowson_film_thickness,
    load_parameter, materials_parameter, oil_excitation_from_film_ratio, oil_viscosity, speed_parameter,
    starved_film_thickness, viscosity_at_temperature)

RPM_100 = 100 * 2 * math.pi / 60  # 10.47198 rad/s
R_X = 3e-3 * math.sqrt(2)  # default actuator: 1 / (58.92557 + 176.7767) = 4.242641e-3 m (R_x^2 = 1.8e-5)


def test_effective_modulus_is_hamrock_form():
    # E' = 2 / (2 * 0.91 / 2.06e11) = 2.06e11 / 0.91 = 2.263736e11 Pa
    assert effective_modulus(2.06e11, 0.3) == pytest.approx(2.263736e11, rel=1e-6)


def test_dimensionless_parameters():
    modulus = 2.263736e11
    # U = 0.1 * 1 / (2.263736e11 * 4.242641e-3) = 0.1 / 9.604222e8 = 1.041209e-10
    assert speed_parameter(0.1, 1.0, modulus, R_X) == pytest.approx(1.041209e-10, rel=1e-6)
    assert speed_parameter(0.1, -1.0, modulus, R_X) == pytest.approx(1.041209e-10, rel=1e-6)
    # G = 2e-8 * 2.263736e11 = 4527.472
    assert materials_parameter(2e-8, modulus) == pytest.approx(4527.472, rel=1e-6)
    # W = 1.181100 / (2.263736e11 * 1.8e-5) = 1.181100 / 4.074725e6 = 2.898601e-7
    assert load_parameter(1.181100, modulus, R_X) == pytest.approx(2.898601e-7, rel=1e-6)


def test_hamrock_dowson_eq8_hand_value():
    # U = 1e-11, G = 5000, W = 1e-6, k = 1:
    # U^0.68 = 10^-7.48 = 3.311311e-8 ; G^0.49 = exp(0.49 * 8.517193) = 64.93396
    # W^-0.073 = 10^0.438 = 2.741574
    # 1 - exp(-0.68) = 0.4933835 ; H = 3.63 * 3.311311e-8 * 64.93396 * 2.741574 * 0.4933835 = 1.055811e-5
    h_dimensionless = dimensionless_minimum_film(1e-11, 5000.0, 1e-6, 1.0)
    assert h_dimensionless == pytest.approx(1.055811e-5, rel=1e-5)
    # h = H R_x = 1.055811e-5 * 4.242641e-3 = 4.479424e-8 m
    assert film_thickness_from_dimensionless(h_dimensionless, R_X) == pytest.approx(4.479424e-8, rel=1e-5)


def test_default_actuator_film_at_100_rpm_100_n():
    # |v_SR| = 0.0269939 m * 10.47198 rad/s = 0.282680 m/s (k_v with delta(100 N) = 2.318e-7 m)
    # U = 0.1 * 0.282680 / 9.604222e8 = 2.94329e-11 -> U^0.68 = exp(0.68 * -24.24891) = 6.8995e-8
    # G^0.49 = exp(0.49 * ln 4527.472) = exp(4.12479) = 61.866
    # W = 2.89860e-7 -> W^-0.073 = exp(1.098933) = 3.00093
    # k = 1.21133 -> 1 - exp(-0.823704) = 0.561200
    # H = 3.63 * 6.8995e-8 * 61.866 * 3.00093 * 0.561200 = 2.60946e-5 ; h = H R_x = 1.10710e-7 m
    film = fully_lubricated_film_thickness(Actuator(), RPM_100, 100.0)
    assert film == pytest.approx(1.1071e-7, rel=1e-3)
    # lambda = 1.1071e-7 / 4e-7 = 0.2768 ; Phi_Oil = exp(-0.2768) = 0.7582
    assert film_ratio(film, 4e-7) == pytest.approx(0.2768, rel=1e-3)
    assert oil_excitation_from_film_ratio(film_ratio(film, 4e-7)) == pytest.approx(0.7582, rel=1e-3)


def test_eq9_constant_reproduces_eq8():
    actuator = Actuator()
    modulus = effective_modulus(actuator.youngs_modulus, actuator.poisson_ratio)
    speed, force = 0.3, 2.0
    eq8 = hamrock_dowson_film_thickness(0.1, speed, force, 2e-8, modulus, R_X, 1.2113250)
    assert film_constant(actuator) * speed ** 0.68 * force ** -0.073 == pytest.approx(eq8, rel=1e-6)


def test_film_scalings():
    actuator = Actuator()
    base = fully_lubricated_film_thickness(actuator, RPM_100, 100.0)
    # h ~ eta^0.68: doubling viscosity multiplies the film by 2^0.68 = 1.602140
    assert fully_lubricated_film_thickness(actuator, RPM_100, 100.0, viscosity=0.2) == pytest.approx(
        1.602140 * base, rel=1e-6)
    assert film_constant(actuator, 0.2) == pytest.approx(1.602140 * film_constant(actuator, 0.1), rel=1e-6)
    # h ~ omega^0.68 at fixed load, and either screw direction gives the same film
    np.testing.assert_allclose(fully_lubricated_film_thickness(actuator, [2 * RPM_100, -RPM_100], 100.0),
                               [1.602140 * base, base], rtol=1e-6)
    # h ~ F^-0.073 up to the 1e-4-level delta dependence of k_v: 2^-0.073 = 0.950677
    double_load = fully_lubricated_film_thickness(actuator, RPM_100, 200.0)
    assert double_load == pytest.approx(0.950677 * base, rel=1e-4)


def test_starved_film_and_ratio():
    # Eq. 10: 0.72 * 1e-7 = 7.2e-8 m ; Eq. 11: 7.2e-8 / 4e-7 = 0.18 ; Eq. 12: exp(-0.18) = 0.835270
    assert starved_film_thickness(1e-7, 0.72) == pytest.approx(7.2e-8, rel=1e-12)
    assert film_ratio(7.2e-8, 4e-7) == pytest.approx(0.18, rel=1e-12)
    assert oil_excitation_from_film_ratio(0.18) == pytest.approx(0.835270, rel=1e-6)
    assert oil_excitation_from_film_ratio(0.0) == 1.0


def test_viscosity_temperature_law():
    # eta(50 degC) = 0.1 exp(-0.03 * 10) = 0.0740818 Pa s ; beta = 0.02: 0.1 exp(-0.2) = 0.0818731
    assert viscosity_at_temperature(50.0, 0.1, 40.0) == pytest.approx(0.0740818, rel=1e-6)
    assert viscosity_at_temperature(50.0, 0.1, 40.0, coefficient=0.02) == pytest.approx(0.0818731, rel=1e-6)
    assert oil_viscosity(Actuator(), 40.0) == pytest.approx(0.1, rel=1e-12)
    assert oil_viscosity(Actuator()) == 0.1
    # so a 10 K warmer oil thins the film by exp(-0.3 * 0.68) = 0.815462
    actuator = Actuator()
    warm = fully_lubricated_film_thickness(actuator, RPM_100, 100.0, viscosity=oil_viscosity(actuator, 50.0))
    cold = fully_lubricated_film_thickness(actuator, RPM_100, 100.0)
    assert warm / cold == pytest.approx(0.815462, rel=1e-6)


def test_film_ratio_coefficient_matches_eq19():
    actuator = Actuator()
    c_lambda = film_ratio_coefficient(actuator)
    # lambda(100 rpm, 100 N) = 0.27671 ; omega^0.68 F^-0.073 = exp(0.68 * 2.348783) * exp(-0.073 * 4.605170)
    #   = 4.93894 * 0.714500 = 3.52888 -> C_lambda = 0.27671 / 3.52888 = 0.078413 (rad/s)^-0.68 N^0.073
    assert c_lambda == pytest.approx(0.07841, rel=1e-3)
    for speed, load in ((RPM_100, 100.0), (2 * RPM_100, 200.0)):
        lam = film_ratio(fully_lubricated_film_thickness(actuator, speed, load), actuator.composite_roughness)
        assert c_lambda * speed ** 0.68 * load ** -0.073 == pytest.approx(lam, rel=1e-4)
    # rougher surfaces: C_lambda ~ 1/sigma
    rough = actuator.with_changes(composite_roughness=8e-7)
    assert film_ratio_coefficient(rough) == pytest.approx(c_lambda / 2, rel=1e-9)


def test_bad_inputs_raise_input_error():
    actuator = Actuator()
    with pytest.raises(InputError, match='axial_load'):
        fully_lubricated_film_thickness(actuator, RPM_100, 0.0)
    with pytest.raises(InputError, match='viscosity'):
        fully_lubricated_film_thickness(actuator, RPM_100, 100.0, viscosity=-1.0)
    with pytest.raises(InputError, match='composite_roughness'):
        film_ratio(1e-7, 0.0)
    with pytest.raises(InputError, match='theta_oil'):
        starved_film_thickness(1e-7, -0.5)
