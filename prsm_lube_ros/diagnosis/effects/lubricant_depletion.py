# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit lubricant depletion (the law: :mod:`prsm_lube_ros.physics.effects.lubricant_depletion`).

N_rev counts screw revolutions since the start of each recording (taken as
the last lubrication).  Parameter: the depletion rate 1/N_d per revolution;
internally ``N_max / N_d`` with N_max the most revolutions in one recording.

In assessment the fall of theta is real (it is what theta_Oil measures), so
this extension corrects the constants, not theta: its assessment film factor is 1.
"""
from __future__ import annotations

import numpy as np

from ...physics.effects import lubricant_depletion as law
from .base import Effect, register

#: Bounds of N_max / N_d (theta falls by 1 - exp(-x) over the longest recording).
RATE_RANGE = (0.0, 3.0)


@register
class LubricantDepletion(Effect, law.Extension):
    """theta_Oil falls with revolutions run since the last lubrication."""

    id = 'lubricant_depletion'
    title = 'lubricant depletion'
    physics = ('Oil is flung out of the thread contacts as the screw turns, so the effective theta_Oil falls '
               'with the revolutions run since the last lubrication and the amplitude rises through the session.')
    equations = 'theta_eff = theta_Oil exp(-N_rev / N_d)'
    parameter_names = ('depletion_fraction',)
    covariate = 'revolutions'
    to_separate = ('runs in random order of speed and load, repeated conditions early and late in the session, '
                   'and a temperature record')

    def applicable(self, table) -> str:
        """Needs revolutions that grow through the recordings."""
        finite = np.isfinite(table.revolutions)
        if finite.mean() < 0.8:
            return 'revolutions are not known (no screw angle in joint_states)'
        if np.ptp(table.revolutions[finite]) < 1.0:
            return 'the screw turns less than one revolution over the recordings'
        return ''

    def scales(self, table) -> dict:
        """Most revolutions in the recordings."""
        return {'revolution_scale': float(max(np.nanmax(table.revolutions), 1.0))}

    def bounds(self):
        """N_max / N_d in :data:`RATE_RANGE`."""
        return np.array([RATE_RANGE[0]]), np.array([RATE_RANGE[1]])

    def starts(self):
        """Small, medium and large falls."""
        return [np.array([0.05]), np.array([0.2]), np.array([0.6])]

    def to_params(self, p, scales):
        """depletion_per_revolution (1/N_d) and the revolution scale."""
        return {'depletion_per_revolution': float(p[0] / scales['revolution_scale']), **scales}

    def describe(self, params):
        """N_d and the fall of theta over the longest recording."""
        rate = params['depletion_per_revolution']
        fall = 1 - np.exp(-rate * params['revolution_scale'])
        n_d = f'{1 / rate:.3g} revolutions' if rate > 0 else 'infinite'
        return (f'theta_Oil decays with N_d = {n_d}: it falls by {100 * fall:.1f} % over '
                f'{params["revolution_scale"]:.0f} revolutions. ' + self.physics)
