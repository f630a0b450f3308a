# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Eq. 22-23 of vibration_model: hand value, exact inversion, linear form and NaN behaviour."""
import math
import warnings

import numpy as np
import pytest

from prsm_lube_ros.physics.vibration_model import (
    ModelConstants, acceleration_amplitude, design_matrix, lubrication_index, reduced_log_amplitude)

CONSTANTS = ModelConstants(c_sys=0.01, c_f=1e-3, c_lambda=0.05)


def test_eq22_hand_value():
    # omega = 10 rad/s, F_a = 100 N, theta = 0.8:
    # omega^2 = 100 ; F^-1/3 = 0.2154435 ; omega^0.68 F^-0.073 = 4.786301 * 0.7144964 = 3.419794
    # exponent = 1e-3 * 100 - 0.8 * 0.05 * 3.419794 = 0.1 - 0.1367918 = -0.0367918 -> exp = 0.9638768
    # A_0 = 0.01 * 100 * 0.2154435 * 0.9638768 = 0.2076610 m/s^2
    assert acceleration_amplitude(10.0, 100.0, 0.8, CONSTANTS) == pytest.approx(0.2076610, rel=1e-6)


def test_eq23_inverts_eq22_on_a_grid():
    speed, load, theta = np.meshgrid(np.linspace(5.0, 30.0, 6), np.linspace(50.0, 400.0, 5),
                                     np.linspace(0.2, 1.5, 7), indexing='ij')
    amplitude = acceleration_amplitude(speed, load, theta, CONSTANTS)
    np.testing.assert_allclose(lubrication_index(amplitude, speed, load, CONSTANTS), theta, rtol=1e-10)
    # scalars come back as floats
    value = lubrication_index(acceleration_amplitude(10.0, 100.0, 0.8, CONSTANTS), 10.0, 100.0, CONSTANTS)
    assert isinstance(value, float) and value == pytest.approx(0.8, rel=1e-12)


def test_eq23_is_nan_without_warnings_where_undefined():
    speed = np.array([0.0, 10.0, 10.0, 10.0, 10.0])
    load = np.array([100.0, 0.0, 100.0, 100.0, 100.0])
    amplitude = np.array([0.2, 0.2, 0.0, -0.2, 0.2])
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        theta = lubrication_index(amplitude, speed, load, CONSTANTS)
        scalar = lubrication_index(0.2, 0.0, 100.0, CONSTANTS)
    assert np.all(np.isnan(theta[:4]))
    assert math.isfinite(theta[4])
    assert math.isnan(scalar)


def test_design_matrix_times_parameters_is_reduced_log_amplitude():
    rng = np.random.default_rng(3)
    speed = rng.uniform(5.0, 30.0, 40)
    load = rng.uniform(50.0, 400.0, 40)
    theta = rng.uniform(0.3, 1.2, 40)
    amplitude = acceleration_amplitude(speed, load, theta, CONSTANTS)
    np.testing.assert_allclose(design_matrix(speed, load, theta) @ CONSTANTS.as_vector(),
                               reduced_log_amplitude(amplitude, speed, load), rtol=1e-12, atol=1e-12)
    # hand check of one row: [1, 100, -0.8 * 3.419794] = [1, 100, -2.735835]
    np.testing.assert_allclose(design_matrix(10.0, 100.0, 0.8)[0], [1.0, 100.0, -2.735835], rtol=1e-6)


def test_eq13_to_15_one_degree_of_freedom_by_hand():
    """Eq. 13-15 for m = 2 kg, c = 40 N s/m, k = 8e6 N/m, F_0 = 10 N, w = 1000 rad/s."""
    from prsm_lube_ros.physics.vibration_model import (acceleration_from_displacement, forced_response_amplitude,
                                                       quasi_static_amplitude)
    # Eq. 14: X_0 = F_0 / K_0 = 10 / 8e6 = 1.25e-6 m
    assert quasi_static_amplitude(10.0, 8e6) == pytest.approx(1.25e-6)
    # Eq. 13: X = 10 / sqrt((8e6 - 2 * 1e6)^2 + (40 * 1000)^2) = 10 / sqrt(3.6e13 + 1.6e9) = 1.666630e-6 m
    assert forced_response_amplitude(10.0, 8e6, 2.0, 40.0, 1000.0) == pytest.approx(1.666630e-6, rel=1e-6)
    # far below resonance (w = 10 rad/s) Eq. 13 tends to Eq. 14
    assert forced_response_amplitude(10.0, 8e6, 2.0, 40.0, 10.0) == pytest.approx(1.25e-6, rel=1e-4)
    # Eq. 15: A_0 = w^2 X_0 = 1e6 * 1.25e-6 = 1.25 m/s^2
    assert acceleration_from_displacement(1.25e-6, 1000.0) == pytest.approx(1.25)
