# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Step 5 of ``prsm-lube demo``: a spalled screw is not a dry one.

A surface defect (``surface_defect``: a spall struck by every passing contact,
ringing a mode; its component, size and growth drawn from the seed) is
hidden in two sessions of the paper's plan at theta_Oil = 1.  With step 1's
calibration (healthy stage 3, with its condition baseline) ``prsm-lube
assess`` reads the defect recording and step 1's stage 1 (an oil loss, true
theta_Oil 0.72, no defect); ``prsm-lube diagnose`` reads the defect recording.
Checks: most runs of the defect recording are marked ``defect_suspected``
(their theta_oil is no lubrication measure), none of the oil-loss stage is,
and diagnose names ``surface_defect``.
"""
from __future__ import annotations

import json
from pathlib import Path
import shutil
import time
from typing import TYPE_CHECKING

from .demo_steps import _check, run_command, StepResult

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ['MOST_RUNS', 'defect_step']

#: Share of the defect recording's runs that must be marked (a growing spall starts small).
MOST_RUNS = 0.5


def _flagged(path: Path) -> tuple[int, int]:
    """(runs marked defect_suspected, runs) of an assess JSON."""
    runs = json.loads(path.read_text())['runs']
    return sum(bool(run['defect_suspected']) for run in runs), len(runs)


def defect_step(out: Path, seed: int, say: Callable[[str], None]) -> StepResult:
    """Hide a surface defect drawn from ``seed``; assess must withhold theta where it is, diagnose must name it."""
    from ..simulation.recordings import draw_effects, simulate_experiment
    from ..simulation.rig_config import ExperimentPlan
    step = StepResult(5, 'A spalled screw is not a dry one', 'a recording (two sessions of the paper\'s plan at '
                      'theta_Oil = 1) with a surface defect drawn from the seed, beside step 1\'s oil loss '
                      '(stage 1, theta_Oil 0.72): assess must mark the defect\'s runs and not the oil loss\'s, '
                      'diagnose must name surface_defect')
    started = time.perf_counter()
    folder = out / 'defect'
    if folder.exists():
        shutil.rmtree(folder)
    plan = ExperimentPlan(stage_thetas=(1.0, 1.0))
    effects = draw_effects(['surface_defect'], seed=seed, plan=plan)
    law = effects.as_dict()['surface_defect']
    say(f'    simulating a {law["growth"]} {law["component"]} defect (seed {seed}; all of it in '
        f'{folder / "bags" / "truth.json"})')
    bags = simulate_experiment(folder / 'bags', plan=plan, seed=seed, effects=effects, run_order='random')
    calibration = out / 'calibration.yaml'
    readings = {}
    for name, paths in (('defect', bags), ('oil loss', [out / 'bags' / 'stage_1'])):
        target = folder / f'assess_{name.replace(" ", "_")}.json'
        status, text = run_command(['assess', *paths, '--calibration', calibration, '--json', target],
                                   folder / 'assess.log')
        say(f'    $ prsm-lube assess {" ".join(p.name for p in paths)} --calibration calibration.yaml')
        lines = text.rstrip().splitlines()
        evidence = [line for line in lines if line.startswith('D ')]
        for line in lines:
            if not line.startswith(('D ', 'warning', 'calibration', '!', '~', 'wrote')) and ' NaN ' not in line:
                say(f'    | {line}')
        for line in evidence[:2]:
            say(f'    | {line}')
        if len(evidence) > 2:
            say(f'    | ({len(evidence) - 2} more D lines in {folder / "assess.log"})')
        readings[name] = _flagged(target) if status == 0 else (0, 0)
    status, text = run_command(['diagnose', *bags, '--theta', '1', '--json', folder / 'diagnosis.json'],
                               folder / 'diagnose.log')
    verdict = json.loads((folder / 'diagnosis.json').read_text()).get('verdict') if status == 0 else None
    say(f'    $ prsm-lube diagnose {" ".join(b.name for b in bags)} --theta 1: verdict {verdict}')
    (marked, runs), (oil_marked, oil_runs) = readings['defect'], readings['oil loss']
    _check(step, say, f'{marked} of {runs} runs of the defect recording marked defect_suspected (at least '
           f'{100 * MOST_RUNS:.0f} %)', runs > 0 and marked >= MOST_RUNS * runs)
    _check(step, say, f'{oil_marked} of {oil_runs} runs of the oil loss (stage 1) marked', oil_runs > 0 and
           oil_marked == 0)
    _check(step, say, f'diagnose named the concealed defect (verdict {verdict})', verdict == 'surface_defect')
    step.lines = [f'defect: {marked}/{runs} runs marked; oil loss: {oil_marked}/{oil_runs}; diagnose: {verdict}']
    step.links += [(folder / 'assess_defect.json', 'assessment of the defect recording'),
                   (folder / 'diagnosis.json', 'diagnosis JSON'), (folder / 'bags' / 'truth.json', 'the truth')]
    step.seconds = time.perf_counter() - started
    return step
