# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What a lower BIC margin would name: read from a random study's candidate scores, without rerunning it.

Every case of ``results.json`` keeps each candidate's held-out gain and BIC
against the paper's model, fitted alone (:func:`.random_study.run_random_case`).
A candidate the engine rejected for its BIC alone (physical constants, held-out
gain of :attr:`~prsm_lube_ros.diagnosis.rules.DiagnosisRules.min_gain` or more, BIC drop short
of :attr:`~prsm_lube_ros.diagnosis.rules.DiagnosisRules.bic_margin`) would earn at a lower
margin.  Listed per margin: whether the effect was concealed in that case (a
miss the margin would catch) or not (a false name it would risk).  The engine's
later steps (ties, pairs, the empirical terms) are not replayed: the list is
what would *enter* them.
"""
from __future__ import annotations

from typing import Sequence

from ..diagnosis.rules import DEFAULT_RULES

_BIC_MARGIN, _MIN_GAIN = DEFAULT_RULES.bic_margin, DEFAULT_RULES.min_gain

__all__ = ['MARGINS', 'margin_entrants', 'margins_markdown']

#: Lower BIC margins tried.
MARGINS = (8.0, 6.0)


def margin_entrants(records: Sequence[dict], margin: float) -> list[dict]:
    """Candidates rejected at the engine's margin that would earn at ``margin`` (``kind``, ``seed``, ``effect``...)."""
    found = []
    for record in records:
        for candidate in record.get('candidates') or []:
            gain, delta_bic = candidate.get('gain'), candidate.get('delta_bic')
            if candidate.get('status') != 'rejected' or gain is None or delta_bic is None:
                continue
            if 'unphysical' in (candidate.get('reason') or '') or gain < _MIN_GAIN:
                continue
            if -_BIC_MARGIN < delta_bic <= -margin:
                found.append({'kind': record['kind'], 'seed': record['seed'], 'effect': candidate['effect'],
                              'delta_bic': delta_bic, 'gain': gain, 'verdict': record.get('verdict'),
                              'concealed': candidate['effect'] in record.get('effects', [])})
    return found


def margins_markdown(records: Sequence[dict], command: str, margins: Sequence[float] = MARGINS) -> str:
    """The entrants of each margin as Markdown."""
    lines = ['# What a lower BIC margin would name', '', f'Command: `{command}`', '',
             f'Candidates rejected at the engine\'s margin (BIC drop of {_BIC_MARGIN:g}) with physical constants '
             f'and a held-out gain of {100 * _MIN_GAIN:.0f} % or more, whose BIC drop reaches the lower margin '
             '(see `prsm_lube_ros/experiments/margins.py`).', '']
    if any('reason' not in c for record in records for c in record.get('candidates') or []):
        lines += ['The study\'s records do not keep the candidates\' reasons (written before they did): a candidate '
                  'rejected for unphysical constants cannot be left out, and is listed if its scores qualify.', '']
    for margin in margins:
        entrants = margin_entrants(records, margin)
        caught = sum(e['concealed'] for e in entrants)
        lines += [f'## Margin {margin:g}: {caught} concealed, {len(entrants) - caught} not concealed', '']
        if not entrants:
            lines += ['none', '']
            continue
        lines += ['| kind | seed | candidate | concealed | BIC | held-out gain | verdict now |',
                  '|---|---|---|---|---|---|---|']
        lines += [f'| {e["kind"]} | {e["seed"]} | {e["effect"]} | {"yes" if e["concealed"] else "no"} | '
                  f'{e["delta_bic"]:+.1f} | {100 * e["gain"]:.1f} % | {e["verdict"]} |' for e in entrants]
        lines.append('')
    return '\n'.join(lines)
