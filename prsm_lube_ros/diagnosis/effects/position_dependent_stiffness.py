# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Screw shaft axial stiffness in series with the thread contacts, changing with nut position.

Physics: the load path from nut to frame runs through the Hertzian thread
contacts (stiffness ``k_c = k_delta F^(1/3)``, Eq. 17) and, in series, the
screw shaft between the nut and the axially fixed bearing, ``k_s = E A / L(x)``
with ``L`` the free shaft length.  The series stiffness
``K = k_c k_s / (k_c + k_s)`` replaces K_0 in Eq. 14, so

    X_0 = F_0 / K = (F_0 / k_c) (1 + k_c / k_s(x)).

The shaft compliance ``L(x) / (E A)`` is linear in nut position x, and
``k_c ~ F^(1/3)``, so with ``rho = k_c / k_s`` at the reference load:

    A = A_22 (1 + rho(x) (F / F_ref)^(1/3)),  rho(x) = rho_0 + (rho_1 - rho_0) x / stroke

Parameters: rho_0 and rho_1, the contact-to-shaft stiffness ratio at the start
and the end of the stroke (>= 0).  A fixed bearing beyond the far end gives
rho_1 < rho_0 (amplitude falls along the stroke, as in the paper's Fig. 4),
one at the near end rho_1 > rho_0; the bearing's distance from the start of the
stroke is ``stroke rho_0 / (rho_0 - rho_1)``.  That is the fixed-free (and
fixed-supported) arrangement.

A shaft held axially at both ends (fixed-fixed) has ``k_s = E A (1/a + 1/b)``
with a, b the free lengths on each side of the nut: the compliance is an arch,
largest mid-travel, and the law adds ``4 rho_arch u (1 - u)`` (u = x / stroke)
to rho (see the law module).  Both forms are fitted
(:meth:`PositionDependentStiffness.variants`); the engine keeps the one with the
lower BIC, so the fit chooses the arrangement.
"""
from __future__ import annotations

import numpy as np

from ...physics.effects import position_dependent_stiffness as law
from .base import Effect, register

#: Bounds of the stiffness ratio k_c / k_s.
RATIO_RANGE = (0.0, 3.0)


@register
class PositionDependentStiffness(Effect, law.Extension):
    """Series shaft compliance that changes as the nut travels (amplitude trends with nut position)."""

    id = 'position_dependent_stiffness'
    title = 'position-dependent shaft stiffness'
    physics = ('The screw shaft between nut and fixed bearing is a spring in series with the thread contacts; '
               'its stiffness EA/L changes as the nut travels, so the vibration amplitude trends with nut '
               'position inside every run.')
    equations = ('A = A_22 (1 + rho(x) (F/F_ref)^(1/3)), rho(x) = rho_0 + (rho_1 - rho_0) x / stroke, '
                 'rho = k_c / k_s = k_delta F^(1/3) L(x) / (E A)')
    parameter_names = ('ratio_at_start', 'ratio_at_end')
    covariate = 'position'
    to_separate = 'full-stroke runs in both directions, so nut position is not tied to time or revolutions'

    def applicable(self, table) -> str:
        """Needs nut positions that span part of the stroke inside runs."""
        finite = np.isfinite(table.position)
        if finite.mean() < 0.8:
            return 'nut position is not known (no screw angle in joint_states)'
        span = np.ptp(table.position[finite]) if finite.any() else 0.0
        if span < 1e-3:
            return f'the nut moves {span * 1e3:.2f} mm at most in steady windows'
        return ''

    def scales(self, table) -> dict:
        """Reference load (median) and stroke (largest steady position)."""
        finite = np.isfinite(table.position)
        return {'reference_load': float(np.median(table.load)),
                'stroke': float(max(np.max(table.position[finite]), 1e-3))}

    def bounds(self):
        """Both ratios in :data:`RATIO_RANGE`."""
        return np.full(2, RATIO_RANGE[0]), np.full(2, RATIO_RANGE[1])

    def starts(self):
        """Falling, rising and flat compliance."""
        return [np.array([0.2, 0.05]), np.array([0.05, 0.2]), np.array([0.5, 0.1]), np.array([0.1, 0.5])]

    def to_params(self, p, scales):
        """ratio_at_start, ratio_at_end with reference_load (N) and stroke (m)."""
        return {'ratio_at_start': float(p[0]), 'ratio_at_end': float(p[1]), **scales}

    def describe(self, params):
        """Amplitude change along the stroke and where the fixed bearing would be."""
        a, b = params['ratio_at_start'], params['ratio_at_end']
        change = (1 + b) / (1 + a) - 1
        where = ''
        if a > b and a > 0:
            where = f'; fixed bearing about {params["stroke"] * a / (a - b) * 1e3:.0f} mm from the stroke start'
        elif b > a and b > 0:
            where = (f'; fixed bearing about {params["stroke"] * a / (b - a) * 1e3:.0f} mm before the '
                     'stroke start')
        return (f'Bearing arrangement fixed-free or fixed-supported: contact-to-shaft stiffness ratio k_c/k_s '
                f'{a:.3g} at the stroke start and {b:.3g} at its end '
                f'(at {params["reference_load"]:.0f} N): the amplitude changes by {100 * change:+.1f} % '
                f'along the {params["stroke"] * 1e3:.0f} mm stroke{where}. ' + self.physics)

    def variants(self):
        """The linear (fixed-free, fixed-supported) and the arched (fixed-fixed) compliance."""
        return [self, FixedFixedStiffness()]


class FixedFixedStiffness(PositionDependentStiffness):
    """The shaft held axially at both ends: compliance ``a b / (E A (a + b))``, an arch along the stroke."""

    equations = ('A = A_22 (1 + rho(x) (F/F_ref)^(1/3)), rho(u) = rho_0 (1 - u) + rho_1 u + 4 rho_arch u (1 - u), '
                 'u = x / stroke; fixed-fixed: k_s = E A (1/a + 1/b), a, b the free lengths either side of the nut')
    parameter_names = ('ratio_at_start', 'ratio_at_end', 'ratio_arch')

    def bounds(self):
        """All three ratios in :data:`RATIO_RANGE`."""
        return np.full(3, RATIO_RANGE[0]), np.full(3, RATIO_RANGE[1])

    def starts(self):
        """Arches of several heights over flat, falling and rising ends."""
        return [np.array([0.05, 0.05, 0.1]), np.array([0.1, 0.1, 0.3]), np.array([0.2, 0.05, 0.1]),
                np.array([0.05, 0.2, 0.1])]

    def to_params(self, p, scales):
        """ratio_at_start, ratio_at_end, ratio_arch with reference_load (N) and stroke (m)."""
        return {'ratio_at_start': float(p[0]), 'ratio_at_end': float(p[1]), 'ratio_arch': float(p[2]), **scales}

    def variants(self):
        """Only itself."""
        return [self]

    def describe(self, params):
        """Amplitude mid-travel against the ends."""
        a, b, c = params['ratio_at_start'], params['ratio_at_end'], params['ratio_arch']
        mid = 0.5 * (a + b) + c
        rise = (1 + mid) / (1 + max(a, b)) - 1
        return (f'Bearing arrangement fixed-fixed: contact-to-shaft stiffness ratio k_c/k_s {a:.3g} at the '
                f'stroke start, {mid:.3g} mid-travel and {b:.3g} at its end (at {params["reference_load"]:.0f} N): '
                f'the amplitude is {100 * rise:+.1f} % higher mid-travel than at the ends of the '
                f'{params["stroke"] * 1e3:.0f} mm stroke, where the shaft, held at both ends, is softest. '
                + self.physics)
