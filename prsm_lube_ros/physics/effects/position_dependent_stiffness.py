# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Screw shaft axial stiffness in series with the thread contacts, changing with nut position.

Physics: the load path from nut to frame runs through the Hertzian thread
contacts (stiffness k_c = k_delta F^(1/3), Eq. 17) and, in series, the
screw shaft between the nut and the axially fixed bearing, k_s = E A / L(x)
with L the free shaft length.  The series stiffness
K = k_c k_s / (k_c + k_s) replaces K_0 in Eq. 14, so

    X_0 = F_0 / K = (F_0 / k_c) (1 + k_c / k_s(x)),   A = A_22 (1 + k_c(F) / k_s(x)).

How k_s depends on the nut position x depends on the bearing arrangement
(:data:`ARRANGEMENTS`); bearings sit o_1 before the stroke start and o_2 beyond
its end (stroke s), so the free lengths either side of the nut are
``a = x + o_1`` and ``b = s + o_2 - x``:

* fixed-free, the fixed (axial) bearing beyond the far end of travel
  (``fixed-free``) or before its start (``free-fixed``): only the segment to
  the fixed bearing carries the load, ``k_s = E A / b`` or ``E A / a``; the
  compliance is linear in x, falling or rising along the stroke;
* fixed-supported: the support bearing only guides the shaft radially and
  carries no axial load, so the axial law is that of fixed-free with the
  fixed bearing at the same end (the two cannot be told apart by axial
  stiffness; reports name both);
* fixed-fixed: both segments carry the load in parallel,
  ``k_s = E A (1/a + 1/b)``: the compliance ``a b / (E A (a + b))`` is an
  arch, largest mid-travel.

All profiles are quadratics in ``u = x / s``:
``rho(u) = rho_0 (1 - u) + rho_1 u + 4 rho_arch u (1 - u)`` with rho = k_c/k_s,
``rho_arch = 0`` for fixed-free and ``rho_arch = c s^2 / 4`` for fixed-fixed,
``rho_0 = c o_1 (s + o_2)``, ``rho_1 = c o_2 (s + o_1)``, ``c = k_c / (E A (s + o_1 + o_2))``
(:func:`compliance_ratio_profile`, :func:`arrangement_ratios`).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import choose, Extension as EffectExtension, Simulation as EffectSimulation
from ...errors import ConfigError
from ...validation import require, require_all_positive
from ..vibration_model import STIFFNESS_EXPONENT

if TYPE_CHECKING:
    from collections.abc import Mapping

    import numpy.typing as npt

    from . import ContactState, SimulationContext

__all__ = ['ARRANGEMENTS', 'CHANGE_RANGE', 'DRAWN_ARRANGEMENTS', 'Extension', 'FIXED_BEFORE_START', 'Law',
           'MIN_FREE_LENGTH', 'PositionDependentStiffnessLaw', 'Simulation', 'draw',
           'arrangement_ratios', 'compliance_ratio_profile', 'contact_stiffness_at', 'fixed_fixed_shaft_stiffness',
           'series_stiffness_amplification', 'shaft_axial_stiffness', 'shaft_stiffness_for']

#: Shortest free shaft length the law is evaluated at, m (the nut cannot sit on the bearing).
MIN_FREE_LENGTH = 1e-3
#: Drawn range of the amplitude change over one stroke at the reference load (fraction).
CHANGE_RANGE = (0.05, 0.30)
#: Bearing arrangements drawn (fixed-supported has the axial law of fixed-free).
DRAWN_ARRANGEMENTS = ('fixed-free', 'free-fixed', 'fixed-fixed')


def shaft_axial_stiffness(youngs_modulus: float, root_diameter: float,
                          free_length: npt.ArrayLike) -> np.ndarray | float:
    """Axial stiffness of the screw shaft between nut and fixed bearing, ``k_s = E A / L`` in N/m.

    youngs_modulus E in Pa, root_diameter in m (A = pi d^2 / 4), free_length L in m.
    """
    area = math.pi * root_diameter ** 2 / 4.0
    return youngs_modulus * area / np.asarray(free_length, dtype=float)


