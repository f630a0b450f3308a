#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Reference assessments for ``test/cli/test_assess_reference.py``, written by the code of a checkout.

Speed work must not move a theta_oil, a sigma or a verdict.  This script runs
``prsm-lube calibrate`` and ``prsm-lube assess --json`` of the checkout given
(``--code``, default this repository; give a worktree of ``main`` to write the
reference of the code before a change) on recorded cases and keeps the JSON in
``test/data/assess_reference/``; the test assesses the same cases with the
code under test and compares every number to 1e-9 relative.

Cases (see :data:`CASES`): the FEMTO-ST late runs (25.6 kHz, damaged bearings:
condition indicators and defect flags) and healthy early runs, calibrated on
the early learning runs with the PRONOSTIA bearing's geometry; a simulated
4 kHz stage with a growing surface defect (``prsm-lube simulate --seed 3
--stages 1.0 0.72 --effect surface_defect``: the second stage assessed,
calibrated on the first).  Recordings and calibrations are written once (kept
in ``test/data/assess_reference/``); the JSON each run.

Usage: ``python scripts/assess_reference.py [--code CHECKOUT]``, e.g.::

    git worktree add --detach /tmp/main-before main
    python scripts/assess_reference.py --code /tmp/main-before
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / 'test' / 'data'
REFERENCE = DATA / 'assess_reference'
FEMTO = DATA / 'realdata' / 'femto'
FEMTO_ACTUATOR = ROOT / 'config' / 'femto_pronostia_bearing.yaml'
SIMULATED = REFERENCE / 'sim_surface_defect_stage_2'

#: name: (recording, calibration file, extra assess options)
CASES = {
    'femto_all_late': (FEMTO / 'all_late', REFERENCE / 'femto_calibration.yaml', ['--actuator', str(FEMTO_ACTUATOR)]),
    'femto_test_early': (FEMTO / 'test_early', REFERENCE / 'femto_calibration.yaml',
                         ['--actuator', str(FEMTO_ACTUATOR)]),
    'sim_surface_defect': (SIMULATED, REFERENCE / 'sim_calibration.yaml', []),
}


def prsm_lube(code: Path, *argv: object) -> None:
    """Run ``prsm-lube`` of the checkout ``code``; stop with its stderr when it fails."""
    env = dict(os.environ, PYTHONPATH=str(code))
    result = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', *map(str, argv)], cwd=code, env=env,
                            capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f'prsm-lube {argv[0]} failed ({result.returncode}): {result.stderr.strip()}')


def make_inputs(code: Path) -> None:
    """The simulated recording and both calibrations, where missing."""
    REFERENCE.mkdir(parents=True, exist_ok=True)
    calibration = REFERENCE / 'sim_calibration.yaml'
    if not SIMULATED.exists() or not calibration.exists():
        with tempfile.TemporaryDirectory() as folder:
            prsm_lube(code, 'simulate', folder, '--seed', 3, '--stages', 1.0, 0.72, '--effect', 'surface_defect')
            prsm_lube(code, 'calibrate', Path(folder) / 'stage_1', '--out', calibration)
            shutil.rmtree(SIMULATED, ignore_errors=True)
            shutil.copytree(Path(folder) / 'stage_2', SIMULATED)
    if not (REFERENCE / 'femto_calibration.yaml').exists():
        prsm_lube(code, 'calibrate', FEMTO / 'learn_early', '--out', REFERENCE / 'femto_calibration.yaml',
                  '--actuator', FEMTO_ACTUATOR)


def assess_command(name: str, out: Path) -> list[str]:
    """``prsm-lube assess`` arguments of case ``name`` writing its JSON to ``out``."""
    recording, calibration, extra = CASES[name]
    return ['assess', str(recording), '--calibration', str(calibration), '--json', str(out), *extra]


def main() -> int:
    """Write the inputs where missing, then each case's JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--code', type=Path, default=ROOT, help='checkout whose code writes the reference')
    code = parser.parse_args().code.resolve()
    make_inputs(code)
    for name in CASES:
        prsm_lube(code, *assess_command(name, REFERENCE / f'{name}.json'))
        print(f'wrote {REFERENCE / f"{name}.json"} with the code of {code}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
