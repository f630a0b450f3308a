# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How to fit lubricant depletion (the law: :mod:`prsm_lube_ros.physics.effects.lubricant_depletion`).

N_rev counts screw revolutions since the start of each recording (taken as
the last lubrication).  Forms, each fitted: the supply falls exponentially
(``exp(-N/N_d)``) or linearly (``1 - N/N_d``) in revolutions, each with or
without partial recovery at rest (``N_eff <- N_eff exp(-t_rest / tau_r)`` over
each standstill, rests read from the gaps between windows).  Parameters: the
depletion rate 1/N_d per revolution, internally ``N_max / N_d`` with N_max
the most revolutions in one recording; the recovery rate 1/tau_r, internally
``t_typ / tau_r`` with t_typ the median rest between runs.  A recovering form
is chosen only when the data show the recovery (the engine's form margin).

In assessment the fall of theta is real (it is what theta_Oil measures), so
this extension corrects the constants, not theta: its assessment film factor is 1.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...physics.effects import lubricant_depletion as law
from .base import Effect, register

if TYPE_CHECKING:
    from ..table import WindowTable

__all__ = ['LINEAR_RATE_RANGE', 'LinearDepletionCandidate', 'LubricantDepletionCandidate', 'MIN_RESTS', 'RATE_RANGE',
           'RECOVERY_RANGE', 'RecoveringDepletionCandidate', 'RecoveringLinearDepletionCandidate']

#: Bounds of N_max / N_d (exponential: theta falls by 1 - exp(-x) over the longest recording).
RATE_RANGE = (0.0, 3.0)
#: Bounds of N_max / N_d for the linear form (theta stays above the law's floor).
LINEAR_RATE_RANGE = (0.0, 0.95)
#: Bounds of t_typ / tau_r (0: no recovery; 5: nearly full recovery over a typical rest).
RECOVERY_RANGE = (0.0, 5.0)
#: Rests (gaps between runs) needed to fit a recovery.
MIN_RESTS = 3


@register
class LubricantDepletionCandidate(Effect, law.Extension):
    """theta_Oil falls with revolutions run since the last lubrication (exponential form)."""

    id = 'lubricant_depletion'
    title = 'lubricant depletion'
    form = 'exponential in revolutions'
    physics = ('Oil is flung out of the thread contacts as the screw turns, so the effective theta_Oil falls '
               'with the revolutions run since the last lubrication and the amplitude rises through the session.')
    equations = 'theta_eff = theta_Oil exp(-N_rev / N_d)'
    parameter_names: tuple[str, ...] = ('depletion_fraction',)
    covariate = 'revolutions'
    to_separate = ('runs in random order of speed and load, repeated conditions early and late in the session, '
                   'and a temperature record')
    linear = False
    recovers = False

    def applicable(self, table: WindowTable) -> str:
        """Needs revolutions that grow through the recordings (and rests between runs to fit a recovery)."""
        finite = np.isfinite(table.revolutions)
        if finite.mean() < 0.8:
            return 'revolutions are not known (no screw angle in joint_states)'
        if np.ptp(table.revolutions[finite]) < 1.0:
            return 'the screw turns less than one revolution over the recordings'
        if self.recovers and np.count_nonzero(self._rests(table) > 0) < MIN_RESTS:
            return f'fewer than {MIN_RESTS} rests between runs: a recovery at rest cannot show'
        return ''

    @staticmethod
    def _rests(table: WindowTable) -> np.ndarray:
        return law.rest_durations(table.revolutions, table.time, table.speed, table.recording)

    def scales(self, table: WindowTable) -> dict[str, float]:
        """Most revolutions in the recordings (and, for recovery, the median rest, s)."""
        out = {'revolution_scale': float(max(np.nanmax(table.revolutions), 1.0))}
        if self.recovers:
            rests = self._rests(table)
            out['rest_scale'] = float(np.median(rests[rests > 0])) if np.any(rests > 0) else 1.0
        return out

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """N_max / N_d (and t_typ / tau_r) in their ranges."""
        rate = LINEAR_RATE_RANGE if self.linear else RATE_RANGE
        if self.recovers:
            return np.array([rate[0], RECOVERY_RANGE[0]]), np.array([rate[1], RECOVERY_RANGE[1]])
        return np.array([rate[0]]), np.array([rate[1]])

    def starts(self) -> list[np.ndarray]:
        """Small, medium and large falls (each with slow and fast recovery)."""
        falls = (0.05, 0.2, 0.6) if not self.linear else (0.05, 0.2, 0.5)
        if self.recovers:
            return [np.array([f, r]) for f in falls for r in (0.3, 1.5)]
        return [np.array([f]) for f in falls]

    def to_params(self, p: np.ndarray, scales: dict[str, float]) -> dict[str, float]:
        """depletion_per_revolution (1/N_d), ``linear`` (1 or 0), recovery_rate (1/s) and the scales."""
        out = {'depletion_per_revolution': float(p[0] / scales['revolution_scale']),
               'linear': 1.0 if self.linear else 0.0, **scales}
        if self.recovers:
            out['recovery_rate'] = float(p[1] / scales['rest_scale'])
        return out

    def variants(self) -> list[Effect]:
        """Exponential and linear, each without and with recovery at rest."""
        return [self, LinearDepletionCandidate(), RecoveringDepletionCandidate(), RecoveringLinearDepletionCandidate()]

    def describe(self, params: dict[str, float]) -> str:
        """N_d, the fall of theta over the longest recording and the recovery."""
        rate = params['depletion_per_revolution']
        form = 'linear' if params.get('linear') else 'exponential'
        fall = 1 - float(law.theta_factor(params['revolution_scale'], rate, form))
        n_d = f'{1 / rate:.3g} revolutions' if rate > 0 else 'infinite'
        text = (f'theta_Oil falls {form}ly in revolutions with N_d = {n_d}: by {100 * fall:.1f} % over '
                f'{params["revolution_scale"]:.0f} revolutions')
        recovery = params.get('recovery_rate', 0.0)
        if recovery > 0:
            share = 1 - np.exp(-recovery * params['rest_scale'])
            text += (f'; at rest the loss recovers with tau_r = {1 / recovery:.3g} s ({100 * share:.0f} % of it '
                     f'over a typical {params["rest_scale"]:.0f} s rest)')
        return text + '. ' + self.physics


class LinearDepletionCandidate(LubricantDepletionCandidate):
    """A fixed amount of oil lost per revolution: ``theta_eff = theta_Oil (1 - N_rev / N_d)``."""

    form = 'linear in revolutions'
    equations = 'theta_eff = theta_Oil (1 - N_rev / N_d)'
    linear = True

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]


class RecoveringDepletionCandidate(LubricantDepletionCandidate):
    """Exponential loss, partly recovered at rest."""

    form = 'exponential in revolutions, partial recovery at rest'
    equations = 'theta_eff = theta_Oil exp(-N_eff / N_d), N_eff <- N_eff exp(-t_rest / tau_r) at each rest'
    parameter_names = ('depletion_fraction', 'recovery_fraction')
    recovers = True

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]


class RecoveringLinearDepletionCandidate(LubricantDepletionCandidate):
    """Linear loss, partly recovered at rest."""

    form = 'linear in revolutions, partial recovery at rest'
    equations = 'theta_eff = theta_Oil (1 - N_eff / N_d), N_eff <- N_eff exp(-t_rest / tau_r) at each rest'
    parameter_names = ('depletion_fraction', 'recovery_fraction')
    linear = True
    recovers = True

    def variants(self) -> list[Effect]:
        """Only itself."""
        return [self]
