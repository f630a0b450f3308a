# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""An effect is its two plug-in files and one row: the package works with ``surface_defect`` taken out that way.

The package is copied, the defect's physics and diagnosis modules deleted and
its ``CONTRACT_ORDER`` entry removed, nothing else; in that copy the registry
holds the other five, a recording with one of them is simulated and diagnosed,
and ``prsm-lube simulate --effect surface_defect`` is refused (argparse's invalid choice).  So
the addition of ``surface_defect`` is those two files, the row, its tests and
docs (``docs/adding-an-effect.md`` shows the ``git diff --stat``).  The demo's
defect step (``cli/demo_defect.py``, a user-facing demonstration of that effect)
is the one other place naming it, and is left out of the copy's checks.
"""
from pathlib import Path
import shutil
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[2]
EFFECT = 'surface_defect'

CHECK = r'''
import sys
import numpy as np
from prsm_lube_ros.physics.effects import effect_ids
from prsm_lube_ros.diagnosis.effects import candidate_ids
from prsm_lube_ros.diagnosis.engine import diagnose_table
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
assert 'surface_defect' not in effect_ids() and effect_ids() == candidate_ids(), (effect_ids(), candidate_ids())
table, _ = synthetic_table(np.random.default_rng(3), 'background_vibration', plan=SyntheticPlan(sessions=2))
print(len(effect_ids()), diagnose_table(table).verdict)
'''


def _without_the_effect(tmp_path: Path) -> Path:
    copy = tmp_path / 'prsm_lube_ros'
    shutil.copytree(ROOT / 'prsm_lube_ros', copy, ignore=shutil.ignore_patterns('__pycache__'))
    (copy / 'physics' / 'effects' / f'{EFFECT}.py').unlink()
    (copy / 'diagnosis' / 'effects' / f'{EFFECT}.py').unlink()
    registry = copy / 'physics' / 'effects' / '__init__.py'
    text = registry.read_text()
    row = f", '{EFFECT}')"
    assert text.count(row) == 1, 'the effect is no longer the last entry of CONTRACT_ORDER'
    registry.write_text(text.replace(row, ')'))
    return tmp_path


def test_the_package_without_the_effect_s_two_files_and_row_still_works(tmp_path):
    root = _without_the_effect(tmp_path)
    run = subprocess.run([sys.executable, '-c', CHECK], cwd=root, capture_output=True, text=True, timeout=300,
                         env={'PATH': '/usr/bin:/bin', 'PYTHONPATH': str(root), 'MPLBACKEND': 'Agg'})
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split() == ['5', 'background_vibration']


def test_simulate_refuses_the_removed_effect(tmp_path):
    root = _without_the_effect(tmp_path)
    run = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'simulate', str(tmp_path / 'out'),
                          '--effect', EFFECT], cwd=root, capture_output=True, text=True, timeout=300,
                         env={'PATH': '/usr/bin:/bin', 'PYTHONPATH': str(root), 'MPLBACKEND': 'Agg'})
    assert run.returncode != 0
    last = run.stderr.strip().splitlines()[-1]      # argparse: the usage, then one error line
    assert EFFECT in last and 'invalid choice' in last and 'Traceback' not in run.stderr, run.stderr
