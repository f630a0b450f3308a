#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""CPU time the live estimator spends per actuator-second in its window path, without ROS: robust to a busy machine.

``live_latency.py`` measures the node on a real graph, but on a shared
machine its capacity moves with whatever else runs on the core.  This
measures only what the estimator does with one 4 kHz actuator's inputs (the
same stream as ``live_latency.py``: 0.1 s blocks, joint states 100 Hz, load
50 Hz, temperature 1 Hz, 20 rad/s and 150 N, 1 s windows), in process CPU
time (``time.process_time``, which other processes do not inflate): the
window builder, the assessment of each window and, when the node has it, the
surface defect screen of its last windows (``LubricationEstimator._screen``;
the node's Assessor then leaves out each window's own screen).
Three calibrations as in ``live_latency.py``: raw RMS (no indicators), band
(indicators computed), band and baseline (indicators and screen).

Usage: ``python benchmarks/live_window_cost.py [--seconds 120] [--repeat 3] [--name live_window_cost]
[--code CHECKOUT]`` (``--code``: the code of another checkout, e.g. a worktree of main, measured by this file)
(after ``source .env-jazzy.sh``); the best of the repeats per configuration goes to
``benchmarks/results/<name>.{json,md}``.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path
import platform
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'benchmarks'))

from results_files import write_results  # noqa: E402  (beside this file)


def stream(seconds: float):
    """One actuator's input batches in stamp order, as the node takes them: every 0.1 s the joint states, loads
    and temperatures queued meanwhile (drained and joined into one batch each), then the vibration block."""
    import numpy as np
    from live_latency import BLOCK, LOAD, RATE, SPEED
    from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch
    rng = np.random.default_rng(0)
    size = int(RATE * BLOCK)
    blocks = [(rng.standard_normal(size) * 0.5).astype(np.float32) for _ in range(10)]
    t0 = 1767225600.0
    items = []
    for block in range(1, int(round(seconds / BLOCK))):
        ticks = np.arange((block - 1) * 10, block * 10)
        t = t0 + ticks * 0.01
        items.append(ScrewStateBatch(t, SPEED * ticks * 0.01, np.full(ticks.size, SPEED)))
        items.append(AxialLoadBatch(t[::2], np.full(t[::2].size, -LOAD)))
        if block % 10 == 1:
            items.append(TemperatureBatch(t[:1], np.array([31.0])))
        items.append(VibrationBatch.single(t0 + block * BLOCK - BLOCK, RATE, blocks[block % 10]))
    return items


def cost(items, mode: str, seconds: float) -> dict:
    """CPU ms per actuator-second of the window path in ``mode`` ('raw', 'indicators', 'screen')."""
    from live_latency import benchmark_calibration
    from prsm_lube_ros.estimation.assessment import Assessor
    from prsm_lube_ros.estimation.windowing import WindowBuilder, WindowSettings
    calibration = benchmark_calibration(raw_band=mode == 'raw')
    settings = WindowSettings(band=calibration.band)
    builder = WindowBuilder(settings, lead=0.005)
    assessor = Assessor(calibration)
    monitor = None
    if mode == 'screen':      # as the node does it: the pooled screen of its last windows beside the Assessor
        from prsm_lube_ros.estimation.surface_health import SurfaceMonitor
        monitor = SurfaceMonitor(settings.defect_orders)
        monitor.set_baseline(calibration.condition_baseline)
    windows = 0
    start = time.process_time()
    for batch in items:
        builder.add(batch)
        if type(batch).__name__ == 'VibrationBatch':
            for window in builder.pop_closed():
                if monitor is not None and window.steady:
                    monitor.observe(window.condition, window.end)
                assessor.assess_window(window)
                windows += 1
    used = time.process_time() - start
    return {'mode': mode, 'cpu_ms_per_actuator_second': 1e3 * used / seconds, 'windows': windows}


def main(argv=None) -> int:
    """Measure the three configurations and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=120.0, help='s of one actuator\'s stream')
    parser.add_argument('--repeat', type=int, default=3, help='repeats per configuration (the best is kept)')
    parser.add_argument('--name', default='live_window_cost', help='results file name in benchmarks/results')
    parser.add_argument('--code', default='', metavar='CHECKOUT',
                        help='measure the code of this checkout (e.g. a worktree of main) instead of this one\'s')
    args = parser.parse_args(argv)
    if args.code:       # before anything imports the package
        sys.path.insert(0, str(Path(args.code).resolve()))
    items = stream(args.seconds)
    try:
        import prsm_lube_ros.estimation.surface_health  # noqa: F401
        modes = ('raw', 'indicators', 'screen')
    except ImportError:                      # a checkout from before the live screen
        modes = ('raw', 'indicators')
    rows = []
    for mode in modes:
        best = min((cost(items, mode, args.seconds) for _ in range(args.repeat)),
                   key=lambda r: r['cpu_ms_per_actuator_second'])
        rows.append(best)
        print(f'{mode}: {best["cpu_ms_per_actuator_second"]:.2f} ms CPU per actuator-second '
              f'({best["windows"]} windows)', flush=True)
    commit = subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], cwd=args.code or ROOT, capture_output=True,
                            text=True)
    results = {'python': f'Python {platform.python_version()}', 'commit': commit.stdout.strip() or '?',
               'seconds': args.seconds, 'repeat': args.repeat, 'rows': rows}
    words = {'raw': 'raw RMS (no indicators)',
             'indicators': "band: condition indicators per window, each window screened alone (main's node)",
             'screen': 'band and baseline: indicators, the pooled screen of the last 10 windows (the node now)'}
    lines = ['# Live estimator window path: CPU per actuator-second (`python benchmarks/live_window_cost.py`)', '',
             f'{results["python"]}, commit {results["commit"]}; one 4 kHz actuator, {args.seconds:g} s of stream as '
             'in live_latency.py, process CPU time, best of '
             f'{args.repeat}. Window builder, assessment and (where present) the surface screen; no ROS, no DDS.', '',
             '| calibration | CPU ms per actuator-second | share of one core per 50 actuators |', '|---|---|---|']
    lines += [f'| {words[r["mode"]]} | {r["cpu_ms_per_actuator_second"]:.2f} | '
              f'{5 * r["cpu_ms_per_actuator_second"]:.1f} % |' for r in rows]
    write_results(args.name, results, lines)
    return 0 if all(math.isfinite(r['cpu_ms_per_actuator_second']) for r in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
