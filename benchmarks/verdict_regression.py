#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Does a change of the diagnosis engine change any verdict?  Re-diagnose stored study cases and compare.

A refactor of the rules (issue 35) must leave every verdict of the recorded
studies as it was.  This command builds the window tables of a fixed set of
study cases once and keeps them (``--tables``, default
``out/verdict_regression/tables``: pickled :class:`WindowTable` objects, so a
second run diagnoses the very same tables), diagnoses each with the current
engine and writes every case's *fingerprint*: the verdict, whether it is
confident, the named effects with their forms, the tie, and each candidate's
status with its reason, and the notes.

- ``--record FILE`` writes the fingerprints (run it on the engine before a change);
- ``--compare FILE`` diagnoses again and lists every case whose fingerprint
  differs: verdict, named effects or statuses (a *verdict change*), or only
  the words of a reason or note (a *text change*); it exits 1 on a verdict
  change.  The list goes to ``--report`` (Markdown) as well.

Cases: the random study's kinds (rig simulator, bags written and read back
as ``prsm-lube diagnose`` reads them; :mod:`prsm_lube_ros.experiments.random_study`)
for ``--rig-seeds`` seeds from ``--first-seed`` on, and the window-table
simulator's every form of every effect, no effect and every pair
(:mod:`diagnose_forms`) for ``--synthetic-seeds`` seeds.

Usage: ``python benchmarks/verdict_regression.py --record benchmarks/results/verdict_regression_before.json``
then, after the change, ``python benchmarks/verdict_regression.py --compare
benchmarks/results/verdict_regression_before.json --report benchmarks/results/verdict_regression.md``.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
from pathlib import Path
import pickle
import shutil
import sys
import tempfile
import time
from typing import Any

import numpy as np

from prsm_lube_ros.diagnosis import diagnose_table

ROOT = Path(__file__).resolve().parents[1]


def _rig_table(kind: str, seed: int) -> Any:
    """The window table of one random-study case, as the study reads its bags (None when diagnose refuses it)."""
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.experiments.random_study import case_recordings, case_table, simulate_case
    folder = Path(tempfile.mkdtemp(prefix='prsm_verdicts_'))
    try:
        paths, setup, _, _ = simulate_case(kind, seed, list(candidate_ids()), folder=folder)
        try:
            return case_table(paths, case_recordings(paths, setup))
        except InputError:
            return None
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _synthetic_table(case: tuple) -> Any:
    """The window table of one window-table-simulator case of ``diagnose_forms``."""
    import diagnose_forms as forms
    from prsm_lube_ros.experiments.synthetic_tables import synthetic_table
    kind, effect, form, seed, warm = case[1:]
    if kind == 'pair':
        table, _ = synthetic_table(np.random.default_rng(seed), tuple(effect), forms.PLAN)
        return table
    plan = forms.WARM if warm else forms.PLAN
    params = forms.drawn_params(effect, form, seed, plan) if effect else None
    table, _ = synthetic_table(np.random.default_rng(seed), effect, plan, params=params)
    return table


def cases(rig_seeds: range, synthetic_seeds: range) -> list[tuple]:
    """Every case: ``('rig', kind, seed)`` or ``('synthetic', 'single'|'pair', effect(s), form, seed, warm)``."""
    import diagnose_forms as forms
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    from prsm_lube_ros.experiments.random_study import NONE, OUTSIDE_KINDS, THERMAL_FREE, TWO
    effects = list(candidate_ids())
    kinds = effects + [NONE, TWO] + list(OUTSIDE_KINDS) + [THERMAL_FREE]
    out: list[tuple] = []
    for seed in synthetic_seeds:
        out += [('synthetic', 'single', effect, form, seed, False) for effect in forms.EFFECTS
                for form in forms.FORMS[effect]]
        out += [('synthetic', 'single', 'thermal_viscosity', form, seed, True)
                for form in forms.FORMS['thermal_viscosity']]
        out.append(('synthetic', 'single', None, '', seed, False))
        out += [('synthetic', 'pair', list(pair), '', 100 + seed, False) for pair in forms.PAIRS]
    return out + [('rig', kind, seed) for seed in rig_seeds for kind in kinds]     # the slow ones last


def case_key(case: tuple) -> str:
    """A file-name-safe name of a case."""
    parts = [str(p if not isinstance(p, list) else '+'.join(p)) for p in case]
    return '_'.join(p.replace(' ', '-').replace('/', '-').replace('(', '').replace(')', '') for p in parts)


def fingerprint(document: dict) -> dict:
    """What a refactor must keep: verdict, named effects and forms, tie, statuses (the decisions), and the words."""
    return {'verdict': document['verdict'], 'confident': document['confident'],
            'named': [[e['effect'], e.get('form', '')] for e in document['effects']],
            'tied': list(document['tied']),
            'statuses': {c['effect']: c['status'] for c in document['candidates']},
            'forms': {c['effect']: c['form'] for c in document['candidates']},
            'reasons': {c['effect']: c['reason'] for c in document['candidates']},
            'notes': list(document['notes']), 'what_to_record': document['what_to_record']}


