# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Hertzian point contact of the screw-roller threads (Eq. 16-17).

Assumed geometry (the paper gives none; this is the usual PRSM one):

* The roller thread flank is a sphere whose centre lies on the roller axis and
  which meets the roller mean diameter d_R with its normal tilted by the flank
  angle beta from the radial direction; its radius is ``d_R / (2 cos beta)``,
  so both principal curvatures of the roller are ``2 cos(beta) / d_R``.
* The screw thread flank is straight in the axial plane (curvature 0) and,
  circumferentially, a surface of revolution of radius d_S / 2 whose normal is
  tilted by beta from the radial direction, so its circumferential curvature
  is ``2 cos(beta) / d_S`` (Meusnier).
* Both bodies are convex (positive curvatures).  Plane 1 is circumferential,
  which is also the rolling (entrainment) direction x of the film model;
  plane 2 is the axial plane, y.

Note on E': the ``E'`` of Eq. 16 is the *reduced compliance*
``(1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2`` in m^2/N (Harris' form), not the
Hamrock-Dowson effective modulus of the film model
(:func:`prsm_lube_ros.physics.film.effective_modulus`), which is ``2 / compliance``.

Load sharing: the paper assumes the axial load is shared uniformly by all
rollers and all engaged threads of each roller, so every thread contact
carries the same normal force (:func:`contact_normal_force`).

Units: curvatures in 1/m, forces in N, deformations in m, compliance in m^2/N,
stiffness in N/m.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from ..errors import InputError
from ..validation import require_all_positive
from .actuator import Actuator

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ['MAX_ELLIPTICITY', 'PrincipalCurvatures', 'ThreadContact', 'contact_deformation', 'contact_normal_force',
           'contact_stiffness', 'curvature_difference', 'curvature_difference_of_ellipticity', 'curvature_sum',
           'deformation_per_force', 'effective_radii', 'elliptic_integrals', 'ellipticity', 'load_sharing_factor',
           'normal_deformation', 'normal_stiffness', 'principal_curvatures', 'reduced_compliance',
           'semi_major_axis_coefficient', 'stiffness_coefficient', 'thread_contact']

#: Largest ellipticity a/b searched for; F(rho) closer to 1 than this allows is rejected.
MAX_ELLIPTICITY = 1.0e6


@dataclass(frozen=True)
class PrincipalCurvatures:
    """Principal curvatures of the two bodies at the contact, 1/m (convex > 0).

    Body I is the screw flank, body II the roller flank; plane 1 is the
    circumferential (rolling) direction, plane 2 the axial plane.
    """

    screw_circumferential: float
    screw_axial: float
    roller_circumferential: float
    roller_axial: float


def principal_curvatures(actuator: Actuator) -> PrincipalCurvatures:
    """Principal curvatures of the screw-roller thread contact, 1/m (geometry in the module doc).

    Screw: ``2 cos(beta) / d_S`` circumferentially, 0 axially; roller:
    ``2 cos(beta) / d_R`` in both planes.
    """
    cos_beta = math.cos(actuator.flank_angle)
    roller = 2.0 * cos_beta / actuator.roller_mean_diameter
    return PrincipalCurvatures(screw_circumferential=2.0 * cos_beta / actuator.screw_mean_diameter,
                               screw_axial=0.0, roller_circumferential=roller, roller_axial=roller)


def curvature_sum(curvatures: PrincipalCurvatures) -> float:
    """Curvature sum ``sum rho = rho_I1 + rho_I2 + rho_II1 + rho_II2`` of Eq. 16, 1/m."""
    total = (curvatures.screw_circumferential + curvatures.screw_axial
             + curvatures.roller_circumferential + curvatures.roller_axial)
    if not (math.isfinite(total) and total > 0):
        raise InputError(f'curvature sum must be positive, got {total!r} 1/m')
    return total


def curvature_difference(curvatures: PrincipalCurvatures) -> float:
    """Curvature difference ``F(rho) = |(rho_I1 - rho_I2) + (rho_II1 - rho_II2)| / sum rho``, in [0, 1)."""
    return abs((curvatures.screw_circumferential - curvatures.screw_axial)
               + (curvatures.roller_circumferential - curvatures.roller_axial)) / curvature_sum(curvatures)


def effective_radii(curvatures: PrincipalCurvatures) -> tuple[float, float]:
    """Effective radii ``(R_x, R_y)`` in m: rolling (circumferential) and transverse (axial).

    ``1/R_x = rho_I1 + rho_II1``, ``1/R_y = rho_I2 + rho_II2``; these are the
    radii of the Hamrock-Dowson film model (Eq. 8).
    """
    return (1.0 / (curvatures.screw_circumferential + curvatures.roller_circumferential),
            1.0 / (curvatures.screw_axial + curvatures.roller_axial))


def elliptic_integrals(ellipticity: float) -> tuple[float, float]:
    """Complete elliptic integrals ``(K(e), E(e))`` of the contact ellipse with a/b = ellipticity >= 1.

    Eccentricity ``e = sqrt(1 - (b/a)^2)``; scipy's ``ellipk``/``ellipe`` take
    the parameter ``m = e^2``, not e.
    """
    if not (math.isfinite(ellipticity) and ellipticity >= 1.0):
        raise InputError(f'ellipticity a/b must be a number >= 1, got {ellipticity!r}')
    parameter = 1.0 - 1.0 / ellipticity ** 2
    return float(ellipk(parameter)), float(ellipe(parameter))


def curvature_difference_of_ellipticity(ellipticity: float) -> float:
    """Hertz relation ``F(rho) = [(kappa^2 + 1) E(e) - 2 K(e)] / [(kappa^2 - 1) E(e)]`` (Harris).

    kappa = a/b >= 1; gives 0 for the circle kappa = 1 (its limit).
    """
    k_integral, e_integral = elliptic_integrals(ellipticity)
    if ellipticity == 1.0:
        return 0.0
    return (((ellipticity ** 2 + 1.0) * e_integral - 2.0 * k_integral)
            / ((ellipticity ** 2 - 1.0) * e_integral))


def ellipticity(curvature_difference_value: float) -> float:
    """Ellipticity ``kappa = a/b >= 1`` of the contact ellipse, solved exactly from F(rho).

    Inverts :func:`curvature_difference_of_ellipticity` with brentq; F(rho) = 0
    gives the circle kappa = 1.
    """
    target = float(curvature_difference_value)
    if not (math.isfinite(target) and 0.0 <= target < 1.0):
        raise InputError(f'curvature difference F(rho) must lie in [0, 1), got {target!r}')
    if target == 0.0:
        return 1.0
    upper = 2.0
    while curvature_difference_of_ellipticity(upper) < target:
        upper *= 2.0
        if upper > MAX_ELLIPTICITY:
            raise InputError(f'curvature difference F(rho) = {target!r} is too close to 1 '
                             f'(contact ellipse a/b beyond {MAX_ELLIPTICITY:g})')
    return brentq(lambda kappa: curvature_difference_of_ellipticity(kappa) - target,
                  1.0, upper, xtol=1e-14, rtol=1e-14)


def semi_major_axis_coefficient(ellipticity_value: float) -> float:
    """Coefficient m of Eq. 16: ``m = (2 kappa^2 E(e) / pi)^(1/3)`` (Harris' a*), dimensionless."""
    _, e_integral = elliptic_integrals(ellipticity_value)
    return (2.0 * ellipticity_value ** 2 * e_integral / math.pi) ** (1.0 / 3.0)


def reduced_compliance(youngs_modulus_1: float, poisson_ratio_1: float,
                       youngs_modulus_2: float | None = None, poisson_ratio_2: float | None = None) -> float:
    """Reduced compliance, the E' of Eq. 16: ``(1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2`` in m^2/N.

    Not the Hamrock-Dowson modulus (that is ``2 / compliance``, Pa).  Body 2
    defaults to the material of body 1.  Moduli in Pa.
    """
    if youngs_modulus_2 is None:
        youngs_modulus_2 = youngs_modulus_1
    if poisson_ratio_2 is None:
        poisson_ratio_2 = poisson_ratio_1
    require_all_positive('contact', youngs_modulus_1=youngs_modulus_1, youngs_modulus_2=youngs_modulus_2)
    for name, value in (('poisson_ratio_1', poisson_ratio_1), ('poisson_ratio_2', poisson_ratio_2)):
        if not (math.isfinite(value) and -1.0 < value < 0.5):
            raise InputError(f'{name} must lie in (-1, 0.5), got {value!r}')
    return ((1.0 - poisson_ratio_1 ** 2) / youngs_modulus_1
            + (1.0 - poisson_ratio_2 ** 2) / youngs_modulus_2)


def _forces(normal_force: npt.ArrayLike) -> np.ndarray:
    """Return normal forces as a float array; InputError unless finite and >= 0."""
    force = np.asarray(normal_force, dtype=float)
    if not np.all(np.isfinite(force) & (force >= 0)):
        raise InputError('normal_force must be finite and >= 0 N')
    return force


def _scalar_or_array(values: np.ndarray | np.float64) -> np.ndarray | float:
    """Return a float for 0-d results (numpy gives a 0-d array or a numpy scalar), else the array."""
    return float(values) if values.ndim == 0 else values


def deformation_per_force(curvature_sum_value: float, curvature_difference_value: float,
                          compliance: float) -> float:
    """``c = delta / F_n^(2/3)`` of Eq. 16, m N^(-2/3): the deformation at a 1 N normal force.

    ``c = 2 K(e) / (pi m) (3 E' / (2 sum rho))^(2/3) sum rho / 2`` with E' the
    reduced compliance (m^2/N) and sum rho in 1/m.
    """
    if not (math.isfinite(curvature_sum_value) and curvature_sum_value > 0):
        raise InputError(f'curvature sum must be positive, got {curvature_sum_value!r} 1/m')
    if not (math.isfinite(compliance) and compliance > 0):
        raise InputError(f'compliance E\' must be positive, got {compliance!r} m^2/N')
    kappa = ellipticity(curvature_difference_value)
    k_integral, _ = elliptic_integrals(kappa)
    coefficient = semi_major_axis_coefficient(kappa)
    return (2.0 * k_integral / (math.pi * coefficient)
            * (3.0 * compliance / (2.0 * curvature_sum_value)) ** (2.0 / 3.0)
            * curvature_sum_value / 2.0)


def normal_deformation(normal_force: npt.ArrayLike, curvature_sum_value: float, curvature_difference_value: float,
                       compliance: float) -> np.ndarray | float:
    """Eq. 16: normal contact deformation delta in m.

    ``delta = 2 K(e) / (pi m) (3 F_n E' / (2 sum rho))^(2/3) sum rho / 2``,
    normal_force F_n in N (>= 0, arrays welcome), sum rho in 1/m, F(rho)
    dimensionless, compliance E' in m^2/N (the reduced compliance, not a modulus).
    """
    force = _forces(normal_force)
    scale = deformation_per_force(curvature_sum_value, curvature_difference_value, compliance)
    return _scalar_or_array(scale * force ** (2.0 / 3.0))


def stiffness_coefficient(curvature_sum_value: float, curvature_difference_value: float,
                          compliance: float) -> float:
    """k_delta of Eq. 17 in N^(2/3)/m: ``K_n = k_delta F_n^(1/3)``.

    From ``delta = c F^(2/3)`` (Eq. 16), ``dF/d delta = 3 / (2 c) F^(1/3)``,
    so ``k_delta = 3 / (2 c)`` with c from :func:`deformation_per_force`.
    """
    return 1.5 / deformation_per_force(curvature_sum_value, curvature_difference_value, compliance)


def normal_stiffness(normal_force: npt.ArrayLike, curvature_sum_value: float, curvature_difference_value: float,
                     compliance: float) -> np.ndarray | float:
    """Eq. 17: normal contact stiffness ``K_n = dF_n/d delta = k_delta F_n^(1/3)`` in N/m.

    normal_force F_n in N (>= 0), other arguments as :func:`normal_deformation`.
    """
    force = _forces(normal_force)
    return _scalar_or_array(stiffness_coefficient(curvature_sum_value, curvature_difference_value,
                                                  compliance) * force ** (1.0 / 3.0))


def load_sharing_factor(actuator: Actuator) -> float:
    """Load-sharing divisor N in ``F_n = F_a / N``: ``n_rollers n_threads cos(beta) cos(alpha_S)``.

    The axial load is shared uniformly by all rollers and all engaged threads
    (the paper's assumption before Eq. 19); each contact's normal force is
    tilted from the axis by the flank angle beta and the lead angle alpha_S.
    """
    return (actuator.roller_count * actuator.threads_per_roller
            * math.cos(actuator.flank_angle) * math.cos(actuator.lead_angle))


def contact_normal_force(actuator: Actuator, axial_load: npt.ArrayLike) -> np.ndarray | float:
    """Per-contact normal force in N from the axial load F_a in N (uniform sharing, paper's assumption).

    ``F_n = |F_a| / (roller_count threads_per_roller cos(beta) cos(alpha_S))``;
    the sign of F_a only picks which flank carries the load.
    """
    load = np.asarray(axial_load, dtype=float)
    if not np.all(np.isfinite(load)):
        raise InputError('axial_load must be finite N')
    return _scalar_or_array(np.abs(load) / load_sharing_factor(actuator))


@dataclass(frozen=True)
class ThreadContact:
    """Load-independent Hertz quantities of an actuator's screw-roller thread contact.

    curvature_sum (1/m), curvature_difference F(rho), ellipticity kappa = a/b,
    elliptic_k K(e), elliptic_e E(e), coefficient m of Eq. 16, compliance E'
    (m^2/N), stiffness_coefficient k_delta (N^(2/3)/m), rolling_radius R_x and
    transverse_radius R_y (m).
    """

    curvature_sum: float
    curvature_difference: float
    ellipticity: float
    elliptic_k: float
    elliptic_e: float
    coefficient: float
    compliance: float
    stiffness_coefficient: float
    rolling_radius: float
    transverse_radius: float

    @property
    def film_ellipticity(self) -> float:
        """Hamrock-Dowson k = (transverse semi-axis) / (rolling semi-axis) of Eq. 8.

        kappa when the long axis is transverse to rolling (R_y >= R_x, as for the
        default actuator), else 1 / kappa.
        """
        return self.ellipticity if self.transverse_radius >= self.rolling_radius else 1.0 / self.ellipticity

    def deformation(self, normal_force: npt.ArrayLike) -> np.ndarray | float:
        """Eq. 16 for this contact: delta in m from F_n in N."""
        return _scalar_or_array(1.5 / self.stiffness_coefficient * _forces(normal_force) ** (2.0 / 3.0))

    def stiffness(self, normal_force: npt.ArrayLike) -> np.ndarray | float:
        """Eq. 17 for this contact: K_n in N/m from F_n in N."""
        return _scalar_or_array(self.stiffness_coefficient * _forces(normal_force) ** (1.0 / 3.0))


def thread_contact(actuator: Actuator) -> ThreadContact:
    """Hertz quantities of the actuator's screw-roller contact (same steel for screw and roller)."""
    curvatures = principal_curvatures(actuator)
    total = curvature_sum(curvatures)
    difference = curvature_difference(curvatures)
    kappa = ellipticity(difference)
    k_integral, e_integral = elliptic_integrals(kappa)
    compliance = reduced_compliance(actuator.youngs_modulus, actuator.poisson_ratio)
    rolling_radius, transverse_radius = effective_radii(curvatures)
    return ThreadContact(curvature_sum=total, curvature_difference=difference, ellipticity=kappa,
                         elliptic_k=k_integral, elliptic_e=e_integral,
                         coefficient=semi_major_axis_coefficient(kappa), compliance=compliance,
                         stiffness_coefficient=stiffness_coefficient(total, difference, compliance),
                         rolling_radius=rolling_radius, transverse_radius=transverse_radius)


def contact_deformation(actuator: Actuator, axial_load: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 16 for an actuator: thread-contact deformation delta in m from the axial load F_a in N."""
    return thread_contact(actuator).deformation(contact_normal_force(actuator, axial_load))


def contact_stiffness(actuator: Actuator, axial_load: npt.ArrayLike) -> np.ndarray | float:
    """Eq. 17 for an actuator: thread-contact stiffness K_n in N/m from the axial load F_a in N."""
    return thread_contact(actuator).stiffness(contact_normal_force(actuator, axial_load))
