# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Figures a vibration analyst expects of a condition report, drawn from plain arrays (matplotlib, Agg).

* :func:`order_spectrum` — power spectral density against screw orders, one
  curve per speed, the analysis band's edges marked where they fall in range;
* :func:`envelope_spectrum` — a run's envelope spectrum in screw orders (dB
  over its floor), every defect order and its harmonics marked, the suspected
  line highlighted, the screen's threshold drawn;
* :func:`waterfall` — spectra of many runs stacked over run time or speed
  (offset lines up to :data:`STACKED_ROWS` runs, an image beyond);
* :func:`indicator_trends` — kurtosis, crest factor, the strongest
  defect-order envelope line and theta_Oil per run, suspected runs marked.

A base module: it imports nothing of the package but :mod:`.atomic_file`, so
callers pass arrays and labels in.  Every figure is written atomically (a
temporary beside it renamed over it), legends sit outside the axes, and the
path written is returned.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .atomic_file import write_atomically

if TYPE_CHECKING:
    from collections.abc import Sequence
    from types import ModuleType

    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    import numpy.typing as npt

__all__ = ['MARKED_HARMONICS', 'STACKED_ROWS', 'Mark', 'envelope_spectrum', 'indicator_trends', 'order_spectrum',
           'waterfall']

#: A marked order: (order in multiples of the screw speed, label).
Mark = tuple[float, str]
#: Most runs a waterfall draws as offset lines; more are drawn as an image (one row per run).
STACKED_ROWS = 40
#: Harmonics of each defect order marked on envelope spectra (the fundamental labelled, the others thinner).
MARKED_HARMONICS = 3
#: Line styles that tell defect orders apart beside their colours.
_STYLES = ('--', ':', '-.', (0, (5, 1, 1, 1)))


def _pyplot() -> ModuleType:
    """Matplotlib's pyplot on the file-only Agg backend (unless one was chosen already)."""
    import matplotlib
    matplotlib.use('Agg', force=False)
    import matplotlib.pyplot as plt
    return plt


def _write(fig: Figure, path: Path, plt: ModuleType) -> Path:
    """``fig`` as PNG at ``path`` (temporary renamed over it; legends outside the axes kept in), closed."""
    path = Path(path)
    try:
        write_atomically(path, lambda stream: fig.savefig(stream, format='png', bbox_inches='tight'))
    finally:
        plt.close(fig)
    return path


def _outside_legend(ax: Axes, **kwargs: object) -> None:
    """The legend to the right of the axes, never over the data."""
    handles, _ = ax.get_legend_handles_labels()
    if handles:
        ax.legend(loc='upper left', bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=7, **kwargs)


def _mark_orders(ax: Axes, marks: Sequence[Mark], order_max: float, *, harmonics: int = MARKED_HARMONICS) -> None:
    """Each mark's order as a coloured vertical line with its label in the legend; harmonics thinner, unlabelled."""
    for i, (order, label) in enumerate(sorted(marks)):
        color, style = f'C{(i + 2) % 10}', _STYLES[i % len(_STYLES)]
        for h in range(1, harmonics + 1):
            if h * order > order_max:
                break
            thin = ' (thin: ' + ', '.join(f'{k}x' for k in range(2, harmonics + 1)) + ')' if harmonics > 1 else ''
            ax.axvline(h * order, color=color, linestyle=style, linewidth=1.1 if h == 1 else 0.7,
                       alpha=0.9 if h == 1 else 0.45, label=f'{order:.3g}x {label}{thin}' if h == 1 else None)


def order_spectrum(path: Path, orders: npt.ArrayLike, curves: Sequence[tuple[str, npt.ArrayLike]],
                   band_edges: Sequence[Sequence[Mark]], title: str, *, order_max: float,
                   ylabel: str = 'PSD, dB re 1 (m/s$^2$)$^2$/Hz') -> Path:
    """Curves (label, values on ``orders``) over screw orders; ``band_edges[i]`` the i-th curve's band edges.

    Edges outside ``[0, order_max]`` are left out (the caller says where they
    fall, e.g. in the curve's label); those in range are drawn dashed in
    their curve's colour, with one legend entry for all.
    """
    plt = _pyplot()
    x = np.asarray(orders, dtype=float)
    fig, ax = plt.subplots(figsize=(8.5, 3.8), dpi=110)
    drawn_edge = False
    for i, (label, values) in enumerate(curves):
        color = f'C{i % 10}'
        ax.plot(x, np.asarray(values, dtype=float), color=color, linewidth=0.8, label=label)
        edges = band_edges[i] if i < len(band_edges) else ()
        for order, _ in edges:
            if 0.0 <= order <= order_max:
                ax.axvline(order, color=color, linestyle='--', linewidth=1.0)
                drawn_edge = True
    if drawn_edge:
        ax.plot([], [], color='0.3', linestyle='--', linewidth=1.0,
                label='analysis band edge in range\n(dashed, in its curve\'s colour)')
    ax.set_xlim(0.0, order_max)
    ax.set_xlabel('screw order (frequency / shaft frequency)')
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    _outside_legend(ax)
    return _write(fig, path, plt)


