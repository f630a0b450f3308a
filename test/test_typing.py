# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Static type check of the ROS-free core with mypy, configured in setup.cfg's ``[mypy]`` sections.

Everything of the package but the ROS layer (``nodes/`` and the ``run``
command) is checked, with ``check_untyped_defs``; third-party packages
without type hints are Any there.  The cache goes to a temporary directory,
so the check always starts from the sources.
"""
from pathlib import Path
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.linter
def test_mypy(tmp_path):
    """Mypy finds no error in the ROS-free core."""
    result = subprocess.run([sys.executable, '-m', 'mypy', '--config-file', 'setup.cfg', '--cache-dir',
                             str(tmp_path / 'mypy_cache'), 'prsm_lube_ros'], cwd=ROOT, capture_output=True,
                            text=True)
    assert result.returncode == 0, f'mypy found problems:\n{result.stdout}{result.stderr}'
