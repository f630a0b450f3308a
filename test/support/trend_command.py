# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend`` as users run it (the installed command, a fresh process) and what its report holds."""
import json
from pathlib import Path
import subprocess
import sys

ROOT = Path(__file__).resolve().parents[2]
INSTALLED = [sys.executable, str(ROOT / 'scripts' / 'prsm-lube')]


def trend(*args, entry=INSTALLED):
    """``prsm-lube trend ARGS`` in a fresh process (``entry``: how it is started)."""
    return subprocess.run(entry + ['trend', *map(str, args)], capture_output=True, text=True, timeout=300)


def error_lines(result) -> list[str]:
    """The non-blank stderr lines of a finished command (never a traceback)."""
    assert 'Traceback' not in result.stderr
    return [line for line in result.stderr.splitlines() if line.strip()]


def table_rows(markdown: str) -> list[str]:
    """The table lines of a Markdown text."""
    return [line for line in markdown.splitlines() if line.startswith('|')]


def actuators(report) -> dict:
    """trend.json's actuator entries by name."""
    return {a['actuator']: a for a in json.loads((report / 'trend.json').read_text())['actuators']}
