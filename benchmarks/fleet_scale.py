#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Fleet scale, whole process: ``prsm-lube assess`` serial, ``--jobs 2``, ``--scheduler local`` and an external one.

Two kinds of work, each at several sizes so that the start-up and the
per-recording cost of each mode can be told apart:

* short recordings: the fleet simulator's (``--fleet 100 --days 20``: one
  ~20 s recording a day per actuator, 2,000 in all), the first N of them;
* one-hour recordings: the rig simulator's endurance hour (4 kHz), N hard links
  to one simulated file (each is read, windowed, assessed and hashed in full;
  links keep the disk use at one hour).

Each run is the installed command as a user types it (``prsm-lube assess
PATHS --calibration C [--jobs 2 | --scheduler ...]``, stdout discarded), timed
from process start to exit.  The external scheduler is a ``dask scheduler``
and a ``dask worker --nworkers 2 --nthreads 1`` started once on localhost
before the timings (its start-up is not in them, as for a cluster that is
already running).  The whole grid is run ``--repeat`` times in turn and the
fastest of each cell kept (the machine is shared: a cell's time varies with
the load of other jobs).  Per mode and kind, a straight line ``seconds = start-up +
N x per-recording`` is fitted to the sizes; Dask overtakes serial from the N
where the lines cross, if the per-recording cost of Dask is the lower one.
Results: ``benchmarks/results/fleet_scale.{json,md}``.

Usage: ``python benchmarks/fleet_scale.py [--data DIR] [--short 100 500 2000] [--long 5 20 50] [--repeat 2]``
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import platform
import shutil
import socket
import subprocess
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'benchmarks'))


def command() -> list[str]:
    """The installed ``prsm-lube`` (as on PATH), else the repository's entry point script."""
    found = shutil.which('prsm-lube')
    return [found] if found else [sys.executable, str(ROOT / 'scripts' / 'prsm-lube')]


def short_fleet(data: Path) -> tuple[list[str], Path]:
    """The 2,000 short recordings (100 actuators x 20 days) and the fleet's reference recording."""
    fleet = data / 'fleet'
    if not (fleet / 'truth.json').exists():
        print('simulating 100 actuators x 20 days ...', file=sys.stderr, flush=True)
        subprocess.run(command() + ['simulate', str(fleet), '--fleet', '100', '--days', '20', '--seed', '5',
                                    '--storage', 'mcap-file'], check=True, stdout=subprocess.DEVNULL)
    bags = sorted(str(p) for p in fleet.glob('A*/*.mcap'))
    return sorted(bags, key=lambda p: Path(p).name), fleet / 'reference.mcap'


def long_recordings(data: Path, count: int) -> list[str]:
    """``count`` hard links to one simulated hour."""
    from read_memory import endurance_bag
    (hour,) = sorted(endurance_bag(data, 3600.0).glob('*.mcap'))
    links = data / 'hours'
    links.mkdir(exist_ok=True)
    paths = []
    for index in range(count):
        link = links / f'hour_{index:03d}.mcap'
        if not link.exists():
            os.link(hour, link)
        paths.append(str(link))
    return paths


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


def external_cluster(workers: int = 2) -> tuple[str, list[subprocess.Popen]]:
    """A ``dask scheduler`` and ``dask worker`` on localhost, waited for until the workers are in."""
    port = free_port()
    address = f'tcp://127.0.0.1:{port}'
    dask = [sys.executable, '-m', 'distributed.cli.dask_scheduler']
    logs = open(os.devnull, 'w')
    scheduler = subprocess.Popen(dask + ['--host', '127.0.0.1', '--port', str(port), '--dashboard-address', ':0'],
                                 stdout=logs, stderr=logs)
    worker = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_worker', address, '--nworkers',
                               str(workers), '--nthreads', '1', '--no-dashboard'], stdout=logs, stderr=logs)
    from distributed import Client
    with Client(address, timeout='60s') as client:
        client.wait_for_workers(workers, timeout=120)
    return address, [worker, scheduler]


def timed(paths: list[str], calibration: Path, options: list[str]) -> float:
    """Seconds of one whole ``prsm-lube assess`` process; raises if it fails."""
    start = time.perf_counter()
    done = subprocess.run(command() + ['assess', *paths, '--calibration', str(calibration), *options],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f'assess {options} failed: {done.stderr[-2000:]}')
    return elapsed


def line_fit(sizes: list[int], seconds: list[float]) -> dict:
    """Start-up (s) and per-recording cost (s) of ``seconds = a + b N``."""
    slope, intercept = np.polyfit(np.asarray(sizes, float), np.asarray(seconds, float), 1)
    return {'startup_seconds': float(intercept), 'seconds_per_recording': float(slope)}


