# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The live surface defect screen (estimation.surface_health): pooling, latch, messages, theta withheld."""
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.condition_indicators import condition_indicators
from prsm_lube_ros.estimation.defect_screen import ConditionBaseline
from prsm_lube_ros.estimation.health import ERROR, HealthMonitor, OK, STALE, WARN
from prsm_lube_ros.estimation.surface_health import (defect_orders_text, kurtosis_limit, nominal_order,
                                                     SurfaceMonitor, withheld)
from prsm_lube_ros.estimation.windowing import DEFAULT_DEFECT_ORDERS

from synthetic_inputs import defect_vibration

RATE, SPEED, BAND = 4000.0, 40.0, (0.5, 1600.0)
HEALTHY = ConditionBaseline(runs=6, kurtosis_median=3.0, kurtosis_max=3.1, crest_median=4.0, crest_max=4.4,
                            envelope_levels=((6.25, 4.0), (3.75, 4.0)))


def windows(count, strike=0.0, seed=0, start=0.0):
    """Indicators of ``count`` consecutive 1 s windows of the synthetic vibration."""
    out = []
    for k in range(count):
        t = start + k + np.arange(int(RATE)) / RATE
        x = defect_vibration(t, SPEED, strike=strike, seed=seed + k)
        out.append(condition_indicators(x, RATE, SPEED, BAND, DEFAULT_DEFECT_ORDERS))
    return out


def feed(monitor, indicators, start=0.0):
    for k, item in enumerate(indicators):
        monitor.observe(item, start + k + 1.0)


def test_nothing_is_judged_before_the_group_is_full():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=4)
    feed(monitor, windows(3, strike=8.0))
    status = monitor.status()
    assert status.level == OK and status.message.startswith('not screened yet') and status.windows == 3


def test_a_spall_at_the_screw_raceway_order_is_error_with_the_component_and_a_stable_message():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=4)
    monitor.set_baseline(HEALTHY)
    feed(monitor, windows(4, strike=8.0))
    status = monitor.status()
    assert status.level == ERROR and status.suspected
    assert status.finding.component == 'screw raceway'
    assert status.message == ('impulsive at 6.25x screw speed: screw raceway defect suspected; theta_Oil is not a '
                              'lubrication measure while it lasts')
    assert status.since == 4.0
    feed(monitor, windows(3, strike=8.0, seed=50), start=4.0)
    assert monitor.status().message == status.message      # numbers change, the message does not


def test_healthy_vibration_is_ok_and_says_the_limit():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=4)
    monitor.set_baseline(HEALTHY)
    feed(monitor, windows(8))
    status = monitor.status()
    assert status.level == OK and not status.suspected
    assert status.message == 'no surface defect: kurtosis below 4.0, no envelope line at a defect order'
    assert 2.8 < status.condition.kurtosis < 3.3


def test_a_suspicion_clears_only_after_a_whole_group_of_clean_judgements():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=3)
    monitor.set_baseline(HEALTHY)
    feed(monitor, windows(3, strike=8.0))
    assert monitor.suspected
    levels = []
    for k, item in enumerate(windows(6, seed=100)):
        monitor.observe(item, 10.0 + k)
        levels.append(monitor.status().level)
    # Windows 1-2 still pool strikes; clean judgements from window 3 on; cleared after 3 in a row.
    assert levels[:4] == [ERROR] * 4 and levels[-1] == OK


def test_a_new_baseline_judges_the_group_afresh():
    """A machine whose healthy vibration is impulsive at the strike order: absolute limits flag it, its baseline not."""
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=4)
    feed(monitor, windows(4, strike=5.0))
    assert monitor.status().level == ERROR
    own = monitor.status().condition
    monitor.set_baseline(ConditionBaseline(runs=4, kurtosis_median=own.kurtosis, kurtosis_max=own.kurtosis + 1,
                                           crest_median=own.crest_factor, crest_max=own.crest_factor + 1,
                                           envelope_levels=((6.25, 40.0), (3.75, 40.0))))
    status = monitor.status()
    assert status.level == OK and status.message == (
        'no surface defect: kurtosis below 6.5; the envelope line at 6.25x screw speed (screw raceway) is within '
        'what the healthy runs show'), status.message
    monitor.set_baseline(HEALTHY, keep_windows=False)
    assert monitor.status().message.startswith('not screened yet')


