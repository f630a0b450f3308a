# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""WindowSettings.condition_every: the condition indicators on every k-th window of the grid only, the rest alike."""
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.conditioning import DEFAULT_BAND
from prsm_lube_ros.estimation.windowing import WindowBuilder, WindowSettings

import synthetic_inputs


def windows(**settings):
    builder = WindowBuilder(WindowSettings(band=DEFAULT_BAND, **settings), lead=0.005)
    for batch in synthetic_inputs.interleave(synthetic_inputs.run_streams(plateau=20.0, hold=8.0)):
        builder.add(batch)
    return [w for w in builder.pop_closed() + builder.finish() if w.steady]


def test_every_second_window_has_indicators_and_every_window_its_rms():
    every, second = windows(), windows(condition_every=2)
    assert len(every) == len(second) >= 6
    assert all(w.condition is not None for w in every)
    for full, half in zip(every, second):
        assert half.vibration_rms == full.vibration_rms
        key = round(full.start / 1.0)
        assert (half.condition is not None) == (key % 2 == 0)
        if half.condition is not None:
            assert half.condition.kurtosis == full.condition.kurtosis


@pytest.mark.parametrize('bad', [0, -2, 1.5])
def test_condition_every_must_be_a_positive_integer(bad):
    with pytest.raises(InputError, match='condition_every'):
        WindowSettings(condition_every=bad)


def test_deferred_indicators_come_with_complete_conditions_and_are_the_same_numbers():
    # A live node publishes theta first: closed windows without indicators, then complete_conditions gives them.
    now = windows()
    builder = WindowBuilder(WindowSettings(band=DEFAULT_BAND), lead=0.005, defer_conditions=True)
    later, completed = [], []
    for batch in synthetic_inputs.interleave(synthetic_inputs.run_streams(plateau=20.0, hold=8.0)):
        builder.add(batch)
        closed = builder.pop_closed()
        assert all(w.condition is None for w in closed)
        assert all(builder.conditions_deferred(w) == w.steady for w in closed)
        later += closed
        pairs = builder.complete_conditions()
        assert all(any(closed_k is w for w in closed) for closed_k, _ in pairs)     # each with the window it completes
        completed += [window for _, window in pairs]
        assert not any(builder.conditions_deferred(w) for w in closed)
    later += builder.finish()
    completed += [window for _, window in builder.complete_conditions()]
    assert builder.complete_conditions() == []
    steady = [w for w in later if w.steady]
    assert [w.start for w in completed] == [w.start for w in steady] == [w.start for w in now]
    for deferred, direct in zip(completed, now):
        assert deferred == direct and deferred.vibration_rms == direct.vibration_rms
        assert deferred.condition.as_dict() == direct.condition.as_dict()
        assert deferred.condition.kurtosis == direct.condition.kurtosis


def test_deferred_windows_sharing_a_start_after_a_clock_reset_each_get_their_own_indicators():
    # Stamps going back (a replay restarted) close the old windows and, within one flush, new ones at the same
    # starts: each deferred window comes back paired with itself, never with its namesake.
    builder = WindowBuilder(WindowSettings(band=DEFAULT_BAND), lead=0.005, defer_conditions=True)
    first = synthetic_inputs.interleave(synthetic_inputs.run_streams(plateau=20.0, hold=14.0, tail=0.0))
    for batch in [b for b in first if float(b.stamps[0]) < synthetic_inputs.T0 + 12.8]:
        builder.add(batch)
        builder.pop_closed()
        builder.complete_conditions()
    second = synthetic_inputs.interleave(synthetic_inputs.run_streams(
        plateau=20.0, hold=14.0, tail=0.0, t0=synthetic_inputs.T0 + 5.8, amplitude=5.0))
    for batch in [b for b in second if float(b.stamps[0]) < synthetic_inputs.T0 + 14.0]:
        builder.add(batch)
    closed = builder.pop_closed()
    starts = [w.start for w in closed if builder.conditions_deferred(w)]
    assert len(starts) > len(set(starts))          # the case: two deferred windows with one start
    pairs = builder.complete_conditions()
    assert sorted(id(window) for window, _ in pairs) == sorted(id(w) for w in closed if w.steady)
    for window, with_condition in pairs:
        assert with_condition.start == window.start and with_condition.vibration_rms == window.vibration_rms
        assert with_condition.condition is not None


def test_complete_conditions_of_given_windows_leaves_later_ones_waiting():
    builder = WindowBuilder(WindowSettings(band=DEFAULT_BAND), lead=0.005, defer_conditions=True)
    batches = synthetic_inputs.interleave(synthetic_inputs.run_streams(plateau=20.0, hold=8.0))
    half = len(batches) // 2
    for batch in batches[:half]:
        builder.add(batch)
    first = [w for w in builder.pop_closed() if w.steady]
    for batch in batches[half:]:
        builder.add(batch)
    second = [w for w in builder.pop_closed() + builder.finish() if w.steady]
    assert first and second
    done = builder.complete_conditions(first)
    assert sorted(id(w) for w, _ in done) == sorted(id(w) for w in first)
    assert all(builder.conditions_deferred(w) for w in second)       # closed later: still waiting
    assert sorted(id(w) for w, _ in builder.complete_conditions(second)) == sorted(id(w) for w in second)
    assert builder.complete_conditions() == []
