# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How large a concealed effect is against the recording's scatter: why a study case may be undetectable.

For a simulated case the effect's true contribution to each window is known:
``e = ln A(with the effects) - ln A(without)``, both the rig simulator's
expected RMS (:func:`~prsm_lube_ros.simulation.rig_acceleration.expected_rms`)
at the window's speed, load, nut position, temperature and revolutions.  The
paper's model absorbs whatever of ``e`` its free constants can follow
(``ln C_sys``, ``C_F`` times the load, ``C_lambda`` times the film term of
Eq. 22), so only the rest can show as a mismatch.  Two sizes are reported:

* ``between_runs``: RMS over runs of the run means of ``e`` left after a least-
  squares fit of those three columns (run means too), against the rig's
  run-to-run scatter ``run_scatter`` (log standard deviation of each
  traverse's amplitude factor): what a depletion, a thermal drift or a
  resonance must beat;
* ``within_runs``: RMS of ``e`` about its run means (a shape along the stroke,
  which window scatter hides only as ``1/sqrt(windows)``).

The ratio ``between_runs / run_scatter`` is the effect's size in units of the
noise it competes with; well below 1 no method can name it from the
amplitudes, whatever its form.  ``runs * ratio**2`` is the noncentrality of the
likelihood-ratio statistic with which an ideal test (true form known, run
scatter known) would see it: :mod:`.detection_power` turns it into the chance
that such a test names the effect.

``recorded_statistic`` is that test's statistic on the recording itself: the
run means of Eq. 22's left side (``ln(A omega^-2 F^(1/3))``) fitted by weighted
least squares on the three columns of the constants, then on those and the
effect's run-mean change with a free strength; the fall of the weighted sum of
squares, each run weighted by ``1 / (run_scatter**2 + s_w**2 / m)`` (``s_w``
the pooled window scatter about the run means, ``m`` the run's windows).  Where
the chance says what the test names on average over recordings like this one,
this says what it names on this one.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..diagnosis.table import WindowTable
    from ..simulation.effects import Effects
    from ..simulation.rig_config import RigConfig

__all__ = ['EffectSize', 'effect_size', 'recorded_statistic']


@dataclass(frozen=True)
class EffectSize:
    """The concealed effects' log-amplitude change beyond the paper's model, and the scatter it competes with."""

    between_runs: float     # RMS over runs of the run-mean change left by the model's constants (ln units)
    within_runs: float      # RMS of the change about its run means (ln units)
    run_scatter: float      # the rig's run-to-run log scatter
    runs: int               # runs of the table
    recorded_statistic: float = math.nan    # the ideal test's likelihood-ratio statistic on this recording

    @property
    def ratio(self) -> float:
        """``between_runs / run_scatter`` (inf without run scatter)."""
        return self.between_runs / self.run_scatter if self.run_scatter > 0 else math.inf

    @property
    def noncentrality(self) -> float:
        """``runs * ratio**2``: the sum over runs of the squared change left, in units of the run scatter."""
        return self.runs * self.ratio ** 2

    def as_json(self) -> dict[str, float]:
        """The sizes, rounded for a results file."""
        return {'between_runs': round(self.between_runs, 5), 'within_runs': round(self.within_runs, 5),
                'run_scatter': round(self.run_scatter, 5), 'ratio': round(self.ratio, 3), 'runs': self.runs,
                'recorded_statistic': round(self.recorded_statistic, 3)}

    @classmethod
    def from_json(cls, raw: dict) -> EffectSize:
        """The size :meth:`as_json` wrote (``recorded_statistic`` NaN when a file written before it lacks it)."""
        recorded = raw.get('recorded_statistic')
        return cls(raw['between_runs'], raw['within_runs'], raw['run_scatter'], int(raw['runs']),
                   math.nan if recorded is None else float(recorded))


def effect_size(table: WindowTable, rig: RigConfig, effects: Effects) -> EffectSize:
    """The :class:`EffectSize` of ``effects`` on the windows of ``table`` recorded on ``rig`` (module doc)."""
    from ..simulation.rig_acceleration import expected_rms
    temperature = np.where(np.isfinite(table.temperature), table.temperature, rig.ambient_temperature)
    state = {'nut_position': table.position, 'temperature': temperature, 'revolutions': table.revolutions}
    speed = np.abs(table.speed)
    change = (np.log(expected_rms(speed, table.load, table.theta, rig, effects, **state))
              - np.log(expected_rms(speed, table.load, table.theta, rig, None, **state)))
    means = table.run_means(change)
    design = _constants_design(table)
    coefficients, *_ = np.linalg.lstsq(design, means, rcond=None)
    left = means - design @ coefficients
    within = change - means[np.searchsorted(table.runs, table.run)]
    return EffectSize(between_runs=float(np.sqrt(np.mean(left ** 2))),
                      within_runs=float(np.sqrt(np.mean(within ** 2))), run_scatter=float(rig.run_scatter),
                      runs=int(means.size), recorded_statistic=recorded_statistic(table, change, rig.run_scatter))


def _constants_design(table: WindowTable) -> np.ndarray:
    """Run means of the columns Eq. 22's constants multiply: 1 (ln C_sys), F_a (C_F), -theta film term (C_lambda)."""
    return np.column_stack([np.ones(table.runs.size), table.run_means(np.abs(table.load)),
                            table.run_means(-table.theta * table.film_term)])


def recorded_statistic(table: WindowTable, change: np.ndarray, run_scatter: float) -> float:
    """The ideal test's likelihood-ratio statistic on the recorded run means (module doc); NaN if not computable.

    ``change``: the effect's change of ln A per window (its form; the strength is fitted); ``run_scatter``:
    the log standard deviation of the run amplitude factors.
    """
    measured = np.isfinite(table.reduced)
    if not measured.all():      # windows without an amplitude count nowhere: not in a mean, nor in the dof
        table, change = table.subset(measured), np.asarray(change)[measured]
    design = _constants_design(table)
    change = table.run_means(change)
    reduced = table.reduced
    means = table.run_means(reduced)
    index = np.searchsorted(table.runs, table.run)
    deviation = reduced - means[index]
    windows = np.bincount(index, minlength=table.runs.size).astype(float)
    usable = np.isfinite(means) & np.isfinite(change) & np.all(np.isfinite(design), axis=1)
    dof = len(table) - table.runs.size
    if dof <= 0 or np.count_nonzero(usable) <= design.shape[1] + 1:
        return math.nan
    window_variance = float(np.sum(deviation ** 2) / dof)
    weight = np.sqrt(1.0 / (run_scatter ** 2 + window_variance / np.maximum(windows, 1.0)))[usable]
    target = means[usable] * weight
    sums = []
    for columns in (design[usable], np.column_stack([design[usable], change[usable]])):
        weighted = columns * weight[:, None]
        coefficients, *_ = np.linalg.lstsq(weighted, target, rcond=None)
        rest = target - weighted @ coefficients
        sums.append(float(rest @ rest))
    return max(sums[0] - sums[1], 0.0)
