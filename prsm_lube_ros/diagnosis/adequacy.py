# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Does a model fit within the noise?  A lack-of-fit F test with replicates inside runs.

Windows of one run share speed and load, so they are replicates of the model's
prediction up to whatever drifts slowly inside the run.  Per run the log
residual ``ln A_model - ln A`` is fitted by a smooth trend (a quadratic in the
window's place in the run, fewer terms in short runs); the scatter around those
trends is *pure error* (window noise), with ``n - sum(terms per run)`` degrees
of freedom.  What the per-run trends carry beyond the model is *lack of fit*:

    SS_lof = SS_residual - SS_pe,   df_lof = sum(terms per run) - model parameters,
    F = (SS_lof / df_lof) / (SS_pe / df_pe).

The lack-of-fit degrees of freedom are counted in runs (three per run), not in
windows: windows of one run are correlated through the run's trend, and the
test asks whether the run trends agree with the model.  With hundreds of
windows any set-up scatter between runs (mounting, sensor coupling) makes
``p`` tiny although the model is fine, so lack of fit counts as *material*
only when also its size, the excess RMS per window
``sqrt(max(SS_lof - df_lof MS_pe, 0) / n)``, exceeds :data:`LOF_TOLERANCE` and
half the pure-error RMS: the model then misses by more than the set-up scatter
and a good fraction of the window scatter.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np
from scipy import stats

#: p-value below which lack of fit is significant.
LOF_P = 1e-3
#: Smallest relative excess RMS that counts as a material lack of fit.
LOF_TOLERANCE = 0.01
#: Terms of the smooth within-run trend (quadratic).
TREND_TERMS = 3


@dataclass
class LackOfFit:
    """Pure error and lack of fit of one model's log residuals."""

    statistic: float        # F
    p_value: float
    dof_lack: float
    dof_pure: float
    pure_error_rms: float   # relative window scatter around the run trends
    excess_rms: float       # relative size of the lack of fit per window
    residual_rms: float     # relative RMS of all residuals

    @property
    def significant(self) -> bool:
        """Significant and material (see module doc)."""
        return (self.p_value < LOF_P
                and self.excess_rms > max(LOF_TOLERANCE, 0.5 * self.pure_error_rms))

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'test': 'lack-of-fit F (pure error within runs, run-clustered dof)',
                'f': _num(self.statistic), 'p_value': _num(self.p_value), 'dof_lack_of_fit': _num(self.dof_lack),
                'dof_pure_error': _num(self.dof_pure), 'pure_error_rms': _num(self.pure_error_rms),
                'lack_of_fit_rms': _num(self.excess_rms), 'residual_rms': _num(self.residual_rms),
                'significant': self.significant}


def _num(value):
    return float(value) if value is not None and math.isfinite(value) else None


def lack_of_fit(table, log_residual, n_params: int) -> LackOfFit:
    """The lack-of-fit test of a model with ``n_params`` fitted parameters (see module doc)."""
    residual = np.asarray(log_residual, dtype=float)
    ss_pe, terms = 0.0, 0
    for r in table.runs:
        sel = np.flatnonzero(table.run == r)
        y = residual[sel]
        order = np.argsort(table.time[sel], kind='stable')
        k = int(min(TREND_TERMS, max(y.size - 2, 1)))
        u = np.linspace(-1.0, 1.0, y.size)
        basis = np.vander(u, k, increasing=True)
        coef, *_ = np.linalg.lstsq(basis, y[order], rcond=None)
        e = y[order] - basis @ coef
        ss_pe += float(e @ e)
        terms += k
    n = residual.size
    ss_total = float(residual @ residual)
    dof_pure = n - terms
    dof_lack = terms - n_params
    if dof_pure <= 0 or dof_lack <= 0 or ss_pe <= 0:
        return LackOfFit(math.nan, math.nan, dof_lack, dof_pure, math.nan, math.nan, math.sqrt(ss_total / n))
    ms_pe = ss_pe / dof_pure
    ss_lof = max(ss_total - ss_pe, 0.0)
    f = (ss_lof / dof_lack) / ms_pe
    p = float(stats.f.sf(f, dof_lack, dof_pure))
    excess = math.sqrt(max(ss_lof - dof_lack * ms_pe, 0.0) / n)
    return LackOfFit(f, p, dof_lack, dof_pure, math.sqrt(ms_pe), excess, math.sqrt(ss_total / n))
