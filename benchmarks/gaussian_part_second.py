#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Second effects sought in the windows' Gaussian part beside a spall: the engine with the rule and without it.

On the window-level simulator (:mod:`prsm_lube_ros.experiments.synthetic_tables`,
an implementation of its own beside the rig's bags) each case hides a surface
defect and one other effect (or the defect alone), with condition indicators
and two sessions.  Every table is diagnosed twice: with the default rules, and
with ``gaussian_part_share`` above 1 (no table carries the Gaussian part in a
larger share than all its windows: the rule off).  A case is right when the
verdict names exactly the hidden effects.

The rule can fail both ways here: beside a spall alone the measured Gaussian
part rises with speed and load where strikes ring densely, which an effect's
law can take (a false second); and beside a second effect it may name the
wrong one.

Usage: ``python benchmarks/gaussian_part_second.py [--seeds 10] [--first-seed 0] [--name gaussian_part_second]``
(after ``source .env-jazzy.sh``); results to ``benchmarks/results/<name>.{md,json}``.
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import json
from pathlib import Path
import sys
import time
import warnings

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
DEFECT = 'surface_defect'


def named(diagnosis) -> list[str]:
    """The effect IDs a verdict names, sorted, as the studies read them from its JSON."""
    from prsm_lube_ros.experiments.random_study import _named_effects
    return sorted(str(e) for e in _named_effects(json.loads(json.dumps(diagnosis.as_json(), default=float))))


def run(kinds: tuple[str, ...], seed: int) -> dict:
    """Both diagnoses of one simulated case."""
    from prsm_lube_ros.diagnosis import DEFAULT_RULES
    from prsm_lube_ros.diagnosis.engine import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    table, _ = synthetic_table(np.random.default_rng(seed), kinds if len(kinds) > 1 else kinds[0],
                               plan=SyntheticPlan(condition_indicators=True, sessions=2))
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        on = diagnose_table(table)
        off = diagnose_table(table, rules=replace(DEFAULT_RULES, gaussian_part_share=1.01))
    truth = sorted(kinds)
    return {'kinds': truth, 'seed': seed, 'with_rule': named(on), 'without_rule': named(off),
            'route': on.second.route if on.second else None,
            'right_with': named(on) == truth, 'right_without': named(off) == truth}


def markdown(records: list[dict], command: str, seconds: float) -> str:
    """The per-kind table and the changed cases."""
    lines = [f'# Second effects in the Gaussian part beside a spall (`{command}`)', '',
             f'Window-level simulator, two sessions, condition indicators; {len(records)} cases in {seconds:.0f} s. '
             'Right: the verdict names exactly the hidden effects.', '',
             '| hidden | cases | right with the rule | right without | named only with the rule |',
             '|---|---|---|---|---|']
    for kinds in sorted({tuple(r['kinds']) for r in records}):
        rows = [r for r in records if tuple(r['kinds']) == kinds]
        extra = sum(1 for r in rows if set(r['with_rule']) - set(r['without_rule']))
        lines.append(f'| {" + ".join(kinds)} | {len(rows)} | {sum(r["right_with"] for r in rows)} | '
                     f'{sum(r["right_without"] for r in rows)} | {extra} |')
    changed = [r for r in records if r['with_rule'] != r['without_rule']]
    lines += ['', f'Verdicts the rule changes: {len(changed)}', '']
    lines += [f'- {" + ".join(r["kinds"])} seed {r["seed"]}: {r["without_rule"]} -> {r["with_rule"]}'
              for r in changed]
    return '\n'.join(lines) + '\n'


def main(argv: list[str] | None = None) -> int:
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--first-seed', type=int, default=0)
    parser.add_argument('--name', default='gaussian_part_second')
    args = parser.parse_args(argv)
    command = 'python benchmarks/gaussian_part_second.py ' + ' '.join(argv if argv is not None else sys.argv[1:])
    pool = [(DEFECT,)] + [tuple(sorted((DEFECT, other))) for other in candidate_ids() if other != DEFECT]
    start, records = time.time(), []
    for kinds in pool:
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            record = run(kinds, seed)
            records.append(record)
            print(f'{" + ".join(kinds):<45} {seed:>3}: {record["without_rule"]} -> {record["with_rule"]}',
                  file=sys.stderr, flush=True)
    out = ROOT / 'benchmarks' / 'results'
    (out / f'{args.name}.json').write_text(json.dumps({'command': command, 'records': records}, indent=1))
    text = markdown(records, command.strip(), time.time() - start)
    (out / f'{args.name}.md').write_text(text)
    print(text)
    return 0


if __name__ == '__main__':
    sys.exit(main())
