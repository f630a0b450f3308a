# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Screw shaft axial stiffness in series with the thread contacts, changing with nut position.

Physics: the load path from nut to frame runs through the Hertzian thread
contacts (stiffness ``k_c = k_delta F^(1/3)``, Eq. 17) and, in series, the
screw shaft between the nut and the axially fixed bearing(s).  The series
stiffness ``K = k_c k_s / (k_c + k_s)`` replaces K_0 in Eq. 14, so

    X_0 = F_0 / K = (F_0 / k_c) (1 + k_c / k_s(x)),
    A = A_22 (1 + rho(x) (F / F_ref)^(1/3)),  rho = k_c / k_s at F_ref.

The shaft stiffness is E A over the free lengths either side of the nut,
``a = x + o_1`` (to a bearing o_1 before the stroke start) and
``b = s + o_2 - x`` (to a bearing o_2 beyond its end, stroke s).  Each bearing
arrangement used on roller screws is a form, fitted with the physical
parameters ``c s = k_c s / (E A)`` (dimensionless) and the bearing offsets
over the stroke:

* fixed-free (or fixed-supported: the support bearing carries no axial load),
  the fixed bearing beyond the far end: ``k_s = E A / b``, rho falls linearly
  along the stroke (the paper's Fig. 4); parameters c s, o_2 / s;
* the same with the fixed bearing before the stroke start: ``k_s = E A / a``,
  rho rises along the stroke; parameters c s, o_1 / s;
* fixed-fixed: both segments in parallel, ``k_s = E A (1/a + 1/b)``, rho an
  arch largest mid-travel (skewed when o_1 != o_2); parameters c s, o_1 / s,
  o_2 / s.

The law module turns each into ``rho(u) = rho_0 (1 - u) + rho_1 u + 4 rho_arch u (1 - u)``
(:func:`~prsm_lube_ros.physics.effects.position_dependent_stiffness.arrangement_ratios`),
which is what a calibration stores.  The engine chooses the arrangement by BIC.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...physics.effects import position_dependent_stiffness as law
from .base import Effect, register

if TYPE_CHECKING:
    from ..table import WindowTable

__all__ = ['FixedBeforeStartStiffnessCandidate', 'FixedFixedStiffnessCandidate', 'OFFSET_RANGE',
           'PositionDependentStiffnessCandidate', 'SCALE_RANGE']

#: Bounds of c s = k_c s / (E A), the contact-to-shaft stiffness ratio over one stroke length of shaft.
SCALE_RANGE = (0.0, 5.0)
#: Bounds of a bearing offset over the stroke (bearing to the nearest end of travel).
OFFSET_RANGE = (0.0, 5.0)


@register
class PositionDependentStiffnessCandidate(Effect, law.Extension):
    """Series shaft compliance that changes as the nut travels; the fixed bearing beyond the far end."""

    id = 'position_dependent_stiffness'
    title = 'position-dependent shaft stiffness'
    form = 'fixed-free, fixed bearing beyond the stroke end'
    arrangement = 'fixed-free'
    physics = ('The screw shaft between nut and axially fixed bearing is a spring in series with the thread '
               'contacts; its stiffness EA over the free length changes as the nut travels, so the vibration '
               'amplitude changes with nut position inside every run.')
    equations = ('A = A_22 (1 + rho(x) (F/F_ref)^(1/3)), rho = k_c / k_s, fixed-free: k_s = E A / b, '
                 'b = s + o_2 - x the free length to the fixed bearing beyond the stroke end')
    parameter_names: tuple[str, ...] = ('contact_over_shaft', 'bearing_after_over_stroke')
    covariate = 'position'
    to_separate = 'full-stroke runs in both directions, so nut position is not tied to time or revolutions'

    def applicable(self, table: WindowTable) -> str:
        """Needs nut positions that span part of the stroke inside runs."""
        finite = np.isfinite(table.position)
        if finite.mean() < 0.8:
            return 'nut position is not known (no screw angle in joint_states)'
        span = np.ptp(table.position[finite]) if finite.any() else 0.0
        if span < 1e-3:
            return f'the nut moves {span * 1e3:.2f} mm at most in steady windows'
        return ''

    def scales(self, table: WindowTable) -> dict[str, float]:
        """Reference load (median) and stroke (largest steady position)."""
        finite = np.isfinite(table.position)
        return {'reference_load': float(np.median(table.load)),
                'stroke': float(max(np.max(table.position[finite]), 1e-3))}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """c s and the offset(s) in their ranges."""
        offsets = len(self.parameter_names) - 1
        return (np.r_[SCALE_RANGE[0], np.full(offsets, OFFSET_RANGE[0])],
                np.r_[SCALE_RANGE[1], np.full(offsets, OFFSET_RANGE[1])])

    def starts(self) -> list[np.ndarray]:
        """Weak and strong compliance, bearings near and far."""
        return [np.array([c, o]) for c in (0.2, 1.0) for o in (0.1, 0.5)]

    def _offsets(self, p: np.ndarray) -> tuple[float, float]:
        """(o_1 / s, o_2 / s) from the internal vector."""
        return 0.0, float(p[1])

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """The profile's ratios (what the law reads) and the physical parameters.

        contact_over_ea k_c / (E A) in 1/m, bearing_before / bearing_after in m
        (the offset of the end that carries no axial load is left out), with
        reference_load (N) and stroke (m).
        """
        stroke = scales['stroke']
        before, after = self._offsets(p)
        contact_over_ea = float(p[0]) / stroke
        ratios = law.arrangement_ratios(self.arrangement, contact_over_ea, stroke, before * stroke, after * stroke)
        out = {'ratio_at_start': float(ratios[0]), 'ratio_at_end': float(ratios[1]),
               'contact_over_ea': contact_over_ea, **scales}
        if self.arrangement == 'fixed-fixed':
            out['ratio_arch'] = float(ratios[2])
        if self.arrangement in ('fixed-fixed',) + law.FIXED_BEFORE_START:
            out['bearing_before'] = before * stroke
        if self.arrangement in ('fixed-fixed', 'fixed-free'):
            out['bearing_after'] = after * stroke
        return out

    def variants(self) -> list[Effect]:
        """Fixed bearing beyond the far end, before the start, and both ends fixed."""
        return [self, FixedBeforeStartStiffnessCandidate(), FixedFixedStiffnessCandidate()]

    def describe(self, params: dict[str, float]) -> str:
        """Arrangement, amplitude change along the stroke and where the bearing(s) would be."""
        a, b = params['ratio_at_start'], params['ratio_at_end']
        change = (1 + b) / (1 + a) - 1
        where = ', '.join(f'{name} {1e3 * params[key]:.0f} mm {side}'
                          for key, name, side in (('bearing_before', 'bearing', 'before the stroke start'),
                                                  ('bearing_after', 'bearing', 'beyond the stroke end'))
                          if key in params)
        return (f'Bearing arrangement {self.form} (fixed-supported has the same axial stiffness): {where}; '
                f'contact-to-shaft stiffness ratio k_c/k_s {a:.3g} at the stroke start and {b:.3g} at its end '
                f'(at {params["reference_load"]:.0f} N): the amplitude changes by {100 * change:+.1f} % along the '
                f'{params["stroke"] * 1e3:.0f} mm stroke. ' + self.physics)


class FixedBeforeStartStiffnessCandidate(PositionDependentStiffnessCandidate):
    """The axially fixed bearing before the stroke start: compliance grows as the nut travels away from it."""

    form = 'fixed-free, fixed bearing before the stroke start'
    arrangement = 'free-fixed'
    equations = ('A = A_22 (1 + rho(x) (F/F_ref)^(1/3)), rho = k_c / k_s, k_s = E A / a, a = x + o_1 the free '
                 'length to the fixed bearing before the stroke start')
    parameter_names = ('contact_over_shaft', 'bearing_before_over_stroke')

    def _offsets(self, p: np.ndarray) -> tuple[float, float]:
        return float(p[1]), 0.0

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]


