# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Windows, runs and steady parts from input batches, and bad input on the way."""
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.recording.batches import VibrationBatch
from prsm_lube_ros.estimation.windowing import WindowBuilder, WindowSettings

from synthetic_inputs import interleave, merge, run_streams, T0


def build_live(streams, settings=None):
    """Feed one message at a time, popping after each (a live node)."""
    builder = WindowBuilder(settings)
    windows = []
    for batch in interleave(streams):
        builder.add(batch)
        windows += builder.pop_closed()
    return windows + builder.finish(), builder


def build_sliced(streams, settings=None):
    """Feed everything as one slice of merged batches (a bag reader)."""
    builder = WindowBuilder(settings)
    for key in ('vibration', 'screw', 'load', 'temperature'):
        builder.add(merge(streams[key]))
    return builder.pop_closed() + builder.finish(), builder


def test_steady_windows_have_the_sine_rms_and_ramps_are_left_out():
    streams = run_streams(amplitude=2.0, plateau=10.0, t_start=1.0, ramp=0.5, hold=10.0)
    windows, builder = build_live(streams)
    steady = [w for w in windows if w.steady]
    # Plateau from t=1.5 s to 11.5 s: grid windows [2,3)...[10,11) are steady (9), [1,2) and [11,12) hold ramps.
    assert [round(w.start - T0) for w in steady] == list(range(2, 11))
    for w in steady:
        assert w.vibration_rms == pytest.approx(2.0 / math.sqrt(2), rel=2e-3)  # 97 whole cycles per second
        assert w.screw_speed == pytest.approx(10.0)
        assert w.axial_load == pytest.approx(150.0)   # magnitude of a negative force.z
        assert w.temperature == pytest.approx(31.0)
        assert w.coverage == pytest.approx(1.0)
        assert w.run_index == 1
    ramp_windows = {round(w.start - T0): w for w in windows if not w.steady}
    assert 'not steady' in ramp_windows[1].reason and 'not steady' in ramp_windows[11].reason
    assert 'at rest' in ramp_windows[0].reason
    # Nut travel: lead 5 mm/rev, 10 rad/s -> 7.96 mm/s; window [2,3) is centred 1.75 s after motion start
    # travel at t: ramp 0.5 s covers 0.5*10*0.5/(2pi)*5mm = 1.99 mm, then 7.96 mm/s.
    w2 = steady[0]
    expected = (0.5 * 10 * 0.5 + 10 * (2.5 - 1.5)) / (2 * math.pi) * 0.005
    assert w2.nut_position == pytest.approx(expected, rel=0.02)
    positions = [w.nut_position for w in steady]
    assert all(b > a for a, b in zip(positions, positions[1:]))
    assert steady[-1].revolutions > steady[0].revolutions > 0
    assert builder.take_problems() == []


def test_live_and_sliced_feeding_give_the_same_windows():
    streams = run_streams()
    live, _ = build_live(streams)
    sliced, _ = build_sliced(streams)
    assert [(w.start, w.steady, w.reason) for w in live] == [(w.start, w.steady, w.reason) for w in sliced]
    for a, b in zip(live, sliced):
        assert a.vibration_rms == pytest.approx(b.vibration_rms, rel=1e-12, nan_ok=True)
        assert a.screw_speed == pytest.approx(b.screw_speed, rel=1e-12, nan_ok=True)


def test_two_runs_are_counted_and_a_window_between_them_is_not_steady():
    first = run_streams(hold=4.0, tail=1.0)
    second = run_streams(hold=4.0, tail=1.0, t0=T0 + first['duration'])
    streams = {k: first[k] + second[k] for k in ('vibration', 'screw', 'load', 'temperature')}
    windows, _ = build_live(streams)
    runs = sorted({w.run_index for w in windows if w.steady})
    assert runs == [1, 2]


def test_nan_and_inf_samples_are_left_out_and_reported_once():
    streams = run_streams()
    bad = streams['vibration'][40]
    samples = bad.samples.copy()
    samples[:10] = np.nan
    samples[10] = np.inf
    streams['vibration'][40] = VibrationBatch.single(float(bad.stamps[0]), 4000.0, samples)
    windows, builder = build_live(streams)
    problems = builder.take_problems()
    assert len(problems) == 1 and '11 NaN or inf sample(s)' in problems[0]
    w = next(w for w in windows if w.start <= bad.stamps[0] < w.end)
    assert w.sample_count == 4000 - 11
    assert math.isfinite(w.vibration_rms)


@pytest.mark.parametrize('rate', [0.0, -4000.0, math.nan, 1e-3, 1e-6, 1e9, math.inf])
def test_blocks_with_a_rate_outside_physical_bounds_are_left_out(rate):
    streams = run_streams()
    bad = streams['vibration'][50]
    streams['vibration'][50] = VibrationBatch.single(float(bad.stamps[0]), rate, bad.samples)
    windows, builder = build_live(streams)
    problems = builder.take_problems()
    assert len(problems) == 1 and 'sample_rate' in problems[0] and 'outside 1 Hz to 1e+06 Hz' in problems[0]
    assert f'sample_rate {rate:g} Hz' in problems[0] and 'np.' not in problems[0]     # a number, not a repr
    w = next(w for w in windows if w.start <= bad.stamps[0] < w.end)
    assert w.sample_count == 3600 and w.steady  # 90% coverage is above the default 80%


