# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Eq. 16-17: Hertz contact of the thread flanks, against closed forms and hand values."""
import math

import numpy as np
import pytest
from scipy.integrate import quad

from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.physics.contact import (
    PrincipalCurvatures, contact_deformation, contact_normal_force, contact_stiffness, curvature_difference,
    curvature_difference_of_ellipticity, curvature_sum, effective_radii, elliptic_integrals, ellipticity,
    load_sharing_factor, normal_deformation, normal_stiffness, principal_curvatures, reduced_compliance,
    semi_major_axis_coefficient, stiffness_coefficient, thread_contact)
from prsm_lube_ros.errors import InputError

# Steel: (1 - 0.3^2) / 2.06e11 * 2 = 1.82 / 2.06e11 = 8.834951e-12 m^2/N
STEEL_COMPLIANCE = 8.834951e-12


def test_reduced_compliance_is_sum_of_body_compliances():
    assert reduced_compliance(2.06e11, 0.3) == pytest.approx(STEEL_COMPLIANCE, rel=1e-6)
    # steel on a rigid-ish body: 0.91 / 2.06e11 + 0.91 / 2.06e15 = 4.417476e-12 + 4.417476e-16
    assert reduced_compliance(2.06e11, 0.3, 2.06e15, 0.3) == pytest.approx(4.417917e-12, rel=1e-6)


def test_principal_curvatures_of_default_actuator():
    curv = principal_curvatures(Actuator())
    # 2 cos(45 deg) / 0.024 = 1.4142136 / 0.024 = 58.92557 1/m ; 1.4142136 / 0.008 = 176.7767 1/m
    assert curv.screw_circumferential == pytest.approx(58.92557, rel=1e-6)
    assert curv.screw_axial == 0.0
    assert curv.roller_circumferential == pytest.approx(176.7767, rel=1e-6)
    assert curv.roller_axial == pytest.approx(176.7767, rel=1e-6)
    # sum = 58.92557 + 2 * 176.7767 = 412.4790 1/m ; F(rho) = 58.92557 / 412.4790 = (1/24) / (7/24) = 1/7
    assert curvature_sum(curv) == pytest.approx(412.4790, rel=1e-6)
    assert curvature_difference(curv) == pytest.approx(1.0 / 7.0, rel=1e-12)
    # R_x = 1 / (58.92557 + 176.7767) = 4.242641e-3 m ; R_y = 1 / 176.7767 = 5.656854e-3 m
    r_x, r_y = effective_radii(curv)
    assert r_x == pytest.approx(4.242641e-3, rel=1e-6)
    assert r_y == pytest.approx(5.656854e-3, rel=1e-6)


def _quadrature_integrals(kappa):
    """K(e), E(e) from their defining integrals with e^2 = 1 - 1/kappa^2 (independent of scipy.special)."""
    e2 = 1.0 - 1.0 / kappa ** 2
    k_value = quad(lambda phi: 1.0 / math.sqrt(1.0 - e2 * math.sin(phi) ** 2), 0.0, math.pi / 2)[0]
    e_value = quad(lambda phi: math.sqrt(1.0 - e2 * math.sin(phi) ** 2), 0.0, math.pi / 2)[0]
    return k_value, e_value


@pytest.mark.parametrize('kappa', [1.0, 1.2, 2.0, 5.0, 12.0])
def test_elliptic_integrals_use_e_squared(kappa):
    np.testing.assert_allclose(elliptic_integrals(kappa), _quadrature_integrals(kappa), rtol=1e-10)


def test_ellipticity_of_default_contact_satisfies_hertz_relation():
    kappa = ellipticity(1.0 / 7.0)
    # Hamrock's fit k ~ 1.0339 (R_y/R_x)^0.636 = 1.0339 * (4/3)^0.636 = 1.2413 is good to a few per cent.
    assert kappa == pytest.approx(1.2413, rel=0.04)
    # exact: [(k^2 + 1) E - 2 K] / [(k^2 - 1) E] = 1/7 with K, E by quadrature
    k_value, e_value = _quadrature_integrals(kappa)
    relation = ((kappa ** 2 + 1) * e_value - 2 * k_value) / ((kappa ** 2 - 1) * e_value)
    assert relation == pytest.approx(1 / 7, rel=1e-8)


def test_ellipticity_round_trip_and_circle():
    assert ellipticity(0.0) == 1.0
    assert curvature_difference_of_ellipticity(1.0) == 0.0
    for target in (0.05, 0.5, 0.9, 0.99):
        assert curvature_difference_of_ellipticity(ellipticity(target)) == pytest.approx(target, rel=1e-9)
    # near the circle the Hertz relation is a difference of nearly equal terms: ~1e-4 relative there
    assert curvature_difference_of_ellipticity(ellipticity(1e-6)) == pytest.approx(1e-6, rel=1e-3)
    assert 1.0 < ellipticity(1e-6) < 1.0001


def test_coefficient_m_is_one_for_a_circle():
    # m = (2 * 1^2 * E(0) / pi)^(1/3) = (2 * (pi/2) / pi)^(1/3) = 1
    assert semi_major_axis_coefficient(1.0) == pytest.approx(1.0, rel=1e-12)
    # kappa = 2: e^2 = 0.75, E = 1.2110560 -> m = (2 * 4 * 1.2110560 / pi)^(1/3)
    #   = (9.688448 / 3.141593)^(1/3) = 3.083928^(1/3) = 1.455576
    assert semi_major_axis_coefficient(2.0) == pytest.approx(1.455576, rel=1e-5)


