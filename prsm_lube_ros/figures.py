# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Figures like the paper's Fig. 5: RMS and theta_Oil per operating condition and lubrication stage."""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .atomic_file import save_figure

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence
    import datetime
    from types import ModuleType

    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    import numpy.typing as npt


__all__ = ['grouped_bars', 'history_with_forecast', 'live_theta']


def _pyplot() -> ModuleType:
    """Matplotlib's pyplot on the file-only Agg backend (unless one was chosen already)."""
    import matplotlib
    matplotlib.use('Agg', force=False)
    import matplotlib.pyplot as plt
    return plt


def _save(fig: Figure, ax: Axes, path: Path, title: str, plt: ModuleType) -> Path:
    """Title, legend and grid on ``ax``; ``fig`` written to ``path`` (folders made) and closed."""
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
    plt.close(fig)
    return path


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
    save_figure(fig, path)
    plt.close(fig)
    return path


def history_with_forecast(path: Path, times: Sequence[float], values: Sequence[float], errors: Sequence[float],
                          band_times: Sequence[float] | np.ndarray,
                          band: tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike],
                          levels: Mapping[str, float], events: Sequence[float], title: str,
                          ylabel: str = 'theta_Oil', *, crossings: Sequence[tuple] = (),
                          as_of: float | None = None, confidence: float = 0.95,
                          marked_since: tuple[str, float] | None = None) -> Path:
    """Values with one-sigma bars over UTC dates, a forecast (centre and band), levels, crossings and the as-of date.

    ``times``, ``band_times``, ``events`` (vertical dotted lines, e.g.
    relubrications) and ``as_of`` in s since the epoch; ``levels`` maps a
    label to a value; ``crossings`` are ``(label, level, estimate, low,
    high)`` (s since the epoch, None where unknown), drawn as a marker at the
    estimate and a bar over the interval on the level's line.
    ``marked_since`` ``(label, time)`` shades from that time (s since the
    epoch) to the right edge (a suspected defect: the values there are no
    lubrication measure).
    """
    import datetime
    plt = _pyplot()

    def dates(seconds: npt.ArrayLike) -> list[datetime.datetime]:
        return [datetime.datetime.fromtimestamp(float(t), datetime.UTC) for t in np.atleast_1d(seconds)]
    fig, ax = plt.subplots(figsize=(10.5, 4.4), dpi=120)
    if len(times):
        ax.errorbar(dates(times), values, yerr=errors, fmt='o', markersize=3, capsize=2,
                    label='recordings (one-sigma)')
    centre, low, high = (np.asarray(v, float) for v in band)
    if len(band_times) and np.isfinite(centre).any():
        ax.plot(dates(band_times), centre, color='C1', label='forecast')
        ax.fill_between(dates(band_times), low, high, color='C1', alpha=0.25,
                        label=f'{confidence:.0%} band of theta_Oil (fit, calibration, usage, model form)')
    for i, (label, value) in enumerate(levels.items()):
        ax.axhline(value, color=('C3' if i else 'C8'), linestyle='--', linewidth=1, label=label)
    _crossing_marks(ax, crossings, dates, confidence)
    for j, event in enumerate(events):
        ax.axvline(dates(event)[0], color='0.4', linestyle=':', linewidth=1,
                   label='relubrication' if j == 0 else None)
    if as_of is not None:
        ax.axvline(dates(as_of)[0], color='k', linewidth=1, label='as of')
    if marked_since is not None:
        from matplotlib.dates import date2num
        left, right = ax.get_xlim()
        start = float(date2num(dates(marked_since[1])[0]))
        ax.axvspan(start, max(right, start), color='C3', alpha=0.12, hatch='//', label=marked_since[0])
        ax.set_xlim(left, max(right, start))
    ax.set_xlabel('date (UTC)')
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    # beside the axes, never over the data
    ax.legend(fontsize=7, loc='upper left', bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(alpha=0.3)
    fig.autofmt_xdate()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)
    plt.close(fig)
    return path


def _crossing_marks(ax: Axes, crossings: Sequence[tuple], dates: Callable[[npt.ArrayLike], list[datetime.datetime]],
                    confidence: float) -> None:
    """A diamond at each crossing estimate and a bar over its interval (open ends drawn to the plot's edge)."""
    # The ignores below: matplotlib's stubs type plot()'s data as numbers and text, leaving out the datetimes
    # its unit converters take (date axes, as everywhere in this module).
    from matplotlib.dates import num2date
    for i, (label, level, estimate, low, high) in enumerate(crossings):
        color = 'C3' if i else 'C8'
        if low is not None:
            # An open end runs to the plot's right edge, a date number that must be a datetime beside ``low``.
            right = dates(high)[0] if high is not None else num2date(ax.get_xlim()[1])
            ax.plot([dates(low)[0], right], [level, level],  # type: ignore[arg-type]
                    color=color, linewidth=4, alpha=0.5, label=f'{label}: {confidence:.0%} interval')
        if estimate is not None:
            ax.plot(dates(estimate), [level], 'D', color=color, markersize=6,  # type: ignore[arg-type]
                    label=f'{label}: estimate')


def live_theta(path: Path, windows: Sequence[tuple], event_time: float, truth: float, title: str) -> Path:
    """theta_Oil per window over wall time as a live observer received it, an event line and the truth.

    ``windows`` are ``(s since the observer started, theta_Oil, ...)``;
    ``event_time`` (s, same clock) is drawn as a vertical line (the new
    calibration's answer), ``truth`` as a dashed horizontal one.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8.0, 4.2), dpi=120)
    t = np.array([w[0] for w in windows], float)
    theta = np.array([w[1] for w in windows], float)
    before = t < event_time if np.isfinite(event_time) else np.ones(t.size, bool)
    ax.plot(t[before], theta[before], 'o', markersize=3, color='C1', label='before the calibration')
    ax.plot(t[~before], theta[~before], 'o', markersize=3, color='C0', label='after')
    if np.isfinite(event_time):
        ax.axvline(event_time, color='0.3', linewidth=1, label='calibrate service answered')
    ax.axhline(truth, color='C2', linestyle='--', linewidth=1, label=f'truth {truth:g}')
    ax.set_xlabel('wall time, s')
    ax.set_ylabel(r'$\theta_{Oil}$')
    return _save(fig, ax, path, title, plt)
