# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How often an ideal test would name a concealed effect: the ceiling a study's misses are measured against.

The ideal test knows everything about the case but the effect's strength: its
form, its covariate and the rig's run-to-run scatter.  Its likelihood-ratio
statistic on the run amplitudes is then noncentral chi^2 with one degree of
freedom and noncentrality ``lambda = runs * ratio**2``
(:attr:`.effect_size.EffectSize.noncentrality`; the ratio is the change the
paper's constants cannot absorb over the run scatter).

The engine names an effect from its amplitudes when its BIC falls by
:attr:`~prsm_lube_ros.diagnosis.rules.DiagnosisRules.bic_margin`: a statistic of at least
``_BIC_MARGIN + k ln(n_eff)`` for ``k`` parameters over ``n_eff`` effective
windows.  The ideal test gets that threshold with ``k = 1`` and ``ln(runs)``
(``n_eff >= runs``), the window scatter in the run means neglected: its chance
(:func:`ideal_detection`) bounds what the engine's amplitude test can reach on
the case.  It is not a bound for every test with the same false-name rate:

* knowing the effect's sign, a one-sided test at that rate does better
  (:func:`one_sided_detection`, reported beside it);
* the shape within runs (``within_runs``, against the window scatter) is left out;
* resonance and background can also be named from evidence outside the
  amplitudes (spectra, standstill), where no such ceiling holds.

Summed over a kind's cases the chance is the number of cases the ideal test is
expected to name, and :func:`chance_of_at_least` the chance it reaches a
study's target on those drawn cases (independent cases; it says nothing of
strengths the study did not draw).  :func:`names_on_recording` is what the
ideal test does on the recording itself (its statistic computed from the
recorded run means, :attr:`.effect_size.EffectSize.recorded_statistic`): the
chance averages over the run scatter a recording might have drawn, this takes
the scatter it did draw.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from scipy import stats

from ..diagnosis.rules import DEFAULT_RULES

_BIC_MARGIN = DEFAULT_RULES.bic_margin

if TYPE_CHECKING:
    from .effect_size import EffectSize

__all__ = ['TARGET_SHARE', 'chance_of_at_least', 'ideal_detection', 'names_on_recording', 'on_recording',
           'one_sided_detection', 'power_markdown']

#: The share of a kind's cases a study must name (issue 17: 95 %).
TARGET_SHARE = 0.95


def _threshold(size: EffectSize, margin: float) -> float:
    """The statistic the ideal test must reach: ``margin`` plus one parameter's BIC penalty over the runs."""
    return margin + math.log(max(size.runs, 2))


def ideal_detection(size: EffectSize, margin: float = _BIC_MARGIN) -> float:
    """Chance that the ideal test (module doc) names an effect of ``size`` with a BIC guard of ``margin``."""
    noncentrality = size.noncentrality
    if not math.isfinite(noncentrality):
        return 1.0
    if noncentrality <= 0.0:
        return float(stats.chi2.sf(_threshold(size, margin), df=1))
    return float(stats.ncx2.sf(_threshold(size, margin), df=1, nc=noncentrality))


def one_sided_detection(size: EffectSize, margin: float = _BIC_MARGIN) -> float:
    """Chance that a one-sided test (the effect's sign known) names ``size``, false names as :func:`ideal_detection`."""
    noncentrality = size.noncentrality
    if not math.isfinite(noncentrality):
        return 1.0
    critical = float(stats.norm.isf(stats.chi2.sf(_threshold(size, margin), df=1)))
    return float(stats.norm.sf(critical - math.sqrt(max(noncentrality, 0.0))))


def names_on_recording(size: EffectSize, margin: float = _BIC_MARGIN) -> bool | None:
    """Whether the ideal test names the effect on the recording of ``size`` (None: statistic not known)."""
    if not math.isfinite(size.recorded_statistic):
        return None
    return size.recorded_statistic >= _threshold(size, margin)


def on_recording(size: EffectSize) -> str:
    """The ideal test on the recording as a table cell: ``statistic of threshold: names`` (or ``misses``; ``-``)."""
    recorded = names_on_recording(size)
    if recorded is None:
        return '-'
    return (f'{size.recorded_statistic:.1f} of {_threshold(size, _BIC_MARGIN):.1f}: '
            f'{"names" if recorded else "misses"}')


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
             f'drop of {_BIC_MARGIN:g}), "one-sided" the same knowing the effect\'s sign (same false-name rate), '
             '"plain BIC" without the guard (see `prsm_lube_ros/experiments/detection_power.py`, also for what the '
             'ideal test leaves out). "On this recording": the ideal test\'s statistic computed from the recorded '
             'run means, against its threshold (the guard plus ln(runs)), and whether it names the effect there.', '',
             '| kind | seed | verdict | right | runs | ratio | noncentrality | ideal | one-sided | plain BIC | '
             'on this recording |',
             '|---|---|---|---|---|---|---|---|---|---|---|']
    per_kind: dict[str, list[tuple[bool, float, float, float, bool | None]]] = {}
    for record in records:
        raw = size_of.get((record['kind'], record['seed']))
        if raw is None:
            continue
        size = EffectSize.from_json(raw)
        guarded, sided, plain = ideal_detection(size), one_sided_detection(size), ideal_detection(size, 0.0)
        recorded = names_on_recording(size)
        per_kind.setdefault(record['kind'], []).append((bool(record.get('right')), guarded, sided, plain, recorded))
        lines.append(f'| {record["kind"]} | {record["seed"]} | {record.get("verdict")} | '
                     f'{"yes" if record.get("right") else "no"} | {size.runs} | {size.ratio:.2f} | '
                     f'{size.noncentrality:.1f} | {100 * guarded:.0f} % | {100 * sided:.0f} % | {100 * plain:.0f} % | '
                     f'{on_recording(size)} |')
    lines += ['', '| kind | cases | right | expected right: ideal | one-sided | plain BIC | chance of the target: '
              'ideal | one-sided | ideal names on these recordings |', '|---|---|---|---|---|---|---|---|---|']
    for kind, rows in sorted(per_kind.items()):
        needed = math.ceil(TARGET_SHARE * len(rows) - 1e-9)
        ideal_chances, sided_chances = [row[1] for row in rows], [row[2] for row in rows]
        lines.append(f'| {kind} | {len(rows)} | {sum(row[0] for row in rows)} | {sum(ideal_chances):.1f} | '
                     f'{sum(sided_chances):.1f} | {sum(row[3] for row in rows):.1f} | '
                     f'{100 * chance_of_at_least(ideal_chances, needed):.0f} % ({needed} or more) | '
                     f'{100 * chance_of_at_least(sided_chances, needed):.0f} % | {_recorded_count(rows)} |')
    return '\n'.join(lines) + '\n'


def _recorded_count(rows: Sequence[tuple[bool, float, float, float, bool | None]]) -> str:
    """How many of a kind's cases the ideal test names on the recordings ('-' when none has the statistic)."""
    known = [row[4] for row in rows if row[4] is not None]
    return f'{sum(known)} of {len(known)}' if known else '-'
