# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Figures like the paper's Fig. 5: RMS and theta_Oil per operating condition and lubrication stage."""
from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import numpy as np


def _pyplot():
    import matplotlib
    matplotlib.use('Agg', force=False)
    import matplotlib.pyplot as plt
    return plt


def grouped_bars(path: Path, conditions: Sequence[str], stages: Sequence[str],
                 values: Mapping[tuple[str, str], float], errors: Mapping[tuple[str, str], float] | None,
                 ylabel: str, title: str, reference_lines: Mapping[str, float] | None = None) -> Path:
    """Bars per condition, one per stage, with one-sigma error bars; optional horizontal truth lines."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8.0, 4.2), dpi=120)
    width = 0.8 / max(len(stages), 1)
    x = np.arange(len(conditions))
    colors = plt.rcParams['axes.prop_cycle'].by_key()['color']
    for i, stage in enumerate(stages):
        heights = [values.get((c, stage), np.nan) for c in conditions]
        err = [errors.get((c, stage), 0.0) for c in conditions] if errors else None
        ax.bar(x + (i - (len(stages) - 1) / 2) * width, heights, width, yerr=err, capsize=3,
               label=stage, color=colors[i % len(colors)])
        if reference_lines and stage in reference_lines:
            ax.axhline(reference_lines[stage], color=colors[i % len(colors)], linestyle='--', linewidth=1)
    ax.set_xticks(x, conditions, rotation=0, fontsize=8)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, ncols=len(stages))
    ax.grid(axis='y', alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
