# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Eq. 1-7: roller speeds, contact velocities and the sliding velocity, against hand values."""
import math

import numpy as np
import pytest

from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.errors import InputError
from prsm_lube_ros.physics.kinematics import (
    actuator_sliding_velocity, roller_contact_velocity, roller_revolution_speed, roller_rotation_speed,
    screw_contact_velocity, sliding_speed, sliding_velocity, sliding_velocity_coefficient,
    sliding_velocity_coefficient_from_geometry, sliding_velocity_from_contact_velocities)

D_S, D_R = 0.024, 0.008
# Exaggerated but arithmetic-friendly inputs: omega_S = 10 rad/s, delta = 1 mm,
# beta = 60 deg (cos = 0.5), alpha_S = 45 deg (tan^2 = 1, cos = sqrt(2)/2).
OMEGA_S, DELTA, BETA, ALPHA = 10.0, 1e-3, math.radians(60.0), math.radians(45.0)


def test_roller_revolution_speed_eq1():
    # omega_P = d_S / (2 (d_S + d_R)) omega_S = 0.024 / (2 * 0.032) * 10 = 0.375 * 10 = 3.75 rad/s
    assert roller_revolution_speed(OMEGA_S, D_S, D_R) == pytest.approx(3.75, rel=1e-12)


def test_roller_rotation_speed_eq2():
    # omega_R = d_S (d_S + 2 d_R) / (2 d_R (d_S + d_R)) omega_S
    #         = 0.024 * 0.040 / (2 * 0.008 * 0.032) * 10 = 0.00096 / 0.000512 * 10 = 18.75 rad/s
    assert roller_rotation_speed(OMEGA_S, D_S, D_R) == pytest.approx(18.75, rel=1e-12)


def test_contact_velocities_eq4_eq5_and_sliding_eq3():
    # Eq. 4: v_S = (0.012 - 0.001 * 0.5) * 10 * 0.7071068 = 0.0115 * 7.071068 = 0.08131728 m/s
    v_s = screw_contact_velocity(OMEGA_S, D_S, DELTA, BETA, ALPHA)
    assert v_s == pytest.approx(0.0115 * 10 * math.sqrt(0.5), rel=1e-12)
    assert v_s == pytest.approx(0.08131728, rel=1e-6)
    # Eq. 5: v_R = [18.75 (-0.008 - 2 * 0.001 * 0.5) - 0.024 * 10 * 1 / 2] * 0.7071068
    #            = [-0.16875 - 0.12] * 0.7071068 = -0.28875 * 0.7071068 = -0.2041771 m/s
    v_r = roller_contact_velocity(OMEGA_S, 18.75, D_S, D_R, DELTA, BETA, ALPHA)
    assert v_r == pytest.approx(-0.2041771, rel=1e-6)
    # Eq. 3: v_SR = v_R - v_S = (-0.28875 - 0.115) * 0.7071068 = -0.40375 * 0.7071068 = -0.2854944 m/s
    assert sliding_velocity_from_contact_velocities(v_r, v_s) == pytest.approx(-0.2854944, rel=1e-6)


def test_sliding_velocity_eq6_hand_value():
    # Eq. 6: [(10 - 2 * 18.75) * 0.001 * 0.5 - 0.024 * 10 * (1 + 1) / 2 - 0.008 * 18.75] * 0.7071068
    #      = [-0.01375 - 0.24 - 0.15] * 0.7071068 = -0.40375 * 0.7071068 = -0.2854944 m/s
    eq6 = sliding_velocity(OMEGA_S, 18.75, D_S, D_R, DELTA, BETA, ALPHA)
    assert eq6 == pytest.approx(-0.2854944, rel=1e-6)


def test_eq3_equals_eq6_on_a_grid():
    rng = np.random.default_rng(7)
    screw_speed = rng.uniform(-200.0, 200.0, 50)
    d_s, d_r = rng.uniform(0.01, 0.1, 50), rng.uniform(0.003, 0.03, 50)
    delta = rng.uniform(0.0, 1e-4, 50)
    beta, alpha = rng.uniform(0.2, 1.2, 50), rng.uniform(0.01, 0.3, 50)
    for i in range(50):
        omega_r = roller_rotation_speed(screw_speed[i], d_s[i], d_r[i])
        eq3 = sliding_velocity_from_contact_velocities(
            roller_contact_velocity(screw_speed[i], omega_r, d_s[i], d_r[i], delta[i], beta[i], alpha[i]),
            screw_contact_velocity(screw_speed[i], d_s[i], delta[i], beta[i], alpha[i]))
        eq6 = sliding_velocity(screw_speed[i], omega_r, d_s[i], d_r[i], delta[i], beta[i], alpha[i])
        assert eq3 == pytest.approx(eq6, rel=1e-12, abs=1e-15)


def test_sliding_velocity_coefficient_eq7_default_actuator():
    # tan(alpha_S) = 0.005 / (pi * 0.024) = 0.06631456, tan^2 = 0.00439762
    # cos(alpha_S) = 1/sqrt(1.00439762) = 0.9978082
    # omega_R / omega_S = 1.875 (Eq. 2), delta = 0:
    # k_v = -(0.012 * 1.00439762 + 0.008 * 1.875) * 0.9978082 = -0.02705277 * 0.9978082 = -0.02699348 m
    assert sliding_velocity_coefficient(Actuator()) == pytest.approx(-0.02699348, rel=1e-6)
    # delta term: (1 - 2 * 1.875) * delta * cos(45 deg) * cos(alpha_S) = -2.75 * 0.7071068 * 0.9978082 * delta
    #           = -1.940270 * delta; with delta = 1e-5 m that adds -1.940270e-5 m.
    shifted = sliding_velocity_coefficient(Actuator(), 1e-5)
    assert shifted - sliding_velocity_coefficient(Actuator()) == pytest.approx(-1.940270e-5, rel=1e-5)


def test_eq7_is_eq6_over_screw_speed():
    k_v = sliding_velocity_coefficient_from_geometry(D_S, D_R, DELTA, BETA, ALPHA)
    # -0.2854944 m/s at 10 rad/s (hand value above) gives k_v = -0.02854944 m
    assert k_v == pytest.approx(-0.02854944, rel=1e-6)


def test_sliding_speed_is_a_magnitude_and_sign_follows_printed_formula():
    actuator = Actuator()
    speeds = np.array([-10.0, 0.0, 10.0])
    signed = actuator_sliding_velocity(actuator, speeds)
    # printed convention: v_SR < 0 for omega_S > 0; 10 rad/s * 0.02699348 m = 0.2699348 m/s
    assert signed[2] == pytest.approx(-0.2699348, rel=1e-6)
    assert signed[0] == pytest.approx(0.2699348, rel=1e-6)
    np.testing.assert_allclose(sliding_speed(actuator, speeds), [0.2699348, 0.0, 0.2699348], rtol=1e-6)


@pytest.mark.parametrize('diameters', [(0.0, 0.008), (0.024, -0.008), (float('nan'), 0.008)])
def test_bad_diameters_raise_input_error(diameters):
    with pytest.raises(InputError, match='diameter'):
        roller_rotation_speed(1.0, *diameters)
