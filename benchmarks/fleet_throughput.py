#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Fleet assessment throughput: serial, ``--jobs 2`` processes and a local Dask cluster of 2 workers.

The fleet is the simulator's (``prsm-lube simulate --fleet 20 --days 10``: 20
actuators, one short recording a day each, 200 recordings of about 20 s, mcap
folders), calibrated on its reference recording.  Each mode assesses all 200
recordings with :func:`prsm_lube_ros.fleet.parallel.assess_bags` (read,
window, assess, SHA-256 of the files for the history), timed from the call to
the last outcome, best of ``--repeat``; the Dask time includes starting and
stopping the local cluster, as ``prsm-lube assess --scheduler local`` does.
Recording-hours are the spans from each recording's first window start to its
last window end.  The outcomes of the three modes are compared number by
number (``identical``).  Results go to ``benchmarks/results/fleet_throughput.{json,md}``.

Usage: ``python benchmarks/fleet_throughput.py [--repeat 2] [--data DIR]``
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import platform
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
sys.path.insert(0, str(ROOT))

MODES = (('serial', {'jobs': 1}), ('--jobs 2', {'jobs': 2}),
         ('Dask local, 2 workers', {'jobs': 2, 'scheduler': 'local'}))


def main(argv=None) -> int:
    """Simulate (or reuse) the fleet, time the three modes, write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--repeat', type=int, default=2)
    parser.add_argument('--data', default=None, help='folder for the fleet (kept; reused when it has one)')
    args = parser.parse_args(argv)
    from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
    from prsm_lube_ros.fleet.parallel import assess_bags, BagJob, outcomes_fingerprint
    from prsm_lube_ros.physics.actuator import load_actuator
    from prsm_lube_ros.simulation.fleet import FleetPlan, simulate_fleet
    data = Path(args.data) if args.data else Path(tempfile.mkdtemp(prefix='fleet_throughput_'))
    if not (data / 'truth.json').exists():
        simulate_fleet(data, fleet=FleetPlan(actuators=20, days=10), seed=0)
    bags = sorted(str(p) for p in data.glob('A*/*') if p.is_dir())
    lead = load_actuator(None).lead
    calibration = calibrate_recordings([recording_windows(data / 'reference', lead=lead)])
    job = BagJob(calibration, lead, hash_content=True)
    rows, prints = [], {}
    load_before = os.getloadavg()[0]
    for name, options in MODES:
        best = None
        for _ in range(args.repeat):
            start = time.perf_counter()
            outcomes = assess_bags(bags, job, **options)
            elapsed = time.perf_counter() - start
            best = elapsed if best is None else min(best, elapsed)
        prints[name] = outcomes_fingerprint(outcomes)
        hours = sum(o.assessment.windows[-1].window.end - o.assessment.windows[0].window.start
                    for o in outcomes if o.assessment) / 3600.0
        rows.append({'mode': name, 'recordings': len(bags), 'failed': sum(bool(o.error) for o in outcomes),
                     'recording_hours': hours, 'seconds': best, 'recording_hours_per_second': hours / best,
                     'recordings_per_second': len(bags) / best})
        print(f'{name:<24} {best:7.2f} s  {hours / best:6.3f} recording-h/s', file=sys.stderr, flush=True)
    startup = None
    for _ in range(args.repeat):     # what the Dask row spends on starting and stopping its cluster
        from distributed import Client, LocalCluster
        start = time.perf_counter()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            with Client(cluster) as client:
                client.submit(sum, [1, 2]).result()
        elapsed = time.perf_counter() - start
        startup = elapsed if startup is None else min(startup, elapsed)
    identical = len(set(prints.values())) == 1
    arguments = sys.argv[1:] if argv is None else argv
    result = {'command': 'python benchmarks/fleet_throughput.py ' + ' '.join(arguments),
              'machine': {'cpus': os.cpu_count(), 'python': platform.python_version(),
                          'platform': platform.platform()},
              'repeat': args.repeat, 'identical': identical, 'rows': rows,
              'dask_cluster_start_stop_seconds': startup,
              'load_average_1min': {'before': load_before, 'after': os.getloadavg()[0]}}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'fleet_throughput.json').write_text(json.dumps(result, indent=1))
    lines = ['# Fleet assessment throughput', '', f'`{result["command"]}` on {os.cpu_count()} CPUs, best of '
             f'{args.repeat}; {len(bags)} recordings of the simulated fleet (20 actuators x 10 days), '
             f'{rows[0]["recording_hours"]:.2f} recording-hours.', '',
             '| mode | s | recording-h/s | recordings/s | failed |', '|---|---|---|---|---|']
    lines += [f'| {r["mode"]} | {r["seconds"]:.2f} | {r["recording_hours_per_second"]:.3f} | '
              f'{r["recordings_per_second"]:.1f} | {r["failed"]} |' for r in rows]
    lines += ['', f'Load average of the machine (1 min) before and after: {load_before:.1f} and '
              f'{result["load_average_1min"]["after"]:.1f} (other jobs share its {os.cpu_count()} CPUs; with a '
              'load above the CPU count, extra processes cannot run in parallel).']
    lines += ['', f'Starting and stopping the local Dask cluster (2 worker processes) alone takes {startup:.2f} s '
              'of the Dask row.']
    lines += ['', f'Outcomes identical across the three modes (every theta, sigma, RMS, window and hash): '
              f'{"yes" if identical else "NO"}.']
    (RESULTS / 'fleet_throughput.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0 if identical else 1


if __name__ == '__main__':
    sys.exit(main())
