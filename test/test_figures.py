# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The figures the commands write, drawn from edge-case inputs (matplotlib, Agg backend)."""
import numpy as np

from prsm_lube_ros.figures import history_with_forecast

DAY = 86400.0


def test_a_crossing_without_an_upper_bound_is_drawn_to_the_plot_edge(tmp_path):
    """``trend`` passes ``high`` None when a crossing's interval is open-ended; the bar must still be drawn."""
    start = 1.7e9
    times = start + DAY * np.arange(5)
    future = np.linspace(times[-1], times[-1] + 30 * DAY, 20)
    centre = np.linspace(0.9, 0.6, future.size)
    path = history_with_forecast(
        tmp_path / 'unit.png', list(times), [0.98, 0.96, 0.95, 0.93, 0.92], [0.01] * 5, future,
        (centre, centre - 0.05, centre + 0.05), {'warn 0.7': 0.7, 'error 0.5': 0.5}, [start + 0.5 * DAY],
        'unit: theta_Oil and forecast',
        crossings=[('warn 0.7', 0.7, times[-1] + 20 * DAY, times[-1] + 12 * DAY, None),     # open-ended
                   ('error 0.5', 0.5, None, times[-1] + 28 * DAY, times[-1] + 40 * DAY)],
        as_of=times[-1])
    assert path.stat().st_size > 10_000 and path.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


# -- condition figures (issue 34, item 5) ------------------------------------------------------------------------------
import pytest  # noqa: E402

from prsm_lube_ros import condition_figures  # noqa: E402

PNG = b'\x89PNG\r\n\x1a\n'
ORDERS = np.arange(0.0, 24.0 + 0.0125, 0.025)
MARKS = [(0.375, 'carrier'), (3.75, 'nut raceway or roller'), (6.25, 'screw raceway')]


@pytest.fixture
def legends_clear_of_the_axes(monkeypatch):
    """Every figure written is checked first: no legend lies over any axes (data or colour bar) of its figure."""
    original = condition_figures._write
    checked = []

    def check_then_write(fig, path, plt):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        for ax in fig.axes:
            legend = ax.get_legend()
            if legend is None:
                continue
            box = legend.get_window_extent(renderer)
            for other in fig.axes:
                assert not box.overlaps(other.get_window_extent(renderer)), f'{path.name}: legend over an axes'
        checked.append(path.name)
        return original(fig, path, plt)
    monkeypatch.setattr(condition_figures, '_write', check_then_write)
    return checked


def _spectrum(rng, lines=(), size=ORDERS.size):
    db = rng.normal(0.0, 3.0, size)
    for order, level in lines:
        db[np.argmin(np.abs(ORDERS - order))] = level
    return db


def test_envelope_spectrum_marks_every_defect_order_and_the_suspected_line(tmp_path, legends_clear_of_the_axes):
    rng = np.random.default_rng(1)
    db = _spectrum(rng, [(6.25, 22.0), (12.5, 14.0)])
    db[:5] = np.nan                                  # the lowest orders not held
    path = condition_figures.envelope_spectrum(tmp_path / 'env.png', ORDERS, db, MARKS, 'unit run', order_max=24.0,
                                               threshold_db=10.0, highlight=(6.25, 22.0, '6.25x, 22 dB: screw raceway'))
    assert path.read_bytes()[:8] == PNG and path.stat().st_size > 10_000
    assert legends_clear_of_the_axes == ['env.png']
    # No mark, no threshold, all NaN: still a figure, no exception.
    blank = condition_figures.envelope_spectrum(tmp_path / 'blank.png', ORDERS, np.full(ORDERS.size, np.nan), (),
                                                'nothing measured', order_max=24.0)
    assert blank.read_bytes()[:8] == PNG


@pytest.mark.parametrize('runs', [3, condition_figures.STACKED_ROWS + 20])
def test_waterfall_is_offset_lines_for_few_runs_and_an_image_for_many(tmp_path, runs, legends_clear_of_the_axes):
    rng = np.random.default_rng(runs)
    rows = np.vstack([_spectrum(rng, [(6.25, 3.0 + 0.4 * k)]) for k in range(runs)])
    rows[1, :] = np.nan                              # a run without an envelope
    path = condition_figures.waterfall(tmp_path / 'fall.png', ORDERS, rows, [f'{k} min' for k in range(runs)],
                                       'run start, min', 'unit waterfall', order_max=20.0, marks=MARKS,
                                       suspected=[k > runs // 2 for k in range(runs)])
    assert path.read_bytes()[:8] == PNG and path.stat().st_size > 10_000
    assert legends_clear_of_the_axes == ['fall.png']


def test_order_spectrum_draws_band_edges_in_range_only_and_trends_take_nan(tmp_path, legends_clear_of_the_axes):
    rng = np.random.default_rng(3)
    orders = np.arange(0.0, 50.0, 0.025)
    curves = [('300 r/min', rng.normal(-30, 3, orders.size)), ('100 r/min', rng.normal(-40, 3, orders.size))]
    edges = [[(0.1, '0.5 Hz'), (320.0, '1600 Hz')], [(0.3, '0.5 Hz'), (960.0, '1600 Hz')]]
    condition_figures.order_spectrum(tmp_path / 'orders.png', orders, curves, edges, 'unit', order_max=50.0)
    x = np.arange(8.0)
    condition_figures.indicator_trends(
        tmp_path / 'trends.png', x, 'run start, min', 3 + 0.3 * x, 4 + 0.2 * x, [np.nan] + list(5 + x[1:]),
        [1.0, 0.98, np.nan, 0.9, 0.6, -0.1, 0.5, 0.4], [0.02] * 8, [False] * 4 + [True] * 4, 'unit trends',
        limits=[(0, 4.0, 'impulsive from 4'), (2, 10.0, 'periodic from 10 dB')],
        theta_flagged=[False] * 5 + [True] + [False] * 2)
    for name in ('orders.png', 'trends.png'):
        assert (tmp_path / name).read_bytes()[:8] == PNG
    assert legends_clear_of_the_axes == ['orders.png', 'trends.png']
    assert not list(tmp_path.glob('.*.tmp'))         # written through temporaries renamed over the targets