def fixed_fixed_shaft_stiffness(youngs_modulus: float, root_diameter: float, length_before: npt.ArrayLike,
                                length_after: npt.ArrayLike) -> np.ndarray | float:
    """Axial stiffness of a shaft held axially at both ends, ``k_s = E A (1/a + 1/b)`` in N/m.

    length_before a and length_after b, m, are the free lengths between the nut
    and each bearing; the two segments carry the load in parallel.
    """
    area = math.pi * root_diameter ** 2 / 4.0
    a = np.maximum(np.asarray(length_before, dtype=float), MIN_FREE_LENGTH)
    b = np.maximum(np.asarray(length_after, dtype=float), MIN_FREE_LENGTH)
    return youngs_modulus * area * (1.0 / a + 1.0 / b)


#: Bearing arrangements (see module doc): the fixed bearing beyond the far end (fixed-free, fixed-supported),
#: before the stroke start (free-fixed, supported-fixed), or both ends fixed.
ARRANGEMENTS = ('fixed-free', 'free-fixed', 'fixed-supported', 'supported-fixed', 'fixed-fixed')
#: Arrangements whose axially fixed bearing lies before the stroke start.
FIXED_BEFORE_START = ('free-fixed', 'supported-fixed')


def shaft_stiffness_for(arrangement: str, youngs_modulus: float, root_diameter: float, nut_position: npt.ArrayLike,
                        stroke: float, bearing_before: float, bearing_after: float) -> np.ndarray | float:
    """Shaft stiffness k_s(x), N/m, for a bearing arrangement (one of :data:`ARRANGEMENTS`).

    Bearings sit ``bearing_before`` m before the stroke start and ``bearing_after``
    m beyond its end; for the fixed-free and fixed-supported arrangements only
    the segment to the axially fixed bearing carries the load.
    """
    x = np.asarray(nut_position, dtype=float)
    before, after = x + bearing_before, stroke + bearing_after - x
    if arrangement == 'fixed-fixed':
        return fixed_fixed_shaft_stiffness(youngs_modulus, root_diameter, before, after)
    if arrangement not in ARRANGEMENTS:
        raise ValueError(f'unknown bearing arrangement {arrangement!r}; known: {", ".join(ARRANGEMENTS)}')
    length = before if arrangement in FIXED_BEFORE_START else after
    return shaft_axial_stiffness(youngs_modulus, root_diameter, np.maximum(length, MIN_FREE_LENGTH))


def arrangement_ratios(arrangement: str, contact_over_ea: float, stroke: float, bearing_before: float,
                       bearing_after: float) -> tuple[float, float, float]:
    """``(rho_0, rho_1, rho_arch)`` of :func:`compliance_ratio_profile` for an arrangement, dimensionless.

    contact_over_ea = k_c / (E A) in 1/m; stroke and bearing offsets in m (see module doc).
    """
    if arrangement == 'fixed-fixed':
        c = contact_over_ea / (stroke + bearing_before + bearing_after)
        return (c * bearing_before * (stroke + bearing_after), c * bearing_after * (stroke + bearing_before),
                c * stroke ** 2 / 4.0)
    if arrangement in FIXED_BEFORE_START:
        return contact_over_ea * bearing_before, contact_over_ea * (stroke + bearing_before), 0.0
    if arrangement not in ARRANGEMENTS:
        raise ValueError(f'unknown bearing arrangement {arrangement!r}; known: {", ".join(ARRANGEMENTS)}')
    return contact_over_ea * (stroke + bearing_after), contact_over_ea * bearing_after, 0.0


def compliance_ratio_profile(u: npt.ArrayLike, ratio_at_start: float, ratio_at_end: float,
                             ratio_arch: float = 0.0) -> np.ndarray | float:
    """``rho(u) = rho_0 (1 - u) + rho_1 u + 4 rho_arch u (1 - u)``, k_c/k_s along the stroke (u = x / stroke).

    Exact for every arrangement: ``ratio_arch = 0`` fixed-free or fixed-supported, ``> 0`` fixed-fixed.
    """
    u = np.asarray(u, dtype=float)
    return ratio_at_start * (1 - u) + ratio_at_end * u + 4.0 * ratio_arch * u * (1 - u)


