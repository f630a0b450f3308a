# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""One-degree-of-freedom vibration model and the lubrication index (Eq. 13-15, 18-23).

Units: screw speed omega_S in rad/s, axial load F_a in N, acceleration
amplitude A_0 (the RMS of the nut acceleration) in m/s^2.  With these units the
fitted constants carry the units
``C_sys``: m s^-2 * s^2 * N^(1/3) = m N^(1/3), ``C_F``: 1/N and
``C_lambda``: (rad/s)^-0.68 N^0.073.

The Hertzian stiffness of Eq. 16-17 lives in :mod:`prsm_lube_ros.physics.contact`; here
only its load scaling (Eq. 20) enters.  All functions accept numpy arrays.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
import math
from typing import overload, TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy.typing as npt

__all__ = ['FREQUENCY_EXPONENT', 'LOAD_EXPONENT', 'ModelConstants', 'STIFFNESS_EXPONENT', 'VELOCITY_EXPONENT',
           'acceleration_amplitude', 'acceleration_from_displacement', 'design_matrix', 'excitation_scale',
           'film_speed_load_term', 'forced_response_amplitude', 'load_excitation_factor', 'lubrication_index',
           'oil_excitation_factor', 'quasi_static_amplitude', 'reduced_log_amplitude', 'stiffness_load_scale']

#: Exponent of the sliding velocity in the Hamrock-Dowson film (Eq. 8, 9, 19).
VELOCITY_EXPONENT = 0.68
#: Exponent of the contact load in the Hamrock-Dowson film (Eq. 8, 9, 19).
LOAD_EXPONENT = -0.073
#: Exponent of the load in the Hertzian contact stiffness K ~ F^(1/3) (Eq. 17, 20).
STIFFNESS_EXPONENT = 1.0 / 3.0
#: The acceleration amplitude follows the square of the dominant frequency (Eq. 15).
FREQUENCY_EXPONENT = 2.0


@dataclass(frozen=True)
class ModelConstants:
    """The three constants of Eq. 22/23, fitted on a reference lubrication state.

    c_sys: system constant C_sys, m N^(1/3).
    c_f: load influence coefficient C_F, 1/N.
    c_lambda: film-ratio coefficient C_lambda, (rad/s)^-0.68 N^0.073.
    """

    c_sys: float
    c_f: float
    c_lambda: float

    def as_vector(self) -> np.ndarray:
        """Parameters in the linear form of the fit: (ln C_sys, C_F, C_lambda)."""
        return np.array([math.log(self.c_sys), self.c_f, self.c_lambda])

    def by_name(self) -> dict[str, float]:
        """``{'c_sys': ..., 'c_f': ..., 'c_lambda': ...}``: the keys of calibration files and JSON documents."""
        return asdict(self)

    @classmethod
    def from_vector(cls, vector: Sequence[float] | np.ndarray) -> ModelConstants:
        """Inverse of :meth:`as_vector`."""
        return cls(c_sys=float(np.exp(vector[0])), c_f=float(vector[1]),
                   c_lambda=float(vector[2]))


def forced_response_amplitude(force_amplitude: np.ndarray | float, stiffness: np.ndarray | float,
                              mass: np.ndarray | float, damping: np.ndarray | float,
                              frequency: npt.ArrayLike) -> np.ndarray | float:
    """Steady-state displacement amplitude of Eq. 13 under harmonic forcing, m.

    Eq. 13, ``m x'' + c x' + k x = F_0 sin(w t)``, has the steady amplitude
    ``X = F_0 / sqrt((k - m w^2)^2 + (c w)^2)``.
    force_amplitude F_0 in N, stiffness k in N/m, mass m in kg, damping c in
    N s/m, frequency w in rad/s.
    """
    frequency = np.asarray(frequency, dtype=float)
    return force_amplitude / np.hypot(stiffness - mass * frequency ** 2, damping * frequency)


def quasi_static_amplitude(force_amplitude: npt.ArrayLike, stiffness: np.ndarray | float) -> np.ndarray | float:
    """Eq. 14: far from resonance, ``X_0 = F_0 / K_0``; N and N/m give m."""
    return np.asarray(force_amplitude, dtype=float) / stiffness


