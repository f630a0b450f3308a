# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Static type check of the ROS-free core with mypy, configured in setup.cfg's ``[mypy]`` sections.

Everything of the package but the ROS layer (``nodes/`` and the ``run``
command) is checked, strict but for ``disallow_any_generics`` and
``warn_return_any`` (setup.cfg says why): every function fully annotated, no
untyped call of ours, no implicit re-export; third-party packages without type
hints are Any there.  The cache goes to a temporary directory, so the check
always starts from the sources.  Also here: no function of the package is
longer than a screen (:data:`MAX_FUNCTION_LINES`).
"""
import ast
from pathlib import Path
import subprocess
import sys
from typing import cast

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Lines of the longest function, from ``def`` to its last line (docstring included).
MAX_FUNCTION_LINES = 60


@pytest.mark.linter
def test_mypy(tmp_path):
    """Mypy finds no error in the ROS-free core."""
    result = subprocess.run([sys.executable, '-m', 'mypy', '--config-file', 'setup.cfg', '--cache-dir',
                             str(tmp_path / 'mypy_cache'), 'prsm_lube_ros'], cwd=ROOT, capture_output=True,
                            text=True)
    assert result.returncode == 0, f'mypy found problems:\n{result.stdout}{result.stderr}'


@pytest.mark.linter
def test_every_function_fits_on_a_screen():
    """No function or method of the package spans more than MAX_FUNCTION_LINES lines."""
    long = []
    for path in sorted((ROOT / 'prsm_lube_ros').rglob('*.py')):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                lines = cast(int, node.end_lineno) - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long.append(f'{path.relative_to(ROOT)}:{node.lineno} {node.name} ({lines} lines)')
    assert not long, 'functions longer than a screen:\n' + '\n'.join(long)
