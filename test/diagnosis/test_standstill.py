# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Vibration recorded with the screw still: what the window table keeps of it."""
import math

import numpy as np

from prsm_lube_ros.diagnosis.table import REST_SPEED, table_from_windows
from prsm_lube_ros.estimation.windowing import AT_REST, Window


def window(start, rms, speed, *, run=1, reason_kind=''):
    return Window(start=float(start), end=float(start) + 1.0, vibration_rms=rms, sample_count=4000, coverage=1.0,
                  screw_speed=speed, speed_spread=0.0, axial_load=2000.0, temperature=math.nan,
                  nut_position=0.01 * start, revolutions=float(start), run_index=run, reason_kind=reason_kind,
                  reason='at rest' if reason_kind else '')


def running(count=12):
    return [window(t, 1.0 + 0.1 * (t % 3), 10.0 + 5.0 * (t % 3), run=1 + t // 4) for t in range(count)]


def test_the_table_keeps_the_median_rms_of_windows_at_standstill_and_leaves_out_those_still_turning():
    still = [window(100 + i, rms, 0.0, run=0, reason_kind=AT_REST) for i, rms in enumerate([0.30, 0.32, 0.34])]
    slowing = [window(110 + i, 0.9, 0.5, run=0, reason_kind=AT_REST) for i in range(5)]   # end of a deceleration
    holding = window(120, 0.31, 0.5 * REST_SPEED, run=0, reason_kind=AT_REST)             # servo jitter
    table = table_from_windows([running() + still[:2] + slowing, [holding, still[2]] + running()])
    assert table.rest_windows == 4
    assert math.isclose(table.rest_rms, np.median([0.30, 0.32, 0.31, 0.34]))
    # Rows are the running windows only, so subsets (held-out folds) keep the standstill figure.
    assert len(table) == 24 and math.isclose(table.subset(np.arange(5)).rest_rms, table.rest_rms)


def test_too_few_windows_at_standstill_give_no_figure():
    table = table_from_windows([running() + [window(100, 0.3, 0.0, run=0, reason_kind=AT_REST)] * 2])
    assert table.rest_windows == 2 and math.isnan(table.rest_rms)
