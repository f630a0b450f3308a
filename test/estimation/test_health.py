# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Diagnostic levels from theta_Oil: thresholds, hysteresis, NaN windows and staleness."""
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.health import ERROR, format_value, HealthMonitor, HealthThresholds, OK, STALE, \
    theta_level, WARN

#: Each window judged alone (level_smoothing 1): the rules below are per judged theta.
T = HealthThresholds(warn_below=0.85, error_below=0.70, hysteresis=0.03, stale_timeout=2.0,
                     max_unassessed_windows=3, level_smoothing=1)


def levels(thetas, thresholds=T):
    """Theta levels window after window, starting fresh."""
    monitor = HealthMonitor(thresholds)
    return [monitor.observe(theta) for theta in thetas]


def test_levels_from_a_fresh_start_follow_the_thresholds():
    assert levels([0.95]) == [OK]
    assert levels([0.85]) == [OK]      # 'below 0.85' is WARN, 0.85 itself is not
    assert levels([0.849]) == [WARN]
    assert levels([0.70]) == [WARN]
    assert levels([0.699]) == [ERROR]


def test_worsening_is_immediate_and_recovery_needs_the_margin():
    #        OK    WARN  ERROR  ERROR  ERROR  WARN   WARN  WARN  WARN  OK
    thetas = [0.9, 0.84, 0.69, 0.72, 0.73, 0.731, 0.86, 0.88, 0.80, 0.881]
    assert levels(thetas) == [OK, WARN, ERROR, ERROR, ERROR, WARN, WARN, WARN, WARN, OK]


def test_a_theta_hovering_at_a_threshold_does_not_flicker():
    assert levels([0.84, 0.86, 0.84, 0.87, 0.849]) == [WARN] * 5


def level_changes(thetas, thresholds):
    """How often the level changes over ``thetas`` (from the first window's level)."""
    judged = levels(thetas, thresholds)
    return sum(a != b for a, b in zip(judged, judged[1:]))


@pytest.mark.parametrize('threshold', [0.70, 0.85])
def test_scatter_at_a_threshold_does_not_flap_the_level_with_the_default_smoothing(threshold):
    """155 windows at the threshold with the per-window scatter of real data (0.02): at most one change.

    Judged window by window (level_smoothing 1) the same thetas flip the level again and again.
    """
    rng = np.random.default_rng(7)
    smoothed = HealthThresholds(warn_below=0.85, error_below=0.70, hysteresis=0.03)
    for _ in range(20):
        thetas = threshold + 0.02 * rng.standard_normal(155)
        assert level_changes(thetas, smoothed) <= 1
    assert level_changes(threshold + 0.02 * rng.standard_normal(155), T) >= 3


def test_a_real_step_is_followed_after_six_windows_with_the_default_smoothing():
    smoothed = HealthThresholds(warn_below=0.85, error_below=0.70, hysteresis=0.03)
    assert levels([0.95] * 8 + [0.6] * 7, smoothed) == [OK] * 8 + [OK, OK, WARN, WARN, WARN, ERROR, ERROR]
    monitor = HealthMonitor(smoothed)
    monitor.note_input(0.0)
    for theta in (0.95, 0.94, 0.96):
        monitor.observe(theta)
    status = monitor.status(0.0)
    assert status.message == 'lubrication good' and status.theta_mean == pytest.approx(0.950)


def test_a_restart_of_the_smoothing_judges_the_next_window_alone():
    """After a new calibration the old windows' thetas are forgotten: 0.5 x 8 then 1.0 is OK at once."""
    monitor = HealthMonitor(HealthThresholds())
    for _ in range(8):
        monitor.observe(0.5)
    assert monitor.observe(1.0) == ERROR              # mean of 0.5 x 7 and 1.0
    monitor.restart_smoothing()
    assert monitor.observe(1.0) == OK


def test_a_theta_out_of_its_range_is_at_least_warn_with_the_reason():
    from prsm_lube_ros.estimation.health import HealthStatus, out_of_range
    good = HealthStatus(OK, 'lubrication good: theta_oil 2.000', OK, 0)
    flagged = out_of_range(good, 'theta_oil 2.00 far above 1')
    assert flagged.level == WARN and flagged.message.endswith('far above 1')
    assert out_of_range(good, '') is good
    bad = HealthStatus(ERROR, 'lubrication insufficient', ERROR, 0)
    assert out_of_range(bad, 'theta_oil -0.48 below 0') is bad


def test_level_smoothing_must_be_a_positive_integer():
    with pytest.raises(InputError, match='level_smoothing'):
        HealthThresholds(level_smoothing=0)


def test_a_big_recovery_jumps_straight_back_to_ok():
    assert levels([0.5, 0.95]) == [ERROR, OK]
    assert levels([0.5, 0.80]) == [ERROR, WARN]


def test_theta_level_function_directly():
    assert theta_level(0.80, None, T) == WARN
    assert theta_level(0.80, ERROR, T) == WARN     # 0.80 > 0.70 + 0.03
    assert theta_level(0.86, WARN, T) == WARN      # 0.86 <= 0.85 + 0.03
    assert theta_level(0.86, OK, T) == OK