def series_stiffness_amplification(contact_stiffness: npt.ArrayLike,
                                   shaft_stiffness: npt.ArrayLike) -> np.ndarray | float:
    """``K_hertz / K_series = 1 + k_c / k_s``: how much a compliant shaft in series raises X0 = F0/K."""
    return 1.0 + np.asarray(contact_stiffness, dtype=float) / np.asarray(shaft_stiffness, dtype=float)


def contact_stiffness_at(load: npt.ArrayLike, contact_stiffness: float, reference_load: float) -> np.ndarray | float:
    """``k_c(F) = k_c(F_ref) (|F| / F_ref)^(1/3)`` (Eq. 17, 20), N/m."""
    return contact_stiffness * (np.abs(np.asarray(load, dtype=float)) / reference_load) ** STIFFNESS_EXPONENT


@dataclass(frozen=True)
class PositionDependentStiffnessLaw:
    """Shaft compliance in series with the thread contacts, for any bearing arrangement.

    Default (fixed-free, the fixed bearing beyond the far end of travel): the
    free shaft length ``L(x) = free_length_at_start - x`` shrinks as the nut
    travels by x (m, from the start of the stroke) and ``k_s = E A / L``
    grows: the amplitude falls along the stroke, as the paper saw.  With a
    bearing ``near_length_at_start`` m before the stroke start, ``free-fixed``
    / ``supported-fixed`` load the segment ``near_length_at_start + x`` and
    ``fixed-fixed`` both segments in parallel.
    """

    contact_stiffness: float        # N/m, k_c at reference_load
    reference_load: float           # N
    youngs_modulus: float           # Pa, shaft material
    root_diameter: float            # m, shaft root diameter
    free_length_at_start: float     # m, nut to the bearing beyond the far end at travel 0
    arrangement: str = 'fixed-free'
    near_length_at_start: float = 0.05   # m, nut to the bearing before the stroke start at travel 0

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('position_dependent_stiffness', contact_stiffness=self.contact_stiffness,
                             reference_load=self.reference_load, youngs_modulus=self.youngs_modulus,
                             root_diameter=self.root_diameter, free_length_at_start=self.free_length_at_start,
                             near_length_at_start=self.near_length_at_start)
        require(self.arrangement in ARRANGEMENTS, 'position_dependent_stiffness arrangement must be one of '
                f'{", ".join(ARRANGEMENTS)}, got {self.arrangement!r}')

    @property
    def stiffness_ratio_at_start(self) -> float:
        """``k_c / k_s`` at travel 0 and the reference load, dimensionless."""
        return float(self.contact_stiffness / self.shaft_stiffness(0.0))

    def shaft_stiffness(self, nut_position: npt.ArrayLike) -> np.ndarray | float:
        """``k_s(x)`` of the arrangement, N/m, for nut_position x in m from the stroke start."""
        # The far bearing lies free_length_at_start beyond travel 0: stroke + bearing_after in shaft_stiffness_for.
        return shaft_stiffness_for(self.arrangement, self.youngs_modulus, self.root_diameter, nut_position,
                                   self.free_length_at_start, self.near_length_at_start, 0.0)

    def amplitude_factor(self, nut_position: npt.ArrayLike, axial_load: npt.ArrayLike) -> np.ndarray | float:
        """``1 + k_c(F) / k_s(x)`` for nut_position x in m and axial_load F in N."""
        return series_stiffness_amplification(
            contact_stiffness_at(axial_load, self.contact_stiffness, self.reference_load),
            self.shaft_stiffness(nut_position))


Law = PositionDependentStiffnessLaw


