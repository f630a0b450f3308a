# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Does a model fit within the noise?  The classic lack-of-fit F test, at the level of runs.

Every run (traverse) of a real rig has its own amplitude factor (sensor
coupling, preload, temperature: 1-4 %), so windows are not the units of
replication: runs are.  A run's *level* is the mean of its windows' log
residuals ``ln A_model - ln A``; runs at the same (speed, load) condition are
replicates of the model's prediction.  With ``G`` runs at ``C`` conditions,
the scatter of run levels around their condition's mean is *pure error* (run
scatter, whatever its cause), and what the condition means carry beyond it is
*lack of fit*::

    SS_pe = sum_c sum_g (r_g - r_c)^2,   df_pe = G - C
    SS_lof = sum_c n_c r_c^2,            df_lof = C - parameters
    F = (SS_lof / df_lof) / (SS_pe / df_pe).

Without a repeated condition (``G = C``) there is no pure error: run scatter
and model error cannot be told apart on that plan, and :attr:`LackOfFit.testable`
says so (``reason``); the same when the model has as many parameters as there
are conditions.  Structure inside runs (a trend along the stroke) is not
tested here but by :mod:`.locate`.

Lack of fit counts as *material* only when it is significant (``p`` below
``DiagnosisRules.lof_p``) and its size, the excess RMS per run
``sqrt(max(SS_lof - df_lof MS_pe, 0) / G)``, exceeds ``DiagnosisRules.lof_tolerance``.
The window scatter inside runs is reported beside it for reference.

The pure error itself is tested too: repeated runs of one unit scatter by
what its set-up gives (1-4 % on rigs), so a scatter significantly above
``DiagnosisRules.setup_scatter`` (chi-square on ``df_pe``, ``p`` below ``DiagnosisRules.lof_p``)
is not noise but something that varies between runs and that the model
leaves out (a step in time, a cycle in revolutions).  Either finding makes the
model's misfit :attr:`LackOfFit.significant`.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy import stats

from ..estimation.calibration import condition_labels
from ..validation import finite_or_none
from .rules import DEFAULT_RULES, DiagnosisRules

if TYPE_CHECKING:
    from .table import WindowTable

__all__ = ['LackOfFit', 'REPEAT_ADVICE', 'lack_of_fit', 'run_conditions']


@dataclass
class LackOfFit:
    """Pure error (between replicate runs) and lack of fit of one model's run levels."""

    statistic: float        # F
    p_value: float
    dof_lack: float
    dof_pure: float
    pure_error_rms: float   # relative scatter of run levels around their condition (replicate runs)
    excess_rms: float       # relative size of the lack of fit per run
    residual_rms: float     # relative RMS of all window residuals
    window_scatter_rms: float = math.nan    # relative scatter of windows around their run's level
    runs: int = 0
    conditions: int = 0
    reason: str = ''        # why the test cannot be made on this plan ('' when it can)
    scatter_p: float = math.nan     # p of the pure error being no larger than rules.setup_scatter (chi-square)
    rules: DiagnosisRules = DEFAULT_RULES   # the thresholds the test is judged by

    @property
    def testable(self) -> bool:
        """Whether the plan has pure error and lack-of-fit degrees of freedom."""
        return not self.reason

    @property
    def lack_of_fit(self) -> bool:
        """The condition means miss the model: significant and material (see module doc)."""
        return self.testable and self.p_value < self.rules.lof_p and self.excess_rms > self.rules.lof_tolerance

    @property
    def excess_scatter(self) -> bool:
        """Repeated runs scatter significantly more than a rig's set-up makes them."""
        return self.scatter_p < self.rules.lof_p

    @property
    def significant(self) -> bool:
        """The model misses: lack of fit, or run scatter beyond set-up scatter (see module doc)."""
        return self.lack_of_fit or self.excess_scatter

    @property
    def finding(self) -> str:
        """What the test found, in words ('' when the model fits within the noise or cannot be tested)."""
        words = []
        if self.lack_of_fit:
            words.append(f'the model misses the condition means by {100 * self.excess_rms:.1f} % RMS per run '
                         f'beyond the {100 * self.pure_error_rms:.1f} % scatter of repeated runs (lack of fit '
                         f'F = {self.statistic:.3g}, p = {self.p_value:.2g})')
        if self.excess_scatter:
            words.append(f'repeated runs of one condition scatter by {100 * self.pure_error_rms:.1f} %, beyond the '
                         f'{100 * self.rules.setup_scatter:.0f} % a rig\'s set-up gives '
                         f'(chi-square p = {self.scatter_p:.2g}): '
                         'something that varies between runs is not in the model')
        return '; '.join(words)

    @property
    def sentence(self) -> str:
        """The test in one sentence for the command line and the report."""
        if not self.testable:
            return f'not testable: {self.reason}'
        scatter = (f'; window scatter inside runs {100 * self.window_scatter_rms:.1f} %'
                   if math.isfinite(self.window_scatter_rms) else '')
        return (f'{self.finding or "within the noise"} (condition means against the {100 * self.pure_error_rms:.1f} % '
                f'scatter of {self.runs} runs at {self.conditions} conditions: F = {self.statistic:.3g}, '
                f'p = {self.p_value:.2g}{scatter})')

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'test': 'lack-of-fit F (condition means against replicate runs)', 'testable': self.testable,
                'reason': self.reason, 'runs': self.runs, 'conditions': self.conditions,
                'f': finite_or_none(self.statistic), 'p_value': finite_or_none(self.p_value),
                'dof_lack_of_fit': finite_or_none(self.dof_lack), 'dof_pure_error': finite_or_none(self.dof_pure),
                'pure_error_rms': finite_or_none(self.pure_error_rms),
                'lack_of_fit_rms': finite_or_none(self.excess_rms),
                'window_scatter_rms': finite_or_none(self.window_scatter_rms),
                'residual_rms': finite_or_none(self.residual_rms), 'lack_of_fit': self.lack_of_fit,
                'scatter_p_value': finite_or_none(self.scatter_p), 'excess_scatter': self.excess_scatter,
                'setup_scatter_limit': self.rules.setup_scatter, 'significant': self.significant}