def test_an_empty_block_is_reported_and_changes_nothing_else():
    streams = run_streams()
    reference, _ = build_live(run_streams())
    streams['vibration'].insert(30, VibrationBatch.single(float(streams['vibration'][30].stamps[0]), 4000.0,
                                                          np.zeros(0, np.float32)))
    windows, builder = build_live(streams)
    assert builder.take_problems() == ['vibration: 1 empty block(s) (no samples) left out']
    assert [w.vibration_rms for w in windows] == pytest.approx([w.vibration_rms for w in reference],
                                                               nan_ok=True)


def test_a_gap_of_lost_blocks_makes_the_window_not_steady_with_its_reason():
    streams = run_streams()
    del streams['vibration'][52:58]   # 0.6 s of a 1 s window lost
    windows, _ = build_live(streams)
    w = next(w for w in windows if round(w.start - T0) == 5)
    assert not w.steady and 'covers 40%' in w.reason and 'lost' in w.reason


def test_stamps_going_backwards_are_left_out_and_reported():
    streams = run_streams()
    items = interleave(streams)
    builder = WindowBuilder()
    windows = []
    for i, batch in enumerate(items):
        builder.add(batch)
        windows += builder.pop_closed()
        if i == len(items) // 2:   # a block 2.5 s old arrives: its window is closed already
            old = max(0, int((float(batch.stamps[0]) - T0 - 2.5) / 0.1))
            builder.add(streams['vibration'][old])
            windows += builder.pop_closed()
    windows += builder.finish()
    assert any('stamped before already closed windows' in p for p in builder.take_problems())
    reference, _ = build_live(run_streams())
    assert [w.vibration_rms for w in windows] == pytest.approx([w.vibration_rms for w in reference],
                                                               nan_ok=True)


def test_a_clock_reset_starts_over_instead_of_dropping_everything():
    first = run_streams()
    windows, builder = build_live(first)
    again = interleave(run_streams())   # the same stamps again: a replay restarted
    for batch in again:
        builder.add(batch)
        windows += builder.pop_closed()
    windows += builder.finish()
    assert any('went back' in p for p in builder.take_problems())
    assert sum(w.steady for w in windows) == 2 * 9


def test_a_stream_that_stops_gives_nan_windows_with_a_reason_not_a_stall():
    streams = run_streams(hold=12.0)
    cut = T0 + 6.0
    streams['screw'] = [b for b in streams['screw'] if b.stamps[0] < cut]
    windows, _ = build_live(streams)
    later = [w for w in windows if w.start >= cut + 1]
    assert later and all('no screw speed' in w.reason for w in later)


def test_spectrum_is_kept_when_asked_and_peaks_at_the_signal_frequency():
    windows, _ = build_live(run_streams(), WindowSettings(spectrum_segment=400))
    w = next(w for w in windows if w.steady)
    peak = np.argmax(w.spectrum) * w.spectrum_resolution
    assert abs(peak - 97.0) <= w.spectrum_resolution


@pytest.mark.parametrize('field, value', [('window_length', 0.0), ('min_coverage', 1.5),
                                          ('min_speed', -1.0), ('max_speed_spread', math.nan)])
def test_settings_out_of_range_are_refused_in_one_line(field, value):
    with pytest.raises(InputError, match=field):
        WindowSettings(**{field: value})


def test_a_repeated_block_is_counted_once():
    streams = run_streams()
    reference, _ = build_sliced(run_streams())
    streams['vibration'].insert(60, streams['vibration'][55])   # same stamp again, in the same slice
    windows, builder = build_sliced(streams)
    assert any('repeating an earlier block' in p for p in builder.take_problems())
    assert [w.sample_count for w in windows] == [w.sample_count for w in reference]


def test_a_gap_of_an_hour_opens_no_windows_in_it():
    first = run_streams()
    second = run_streams(t0=T0 + 3600.0)
    streams = {k: first[k] + second[k] for k in ('vibration', 'screw', 'load', 'temperature')}
    single, _ = build_sliced(run_streams())
    for windows in (build_live(streams)[0], build_sliced(streams)[0]):
        starts = [round(w.start - T0) for w in windows]
        assert starts == [round(w.start - T0) for w in single] + [3600 + round(w.start - T0) for w in single]
        assert sum(w.steady for w in windows) == 2 * 9
        assert sorted({w.run_index for w in windows if w.steady}) == [1, 2]


def test_messages_out_of_time_order_within_a_slice_give_the_same_windows():
    streams = run_streams()
    reference, _ = build_sliced(streams)
    rng = np.random.default_rng(5)
    builder = WindowBuilder()
    for key in ('vibration', 'screw', 'load', 'temperature'):
        items = list(streams[key])
        rng.shuffle(items)
        builder.add(merge(items))
    windows = builder.pop_closed() + builder.finish()
    assert [(w.start, w.sample_count, w.steady, w.reason, w.run_index) for w in windows] == \
        [(w.start, w.sample_count, w.steady, w.reason, w.run_index) for w in reference]
    for a, b in zip(windows, reference):
        for field in ('vibration_rms', 'screw_speed', 'axial_load', 'nut_position', 'revolutions'):
            assert getattr(a, field) == pytest.approx(getattr(b, field), rel=1e-12, nan_ok=True)