class FixedFixedStiffnessCandidate(PositionDependentStiffnessCandidate):
    """The shaft held axially at both ends: compliance ``a b / (E A (a + b))``, an arch along the stroke."""

    form = 'fixed-fixed'
    arrangement = 'fixed-fixed'
    equations = ('A = A_22 (1 + rho(x) (F/F_ref)^(1/3)), fixed-fixed: k_s = E A (1/a + 1/b), a = x + o_1 and '
                 'b = s + o_2 - x the free lengths either side of the nut')
    parameter_names = ('contact_over_shaft', 'bearing_before_over_stroke', 'bearing_after_over_stroke')

    def starts(self) -> list[np.ndarray]:
        """Arches of several heights, symmetric and skewed."""
        return [np.array([c, o1, o2]) for c in (0.5, 2.0) for o1, o2 in ((0.1, 0.1), (0.05, 0.5), (0.5, 0.05))]

    def _offsets(self, p: np.ndarray) -> tuple[float, float]:
        return float(p[1]), float(p[2])

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]

    def describe(self, params: dict[str, float]) -> str:
        """Amplitude mid-travel against the ends."""
        a, b, c = params['ratio_at_start'], params['ratio_at_end'], params['ratio_arch']
        mid = 0.5 * (a + b) + c
        rise = (1 + mid) / (1 + max(a, b)) - 1
        return (f'Bearing arrangement fixed-fixed, bearings {1e3 * params["bearing_before"]:.0f} mm before the '
                f'stroke start and {1e3 * params["bearing_after"]:.0f} mm beyond its end: contact-to-shaft '
                f'stiffness ratio k_c/k_s {a:.3g} at the stroke start, {mid:.3g} mid-travel and {b:.3g} at its end '
                f'(at {params["reference_load"]:.0f} N): the amplitude is {100 * rise:+.1f} % higher mid-travel '
                f'than at the ends of the {params["stroke"] * 1e3:.0f} mm stroke, where the shaft, held at both '
                'ends, is softest. ' + self.physics)
