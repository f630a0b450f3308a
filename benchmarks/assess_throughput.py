#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Assessment throughput on a one-hour 4 kHz recording, beside the bare read, and peak memory.

The recordings are the rig simulator's endurance bags (the six conditions of
the paper cycled, rewinds included): 4 kHz acceleration in 0.1 s blocks,
joint states at 100 Hz, load at 50 Hz, temperature at 1 Hz, storage mcap.
Each measurement runs in a fresh subprocess so its peak resident memory
(``VmHWM``; ``ru_maxrss`` would carry over the parent's peak) is its own:

* ``bare read``: every message read, decompressed and split, nothing decoded
  (:func:`prsm_lube_ros.recording.reader.bare_read`);
* ``assess``: what ``prsm-lube assess`` does -- read, decode, window, assess
  every window and run with a calibration fitted beforehand.

Both are timed best of ``--repeat``.  Then whole processes, as a user feels
them (interpreter start-up and imports included), best of ``--repeat``:
``prsm-lube --help``, ``prsm-lube assess BAG --calibration C --json OUT`` on
the hour, and beside it the obvious alternative, a short rosbags script that
reads and deserializes the same vibration messages and does less
(``benchmarks/rosbags_baseline.py``).  A 15-minute and a one-hour recording are
assessed so flat memory shows as equal peaks; the hour is measured again with
zstd chunk compression, where the bare read includes decompression.  Results go to
``benchmarks/results/assess_throughput.{json,md}``.

Usage: ``python benchmarks/assess_throughput.py [--repeat 3] [--data DIR]``
"""
from __future__ import annotations

import argparse
import json
import os
import platform
from pathlib import Path
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'


def child(kind: str, bag: str, calibration: str) -> None:
    """Run one measurement in this process and print a JSON line."""
    sys.path.insert(0, str(ROOT))
    from read_memory import peak_rss_mib   # beside this file
    from prsm_lube_ros.physics.actuator import Actuator
    from prsm_lube_ros.estimation.pipeline import assess_recording, recording_windows
    from prsm_lube_ros.recording.reader import bare_read
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    from prsm_lube_ros.recording.typestore import contract_typestore
    # One-time set-up of a process (the ROS type store the layout checks use): timed apart,
    # so the figures below are throughput on the recording itself.
    setup_start = time.perf_counter()
    contract_typestore()
    setup = time.perf_counter() - setup_start
    start = time.perf_counter()
    if kind == 'bare':
        messages = bare_read(bag)
        detail = {'messages': messages}
    else:
        calib = load_calibration(calibration)
        windows = recording_windows(bag, lead=Actuator().lead)
        result = assess_recording(windows, calib)
        detail = {'windows': len(result.windows), 'runs': len(result.runs),
                  'assessed_runs': sum(1 for r in result.runs if not r.reason)}
    elapsed = time.perf_counter() - start
    peak_mib = peak_rss_mib()
    print(json.dumps({'kind': kind, 'seconds': elapsed, 'setup_seconds': setup, 'peak_rss_mib': peak_mib,
                      **detail}))


def measure(kind: str, bag: Path, calibration: Path, repeat: int) -> dict:
    """Best of ``repeat`` fresh subprocesses."""
    from read_memory import best_of_children   # beside this file
    return best_of_children([sys.executable, __file__, '--child', kind, str(bag), str(calibration)], repeat)


def whole_process(argv: list[str], repeat: int) -> float:
    """Best wall time of ``repeat`` runs of ``argv`` as a fresh process, start to exit, s."""
    best = float('inf')
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True, cwd=ROOT)
        best = min(best, time.perf_counter() - start)
    return best


def prepare(data: Path) -> tuple[dict, Path]:
    """Simulate (once) the recordings and a calibration; return {label: (bag, seconds)}, calibration."""
    sys.path.insert(0, str(ROOT))
    from prsm_lube_ros.physics.actuator import Actuator
    from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
    from prsm_lube_ros.estimation.calibration_file import save_calibration
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    from read_memory import endurance_bag   # beside this file
    from prsm_lube_ros.simulation.rig_config import ExperimentPlan
    data.mkdir(parents=True, exist_ok=True)
    bags = {}
    for label, seconds, compression in (('15 min', 900.0, None), ('1 h', 3600.0, None),
                                        ('1 h, zstd chunks', 3600.0, 'zstd')):
        bags[label] = (endurance_bag(data, seconds, compression=compression), seconds)
    calibration = data / 'calibration.yaml'
    if not calibration.exists():
        reference = data / 'reference'
        if not reference.exists():
            simulate_experiment(reference, seed=2, plan=ExperimentPlan(stage_thetas=(1.0,)))
        windows = recording_windows(reference / 'stage_1', lead=Actuator().lead)
        save_calibration(calibrate_recordings([windows]), calibration)
    return bags, calibration


def main() -> int:
    """Measure, write the results, print the table."""
    if len(sys.argv) > 1 and sys.argv[1] == '--child':
        child(*sys.argv[2:5])
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--data', type=Path, default=Path('/tmp/prsm_lube_bench'),
                        help='where the simulated recordings are cached (default /tmp/prsm_lube_bench)')
    args = parser.parse_args()
    bags, calibration = prepare(args.data)
    rows = []
    for label, (bag, seconds) in bags.items():
        size = sum(p.stat().st_size for p in bag.rglob('*') if p.is_file())
        bare = measure('bare', bag, calibration, args.repeat)
        assess = measure('assess', bag, calibration, args.repeat)
        rows.append({'recording': label, 'duration_s': seconds, 'size_mib': size / 2 ** 20,
                     'bare_read_s': bare['seconds'], 'assess_s': assess['seconds'],
                     'assess_x_realtime': seconds / assess['seconds'],
                     'bare_x_realtime': seconds / bare['seconds'],
                     'assess_over_bare': assess['seconds'] / bare['seconds'],
                     'bare_peak_rss_mib': bare['peak_rss_mib'], 'assess_peak_rss_mib': assess['peak_rss_mib'],
                     'setup_s': assess['setup_seconds'],
                     'messages': bare['messages'], 'windows': assess['windows'],
                     'assessed_runs': assess['assessed_runs']})
    hour = next(r for r in rows if r['recording'] == '1 h')
    hour_bag = bags['1 h'][0]
    cli = [sys.executable, '-m', 'prsm_lube_ros.cli']
    processes = {
        'prsm-lube --help': whole_process(cli + ['--help'], args.repeat),
        'prsm-lube assess (1 h)': whole_process(cli + ['assess', str(hour_bag), '--calibration', str(calibration),
                                                       '--json', str(args.data / 'assess.json')], args.repeat),
        'rosbags script (1 h)': whole_process([sys.executable, str(ROOT / 'benchmarks' / 'rosbags_baseline.py'),
                                               str(hour_bag)], args.repeat),
    }
    document = {'benchmark': 'assess_throughput', 'command': 'python benchmarks/assess_throughput.py',
                'machine': {'python': platform.python_version(), 'processor': platform.processor() or
                            platform.machine(), 'cpus': _cpus(), 'load_average_1min_at_end': os.getloadavg()[0]},
                'repeat': args.repeat, 'rows': rows, 'whole_process_s': processes,
                'goals': {'assess_x_realtime >= 5000': hour['assess_x_realtime'] >= 5000,
                          'assess_over_bare <= 2': hour['assess_over_bare'] <= 2.0,
                          'prsm-lube --help < 0.2 s': processes['prsm-lube --help'] < 0.2,
                          'prsm-lube assess faster than the rosbags script':
                              processes['prsm-lube assess (1 h)'] < processes['rosbags script (1 h)']}}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'assess_throughput.json').write_text(json.dumps(document, indent=1))
    lines = ['# Assessment throughput (`python benchmarks/assess_throughput.py`)', '',
             f'Python {document["machine"]["python"]}, {document["machine"]["cpus"]} CPUs, 1-min load average '
             f'{document["machine"]["load_average_1min_at_end"]:.1f} at the end, best of {args.repeat}.',
             'Times exclude the one-time set-up of a process (building the ROS type store for the layout '
             'checks), shown apart.', '',
             '| recording | size MiB | bare read s | assess s | assess x real time | assess / bare '
             '| peak RSS bare MiB | peak RSS assess MiB | one-time set-up s |', '|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        lines.append(f'| {r["recording"]} | {r["size_mib"]:.0f} | {r["bare_read_s"]:.3f} | {r["assess_s"]:.3f} | '
                     f'{r["assess_x_realtime"]:.0f} | {r["assess_over_bare"]:.2f} | {r["bare_peak_rss_mib"]:.0f} | '
                     f'{r["assess_peak_rss_mib"]:.0f} | {r["setup_s"]:.3f} |')
    lines += ['', f'Whole processes, start to exit, best of {args.repeat}:', '', '| command | s |', '|---|---|']
    lines += [f'| {name} | {seconds:.3f} |' for name, seconds in processes.items()]
    lines += ['', 'Goals: ' + ', '.join(
        f'{goal}: {"met" if ok else "NOT met"}' for goal, ok in document['goals'].items())]
    (RESULTS / 'assess_throughput.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


def _cpus() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else os.cpu_count()


if __name__ == '__main__':
    sys.exit(main())
