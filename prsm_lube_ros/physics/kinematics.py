# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Screw-roller kinematics and the thread-contact sliding velocity (Eq. 1-7).

Units: angular speeds in rad/s, diameters and deformations in m, angles in
rad, velocities in m/s.  Every function accepts numpy arrays for the speeds.

Sign convention.  With the formulas as printed in the paper, the roller-side
contact velocity v_R (Eq. 5) and the screw-side one v_S (Eq. 4) have opposite
signs for a positive screw speed, so the sliding velocity
``v_SR = v_R - v_S`` (Eq. 3, 6) is *negative* for ``omega_S > 0`` and its
magnitude is about the sum of the two surface speeds.  The functions below
return the printed, signed values; the film model (Eq. 9) needs a speed and
uses :func:`sliding_speed`, the magnitude ``|v_SR|``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..validation import require_positive
from .actuator import Actuator

if TYPE_CHECKING:
    import numpy.typing as npt


__all__ = ['actuator_sliding_velocity', 'roller_contact_velocity', 'roller_revolution_speed',
           'roller_rotation_speed', 'screw_contact_velocity', 'sliding_speed', 'sliding_velocity',
           'sliding_velocity_coefficient', 'sliding_velocity_coefficient_from_geometry',
           'sliding_velocity_from_contact_velocities']


def roller_revolution_speed(screw_speed: npt.ArrayLike, screw_diameter: float,
                            roller_diameter: float) -> np.ndarray | float:
    """Eq. 1: roller revolution (carrier) speed ``omega_P = d_S / (2 (d_S + d_R)) omega_S``.

    screw_speed omega_S in rad/s, screw_diameter d_S and roller_diameter d_R
    (thread mean diameters) in m; returns rad/s.
    """
    d_s = require_positive('screw_diameter', screw_diameter)
    d_r = require_positive('roller_diameter', roller_diameter)
    return d_s / (2.0 * (d_s + d_r)) * np.asarray(screw_speed, dtype=float)


def roller_rotation_speed(screw_speed: npt.ArrayLike, screw_diameter: float,
                          roller_diameter: float) -> np.ndarray | float:
    """Eq. 2: roller rotation speed ``omega_R = d_S (d_S + 2 d_R) / (2 d_R (d_S + d_R)) omega_S``.

    screw_speed omega_S in rad/s, diameters d_S, d_R in m; returns rad/s.
    """
    d_s = require_positive('screw_diameter', screw_diameter)
    d_r = require_positive('roller_diameter', roller_diameter)
    return d_s * (d_s + 2.0 * d_r) / (2.0 * d_r * (d_s + d_r)) * np.asarray(screw_speed, dtype=float)


def screw_contact_velocity(screw_speed: npt.ArrayLike, screw_diameter: float, contact_deformation: npt.ArrayLike,
                           flank_angle: float, lead_angle: float) -> np.ndarray | float:
    """Eq. 4: screw-side contact velocity ``v_S = (d_S/2 - delta cos(beta)) omega_S cos(alpha_S)``.

    screw_speed omega_S in rad/s, screw_diameter d_S in m, contact_deformation
    delta_SR in m, flank_angle beta and lead_angle alpha_S in rad; returns m/s.
    """
    screw_speed = np.asarray(screw_speed, dtype=float)
    return ((screw_diameter / 2.0 - np.asarray(contact_deformation, dtype=float) * np.cos(flank_angle))
            * screw_speed * np.cos(lead_angle))


def roller_contact_velocity(screw_speed: npt.ArrayLike, roller_speed: npt.ArrayLike, screw_diameter: float,
                            roller_diameter: float, contact_deformation: npt.ArrayLike, flank_angle: float,
                            lead_angle: float) -> np.ndarray | float:
    """Eq. 5: roller-side contact velocity in m/s.

    ``v_R = [omega_R (-d_R - 2 delta cos(beta)) - d_S omega_S tan^2(alpha_S) / 2] cos(alpha_S)``
    with screw_speed omega_S and roller_speed omega_R (Eq. 2) in rad/s,
    diameters d_S, d_R and contact_deformation delta_SR in m, flank_angle beta
    and lead_angle alpha_S in rad.
    """
    screw_speed = np.asarray(screw_speed, dtype=float)
    roller_speed = np.asarray(roller_speed, dtype=float)
    delta = np.asarray(contact_deformation, dtype=float)
    return ((roller_speed * (-roller_diameter - 2.0 * delta * np.cos(flank_angle))
             - screw_diameter * screw_speed * np.tan(lead_angle) ** 2 / 2.0) * np.cos(lead_angle))


