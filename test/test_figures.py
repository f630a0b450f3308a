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