def run_conditions(table: WindowTable) -> np.ndarray:
    """Condition index of each run (in :attr:`WindowTable.runs` order): its (speed level, load level) pair."""
    return condition_labels(table.run_means('speed'), table.run_means('load'))


REPEAT_ADVICE = 'record each (speed, load) condition in two runs or more'


def lack_of_fit(table: WindowTable, log_residual: npt.ArrayLike, n_params: int,
                rules: DiagnosisRules = DEFAULT_RULES) -> LackOfFit:
    """The lack-of-fit test of a model with ``n_params`` fitted parameters (see module doc), judged by ``rules``."""
    residual = np.asarray(log_residual, dtype=float)
    n = residual.size
    residual_rms = math.sqrt(float(residual @ residual) / n)
    levels = table.run_means(residual)
    _, index = np.unique(table.run, return_inverse=True)
    within = residual - levels[index]
    groups = levels.size
    window_scatter = math.sqrt(float(within @ within) / (n - groups)) if n > groups else math.nan
    condition = run_conditions(table)
    conditions = int(condition.max()) + 1
    dof_pure, dof_lack = groups - conditions, conditions - n_params
    counts = np.bincount(condition, minlength=conditions)
    means = np.bincount(condition, weights=levels, minlength=conditions) / counts
    ss_pe = float(np.sum((levels - means[condition]) ** 2))
    scatter_p = float(stats.chi2.sf(ss_pe / rules.setup_scatter ** 2, dof_pure)) if dof_pure > 0 else math.nan
    reason = ''
    if dof_pure <= 0:
        reason = (f'no condition repeated ({groups} runs at {conditions} conditions): run-to-run scatter and '
                  f'model error cannot be told apart; {REPEAT_ADVICE}')
    elif dof_lack <= 0:
        reason = (f'{conditions} conditions for {n_params} parameters leave no degree of freedom to test the '
                  'model\'s form; record more (speed, load) conditions')
    elif ss_pe <= 0:
        reason = 'the repeated runs agree exactly: no pure error to test against'
    if reason:
        pure = math.sqrt(ss_pe / dof_pure) if dof_pure > 0 else math.nan
        return LackOfFit(math.nan, math.nan, dof_lack, dof_pure, pure, math.nan, residual_rms, window_scatter,
                         groups, conditions, reason, scatter_p, rules)
    ms_pe = ss_pe / dof_pure
    ss_lof = float(np.sum(counts * means ** 2))
    f = (ss_lof / dof_lack) / ms_pe
    p = float(stats.f.sf(f, dof_lack, dof_pure))
    excess = math.sqrt(max(ss_lof - dof_lack * ms_pe, 0.0) / groups)
    return LackOfFit(f, p, dof_lack, dof_pure, math.sqrt(ms_pe), excess, residual_rms, window_scatter,
                     groups, conditions, scatter_p=scatter_p, rules=rules)
