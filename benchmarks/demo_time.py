#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How long ``prsm-lube demo`` takes (issue 22's goal: a few minutes at most on 2 cores), per step.

Runs the demo ``--repeats`` times as a child process (a fresh output folder each,
its own ROS domain, localhost discovery), reads the step times it prints
(``step N PASS (S s)``) and measures the whole wall time; writes
``benchmarks/results/demo_time.{json,md}`` with the machine's load average
before and after (other jobs share the CPUs).  The environment is the
workspace's (``source .env-jazzy.sh``), as ``tools/demo`` sets up; set-up
itself is not timed.

Usage: ``python benchmarks/demo_time.py [--repeats 2] [demo options, e.g. --actuators 6 --days 10]``
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import random
import re
import subprocess
import sys
import tempfile
import time

RESULTS = Path(__file__).resolve().parent / 'results'


def run_once(extra: list[str]) -> dict:
    """One demo in a fresh folder: exit status, wall s and the printed step times."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(random.randrange(100, 200)), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               MPLBACKEND='Agg')
    with tempfile.TemporaryDirectory(prefix='prsm_demo_time_') as folder:
        started = time.perf_counter()
        result = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'demo', '--out', folder, *extra],
                                capture_output=True, text=True, env=env)
        wall = time.perf_counter() - started
    steps = {int(n): float(s) for n, s in re.findall(r'^step (\d) \w+ \((\d+) s\)', result.stdout, re.M)}
    return {'status': result.returncode, 'wall_s': wall, 'steps_s': steps,
            'passed': 'DEMO: PASS' in result.stdout}


def main(argv=None) -> int:
    """Time the demo and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--repeats', type=int, default=2)
    args, extra = parser.parse_known_args(argv)
    load_before = os.getloadavg()[0]
    runs = [run_once(extra) for _ in range(args.repeats)]
    load_after = os.getloadavg()[0]
    command = 'python benchmarks/demo_time.py ' + ' '.join(argv if argv is not None else sys.argv[1:])
    lines = ['# prsm-lube demo: wall time per step', '', f'`{command}` on {os.cpu_count()} CPUs, '
             f'{args.repeats} runs; load average (1 min) before and after: {load_before:.1f} and {load_after:.1f} '
             '(other jobs share the CPUs).', '',
             '| run | passed | step 1 s | step 2 s | step 3 s | step 4 s | whole demo s |',
             '|---|---|---|---|---|---|---|']
    for i, run in enumerate(runs, start=1):
        cells = ' | '.join(f'{run["steps_s"].get(n, float("nan")):.0f}' for n in range(1, 5))
        lines.append(f'| {i} | {"yes" if run["passed"] else "NO"} | {cells} | {run["wall_s"]:.0f} |')
    text = '\n'.join(lines) + '\n'
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / 'demo_time.md').write_text(text)
    (RESULTS / 'demo_time.json').write_text(json.dumps({'command': command, 'load_before': load_before,
                                                        'load_after': load_after, 'runs': runs}, indent=1))
    print(text)
    return 0 if all(run['passed'] for run in runs) else 1


if __name__ == '__main__':
    sys.exit(main())