def run_case(job: tuple) -> tuple[str, dict]:
    """Build (or load) one case's table and diagnose it; ``(key, fingerprint)``."""
    case, tables = job
    key = case_key(case)
    path = Path(tables) / f'{key}.pkl'
    if path.exists():
        table = pickle.loads(path.read_bytes())
    else:
        table = _rig_table(case[1], case[2]) if case[0] == 'rig' else _synthetic_table(case)
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_suffix('.tmp')
        temporary.write_bytes(pickle.dumps(table))
        temporary.replace(path)
    if table is None:
        return key, {'verdict': 'refused'}
    try:
        document = json.loads(json.dumps(diagnose_table(table).as_json(), default=float))
    except Exception as exc:  # noqa: BLE001 - a crash is a changed outcome, listed like any other
        return key, {'verdict': f'failed: {type(exc).__name__}: {exc}'}
    return key, fingerprint(document)


DECISIONS = ('verdict', 'confident', 'named', 'tied', 'statuses', 'forms')


def compare(before: dict, after: dict) -> tuple[list[str], list[str]]:
    """``(verdict changes, text changes)``, one Markdown line each."""
    decided, worded = [], []
    for key in sorted(set(before) | set(after)):
        old, new = before.get(key), after.get(key)
        if old is None or new is None:
            worded.append(f'- `{key}`: only {"after" if old is None else "before"} (not compared)')
            continue
        changed = [field for field in DECISIONS if old.get(field) != new.get(field)]
        if changed:
            changes = '; '.join(f'{field} {old.get(field)!r} -> {new.get(field)!r}' for field in changed)
            decided.append(f'- `{key}`: {changes}')
            continue
        texts = [field for field in ('reasons', 'notes', 'what_to_record') if old.get(field) != new.get(field)]
        if texts:
            worded.append(f'- `{key}`: {", ".join(texts)} differ')
    return decided, worded


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument('--record', type=Path, help='write the fingerprints of every case to this JSON file')
    mode.add_argument('--compare', type=Path, help='diagnose again and compare with this recorded JSON file')
    mode.add_argument('--diff', nargs=2, type=Path, metavar=('BEFORE', 'AFTER'),
                      help='compare two recorded files (the cases both hold), diagnosing nothing')
    parser.add_argument('--report', type=Path, default=None, help='with --compare: the list as Markdown')
    parser.add_argument('--tables', type=Path, default=ROOT / 'out' / 'verdict_regression' / 'tables')
    parser.add_argument('--rig-seeds', type=int, default=2)
    parser.add_argument('--first-seed', type=int, default=300)
    parser.add_argument('--synthetic-seeds', type=int, default=2)
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--kinds', nargs='*', default=None, metavar='KIND',
                        help='only these rig kinds (and no synthetic case unless --synthetic-seeds is given)')
    parser.add_argument('--only', nargs='*', default=None, metavar='KEY',
                        help='with --compare: only the cases recorded in the file (a stopped recording)')
    args = parser.parse_args(argv)
    command = 'python benchmarks/verdict_regression.py ' + ' '.join(argv if argv is not None else sys.argv[1:])
    if args.diff:
        before, after = (json.loads(path.read_text()) for path in args.diff)
        return _report(command, before, after, args.diff[0], 0.0, args.report)
    started = time.time()
    rig_seeds = range(args.first_seed, args.first_seed + args.rig_seeds)
    chosen = cases(rig_seeds, range(args.synthetic_seeds))
    if args.kinds is not None:
        chosen = [case for case in chosen if case[0] != 'rig' or case[1] in args.kinds]
    if args.compare and args.only is not None:      # --only with no key: the cases the file holds
        recorded = set(args.only) or set(json.loads(args.compare.read_text()))
        chosen = [case for case in chosen if case_key(case) in recorded]
    jobs = [(case, str(args.tables)) for case in chosen]
    results: dict[str, dict] = {}
    with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        for key, found in pool.map(run_case, jobs):
            results[key] = found
            print(f'{len(results)}/{len(jobs)} {key}: {found["verdict"]}', file=sys.stderr, flush=True)
            if args.record:     # a stopped run keeps what it recorded (compared case by case)
                args.record.write_text(json.dumps(results, indent=1, sort_keys=True) + '\n')
    wall = time.time() - started
    if args.record:
        print(f'{len(results)} cases recorded in {args.record} ({wall:.0f} s)')
        return 0
    return _report(command, json.loads(args.compare.read_text()), results, args.compare, wall, args.report)


def _report(command: str, before: dict, after: dict, against: Path, wall: float, report: Path | None) -> int:
    """Print (and write to ``report``) every change between two sets of fingerprints; 1 on a changed decision."""
    decided, worded = compare(before, after)
    both = len(set(before) & set(after))
    lines = ['# Verdicts before and after', '', f'Command: `{command}` ({wall:.0f} s wall). {both} cases compared '
             f'against `{against}`: **{len(decided)} with a changed decision** (verdict, named effects or '
             f'forms, tie, a candidate\'s status), {len(worded)} with changed words only or not in both.', '']
    lines += ['## Changed decisions', ''] + (decided or ['none']) + ['', '## Changed words only, or not in both', '']
    lines += (worded or ['none']) + ['']
    text = '\n'.join(lines)
    if report:
        report.write_text(text)
    print(text)
    return 1 if decided else 0


if __name__ == '__main__':
    sys.exit(main())
