#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""kill -9 against the history and ``calibrate --out``: what a plain DuckDB read sees after each kill.

History: a writer process adds, re-assesses and moves (to another actuator
id) recordings in a loop, each with 2 runs and 600 windows, through
:func:`prsm_lube_ros.fleet.history.add_assessment`; it is killed with SIGKILL
at a random moment (uniform over 0.05-1.5 s after it starts writing), ``--kills``
times on the same history.  After every kill plain DuckDB reads
``runs/*/*.parquet`` and ``windows/*/*.parquet`` (layout 4, no package code)
and counts duplicate rows (a recording's run or window twice) and half-written
recordings (a content hash or assessment time in one table and not the other,
or runs without their windows: each table is renamed into place on its own,
so a kill between the two renames of one commit leaves the windows one
assessment ahead until the next writer).  The next writer must leave no stale
temporary of a killed one.

Calibration: a writer calls :func:`save_calibration` on one ``--out`` path in a
loop and is killed the same way; after every kill the file must load, and
after the next writer has started, no temporary of a killed writer remains.

Results: ``benchmarks/results/history_kill.{json,md}``.
Usage: ``python benchmarks/history_kill.py [--kills 100] [--seed 0]``
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path
import random
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
sys.path.insert(0, str(ROOT))

HISTORY_WRITER = '''
import datetime, random, sys
sys.path.insert(0, {root!r})
from prsm_lube_ros.estimation.assessment import RunAssessment, WindowAssessment
from prsm_lube_ros.estimation.pipeline import RecordingAssessment
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.atomic_file import remove_stale
from prsm_lube_ros.fleet.history import add_assessment, STAGING
from pathlib import Path
history, rng = Path({history!r}), random.Random({seed})
remove_stale(history / STAGING)
start = datetime.datetime(2026, 3, 4, tzinfo=datetime.timezone.utc).timestamp()
def assessment(number, theta):
    windows, runs = [], []
    for run in (1, 2):
        for k in range(300):
            t = start + 86400 * number + 1000 * run + k
            windows.append(WindowAssessment(Window(t, t + 1, 1.5, 4000, 1.0, 20.9, 0.01, 200.0, 30.0, 0.05, 1.0,
                                                   run), theta, 0.01))
        runs.append(RunAssessment(f'r{{number}}.mcap', run, start + 86400 * number + 1000 * run,
                                  start + 86400 * number + 1000 * run + 300, 20.9, 200.0, 1.5, theta, 0.005, 300, 30))
    return RecordingAssessment(f'r{{number}}.mcap', windows, runs)
print('ready', flush=True)
while True:
    number = rng.randrange(12)
    add_assessment(history, assessment(number, rng.random()), actuator_id=rng.choice(['A', 'B']),
                   content=f'{{number:016x}}' + '0' * 48, calibration='c')
'''

CALIBRATION_WRITER = '''
import sys
sys.path.insert(0, {root!r})
from prsm_lube_ros.estimation.calibration_file import load_calibration, save_calibration
calibration = load_calibration({source!r})
print('ready', flush=True)
while True:
    save_calibration(calibration, {out!r})
'''


def run_killed(script: str, rng: random.Random) -> None:
    """Start ``script``, wait for its ``ready`` line, SIGKILL it at a random moment of its writing loop."""
    process = subprocess.Popen([sys.executable, '-c', script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    if process.stdout.readline().strip() != 'ready':
        raise RuntimeError(process.stderr.read()[-2000:])
    time.sleep(rng.uniform(0.05, 1.5))
    process.kill()
    process.wait()


def plain_read(history: Path) -> dict:
    """Duplicate rows and half-written recordings as plain DuckDB sees them."""
    import duckdb
    table = {name: f"read_parquet('{history}/{name}/*/*.parquet', hive_partitioning = true)"
             for name in ('runs', 'windows')}
    if not list(history.glob('runs/*/*.parquet')) or not list(history.glob('windows/*/*.parquet')):
        return {'recordings': 0, 'duplicate_rows': 0, 'half_written': 0}
    duplicates = 0
    for name, key in (('runs', 'run_index'), ('windows', 'start')):
        duplicates += duckdb.sql(f'select count(*) from (select content_hash, {key} from {table[name]} '
                                 'group by all having count(*) > 1)').fetchall()[0][0]
    pairs = {name: set(duckdb.sql(f'select distinct content_hash, assessed_at from {table[name]}').fetchall())
             for name in table}
    return {'recordings': len(pairs['runs']), 'duplicate_rows': duplicates,
            'half_written': len(pairs['runs'] ^ pairs['windows'])}


def history_trials(work: Path, kills: int, rng: random.Random) -> dict:
    """``kills`` killed writers on one history; the worst seen after any of them."""
    history = work / 'history'
    worst = {'duplicate_rows': 0, 'half_written': 0, 'stale_after_next_writer': 0,
             'kills_that_left_a_staged_folder': 0}
    for trial in range(kills):
        run_killed(HISTORY_WRITER.format(root=str(ROOT), history=str(history), seed=trial), rng)
        worst['kills_that_left_a_staged_folder'] += bool(list((history / '.staging').glob('*')))
        seen = plain_read(history)
        worst['duplicate_rows'] = max(worst['duplicate_rows'], seen['duplicate_rows'])
        worst['half_written'] = max(worst['half_written'], seen['half_written'])
    from prsm_lube_ros.atomic_file import remove_stale
    from prsm_lube_ros.fleet.history import STAGING
    remove_stale(history / STAGING)                 # what the next writer does first
    worst['stale_after_next_writer'] = len(list((history / STAGING).glob('*')))
    worst['recordings_at_end'] = plain_read(history)['recordings']
    return worst


def calibration_trials(work: Path, kills: int, rng: random.Random) -> dict:
    """``kills`` killed ``save_calibration`` loops on one ``--out``."""
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    source = work / 'source.yaml'
    subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'simulate', str(work / 'rig'), '--seed', '1'],
                   check=True, stdout=subprocess.DEVNULL)
    subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'calibrate', str(work / 'rig' / 'stage_3'),
                    '--out', str(source)], check=True, stdout=subprocess.DEVNULL)
    out = work / 'out' / 'calibration.yaml'
    unreadable, most_left = 0, 0
    for _ in range(kills):
        run_killed(CALIBRATION_WRITER.format(root=str(ROOT), source=str(source), out=str(out)), rng)
        try:
            load_calibration(out)
        except Exception:  # noqa: BLE001 -- counted, the point of the trial
            unreadable += 1
        most_left = max(most_left, len(list(out.parent.glob('.*.tmp'))))
    subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'calibrate', str(work / 'rig' / 'stage_3'),
                    '--out', str(out)], check=True, stdout=subprocess.DEVNULL)
    return {'unreadable_after_a_kill': unreadable, 'temporaries_left_by_a_kill_at_most': most_left,
            'temporaries_after_the_next_calibrate_out': len(list(out.parent.glob('.*.tmp')))}


