# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube demo``: the whole product in five steps, each checked against the simulator's truth.

1. the paper's experiment (:mod:`prsm_lube_ros.experiments.paper_demo`);
2. both nodes on a live graph, the calibrate service called
   (:func:`.demo_steps.live_step`);
3. a concealed physical effect found by ``diagnose`` (:func:`.demo_steps.diagnosis_step`);
4. a small fleet's history, trend and forecast (:func:`.demo_steps.fleet_step`);
5. a surface defect told from an oil loss (:func:`.demo_defect.defect_step`).

``--quick`` runs step 1 only.  ``<out>/index.html`` ties the figures and
tables together; the exit status is 0 only when every step's check passes.
"""
from __future__ import annotations

import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable
    from pathlib import Path

    from .demo_steps import StepResult


__all__ = ['add_command', 'run']


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``demo`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'demo', help='the whole product in five checked steps: paper, live graph, concealed physics, fleet, '
        'surface defect',
        description='1: simulate the paper\'s experiment, calibrate on the third lubrication stage, assess the '
        'first two (table and figures like the paper\'s Fig. 5); 2: the sensor bridge and the estimator live, '
        'the calibrate service called; 3: an effect concealed in a recording found by diagnose; 4: a small '
        'fleet\'s history, trend and forecast; 5: a surface defect told from an oil loss. Each step is checked '
        'against the simulator\'s truth; '
        '<out>/index.html shows them all.')
    parser.add_argument('--out', default='out/demo', help='output folder (default out/demo)')
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--stages', type=float, nargs=3, default=(0.72, 0.83, 1.0), metavar='THETA',
                        help='true theta_oil of the three lubrication stages (default 0.72 0.83 1.0)')
    parser.add_argument('--window', type=float, default=1.0, metavar='S', help='window length in s')
    parser.add_argument('--storage', choices=('mcap', 'sqlite3', 'mcap-file'), default='mcap')
    parser.add_argument('--quick', action='store_true', help='step 1 only (the paper\'s experiment)')
    parser.add_argument('--playback-rate', type=float, default=10.0, metavar='X',
                        help='step 2: the bridge replays X times faster than real time (default 10)')
    parser.add_argument('--live-windows', type=int, default=12, metavar='N',
                        help='step 2: windows of theta_Oil watched before and after the calibration (default 12)')
    parser.add_argument('--actuators', type=int, default=6, help='step 4: actuators of the fleet (default 6)')
    parser.add_argument('--days', type=int, default=10, help='step 4: days of recordings (default 10)')
    parser.set_defaults(func=run)


class _Tee:
    """A stream that writes to stdout and keeps the lines (step 1's printout for the page)."""

    def __init__(self) -> None:
        self.text: list[str] = []

    def write(self, text: str) -> None:
        self.text.append(text)
        sys.stdout.write(text)

    def flush(self) -> None:
        sys.stdout.flush()


def _paper_step(out: Path, args: argparse.Namespace, say: Callable[[str], None]) -> StepResult:
    """Step 1 as :func:`~prsm_lube_ros.experiments.paper_demo.run_demo` runs it, as a StepResult."""
    import json
    import shutil
    import time
    from ..experiments.paper_demo import run_demo
    from .demo_steps import StepResult
    step = StepResult(1, 'The paper\'s experiment', 'the rig simulator records 3 speeds x 2 loads after three '
                      'lubrication stages; calibrated on stage 3, stages 1 and 2 assessed (cf. the paper\'s '
                      'Table and Fig. 5)')
    started = time.perf_counter()
    for stale in (out / 'bags', out / 'summary.json'):       # a rerun into the same folder starts afresh
        if stale.is_dir():
            shutil.rmtree(stale)
        elif stale.exists():
            stale.unlink()
    tee = _Tee()
    status = run_demo(out, seed=args.seed, stages=args.stages, window=args.window, storage=args.storage,
                      stream=tee)
    step.lines = ''.join(tee.text).rstrip().splitlines()
    summary = json.loads((out / 'summary.json').read_text()) if (out / 'summary.json').exists() else {}
    for name, stage in summary.get('stages', {}).items():
        step.checks.append((f'{name}: mean theta_Oil {stage["mean_theta"]:.3f}, true {stage["true_theta"]:.2f}',
                            stage['pass'] == 'PASS'))
    if status != 0 and all(ok for _, ok in step.checks):
        step.checks.append(('the paper\'s claims hold', False))
    step.figures = [(out / 'fig5a_rms.png', 'vibration RMS per condition and stage (cf. paper Fig. 5a)'),
                    (out / 'fig5b_theta.png', 'theta_Oil per condition and stage, dashed: truth (cf. Fig. 5b)')]
    step.links = [(out / 'calibration.yaml', 'calibration'), (out / 'assessment.json', 'assessment'),
                  (out / 'bags' / 'truth.json', 'the truth')]
    step.seconds = time.perf_counter() - started
    return step


def run(args: argparse.Namespace) -> int:
    """Run the steps, print what each shows and its checks, write index.html; 0 when every check passes."""
    from pathlib import Path
    from .demo_page import write_page
    from .demo_defect import defect_step
    from .demo_steps import diagnosis_step, fleet_step, live_step

    def say(text: str = '') -> None:
        print(text, flush=True)

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    total = 1 if args.quick else 5
    steps = []

    def header(number: int, title: str) -> None:
        say()
        say(f'=== Step {number}/{total}: {title} ===')

    header(1, 'the paper\'s experiment, calibrated on stage 3 and checked against the truth')
    steps.append(_paper_step(out, args, say))
    if not args.quick:
        header(2, 'live graph: sensor bridge playing stage 1, estimator publishing theta_Oil and /diagnostics, '
               'calibrate service called')
        steps.append(live_step(out, out / 'bags', args.stages, playback_rate=args.playback_rate,
                               windows=args.live_windows, say=say, window=args.window, storage=args.storage))
        header(3, 'a physical effect concealed in a recording: located, named and modelled by diagnose')
        steps.append(diagnosis_step(out, args.seed, say))
        header(4, f'a small fleet ({args.actuators} actuators x {args.days} days): history, trend, the most '
               'urgent actuators and their forecast crossing')
        steps.append(fleet_step(out, args.seed, say, actuators=args.actuators, days=args.days))
        header(5, 'a spalled screw is not a dry one: a surface defect beside an oil loss')
        steps.append(defect_step(out, args.seed, say))
    sizes = (f' --actuators {args.actuators} --days {args.days} --playback-rate {args.playback_rate:g} '
             f'--live-windows {args.live_windows}')
    command = f'prsm-lube demo --out {args.out} --seed {args.seed}' + (' --quick' if args.quick else sizes)
    page = write_page(out, steps, command)
    say()
    for step in steps:
        say(f'step {step.number} {"PASS" if step.passed else "FAIL"} ({step.seconds:.0f} s): {step.title}')
    passed = all(step.passed for step in steps)
    say(f'DEMO: {"PASS" if passed else "FAIL"} - {sum(s.passed for s in steps)}/{len(steps)} steps; '
        f'open {page}')
    return 0 if passed else 1
