#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Recorded study cases diagnosed by two checkouts' engines on the very same window tables, where a change can act.

``engine_ab_cases.py`` wraps a rule of this tree to see where it acts; this
command serves a change of the evidence a rule reads (a share, a spectral
line left out, a form added), where that cannot be wrapped.  Each case of the
``--cases`` file (lines ``KIND SEED``, as the study's ``results.json``
names them) is simulated once with ``--after``'s code (the simulators are the
same in both) and its window table pickled in ``--cache``.  ``--where`` says
when the change can act, read on the table by each checkout's code, any of:
``defect`` (the surface defect's evidence for it, exclusive or against it reads
differently on the two; it has evidence, so its forms are fitted; or the
spectrum holds a line fixed in Hz), ``mode-bands`` (the spectrum holds a mode
band, measured against the recorded mean square), ``unphysical`` (the paper's model fits with
unphysical constants) or ``always``.  There both
engines diagnose the table in their own process; elsewhere the two take the
same path by construction.  One JSON line per case in ``--out``
(appended: a stopped run goes on), and ``--summary`` writes what changed.

Usage: ``python benchmarks/engine_ab_tables.py --before CHECKOUT --after CHECKOUT --cases FILE --cache DIR
--where defect mode-bands --out FILE.jsonl --summary FILE.md [--jobs 2]`` (after ``source .env-jazzy.sh``).
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
import os
from pathlib import Path
import pickle
import subprocess
import sys

SIMULATE = '''
import pickle, shutil, sys, tempfile
from pathlib import Path
from prsm_lube_ros.diagnosis.effects import candidate_ids
from prsm_lube_ros.experiments.random_study import case_recordings, case_table, simulate_case
kind, seed, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
folder = Path(tempfile.mkdtemp(prefix='ab_'))
try:
    paths, setup, names, truth = simulate_case(kind, seed, list(candidate_ids()), folder=folder)
    table = case_table(paths, case_recordings(paths, setup))
finally:
    shutil.rmtree(folder, ignore_errors=True)
Path(out).write_bytes(pickle.dumps({'table': table, 'names': names, 'truth': truth}))
'''
WHERE = '''
import json, pickle, sys
from prsm_lube_ros.diagnosis.effects.surface_defect import SurfaceDefectCandidate
from prsm_lube_ros.diagnosis.locate import spectral_lines
wheres, table = sys.argv[1].split(','), pickle.load(open(sys.argv[2], 'rb'))['table']
defect, lines = SurfaceDefectCandidate(), spectral_lines(table)
out = {}
if 'defect' in wheres:
    out.update(evidence=bool(defect.independent_evidence(table, None)),
               exclusive=bool(defect.exclusive_evidence(table, 0.5)),
               contrary=bool(defect.contrary_evidence(table, None)), fixed_lines=bool(lines.frequencies))
if 'mode-bands' in wheres:
    out.update(mode_bands=bool(lines.mode_frequencies))
if 'unphysical' in wheres:
    from prsm_lube_ros.diagnosis.fitting import fit_model
    out.update(unphysical=bool(fit_model(table, None, folds=[]).unphysical()))
if 'always' in wheres:
    out.update(always=True)
print(json.dumps(out))
'''
DIAGNOSE = '''
import json, pickle, sys
from prsm_lube_ros.diagnosis.engine import diagnose_table
from prsm_lube_ros.experiments.random_study import _named_effects
result = diagnose_table(pickle.load(open(sys.argv[1], 'rb'))['table'])
print(json.dumps({'verdict': str(result.verdict),
                  'named': _named_effects(json.loads(json.dumps(result.as_json(), default=float)))}))
'''


def _run(code: Path, program: str, *args: str) -> str:
    """``program`` run by ``code``'s package in a fresh interpreter (outside any checkout); its last output line."""
    done = subprocess.run([sys.executable, '-c', program, *args], capture_output=True, text=True, cwd='/',
                          env={**os.environ, 'PYTHONPATH': str(code)})
    if done.returncode:
        raise RuntimeError(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else 'failed')
    lines = done.stdout.strip().splitlines()
    return lines[-1] if lines else ''


