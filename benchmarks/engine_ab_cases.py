#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Study cases of recorded blocks diagnosed by this tree's engine and, where a new rule acted, by another checkout's.

A change of the diagnosis engine that adds a rule (a measurement that refutes a
fit, a refit it forces) acts on some cases only.  This command simulates again
the cases of recorded study blocks that conceal a given effect (``--effect``,
default ``surface_defect``; pairs first), diagnoses each with this tree's
engine and records whether the rule acted: ``--acted MODULE:CLASS.METHOD``
(default the surface defect's ``measured_against``) returned words (an array:
any element true), or the engine's ``_physical_refit`` ran (not counted with
``--acted-only``, for a rule the other checkout lacks and nothing else).
Where something acted, the very same window table is pickled and diagnosed
by the ``--before`` checkout's engine in a subprocess (its own code on ``PYTHONPATH``); elsewhere the two engines take
the same path, so the verdicts agree by construction.

Each case is one JSON line in ``--out`` (appended; cases already there are
skipped, so a stopped run goes on), and ``--summary`` writes the counts as
Markdown: right on this engine, right on the other, and every case whose
verdict differs.

Usage: ``python benchmarks/engine_ab_cases.py --before /path/to/main --out results.jsonl --summary results.md``
(after ``source .env-jazzy.sh``; this tree first on ``PYTHONPATH``).
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import pickle
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = ('diagnose_study_defect_two_1330', 'diagnose_study_defect_evidence_pairs_1400',
          'diagnose_study_defect_evidence_pairs_1500', 'diagnose_study_two_1600_standstill_evidence',
          'diagnose_study_two_1700_gaussian_part')
OTHER_ENGINE = '''
import json, pickle, sys
from prsm_lube_ros.diagnosis.engine import diagnose_table
from prsm_lube_ros.experiments.random_study import _named_effects
result = diagnose_table(pickle.load(open(sys.argv[1], 'rb')))
print(json.dumps({'verdict': result.verdict,
                  'named': _named_effects(json.loads(json.dumps(result.as_json(), default=float)))}))
'''


def study_cases(blocks: list[str], effect: str) -> list[tuple[str, int, str]]:
    """(kind, seed, block) of every case of ``blocks`` concealing ``effect``, each once, pairs first."""
    cases: list[tuple[str, int, str]] = []
    for block in blocks:
        for case in json.loads((ROOT / 'benchmarks' / 'results' / block / 'results.json').read_text())['cases']:
            if effect in (case.get('effects') or []) and all((case['kind'], case['seed']) != c[:2] for c in cases):
                cases.append((case['kind'], case['seed'], block))
    return sorted(cases, key=lambda c: c[0] != 'two')