def envelope_spectrum(path: Path, orders: npt.ArrayLike, db: npt.ArrayLike, marks: Sequence[Mark], title: str, *,
                      order_max: float, threshold_db: float | None = None,
                      highlight: tuple[float, float, str] | None = None) -> Path:
    """One envelope spectrum (dB over its floor) with the defect orders ``marks`` and the ``highlight`` line.

    ``highlight`` is ``(order, dB, text)`` of the suspected line: a red
    circle on it and its words in the legend.  ``threshold_db`` (the screen's
    periodic limit) is drawn as a horizontal line.
    """
    plt = _pyplot()
    x, y = np.asarray(orders, dtype=float), np.asarray(db, dtype=float)
    fig, ax = plt.subplots(figsize=(8.5, 3.6), dpi=110)
    ax.plot(x, y, color='k', linewidth=0.8, label='envelope spectrum')
    _mark_orders(ax, marks, order_max)
    if threshold_db is not None:
        ax.axhline(threshold_db, color='0.4', linewidth=0.9, label=f'screen: line {threshold_db:g} dB over floor')
    if highlight is not None:
        order, level, text = highlight
        ax.axvspan(order - 0.02 * order_max, order + 0.02 * order_max, color='tab:red', alpha=0.15)
        ax.plot([order], [level], 'o', markersize=11, markerfacecolor='none', markeredgecolor='tab:red',
                markeredgewidth=2, label=f'suspected: {text}')
    finite = y[np.isfinite(y) & (x <= order_max)]
    if finite.size:
        top = max(float(finite.max()), threshold_db or -math.inf, highlight[1] if highlight else -math.inf)
        ax.set_ylim(max(float(finite.min()), -20.0) - 2.0, top + 4.0)
    ax.set_xlim(0.0, order_max)
    ax.set_xlabel('screw order (envelope frequency / shaft frequency)')
    ax.set_ylabel('dB over the floor')
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    _outside_legend(ax)
    return _write(fig, path, plt)


def waterfall(path: Path, orders: npt.ArrayLike, rows: npt.ArrayLike, row_labels: Sequence[str], axis_label: str,
              title: str, *, order_max: float, marks: Sequence[Mark] = (), suspected: Sequence[bool] = (),
              unit: str = 'dB', step: float | None = None) -> Path:
    """Spectra ``rows`` (one per run, on ``orders``, in ``unit``) stacked bottom to top in the order given.

    Up to :data:`STACKED_ROWS` rows are offset lines (each shifted by
    ``step``, default the rows' typical spread), suspected rows in red; more
    are an image with a colour bar.  ``row_labels`` name the rows on the
    vertical axis (run time or speed); ``marks`` are the defect orders.
    """
    plt = _pyplot()
    x = np.asarray(orders, dtype=float)
    data = np.atleast_2d(np.asarray(rows, dtype=float))
    count = data.shape[0]
    shown = x <= order_max
    flagged = list(suspected) + [False] * (count - len(suspected))
    fig, ax = plt.subplots(figsize=(8.5, min(2.2 + 0.22 * min(count, STACKED_ROWS), 11.0)), dpi=110)
    ticks = _tick_rows(count)
    if count <= STACKED_ROWS:
        finite = data[:, shown][np.isfinite(data[:, shown])]
        spread = float(np.percentile(finite, 99) - np.percentile(finite, 5)) if finite.size else 1.0
        offset = step if step is not None else max(spread / 2.0, 1e-12)
        for k in range(count):
            ax.plot(x[shown], data[k, shown] + k * offset, linewidth=0.7,
                    color='tab:red' if flagged[k] else 'C0')
        centre = float(np.median(finite)) if finite.size else 0.0
        ax.set_yticks([k * offset + centre for k in ticks], [row_labels[k] for k in ticks], fontsize=7)
        if finite.size:     # single deep notches (order 0 of a mean-free envelope) must not stretch the axis
            ax.set_ylim(float(np.percentile(finite, 0.5)) - 0.2 * offset,
                        float(np.percentile(finite, 99.9)) + (count - 1) * offset + 0.2 * offset)
        ax.plot([], [], color='tab:red', linewidth=0.7, label='defect suspected')
        ax.set_ylabel(f'{axis_label}  (each run offset by {offset:.3g} {unit})')
    else:
        finite = data[np.isfinite(data)]
        low, high = ((float(np.percentile(finite, 2)), float(np.percentile(finite, 99.5))) if finite.size
                     else (0.0, 1.0))
        mesh = ax.pcolormesh(x[shown], np.arange(count), data[:, shown], shading='nearest', cmap='viridis',
                             vmin=low, vmax=high)
        fig.colorbar(mesh, ax=ax, orientation='horizontal', location='bottom', pad=0.14, fraction=0.04, aspect=50,
                     label=unit)     # below, so the legend to the right stays clear of it
        ax.set_yticks(list(ticks), [row_labels[k] for k in ticks], fontsize=7)
        rows_flagged = [k for k in range(count) if flagged[k]]
        if rows_flagged:
            ax.plot(np.full(len(rows_flagged), x[shown][-1]), rows_flagged, '<', color='tab:red', markersize=4,
                    clip_on=False, label='defect suspected')
        ax.set_ylabel(axis_label)
    _mark_orders(ax, marks, order_max, harmonics=1)
    ax.set_xlim(0.0, order_max)
    ax.set_xlabel('screw order')
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.25)
    _outside_legend(ax)
    return _write(fig, path, plt)