def one_case(job: tuple) -> dict:
    """Simulate (once), test where the change can act, and diagnose with both engines there."""
    (kind, seed), before, after, cache, where = job
    table = cache / f'{kind}_{seed}.pkl'
    record: dict = {'kind': kind, 'seed': seed}
    try:
        if not table.exists():
            _run(after, SIMULATE, kind, str(seed), str(table) + '.part')
            os.replace(str(table) + '.part', table)
        record['names'] = sorted(pickle.loads(table.read_bytes())['names'])
        record['where'] = {side: json.loads(_run(code, WHERE, ','.join(where), str(table)))
                           for side, code in (('before', before), ('after', after))}
        before_reads, after_reads = record['where']['before'], record['where']['after']
        acting = ('evidence', 'fixed_lines', 'mode_bands', 'unphysical', 'always')
        if before_reads != after_reads or any(after_reads.get(k) or before_reads.get(k) for k in acting):
            for side, code in (('before', before), ('after', after)):
                record[side] = json.loads(_run(code, DIAGNOSE, str(table)))
    except Exception as exc:     # one case's failure is recorded on its line; the others go on
        record['error'] = f'{type(exc).__name__}: {exc}'
    return record


def _right(kind: str, names: list[str], result: dict) -> bool:
    """As the study scores: every concealed effect named ('adequate' where none is)."""
    return result['verdict'] == 'adequate' if kind == 'none' else set(names) <= set(result['named'])


def summary(path: Path, command: str) -> str:
    """The cases as Markdown: how many were diagnosed by both, each whose verdict or named effects changed."""
    latest = {(r['kind'], r['seed']): r for r in map(json.loads, path.read_text().splitlines())}
    records = list(latest.values())      # a case tried again after an error: its last line
    both = [r for r in records if 'before' in r]
    changed = [r for r in both if (r['before']['verdict'], r['before']['named'])
               != (r['after']['verdict'], r['after']['named'])]
    lines = ['# Recorded study cases on two engines', '', f'Command: `{command}`', '',
             f'{len(records)} cases; {len(both)} where the change can act, diagnosed by both engines on the same '
             f'table (elsewhere the two take the same path); {sum("error" in r for r in records)} errors; '
             f'{len(changed)} changed.', '', '| case | concealed | before | after | |', '|---|---|---|---|---|']
    for r in changed:
        words = [f"{r[s]['verdict']} ({', '.join(r[s]['named']) or '-'})" for s in ('before', 'after')]
        score = ' -> '.join('right' if _right(r['kind'], r['names'], r[s]) else 'miss' for s in ('before', 'after'))
        lines.append(f"| {r['kind']} {r['seed']} | {', '.join(r['names']) or 'none'} | {words[0]} | {words[1]} | "
                     f'{score} |')
    return '\n'.join(lines) + '\n'


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--before', type=Path, required=True, help='checkout of the engine before the change')
    parser.add_argument('--after', type=Path, required=True, help='checkout of the engine after it')
    parser.add_argument('--cases', type=Path, required=True, help='lines KIND SEED')
    parser.add_argument('--cache', type=Path, required=True, help='folder of the pickled window tables')
    parser.add_argument('--where', nargs='+', choices=('defect', 'mode-bands', 'unphysical', 'always'), required=True)
    parser.add_argument('--out', type=Path, required=True, help='JSON lines, one a case (appended)')
    parser.add_argument('--summary', type=Path, default=None)
    parser.add_argument('--jobs', type=int, default=2)
    args = parser.parse_args(argv)
    args.cache.mkdir(parents=True, exist_ok=True)
    cases = [(kind, int(seed)) for kind, seed in (line.split() for line in args.cases.read_text().splitlines()
                                                  if line.strip())]
    done = set()
    if args.out.exists():
        done = {(r['kind'], r['seed']) for r in map(json.loads, args.out.read_text().splitlines())
                if 'error' not in r}      # a case that failed is tried again
    jobs = [(case, args.before.resolve(), args.after.resolve(), args.cache.resolve(), args.where)
            for case in cases if case not in done]
    with ProcessPoolExecutor(args.jobs) as pool, args.out.open('a') as out:
        for record in pool.map(one_case, jobs):
            out.write(json.dumps(record) + '\n')
            out.flush()
            print(record['kind'], record['seed'], record.get('before', ''), '->', record.get('after', ''),
                  record.get('error', ''), flush=True)
    if args.summary:
        args.summary.write_text(summary(args.out, 'python benchmarks/engine_ab_tables.py ' + ' '.join(sys.argv[1:])))
    return 0


if __name__ == '__main__':
    sys.exit(main())