def test_nan_windows_keep_the_level_and_say_why():
    monitor = HealthMonitor(T)
    monitor.note_input(0.0)
    monitor.observe(0.80, 0.02)
    assert monitor.observe(math.nan, reason='screw at rest', moving=False) == WARN
    status = monitor.status(0.5)
    assert status.level == WARN
    assert status.message.startswith('not assessable: screw at rest')
    assert status.message.endswith('last level WARN') and status.reason == 'screw at rest'


def test_many_nan_windows_at_rest_never_raise_the_level():
    monitor = HealthMonitor(T)
    monitor.note_input(0.0)
    monitor.observe(0.95)
    for _ in range(100):
        monitor.observe(math.nan, reason='screw at rest', moving=False)
    assert monitor.status(0.1).level == OK


def test_nan_windows_while_moving_raise_warn_after_the_limit_and_clear_with_theta():
    monitor = HealthMonitor(T)
    monitor.note_input(0.0)
    monitor.observe(0.95)
    for _ in range(2):
        monitor.observe(math.nan, reason='no axial load in the window')
    assert monitor.status(0.1).level == OK
    monitor.observe(math.nan, reason='no axial load in the window')
    status = monitor.status(0.1)
    assert status.level == WARN and 'max_unassessed_windows 3 reached' in status.message
    assert 'no axial load' in status.message and status.unassessed_moving == 3
    monitor.observe(0.95)
    assert monitor.status(0.1).level == OK


def test_an_error_level_is_not_lowered_by_unassessable_windows():
    monitor = HealthMonitor(T)
    monitor.note_input(0.0)
    monitor.observe(0.5)
    for _ in range(5):
        monitor.observe(math.nan, reason='blocks lost')
    assert monitor.status(0.1).level == ERROR


def test_a_rest_resets_the_count_of_unassessed_moving_windows():
    monitor = HealthMonitor(T)
    monitor.note_input(0.0)
    for moving in (True, True, False, True, True):
        monitor.observe(math.nan, reason='x', moving=moving)
    assert monitor.status(0.1).level == OK


def test_stale_before_the_first_input_and_after_inputs_stop():
    monitor = HealthMonitor(T)
    assert monitor.status(0.0).level == STALE
    assert 'no vibration received yet' in monitor.status(0.0).message
    monitor.note_input(10.0)
    monitor.observe(0.6)
    assert monitor.status(11.9).level == ERROR
    status = monitor.status(12.5)
    assert status.level == STALE
    assert status.message == 'inputs stopped: no vibration for more than stale_timeout (2 s); last level ERROR'
    assert monitor.stale_for(12.5) == pytest.approx(2.5)
    monitor.note_input(13.0)      # inputs come back: the theta level is still there
    assert monitor.status(13.1).level == ERROR


def test_new_thresholds_apply_from_the_next_window():
    monitor = HealthMonitor(T)
    assert monitor.observe(0.80) == WARN
    monitor.set_thresholds(HealthThresholds(warn_below=0.75, error_below=0.5, hysteresis=0.0))
    assert monitor.observe(0.80) == OK


@pytest.mark.parametrize('kwargs, words', [
    (dict(warn_below=0.7, error_below=0.7), 'error_below'),
    (dict(warn_below=0.6, error_below=0.7), 'error_below'),
    (dict(hysteresis=-0.01), 'hysteresis'),
    (dict(hysteresis=0.2), 'hysteresis'),
    (dict(stale_timeout=0.0), 'stale_timeout'),
    (dict(warn_below=math.nan), 'warn_below'),
    (dict(max_unassessed_windows=-1), 'max_unassessed_windows'),
])
def test_thresholds_that_cannot_order_levels_are_refused(kwargs, words):
    with pytest.raises(InputError, match=words):
        HealthThresholds(**kwargs)


def test_key_value_formatting():
    assert format_value(0.123456789) == '0.123457'
    assert format_value(math.nan) == 'nan'
    assert format_value(7) == '7'
    assert format_value('x') == 'x'


def test_messages_stay_the_same_while_the_state_does():
    """Aggregators de-duplicate on the message: thetas, counts and ages change, the words do not."""
    monitor = HealthMonitor(T)
    rng = np.random.default_rng(3)
    messages = set()
    for k in range(40):
        monitor.note_input(float(k))
        monitor.observe(0.95 + 0.01 * rng.standard_normal(), 0.01)
        messages.add(monitor.status(k + 0.5).message)
    assert messages == {'lubrication good'}
    for k in range(40, 80):                     # moving, blocks lost window after window, numbers in the reason
        monitor.note_input(float(k))
        monitor.observe(math.nan, reason=f'vibration covers {k}% of the window (< 80%): blocks lost',
                        kind='blocks_lost')
        messages.add(monitor.status(k + 0.5).message)
    assert len(messages - {'lubrication good'}) == 2      # below max_unassessed_windows, then at it
    assert monitor.status(79.5).reason.startswith('vibration covers 79%')
    stale = {monitor.status(80 + s).message for s in (3.0, 4.0, 60.0)}
    assert len(stale) == 1 and 'last level OK' in stale.pop()
