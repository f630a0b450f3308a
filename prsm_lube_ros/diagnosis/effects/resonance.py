# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit a resonance (the law: :mod:`prsm_lube_ros.physics.effects.resonance`).

``A = A_22 |H(r)|`` with ``r = omega_S / omega_r``.  Only the screw speed at
which the excitation meets the mode, ``omega_r = 2 pi f_r / n`` (rad/s), can
be identified from RMS values, not the order n and f_r separately.
Parameters: omega_r (rad/s) and the damping ratio zeta; internally r at the
highest speed recorded.
"""
from __future__ import annotations

import numpy as np

from ...physics.effects import resonance as law
from .base import Effect, register

#: Bounds of the frequency ratio at the highest recorded speed.
TOP_RATIO_RANGE = (0.05, 3.0)
#: Bounds of the damping ratio.
DAMPING_RANGE = (0.005, 0.5)


@register
class Resonance(Effect, law.Extension):
    """The excitation frequency approaches a structural mode; amplitude departs from the omega^2 law."""

    id = 'resonance'
    title = 'structural resonance'
    physics = ('A rotation-order excitation approaches a lightly damped natural frequency of the structure, so '
               'the quasi-static step X0 = F0/K0 (Eq. 14) no longer holds: the response is magnified by |H(r)| '
               'and the amplitude rises faster with speed than the omega^2 law of Eq. 22.')
    equations = 'A = A_22 / sqrt((1 - r^2)^2 + (2 zeta r)^2), r = omega_S / omega_r'
    parameter_names = ('top_ratio', 'damping_ratio')
    covariate = 'speed'
    to_separate = 'more screw speeds (at least 4, up to the highest the actuator runs) at each load'

    def applicable(self, table) -> str:
        """Needs three speed levels at least (the shape of A against speed)."""
        from ...estimation.calibration import operating_levels
        levels = operating_levels(table.speed)
        if len(levels) < 3:
            return f'{len(levels)} screw speed(s) recorded: a resonance needs 3 or more to show its shape'
        return ''

    def scales(self, table) -> dict:
        """The highest recorded screw speed, rad/s."""
        return {'top_speed': float(np.max(np.abs(table.speed)))}

    def bounds(self):
        """top_ratio and damping_ratio ranges."""
        return (np.array([TOP_RATIO_RANGE[0], DAMPING_RANGE[0]]),
                np.array([TOP_RATIO_RANGE[1], DAMPING_RANGE[1]]))

    def starts(self):
        """A grid of frequency ratios below and above resonance."""
        return [np.array([r, z]) for r in (0.4, 0.6, 0.75, 0.85, 0.93, 1.3) for z in (0.03, 0.1)]

    def to_params(self, p, scales):
        """resonant_speed (rad/s), damping_ratio and top_speed."""
        return {'resonant_speed': float(scales['top_speed'] / p[0]), 'damping_ratio': float(p[1]), **scales}

    def describe(self, params):
        """Where the resonance lies and how much it magnifies the top speed."""
        top = params['top_speed'] / params['resonant_speed']
        gain = float(law.magnification(top, params['damping_ratio']))
        return (f'The excitation meets a mode at a screw speed of {params["resonant_speed"]:.1f} rad/s '
                f'({params["resonant_speed"] * 30 / np.pi:.0f} r/min), damping ratio '
                f'{params["damping_ratio"]:.3f}; at the top speed r = {top:.2f} and the response is magnified '
                f'x{gain:.2f}. ' + self.physics)
