# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Where a benchmark's results go: ``benchmarks/results/<name>.json`` (the data) and ``<name>.md`` (the table)."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / 'results'


def write_results(name: str, data: Any, lines: list[str], indent: int = 2) -> None:
    """Write ``data`` as JSON and ``lines`` as Markdown under ``name`` (a path is taken as it is), and print them."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f'{name}.json').write_text(json.dumps(data, indent=indent))
    (RESULTS / f'{name}.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