class Extension(EffectExtension):
    """Eq. 22 times ``1 + rho(x) (F/F_ref)^(1/3)``, rho(x) from :func:`compliance_ratio_profile`.

    ``ratio_arch`` absent or 0: linear from ``ratio_at_start`` to ``ratio_at_end`` (fixed-free).
    """

    id = 'position_dependent_stiffness'

    def log_gain(self, params: Mapping[str, float], covariates: Any, ln_a22: np.ndarray | float) -> np.ndarray | float:
        """``ln(1 + rho(x) (F/F_ref)^(1/3))``."""
        x = np.nan_to_num(np.asarray(covariates.position, dtype=float)) / params['stroke']
        ratio = compliance_ratio_profile(x, params['ratio_at_start'], params['ratio_at_end'],
                                         params.get('ratio_arch', 0.0))
        contact_ratio = contact_stiffness_at(covariates.load, 1.0, params['reference_load'])
        return np.log(series_stiffness_amplification(np.maximum(ratio, 0.0) * contact_ratio, 1.0))


def draw(rng: np.random.Generator, *, youngs_modulus: float, root_diameter: float, stroke: float,
         fixed_end_offset: float, reference_load: float,
         arrangement: str | None = None) -> PositionDependentStiffnessLaw:
    """Random shaft-compliance effect: 5-30 % amplitude change over the stroke at reference_load.

    ``arrangement`` (default: drawn) is one of :data:`DRAWN_ARRANGEMENTS`:
    the fixed bearing fixed_end_offset (m) beyond the end of the stroke
    (``fixed-free``: the amplitude falls along the stroke), as far before its
    start (``free-fixed``: it rises), or both (``fixed-fixed``: an arch,
    highest mid-travel).  With the shaft compliance q(x) = 1/k_s(x) the
    amplitude factor is ``1 + k_c q(x)``; its relative change over the stroke
    ``c = k_c (q_max - q_min) / (1 + k_c q_max)`` is drawn uniformly from
    :data:`CHANGE_RANGE` and k_c solved from it.  youngs_modulus in Pa,
    root_diameter, stroke and fixed_end_offset in m, reference_load in N.
    """
    arrangement = choose(rng, DRAWN_ARRANGEMENTS, arrangement)
    change = rng.uniform(*CHANGE_RANGE)
    shape = PositionDependentStiffnessLaw(contact_stiffness=1.0, reference_load=reference_load,
                                          youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                          free_length_at_start=stroke + fixed_end_offset, arrangement=arrangement,
                                          near_length_at_start=fixed_end_offset)
    compliance = 1.0 / shape.shaft_stiffness(np.linspace(0.0, stroke, 201))
    spread, largest = float(np.ptp(compliance)), float(np.max(compliance))
    if change >= spread / largest:
        raise ConfigError(f'position_dependent_stiffness: a {change:.0%} change is impossible with '
                          f'fixed_end_offset {fixed_end_offset} m ({arrangement})')
    contact = change / (spread - change * largest)
    return PositionDependentStiffnessLaw(contact_stiffness=float(contact), reference_load=reference_load,
                                         youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                         free_length_at_start=stroke + fixed_end_offset, arrangement=arrangement,
                                         near_length_at_start=fixed_end_offset)


class Simulation(EffectSimulation):
    """The rig's contact amplitude times ``1 + k_c(F) / k_s(x)``; drawn against the actuator's shaft and the plan."""

    id = 'position_dependent_stiffness'

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> PositionDependentStiffnessLaw:
        """:func:`draw` for the actuator's shaft, the plan's stroke and its lowest load as the reference."""
        actuator = context.actuator
        return draw(rng, youngs_modulus=actuator.youngs_modulus, root_diameter=actuator.shaft_root_diameter,
                    stroke=context.stroke, fixed_end_offset=actuator.shaft_fixed_end_offset,
                    reference_load=min(context.loads))

    def amplitude_factor(self, law: PositionDependentStiffnessLaw, state: ContactState) -> np.ndarray | float:
        """``1 + k_c(F) / k_s(x)`` at the nut position and the contacts' load."""
        return law.amplitude_factor(state.nut_position, state.load)