def crossover(serial: dict, other: dict) -> float | None:
    """N from which ``other`` is faster than serial, None when its per-recording cost is not lower."""
    gain = serial['seconds_per_recording'] - other['seconds_per_recording']
    if gain <= 0:
        return None
    return max((other['startup_seconds'] - serial['startup_seconds']) / gain, 0.0)


def main(argv=None) -> int:
    """Simulate (or reuse) the recordings, time every mode and size, write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--data', default='/tmp/fleet_scale', help='folder for the recordings (kept, reused)')
    parser.add_argument('--short', type=int, nargs='+', default=[100, 500, 2000])
    parser.add_argument('--long', type=int, nargs='+', default=[5, 20, 50])
    parser.add_argument('--repeat', type=int, default=2, help='runs of the whole grid; the fastest of each cell')
    args = parser.parse_args(argv)
    data = Path(args.data)
    data.mkdir(parents=True, exist_ok=True)
    bags, reference = short_fleet(data)
    hours = long_recordings(data, max(args.long))
    calibration = data / 'calibration.yaml'
    if not calibration.exists():
        subprocess.run(command() + ['calibrate', str(reference), '--out', str(calibration)], check=True,
                       stdout=subprocess.DEVNULL)
    address, cluster = external_cluster()
    modes = {'serial': [], '--jobs 2': ['--jobs', '2'], '--scheduler local (2 workers)':
             ['--scheduler', 'local', '--jobs', '2'], '--scheduler external (2 workers)': ['--scheduler', address]}
    load_before = os.getloadavg()[0]
    cells: dict[tuple, dict] = {}
    try:
        for _ in range(args.repeat):
            for kind, paths, sizes in (('short', bags, args.short), ('one-hour', hours, args.long)):
                for size in sizes:
                    for mode, options in modes.items():
                        seconds = timed(paths[:size], calibration, options)
                        cell = cells.setdefault((kind, size, mode), {'kind': kind, 'recordings': size, 'mode': mode,
                                                                     'seconds': seconds, 'all_seconds': []})
                        cell['all_seconds'].append(seconds)
                        cell['seconds'] = min(cell['all_seconds'])
                        print(f'{kind:>8} {size:>5} {mode:<34} {seconds:8.2f} s', file=sys.stderr, flush=True)
    finally:
        for process in cluster:
            process.terminate()
            process.wait(timeout=30)
    write_results(args, list(cells.values()), modes, load_before, len(bags))
    return 0


def write_results(args, rows: list[dict], modes: dict, load_before: float, short_count: int) -> None:
    """JSON and Markdown of the timings, the fitted lines and the crossovers."""
    fits = {}
    for kind in ('short', 'one-hour'):
        for mode in modes:
            chosen = [r for r in rows if r['kind'] == kind and r['mode'] == mode]
            fits[f'{kind} | {mode}'] = line_fit([r['recordings'] for r in chosen], [r['seconds'] for r in chosen])
    result = {'command': 'python benchmarks/fleet_scale.py ' + ' '.join(sys.argv[1:]),
              'machine': {'cpus': os.cpu_count(), 'python': platform.python_version(),
                          'platform': platform.platform()},
              'load_average_1min': {'before': load_before, 'after': os.getloadavg()[0]},
              'rows': rows, 'fits': fits,
              'dask_wins_from': {key: crossover(fits[f'{key.split(" | ")[0]} | serial'], fit)
                                 for key, fit in fits.items() if 'scheduler' in key}}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'fleet_scale.json').write_text(json.dumps(result, indent=1))
    lines = ['# Fleet scale, whole process', '', f'`{result["command"]}` on {os.cpu_count()} CPUs; short: the first '
             f'N of {short_count} simulated fleet recordings (~20 s each); one-hour: N links to one simulated hour. '
             f'Seconds from process start to exit of `prsm-lube assess`, fastest of {args.repeat} (all runs in the '
             'JSON).', '', '| kind | N | mode | s | each run s |', '|---|---|---|---|---|']
    lines += [f'| {r["kind"]} | {r["recordings"]} | {r["mode"]} | {r["seconds"]:.1f} | '
              f'{", ".join(f"{t:.1f}" for t in r["all_seconds"])} |' for r in rows]
    lines += ['', '| kind and mode | start-up s | s per recording | Dask faster than serial from N |',
              '|---|---|---|---|']
    for key, fit in fits.items():
        wins = result['dask_wins_from'].get(key, '')
        wins = ('never (per-recording cost not lower)' if wins is None else f'{wins:.0f}') if key in \
            result['dask_wins_from'] else ''
        lines.append(f'| {key} | {fit["startup_seconds"]:.2f} | {fit["seconds_per_recording"]:.4f} | {wins} |')
    lines += ['', f'Load average (1 min) before and after: {load_before:.1f} and '
              f'{result["load_average_1min"]["after"]:.1f} on {os.cpu_count()} CPUs shared with other jobs.']
    (RESULTS / 'fleet_scale.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))


if __name__ == '__main__':
    sys.exit(main())
