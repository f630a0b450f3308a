# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Header fields and values no sensor of the contract gives: one named problem each, bounded memory."""
import math
import resource
import time

import numpy as np
import pytest

from prsm_lube_ros.estimation.windowing import WindowBuilder
from prsm_lube_ros.recording import plausibility
from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch

from synthetic_inputs import interleave, run_streams


def build(streams):
    builder = WindowBuilder()
    windows = []
    open_rows = 0
    for batch in interleave(streams):
        builder.add(batch)
        open_rows = max(open_rows, len(builder._open))
        windows += builder.pop_closed()
    return windows + builder.finish(), builder, open_rows


def steady_starts(windows):
    return [w.start for w in windows if w.steady]


@pytest.mark.parametrize('rate', [1e-3, 1e-6, 1e-9, 5e-324])
def test_one_block_with_a_tiny_rate_opens_no_windows_and_costs_no_memory(rate):
    """The trial's case: one block's sample_rate of 1e-3 Hz made 4000 samples span 46 days of windows."""
    reference, _, _ = build(run_streams())
    streams = run_streams()
    bad = streams['vibration'][50]
    streams['vibration'][50] = VibrationBatch.single(float(bad.stamps[0]), rate, bad.samples)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.process_time()
    windows, builder, open_rows = build(streams)
    assert time.process_time() - start < 30      # not a timing goal: a bound that a blow-up would pass by hours
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000   # kB
    assert open_rows < 10 and len(windows) == len(reference)
    assert steady_starts(windows) == steady_starts(reference)
    assert builder.problem_summary() == {'vibration-rate': 1}


def test_a_block_longer_than_a_minute_is_left_out_in_one_named_line():
    streams = run_streams()
    bad = streams['vibration'][50]
    streams['vibration'][50] = VibrationBatch.single(float(bad.stamps[0]), 1.0, np.ones(4000, np.float32))
    windows, builder, open_rows = build(streams)
    problems = builder.take_problems()
    assert problems == ['vibration: 1 block(s) of 4000 samples at 1 Hz (4e+03 s, longer than 60 s) left out']
    assert open_rows < 10


def test_samples_beyond_any_accelerometer_are_a_named_problem_not_a_window_rms_of_3e36():
    reference, _, _ = build(run_streams())
    streams = run_streams()
    bad = streams['vibration'][50]
    samples = bad.samples.copy()
    samples[7] = 3e36
    samples[8] = -2e6
    streams['vibration'][50] = VibrationBatch.single(float(bad.stamps[0]), float(bad.sample_rates[0]), samples)
    windows, builder, _ = build(streams)
    problems = builder.take_problems()
    assert len(problems) == 1 and '2 sample(s) beyond 100000 m/s^2' in problems[0]
    assert max(w.vibration_rms for w in windows if math.isfinite(w.vibration_rms)) < 10
    for clean, dirty in zip(reference, windows):
        assert dirty.vibration_rms == pytest.approx(clean.vibration_rms, rel=1e-2, nan_ok=True)


def test_speeds_loads_and_temperatures_beyond_the_sensors_are_named_and_left_out():
    reference, _, _ = build(run_streams())
    streams = run_streams()
    screw = streams['screw'][100]
    streams['screw'][100] = ScrewStateBatch(screw.stamps, screw.angles, np.array([1e30]))
    load = streams['load'][40]
    streams['load'][40] = AxialLoadBatch(load.stamps, np.array([-5e12]))
    streams['temperature'] = [TemperatureBatch(np.array([float(streams['load'][10].stamps[0])]), np.array([1e4]))]
    windows, builder, _ = build(streams)
    problems = builder.take_problems()
    assert any('1 screw speed(s) beyond 10000 rad/s' in line for line in problems), problems
    assert any('axial_load: 1 value(s) beyond 1e+07 N' in line for line in problems), problems
    assert any('temperature: 1 value(s) outside -100 to 500 degC' in line for line in problems), problems
    assert steady_starts(windows) == steady_starts(reference)
    assert max(w.axial_load for w in windows if math.isfinite(w.axial_load)) < 1e3


def test_the_bounds_hold_the_contract_rates_with_margin():
    """CONTRACT.md: 1-20 kHz in blocks of 5-200 ms; real accelerometers up to 51.2 kHz."""
    rates = np.array([1e3, 4e3, 20e3, 51.2e3])
    assert plausibility.plausible_rates(rates).all()
    assert plausibility.plausible_durations(rates * 0.2, rates).all()
    assert not plausibility.plausible_rates([0.5, 2e6, math.nan, -1.0]).any()
