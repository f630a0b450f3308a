#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Kept window tables diagnosed by this tree's engine; where two second effects tie, settled by the rule before too.

The tied-seconds rule (``engine._settle_tied_seconds``, ``docs/diagnosis-rules.md``, second effects) only acts
where two second effects earn alike beside a first.  Each pickled window table (as ``engine_ab_tables.py``
keeps them: ``{'table': WindowTable, 'names': [...], ...}``) is diagnosed once; the settling is wrapped, and
wherever it runs, the rule before the change (the location on either tied law's covariate, else the one of
the two only shown outside the amplitude fit, else a tie) is worked out on the same arguments.  Up to there the
two engines take the same path, so where the two settle alike the verdicts agree by construction; where they
differ the line says so (and the named effects are this engine's).

One JSON line per table in ``--out``; ``--summary`` writes the counts and every table that reached a tie.

Usage: ``python benchmarks/engine_ab_tied_seconds.py --out FILE.jsonl --summary FILE.md [--jobs 2] PKL ...``
(after ``source .env-jazzy.sh``; this tree first on ``PYTHONPATH``).
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
from pathlib import Path
import pickle
import sys


def rule_before(table, first, tied, left, location) -> str | None:
    """How the engine before the change settled two tied second effects: the ID named, or None."""
    located = [s for s in tied if s.candidate.effect.covariate == left.located]
    if len(located) == 1:
        return located[0].effect.id
    shown = [s for s in tied if s.effect.independent_evidence(table, location, s.params, beside=s.first_effect)]
    return shown[0].effect.id if len(shown) == 1 else None


def one_table(path: str) -> dict:
    """Diagnose one pickled table with the settling of tied seconds wrapped; what it and the rule before named."""
    from prsm_lube_ros.diagnosis import engine
    from prsm_lube_ros.experiments.random_study import _named_effects
    calls = []
    settle = engine._settle_tied_seconds

    def wrapped(table, first, tied, left, location, rules):
        named, rest = settle(table, first, tied, left, location, rules)
        calls.append({'first': first.effect.id, 'tied': [s.effect.id for s in tied], 'located': left.located,
                      'after': named.effect.id if named is not None else None,
                      'before': rule_before(table, first, tied, left, location)})
        return named, rest
    engine._settle_tied_seconds = wrapped
    case = pickle.loads(Path(path).read_bytes())
    result = engine.diagnose_table(case['table'])
    named = _named_effects(json.loads(json.dumps(result.as_json(), default=float)))
    return {'table': path, 'concealed': sorted(case.get('names', [])), 'named': named, 'ties': calls,
            'differs': any(c['after'] != c['before'] for c in calls)}


def main() -> int:
    """Diagnose, write the JSON lines and the summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('tables', nargs='+', help='pickled window tables')
    parser.add_argument('--out', type=Path, required=True)
    parser.add_argument('--summary', type=Path, required=True)
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args()
    with ProcessPoolExecutor(args.jobs) as pool, args.out.open('w') as out:
        records = []
        for record in pool.map(one_table, args.tables):
            out.write(json.dumps(record) + '\n')
            records.append(record)
    reached = [r for r in records if r['ties']]
    lines = [f'# Tied second effects before and after (`python benchmarks/engine_ab_tied_seconds.py '
             f'{" ".join(sys.argv[1:3])} ...`)', '',
             f'{len(records)} tables; {len(reached)} reached a tie of second effects; '
             f'{sum(r["differs"] for r in records)} settled differently by the rule before.', '',
             '| table | concealed | named (this engine) | first | tied | located | before | after |',
             '|---|---|---|---|---|---|---|---|']
    for r in reached:
        for c in r['ties']:
            lines.append(f'| {Path(r["table"]).name} | {", ".join(r["concealed"])} | {", ".join(r["named"])} | '
                         f'{c["first"]} | {", ".join(c["tied"])} | {c["located"]} | {c["before"]} | {c["after"]} |')
    args.summary.write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
