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

__all__ = ['EffectSize', 'effect_size']


@dataclass(frozen=True)
class EffectSize:
    """The concealed effects' log-amplitude change beyond the paper's model, and the scatter it competes with."""

    between_runs: float     # RMS over runs of the run-mean change left by the model's constants (ln units)
    within_runs: float      # RMS of the change about its run means (ln units)
    run_scatter: float      # the rig's run-to-run log scatter
    runs: int               # runs of the table

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
                'run_scatter': round(self.run_scatter, 5), 'ratio': round(self.ratio, 3), 'runs': self.runs}


def effect_size(table: WindowTable, rig: RigConfig, effects: Effects) -> EffectSize:
    """The :class:`EffectSize` of ``effects`` on the windows of ``table`` recorded on ``rig`` (module doc)."""
    from ..simulation.rig_acceleration import expected_rms
    temperature = np.where(np.isfinite(table.temperature), table.temperature, rig.ambient_temperature)
    state = {'nut_position': table.position, 'temperature': temperature, 'revolutions': table.revolutions}
    speed = np.abs(table.speed)
    change = (np.log(expected_rms(speed, table.load, table.theta, rig, effects, **state))
              - np.log(expected_rms(speed, table.load, table.theta, rig, None, **state)))
    means = table.run_means(change)
    design = np.column_stack([np.ones(means.size), table.run_means(np.abs(table.load)),
                              table.run_means(-table.theta * table.film_term)])
    coefficients, *_ = np.linalg.lstsq(design, means, rcond=None)
    left = means - design @ coefficients
    within = change - means[np.searchsorted(table.runs, table.run)]
    return EffectSize(between_runs=float(np.sqrt(np.mean(left ** 2))),
                      within_runs=float(np.sqrt(np.mean(within ** 2))), run_scatter=float(rig.run_scatter),
                      runs=int(means.size))