def test_sphere_on_plane_matches_textbook_closed_form():
    radius, force = 0.01, 10.0
    sphere_on_plane = PrincipalCurvatures(0.0, 0.0, 1.0 / radius, 1.0 / radius)
    total, difference = curvature_sum(sphere_on_plane), curvature_difference(sphere_on_plane)
    assert difference == 0.0
    delta = normal_deformation(force, total, difference, STEEL_COMPLIANCE)
    e_star = 1.0 / STEEL_COMPLIANCE
    # delta = (9 F^2 / (16 E*^2 R))^(1/3) = (900 / (16 * 1.281125e22 * 0.01))^(1/3) = (4.39068e-19)^(1/3)
    #       = 7.6005e-7 m
    assert delta == pytest.approx((9 * force ** 2 / (16 * e_star ** 2 * radius)) ** (1 / 3), rel=1e-9)
    assert delta == pytest.approx(7.6005e-7, rel=1e-4)


def test_stiffness_is_derivative_of_deformation():
    total, difference = 412.479, 1.0 / 7.0
    for force in (0.5, 1.18, 5.0, 100.0):
        step = force * 1e-5
        d_delta = (normal_deformation(force + step, total, difference, STEEL_COMPLIANCE)
                   - normal_deformation(force - step, total, difference, STEEL_COMPLIANCE)) / (2 * step)
        stiffness = normal_stiffness(force, total, difference, STEEL_COMPLIANCE)
        assert stiffness == pytest.approx(1 / d_delta, rel=1e-7)
    # K_n = k_delta F^(1/3)
    k_delta = stiffness_coefficient(total, difference, STEEL_COMPLIANCE)
    assert normal_stiffness(8.0, total, difference, STEEL_COMPLIANCE) == pytest.approx(2 * k_delta, rel=1e-12)


def test_normal_force_uniform_sharing():
    actuator = Actuator()
    # N = 10 * 12 * cos(45 deg) * cos(alpha_S) = 120 * 0.7071068 * 0.9978082 = 84.66683
    assert load_sharing_factor(actuator) == pytest.approx(84.66683, rel=1e-6)
    # F_n = 100 / 84.66683 = 1.181100 N ; 200 N -> 2.362200 N ; sign ignored
    np.testing.assert_allclose(contact_normal_force(actuator, [100.0, 200.0, -100.0]),
                               [1.181100, 2.362200, 1.181100], rtol=1e-6)


def test_default_actuator_deformation_and_stiffness_hand_values():
    actuator = Actuator()
    contact = thread_contact(actuator)
    # kappa = 1.21133 (solved above); K = 1.72486, E = 1.43705
    # m = (2 * 1.467319 * 1.43705 / pi)^(1/3) = 1.10312
    assert contact.ellipticity == pytest.approx(1.21133, rel=1e-5)
    assert contact.coefficient == pytest.approx(1.10312, rel=1e-5)
    # delta at 1 N: 2 K / (pi m) = 3.44972 / 3.46555 = 0.995432
    #   (3 E' / (2 sum rho))^(2/3) = (2.650485e-11 / 824.958)^(2/3) = (3.212873e-14)^(2/3) = 1.01050e-9
    #   * sum rho / 2 = 206.2395 -> 2.08404e-7 ; * 0.995432 -> 2.07452e-7 m N^-2/3
    # F_n(100 N) = 1.181100 N -> 1.181100^(2/3) = 1.117450 -> delta = 2.31817e-7 m
    assert contact_deformation(actuator, 100.0) == pytest.approx(2.31817e-7, rel=1e-3)
    # k_delta = 3 / (2 * 2.07452e-7) = 7.23059e6 N^(2/3)/m
    # K_n(100 N) = 7.23059e6 * 1.181100^(1/3) = 7.6434e6 N/m
    assert contact.stiffness_coefficient == pytest.approx(7.23059e6, rel=1e-3)
    assert contact_stiffness(actuator, 100.0) == pytest.approx(7.6434e6, rel=1e-3)
    # twice the load: delta * 2^(2/3), K_n * 2^(1/3)
    assert contact_deformation(actuator, 200.0) == pytest.approx(2.31817e-7 * 2 ** (2 / 3), rel=1e-3)
    assert contact_stiffness(actuator, 200.0) == pytest.approx(7.6434e6 * 2 ** (1 / 3), rel=1e-3)
    # the long axis of the ellipse is transverse to rolling (R_y > R_x), so the film's k is kappa
    assert contact.film_ellipticity == contact.ellipticity


def test_bad_inputs_raise_input_error():
    with pytest.raises(InputError, match='normal_force'):
        normal_deformation(-1.0, 400.0, 0.1, STEEL_COMPLIANCE)
    with pytest.raises(InputError, match='F\\(rho\\)'):
        ellipticity(1.0)
    with pytest.raises(InputError, match='poisson_ratio_1'):
        reduced_compliance(2e11, 0.6)
    with pytest.raises(InputError, match='axial_load'):
        contact_normal_force(Actuator(), float('nan'))
