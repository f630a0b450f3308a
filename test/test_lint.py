# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Style checks of the ament_python template: flake8, pep257 docstrings, copyright notices."""
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ['prsm_lube_ros', 'test', 'benchmarks', 'launch', 'setup.py']


def _existing(paths):
    return [p for p in paths if (ROOT / p).exists()]


@pytest.mark.linter
def test_flake8():
    result = subprocess.run([sys.executable, '-m', 'flake8', *_existing(SOURCES)], cwd=ROOT,
                            capture_output=True, text=True)
    assert result.returncode == 0, f'flake8 found problems:\n{result.stdout}{result.stderr}'


@pytest.mark.linter
def test_pep257():
    result = subprocess.run([sys.executable, '-m', 'pydocstyle', *_existing(['prsm_lube_ros', 'setup.py'])],
                            cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 0, f'pydocstyle found problems:\n{result.stdout}{result.stderr}'


NOTICE = ('# Copyright 2026 prsm_lube_ros developers', '# SPDX-License-Identifier: Apache-2.0')


@pytest.mark.linter
def test_copyright():
    """Every tracked source file opens with the copyright notice and the license (after a shebang)."""
    listed = subprocess.run(['git', 'ls-files', '*.py', 'scripts/*', 'tools/*', '.ci/run'], cwd=ROOT,
                            capture_output=True, text=True)
    if listed.returncode != 0:
        pytest.skip('not a git checkout')
    missing = []
    for name in listed.stdout.split():
        head = (ROOT / name).read_text().splitlines()[:3]
        if not all(line in head for line in NOTICE):
            missing.append(name)
    assert not missing, 'files without the copyright notice and license: ' + ', '.join(missing)
