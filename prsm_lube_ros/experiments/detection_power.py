# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How often an ideal test would name a concealed effect: the ceiling a study's misses are measured against.

The ideal test knows everything about the case but the effect's strength: its
form, its covariate and the rig's run-to-run scatter.  Its likelihood-ratio
statistic on the run amplitudes is then noncentral chi^2 with one degree of
freedom and noncentrality ``lambda = runs * ratio**2``
(:attr:`.effect_size.EffectSize.noncentrality`; the ratio is the change the
paper's constants cannot absorb over the run scatter).

The engine names an effect when its BIC falls by
:data:`~prsm_lube_ros.diagnosis.engine.BIC_MARGIN`: a statistic of at least
``BIC_MARGIN + k ln(n_eff)`` for ``k`` parameters over ``n_eff`` effective
windows.  The ideal test is given that guard with ``k = 1`` and ``ln(runs)``
(``n_eff >= runs``), and the window scatter in the run means is neglected: every
approximation favours it, so the chance computed is an upper bound on what any
test with the engine's guard against false names reaches on the case.  Summed
over a kind's cases it is the number of cases such a test is expected to name,
and :func:`chance_of_at_least` the chance it reaches a study's target.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from scipy import stats

from ..diagnosis.engine import BIC_MARGIN

if TYPE_CHECKING:
    from .effect_size import EffectSize

__all__ = ['TARGET_SHARE', 'chance_of_at_least', 'ideal_detection', 'power_markdown']

#: The share of a kind's cases a study must name (issue 17: 95 %).
TARGET_SHARE = 0.95


def ideal_detection(size: EffectSize, margin: float = BIC_MARGIN) -> float:
    """Chance that the ideal test (module doc) names an effect of ``size`` with a BIC guard of ``margin``."""
    noncentrality = size.noncentrality
    if not math.isfinite(noncentrality):
        return 1.0
    threshold = margin + math.log(max(size.runs, 2))
    if noncentrality <= 0.0:
        return float(stats.chi2.sf(threshold, df=1))
    return float(stats.ncx2.sf(threshold, df=1, nc=noncentrality))


def chance_of_at_least(chances: Sequence[float], count: int) -> float:
    """Chance that ``count`` or more of independent events with ``chances`` happen (Poisson binomial)."""
    distribution = np.zeros(len(chances) + 1)
    distribution[0] = 1.0
    for p in chances:
        distribution[1:] = distribution[1:] * (1.0 - p) + distribution[:-1] * p
        distribution[0] *= 1.0 - p
    return float(np.clip(distribution[max(count, 0):].sum(), 0.0, 1.0))


def power_markdown(records: Sequence[dict], sizes: Sequence[dict], command: str) -> str:
    """Per case and per kind: what was named against what the ideal test would name (:func:`ideal_detection`).

    ``sizes``: ``{'kind', 'seed', 'size'}`` items as :func:`.random_study.explain_miss` returns them.
    """
    from .effect_size import EffectSize
    size_of = {(item['kind'], item['seed']): item['size'] for item in sizes}
    lines = ['# What an ideal test would name', '', f'Command: `{command}`', '',
             'Each case simulated again from its seed. The ideal test knows the effect\'s form and the run scatter '
             'and fits its strength only; "ideal" is the chance it names the effect with the engine\'s guard (BIC '
             f'drop of {BIC_MARGIN:g}), "ideal, plain BIC" without the guard (see '
             '`prsm_lube_ros/experiments/detection_power.py`). Every approximation favours the ideal test.', '',
             '| kind | seed | verdict | right | runs | ratio | noncentrality | ideal | ideal, plain BIC |',
             '|---|---|---|---|---|---|---|---|---|']
    per_kind: dict[str, list[tuple[bool, float, float]]] = {}
    for record in records:
        raw = size_of.get((record['kind'], record['seed']))
        if raw is None:
            continue
        size = EffectSize(raw['between_runs'], raw['within_runs'], raw['run_scatter'], raw['runs'])
        guarded, plain = ideal_detection(size), ideal_detection(size, 0.0)
        per_kind.setdefault(record['kind'], []).append((bool(record.get('right')), guarded, plain))
        lines.append(f'| {record["kind"]} | {record["seed"]} | {record.get("verdict")} | '
                     f'{"yes" if record.get("right") else "no"} | {size.runs} | {size.ratio:.2f} | '
                     f'{size.noncentrality:.1f} | {100 * guarded:.0f} % | {100 * plain:.0f} % |')
    lines += ['', '| kind | cases | right | ideal: expected right | ideal: chance of the target | '
              'ideal, plain BIC: expected right |', '|---|---|---|---|---|---|']
    for kind, rows in sorted(per_kind.items()):
        needed = math.ceil(TARGET_SHARE * len(rows) - 1e-9)
        chances = [row[1] for row in rows]
        lines.append(f'| {kind} | {len(rows)} | {sum(row[0] for row in rows)} | {sum(chances):.1f} | '
                     f'{100 * chance_of_at_least(chances, needed):.0f} % ({needed} or more) | '
                     f'{sum(row[2] for row in rows):.1f} |')
    return '\n'.join(lines) + '\n'