def main(argv=None) -> int:
    """Run both trials, write the results; status 1 if a plain read ever saw a duplicate or half a recording."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--kills', type=int, default=100)
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    work = Path(tempfile.mkdtemp(prefix='history_kill_'))
    try:
        history = history_trials(work, args.kills, rng)
        calibration = calibration_trials(work, args.kills, rng)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    result = {'command': 'python benchmarks/history_kill.py ' + ' '.join(sys.argv[1:] if argv is None else argv),
              'kills': args.kills, 'history': history, 'calibrate_out': calibration}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'history_kill.json').write_text(json.dumps(result, indent=1))
    lines = ['# kill -9 against the history and calibrate --out', '', f'`{result["command"]}`: {args.kills} '
             'SIGKILLs of each writer at a random moment (0.05-1.5 s into its writing loop).', '',
             '| what | value |', '|---|---|']
    lines += [f'| history: {key.replace("_", " ")} | {value} |' for key, value in history.items()]
    lines += [f'| calibrate --out: {key.replace("_", " ")} | {value} |' for key, value in calibration.items()]
    (RESULTS / 'history_kill.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    clean = history['duplicate_rows'] == history['half_written'] == history['stale_after_next_writer'] == 0
    return 0 if clean and calibration['temporaries_after_the_next_calibrate_out'] == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