def test_windows_without_indicators_warn_that_nothing_is_screened():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    monitor.observe(None, 1.0)
    status = monitor.status()
    assert status.level == WARN and 'calibrate again' in status.message


def test_stale_inputs_make_it_stale_with_the_last_level():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    feed(monitor, windows(2, strike=8.0))
    status = monitor.status('inputs stopped')
    assert status.level == STALE and status.message == 'inputs stopped; last level ERROR' and status.suspected


def test_the_group_can_shrink_and_grow_and_refuses_nonsense():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=5)
    feed(monitor, windows(3))
    monitor.set_windows(2)
    assert monitor.status().windows == 2 and monitor.windows == 2
    monitor.set_windows(6)
    assert monitor.status().message == 'not screened yet: fewer than 6 steady windows (defect_windows)'
    for bad in (0, -1, 2.5, True):
        with pytest.raises(InputError):
            monitor.set_windows(bad)


def test_nan_indicators_are_not_pooled():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    monitor.observe(condition_indicators(np.zeros(10), RATE, SPEED, BAND, DEFAULT_DEFECT_ORDERS), 1.0)
    assert monitor.status().windows == 0


def test_the_lubrication_status_is_withheld_not_insufficient_while_a_defect_is_suspected():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    feed(monitor, windows(2, strike=8.0))
    lubrication = HealthMonitor()
    lubrication.note_input(0.0)
    lubrication.observe(0.4)
    before = lubrication.status(0.0)
    assert before.level == ERROR and 'insufficient' in before.message
    after = withheld(before, monitor.status())
    assert after.level == WARN
    assert after.message.startswith('theta_oil withheld: screw raceway defect suspected')
    assert 'insufficient' not in after.message and 'degraded' not in after.message
    stale = lubrication.status(100.0)
    assert withheld(stale, monitor.status()) == stale
    assert withheld(before, SurfaceMonitor(DEFAULT_DEFECT_ORDERS).status()) == before


def test_a_low_theta_before_the_first_judgement_is_not_yet_judged_as_oil():
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=3)
    assert not monitor.pending                               # nothing in yet: no screen to wait for
    feed(monitor, windows(2, strike=8.0))
    assert monitor.pending and not monitor.judged
    lubrication = HealthMonitor()
    lubrication.note_input(0.0)
    lubrication.observe(0.4)
    status = withheld(lubrication.status(0.0), monitor.status(), monitor.pending)
    assert status.level == WARN and status.message.startswith('lubrication not yet judged')
    good = HealthMonitor()
    good.note_input(0.0)
    good.observe(1.0)
    assert withheld(good.status(0.0), monitor.status(), monitor.pending) == good.status(0.0)
    feed(monitor, windows(1, strike=8.0, seed=9), start=2.0)
    assert monitor.judged and not monitor.pending and monitor.suspected
    unscreenable = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=3)
    unscreenable.observe(None, 1.0)
    assert not unscreenable.pending


def test_a_window_with_indicators_on_their_way_counts_as_come_in():
    # The live node publishes a window before its indicators reach the screen: pending_with(True) then.
    monitor = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    assert monitor.pending_with(True) and not monitor.pending_with(False) and not monitor.pending
    feed(monitor, windows(1, strike=8.0))
    assert monitor.pending_with(False) == monitor.pending is True
    feed(monitor, windows(1, strike=8.0, seed=9), start=1.0)
    assert monitor.judged and not monitor.pending_with(True)     # judged: nothing to wait for
    unscreenable = SurfaceMonitor(DEFAULT_DEFECT_ORDERS, windows=2)
    unscreenable.observe(None, 1.0)                              # a calibration without a band: nothing screened
    assert not unscreenable.pending_with(False)
    # ... then one with a band: the first window with indicators on their way waits for the screen, not read as oil.
    assert unscreenable.pending_with(True)


def test_helpers():
    assert kurtosis_limit(None) == 4.0 and kurtosis_limit(HEALTHY) == 4.0
    assert kurtosis_limit(ConditionBaseline(2, 4.0, 4.2, 5.0, 5.5)) == 5.0
    assert nominal_order('nut raceway or roller', DEFAULT_DEFECT_ORDERS) == pytest.approx(3.75)
    assert math.isnan(nominal_order('gear', DEFAULT_DEFECT_ORDERS))
    assert defect_orders_text(DEFAULT_DEFECT_ORDERS).startswith('screw raceway 6.25, nut raceway 3.75')
    assert defect_orders_text(()) == 'none'