def sliding_velocity_from_contact_velocities(roller_velocity: npt.ArrayLike,
                                             screw_velocity: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 3: sliding velocity ``v_SR = v_R - v_S`` in m/s (signed, as printed)."""
    return np.asarray(roller_velocity, dtype=float) - np.asarray(screw_velocity, dtype=float)


def sliding_velocity(screw_speed: npt.ArrayLike, roller_speed: npt.ArrayLike, screw_diameter: float,
                     roller_diameter: float, contact_deformation: npt.ArrayLike, flank_angle: float,
                     lead_angle: float) -> np.ndarray | float:
    """Eq. 6: sliding velocity of one screw-roller thread contact in m/s (signed, as printed).

    ``v_SR = [(omega_S - 2 omega_R) delta cos(beta) - d_S omega_S (1 + tan^2(alpha_S)) / 2
    - d_R omega_R] cos(alpha_S)``; it equals Eq. 3 with Eq. 4 and 5 substituted.
    Negative for a positive screw speed (see the module docstring).
    screw_speed omega_S and roller_speed omega_R in rad/s, diameters and
    contact_deformation delta_SR in m, flank_angle beta and lead_angle alpha_S in rad.
    """
    screw_speed = np.asarray(screw_speed, dtype=float)
    roller_speed = np.asarray(roller_speed, dtype=float)
    delta = np.asarray(contact_deformation, dtype=float)
    return (((screw_speed - 2.0 * roller_speed) * delta * np.cos(flank_angle)
             - screw_diameter * screw_speed * (1.0 + np.tan(lead_angle) ** 2) / 2.0
             - roller_diameter * roller_speed) * np.cos(lead_angle))


def sliding_velocity_coefficient_from_geometry(screw_diameter: float, roller_diameter: float,
                                               contact_deformation: npt.ArrayLike, flank_angle: float,
                                               lead_angle: float) -> np.ndarray | float:
    """Eq. 7: ``k_v = v_SR / omega_S`` in m (per rad), signed as Eq. 6 (negative).

    Eq. 6 with omega_R from Eq. 2 is proportional to omega_S, so
    ``k_v = [(1 - 2 r) delta cos(beta) - d_S (1 + tan^2(alpha_S)) / 2 - d_R r] cos(alpha_S)``
    with the speed ratio ``r = omega_R / omega_S`` of Eq. 2.
    """
    ratio = roller_rotation_speed(1.0, screw_diameter, roller_diameter)
    return sliding_velocity(1.0, ratio, screw_diameter, roller_diameter, contact_deformation,
                            flank_angle, lead_angle)


def sliding_velocity_coefficient(actuator: Actuator, contact_deformation: npt.ArrayLike = 0.0) -> np.ndarray | float:
    """Eq. 7 for an actuator: ``k_v = v_SR / omega_S`` in m (per rad), signed (negative).

    contact_deformation delta_SR in m (see
    :func:`prsm_lube_ros.physics.contact.normal_deformation`); its effect on k_v is of
    the order delta / d_S, i.e. about 1e-4 relative for micrometre deformations.
    """
    return sliding_velocity_coefficient_from_geometry(
        actuator.screw_mean_diameter, actuator.roller_mean_diameter, contact_deformation,
        actuator.flank_angle, actuator.lead_angle)


def actuator_sliding_velocity(actuator: Actuator, screw_speed: npt.ArrayLike,
                              contact_deformation: npt.ArrayLike = 0.0) -> np.ndarray | float:
    """Eq. 6/7 for an actuator: signed sliding velocity ``v_SR = k_v omega_S`` in m/s.

    screw_speed omega_S in rad/s, contact_deformation delta_SR in m.
    """
    return (sliding_velocity_coefficient(actuator, contact_deformation)
            * np.asarray(screw_speed, dtype=float))


def sliding_speed(actuator: Actuator, screw_speed: npt.ArrayLike,
                  contact_deformation: npt.ArrayLike = 0.0) -> np.ndarray | float:
    """Magnitude ``|v_SR| = |k_v omega_S|`` in m/s: the speed the film model (Eq. 9) uses.

    screw_speed omega_S in rad/s (either sign), contact_deformation delta_SR in m.
    """
    return np.abs(actuator_sliding_velocity(actuator, screw_speed, contact_deformation))