def _tick_rows(count: int, most: int = 16) -> list[int]:
    """Row indices to label: all of up to ``most`` rows, else an even spread including the first and last."""
    if count <= most:
        return list(range(count))
    return sorted({int(round(v)) for v in np.linspace(0, count - 1, most)})


def indicator_trends(path: Path, x: npt.ArrayLike, x_label: str, kurtosis: npt.ArrayLike, crest: npt.ArrayLike,
                     line_db: npt.ArrayLike, theta: npt.ArrayLike, theta_std: npt.ArrayLike,
                     suspected: Sequence[bool], title: str, *, limits: Sequence[tuple[int, float, str]] = (),
                     theta_flagged: Sequence[bool] = ()) -> Path:
    """Four panels over the runs: kurtosis, crest factor, strongest defect-order line (dB), theta_Oil.

    ``limits`` are ``(panel 0-3, value, label)`` horizontal lines (the
    screen's limits, theta's reference); suspected runs are red crosses on
    every panel, runs whose theta_Oil is out of its physical range hollow.
    """
    plt = _pyplot()
    xs = np.asarray(x, dtype=float)
    flagged = np.zeros(xs.size, bool)
    flagged[:len(suspected)] = np.asarray(suspected, bool)[:xs.size]
    out_of_range = np.zeros(xs.size, bool)
    out_of_range[:len(theta_flagged)] = np.asarray(theta_flagged, bool)[:xs.size]
    values = [np.asarray(v, dtype=float) for v in (kurtosis, crest, line_db, theta)]
    labels = ['kurtosis', 'crest factor', 'defect-order line,\ndB over floor', r'$\theta_{Oil}$']
    fig, axes = plt.subplots(4, 1, figsize=(8.5, 7.6), dpi=110, sharex=True)
    order = np.argsort(xs, kind='stable')
    for panel, (ax, y, label) in enumerate(zip(axes, values, labels)):
        ax.plot(xs[order], y[order], color='0.6', linewidth=0.6)
        if panel == 3:
            err = np.asarray(theta_std, dtype=float)
            ok = ~flagged & ~out_of_range
            ax.errorbar(xs[ok], y[ok], yerr=err[ok], fmt='o', markersize=3, capsize=2, color='C0',
                        label='theta_Oil (one-sigma)')
            plain = out_of_range & ~flagged
            if plain.any():
                ax.errorbar(xs[plain], y[plain], yerr=err[plain], fmt='o', markersize=4, capsize=2, color='C0',
                            markerfacecolor='none', label='theta_Oil out of its physical range')
            if flagged.any():
                ax.errorbar(xs[flagged], y[flagged], yerr=err[flagged], fmt='x', markersize=6, capsize=2,
                            color='tab:red', label='defect suspected: no lubrication measure')
        else:
            ax.plot(xs[~flagged], y[~flagged], 'o', markersize=3, color='C0', label='run')
            if flagged.any():
                ax.plot(xs[flagged], y[flagged], 'x', markersize=6, color='tab:red', label='defect suspected')
        for where, value, text in limits:
            if where == panel and math.isfinite(value):
                ax.axhline(value, color='0.3', linestyle='--', linewidth=0.9, label=text)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
        _outside_legend(ax)
    axes[-1].set_xlabel(x_label)
    axes[0].set_title(title, fontsize=9)
    return _write(fig, path, plt)