def acceleration_from_displacement(displacement_amplitude: np.ndarray | float,
                                   frequency: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 15: ``A_0 = w^2 X_0``; m and rad/s give m/s^2."""
    return np.asarray(frequency, dtype=float) ** FREQUENCY_EXPONENT * displacement_amplitude


@overload
def film_speed_load_term(screw_speed: float, axial_load: float) -> float: ...


@overload
def film_speed_load_term(screw_speed: np.ndarray, axial_load: np.ndarray | float) -> np.ndarray: ...


@overload
def film_speed_load_term(screw_speed: np.ndarray | float, axial_load: np.ndarray) -> np.ndarray: ...


def film_speed_load_term(screw_speed: np.ndarray | float, axial_load: np.ndarray | float) -> np.ndarray | float:
    """``omega_S^0.68 F_a^-0.073``, the speed and load part of the film (Eq. 9, 19).

    screw_speed in rad/s (its magnitude is used), axial_load in N (magnitude).
    """
    screw_speed = np.abs(np.asarray(screw_speed, dtype=float))
    axial_load = np.abs(np.asarray(axial_load, dtype=float))
    with np.errstate(divide='ignore', invalid='ignore'):
        return screw_speed ** VELOCITY_EXPONENT * axial_load ** LOAD_EXPONENT


def oil_excitation_factor(theta_oil: npt.ArrayLike, c_lambda: float, screw_speed: np.ndarray | float,
                          axial_load: np.ndarray | float) -> np.ndarray | float:
    """Eq. 19: ``Phi_Oil = exp(-theta_Oil C_lambda omega_S^0.68 F_a^-0.073)``, dimensionless."""
    return np.exp(-np.asarray(theta_oil, dtype=float) * c_lambda
                  * film_speed_load_term(screw_speed, axial_load))


def load_excitation_factor(axial_load: npt.ArrayLike, c_f: float) -> np.ndarray | float:
    """Eq. 18: ``Phi_F = exp(C_F F_a)``, dimensionless; F_a in N, C_F in 1/N."""
    return np.exp(c_f * np.abs(np.asarray(axial_load, dtype=float)))


def stiffness_load_scale(axial_load: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 20: ``K_0 ~ F_a^(1/3)`` (Hertzian stiffening, Eq. 17); N^(1/3)."""
    return np.abs(np.asarray(axial_load, dtype=float)) ** STIFFNESS_EXPONENT


def excitation_scale(oil_factor: npt.ArrayLike, load_factor: np.ndarray | float) -> np.ndarray | float:
    """Eq. 21: ``F_0 ~ Phi_Oil Phi_F``, dimensionless."""
    return np.asarray(oil_factor, dtype=float) * load_factor


@overload
def acceleration_amplitude(screw_speed: float, axial_load: float, theta_oil: float,
                           constants: ModelConstants) -> float: ...


@overload
def acceleration_amplitude(screw_speed: np.ndarray, axial_load: np.ndarray | float, theta_oil: npt.ArrayLike,
                           constants: ModelConstants) -> np.ndarray: ...


@overload
def acceleration_amplitude(screw_speed: np.ndarray | float, axial_load: np.ndarray, theta_oil: npt.ArrayLike,
                           constants: ModelConstants) -> np.ndarray: ...


@overload
def acceleration_amplitude(screw_speed: np.ndarray | float, axial_load: np.ndarray | float, theta_oil: npt.ArrayLike,
                           constants: ModelConstants) -> np.ndarray | float: ...


def acceleration_amplitude(screw_speed: np.ndarray | float, axial_load: np.ndarray | float, theta_oil: npt.ArrayLike,
                           constants: ModelConstants) -> np.ndarray | float:
    """Eq. 22: acceleration amplitude A_0 in m/s^2.

    ``A_0 = C_sys omega_S^2 F_a^(-1/3) exp(C_F F_a - theta_Oil C_lambda omega_S^0.68 F_a^-0.073)``
    with omega_S in rad/s and F_a in N (magnitudes), theta_Oil dimensionless.
    """
    screw_speed = np.abs(np.asarray(screw_speed, dtype=float))
    axial_load = np.abs(np.asarray(axial_load, dtype=float))
    force = excitation_scale(
        oil_excitation_factor(theta_oil, constants.c_lambda, screw_speed, axial_load),
        load_excitation_factor(axial_load, constants.c_f))
    with np.errstate(divide='ignore', invalid='ignore'):
        return (constants.c_sys * screw_speed ** FREQUENCY_EXPONENT
                * force / stiffness_load_scale(axial_load))


@overload
def reduced_log_amplitude(amplitude: float, screw_speed: float, axial_load: float) -> float: ...


@overload
def reduced_log_amplitude(amplitude: np.ndarray, screw_speed: np.ndarray | float,
                          axial_load: np.ndarray | float) -> np.ndarray: ...


@overload
def reduced_log_amplitude(amplitude: npt.ArrayLike, screw_speed: np.ndarray,
                          axial_load: np.ndarray | float) -> np.ndarray: ...


@overload
def reduced_log_amplitude(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float,
                          axial_load: np.ndarray) -> np.ndarray: ...


@overload
def reduced_log_amplitude(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float,
                          axial_load: np.ndarray | float) -> np.ndarray | float: ...


def reduced_log_amplitude(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float,
                          axial_load: np.ndarray | float) -> np.ndarray | float:
    """``ln(A_0 omega_S^-2 F_a^(1/3))``: the log amplitude with the known factors removed.

    By Eq. 22 this equals ``ln C_sys + C_F F_a - theta_Oil C_lambda omega_S^0.68 F_a^-0.073``,
    which is linear in (ln C_sys, C_F, C_lambda) once theta_Oil is known.
    """
    amplitude = np.asarray(amplitude, dtype=float)
    screw_speed = np.abs(np.asarray(screw_speed, dtype=float))
    axial_load = np.abs(np.asarray(axial_load, dtype=float))
    with np.errstate(divide='ignore', invalid='ignore'):
        return (np.log(amplitude) - FREQUENCY_EXPONENT * np.log(screw_speed)
                + STIFFNESS_EXPONENT * np.log(axial_load))


def design_matrix(screw_speed: npt.ArrayLike, axial_load: np.ndarray | float, theta_oil: npt.ArrayLike) -> np.ndarray:
    """Rows ``[1, F_a, -theta_Oil omega_S^0.68 F_a^-0.073]`` of the linear form of Eq. 22.

    ``reduced_log_amplitude = design_matrix @ (ln C_sys, C_F, C_lambda)``.
    """
    screw_speed = np.atleast_1d(np.asarray(screw_speed, dtype=float))
    axial_load = np.abs(np.atleast_1d(np.asarray(axial_load, dtype=float)))
    theta_oil = np.broadcast_to(np.asarray(theta_oil, dtype=float), screw_speed.shape)
    return np.column_stack([np.ones_like(screw_speed), axial_load,
                            -theta_oil * film_speed_load_term(screw_speed, axial_load)])


@overload
def lubrication_index(amplitude: float, screw_speed: float, axial_load: float, constants: ModelConstants) -> float: ...


@overload
def lubrication_index(amplitude: np.ndarray, screw_speed: np.ndarray | float, axial_load: np.ndarray | float,
                      constants: ModelConstants) -> np.ndarray: ...


@overload
def lubrication_index(amplitude: npt.ArrayLike, screw_speed: np.ndarray, axial_load: np.ndarray | float,
                      constants: ModelConstants) -> np.ndarray: ...


@overload
def lubrication_index(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float, axial_load: np.ndarray,
                      constants: ModelConstants) -> np.ndarray: ...


@overload
def lubrication_index(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float, axial_load: np.ndarray | float,
                      constants: ModelConstants) -> np.ndarray | float: ...


def lubrication_index(amplitude: npt.ArrayLike, screw_speed: np.ndarray | float, axial_load: np.ndarray | float,
                      constants: ModelConstants) -> np.ndarray | float:
    """Eq. 23: theta_Oil from the acceleration amplitude, dimensionless.

    ``theta_Oil = (C_F F_a - ln(C_sys^-1 A_0 omega_S^-2 F_a^(1/3))) / (C_lambda omega_S^0.68 F_a^-0.073)``

    amplitude A_0 in m/s^2, screw_speed in rad/s, axial_load in N.  Where the
    equation means nothing (no speed, no load, no or non-finite amplitude,
    C_lambda = 0) the result is NaN; :func:`prsm_lube_ros.estimation.assessment` says why.
    """
    amplitude = np.asarray(amplitude, dtype=float)
    axial_load = np.abs(np.asarray(axial_load, dtype=float))
    denominator = constants.c_lambda * film_speed_load_term(screw_speed, axial_load)
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        numerator = (constants.c_f * axial_load + math.log(constants.c_sys)
                     - reduced_log_amplitude(amplitude, screw_speed, axial_load))
        theta = numerator / denominator
    valid = (np.isfinite(theta) & (amplitude > 0) & (axial_load > 0)
             & (np.abs(np.asarray(screw_speed, dtype=float)) > 0) & (denominator != 0))
    result = np.where(valid, theta, np.nan)
    return float(result) if result.ndim == 0 else result