def _counting(owner: object, name: str, counter: dict[str, int], key: str, *, truthy: bool) -> None:
    """Wrap ``owner.name`` so each call (each call returning something truthy) counts in ``counter[key]``."""
    original = getattr(owner, name)

    def wrapped(*args: object, **kwargs: object) -> object:
        out = original(*args, **kwargs)
        if not truthy or (bool(np.any(out)) if isinstance(out, np.ndarray) else out):
            counter[key] += 1
        return out
    setattr(owner, name, wrapped)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--before', type=Path, required=True, help='the other checkout (its engine, where ours acted)')
    parser.add_argument('--out', type=Path, required=True, help='JSON lines, one a case (appended)')
    parser.add_argument('--summary', type=Path, default=None, help='counts and changed verdicts as Markdown')
    parser.add_argument('--blocks', nargs='*', default=list(BLOCKS))
    parser.add_argument('--effect', default='surface_defect')
    parser.add_argument('--acted', default='prsm_lube_ros.diagnosis.effects.surface_defect:'
                        'SurfaceDefectCandidate.measured_against',
                        help='MODULE:CLASS.METHOD or MODULE:FUNCTION whose truthy return means the rule acted')
    parser.add_argument('--acted-only', action='store_true',
                        help='the other engine only where --acted acted (not where _physical_refit ran): for a rule '
                             'the other checkout lacks and nothing else')
    parser.add_argument('--kinds', nargs='*', default=None, help='only cases of these kinds (default: all)')
    parser.add_argument('--where-acted', type=Path, default=None,
                        help='only the cases an earlier --out file records the rule acting in (a changed rule '
                             'checked again where it matters)')
    parser.add_argument('--limit', type=int, default=0, help='at most this many cases (0: all)')
    parser.add_argument('--reverse', action='store_true', help='the cases in reverse order (a second worker)')
    args = parser.parse_args(argv)
    import importlib
    from prsm_lube_ros.diagnosis import engine
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    from prsm_lube_ros.experiments.random_study import _named_effects, _right, case_recordings, case_table, \
        simulate_case
    module, _, attribute = args.acted.partition(':')
    owner_name, _, method = attribute.rpartition('.')    # no class: a function of the module
    fired = {'measured': 0, 'refit': 0}
    owner = importlib.import_module(module)
    _counting(getattr(owner, owner_name) if owner_name else owner, method, fired, 'measured', truthy=True)
    if not args.acted_only:
        _counting(engine, '_physical_refit', fired, 'refit', truthy=False)
    done = set()
    if args.out.exists():
        done = {(r['kind'], r['seed']) for r in map(json.loads, args.out.read_text().splitlines())}
    cases = [c for c in study_cases(args.blocks, args.effect) if args.kinds is None or c[0] in args.kinds]
    if args.where_acted is not None:
        acted = {(r['kind'], r['seed']) for r in map(json.loads, args.where_acted.read_text().splitlines())
                 if r['fired'].get('measured')}
        cases = [c for c in cases if c[:2] in acted]
    cases = cases[::-1] if args.reverse else cases
    cases = cases[:args.limit] if args.limit else cases
    print(f'{len(cases)} cases, {sum(c[0] == "two" for c in cases)} pairs', flush=True)
    scratch = Path(tempfile.mkdtemp(prefix='engine_ab_'))
    env = {**os.environ, 'PYTHONPATH': str(args.before)}
    with args.out.open('a') as out:
        for kind, seed, block in cases:
            if (kind, seed) in done:
                continue
            start = time.time()
            folder = scratch / f'{kind}_{seed}'
            paths, setup, names, _ = simulate_case(kind, seed, list(candidate_ids()), folder=folder)
            table = case_table(paths, case_recordings(paths, setup))
            shutil.rmtree(folder, ignore_errors=True)
            fired.update(measured=0, refit=0)
            result = engine.diagnose_table(table)
            document = json.loads(json.dumps(result.as_json(), default=float))
            record = {'kind': kind, 'seed': seed, 'block': block, 'effects': names, 'verdict': result.verdict,
                      'named': _named_effects(document), 'fired': dict(fired)}
            record['right'] = _right(dict(record))
            if fired['measured'] or fired['refit']:
                path = scratch / f'{kind}_{seed}.pkl'
                path.write_bytes(pickle.dumps(table))
                other = subprocess.run([sys.executable, '-c', OTHER_ENGINE, str(path)], capture_output=True,
                                       text=True, env=env, cwd=args.before)
                path.unlink()
                try:
                    before = json.loads(other.stdout.strip().splitlines()[-1])
                    record['before'] = before
                    record['before_right'] = _right({**record, **before})
                except (IndexError, json.JSONDecodeError):
                    record['before_error'] = other.stderr[-500:]
            else:
                record['before_right'] = record['right']
            record['seconds'] = round(time.time() - start, 1)
            out.write(json.dumps(record) + '\n')
            out.flush()
            print(kind, seed, names, '->', record['named'], 'right' if record['right'] else 'MISS',
                  'before:', 'right' if record.get('before_right') else 'MISS', record['fired'], flush=True)
    shutil.rmtree(scratch, ignore_errors=True)
    if args.summary:
        args.summary.write_text(summary(args.out, ' '.join(sys.argv)))
    return 0


def summary(path: Path, command: str) -> str:
    """The recorded cases as Markdown: right on each engine, by kind, and the cases whose verdict differs."""
    records = [json.loads(line) for line in path.read_text().splitlines()]
    lines = ['# Study cases on this engine and on the other', '', f'Command: `{command}`', '',
             '| kind | cases | right here | right on the other | a rule acted |', '|---|---|---|---|---|']
    for kind in sorted({r['kind'] for r in records}):
        mine = [r for r in records if r['kind'] == kind]
        lines.append(f'| {kind} | {len(mine)} | {sum(r["right"] for r in mine)} | '
                     f'{sum(bool(r.get("before_right")) for r in mine)} | '
                     f'{sum(bool(r["fired"]["measured"]) for r in mine)} |')
    changed = [r for r in records if 'before' in r and (r['before']['verdict'], r['before']['named'])
               != (r['verdict'], r['named'])]
    lines += ['', f'{len(changed)} cases with a different verdict or named effects:', '']
    lines += [f'- {r["kind"]} {r["seed"]} ({", ".join(r["effects"])}): {r["before"]["verdict"]} '
              f'{r["before"]["named"]} -> {r["verdict"]} {r["named"]}' for r in changed]
    return '\n'.join(lines) + '\n'


if __name__ == '__main__':
    sys.exit(main())
