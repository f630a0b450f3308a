# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The analysis band: DC out before the RMS, one band whatever the rate, the IMU's high-pass, refusals, spectra."""
import numpy as np
import pytest
from scipy.signal import butter, sosfilt, sosfilt_zi

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.estimation.conditioning import (AnalysisBand, band_mean_square, DEFAULT_BAND, HighPassFilter,
                                                   spectrum_segment)
from prsm_lube_ros.estimation.pipeline import recording_windows
from prsm_lube_ros.estimation.windowing import WindowBuilder, WindowSettings
from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, VibrationBatch

T0 = 1.767e9
BAND_4K = DEFAULT_BAND.resolved(4000.0)   # 0.5-1600 Hz


def blocks_of(signal, rate, sizes, t0=T0):
    """(stamp, samples) blocks of consecutive pieces of ``signal`` with the given sizes."""
    blocks, start = [], 0
    for size in sizes:
        blocks.append((t0 + start / rate, signal[start:start + size]))
        start += size
    return blocks


def filter_blocks(band_filter, blocks, rate):
    """``blocks`` through ``band_filter`` one call per block (live)."""
    return np.concatenate([band_filter.apply(samples, np.array([stamp]), np.array([rate]), np.zeros(1, np.int64),
                                             np.array([samples.size])) for stamp, samples in blocks])


def test_the_imu_high_pass_over_blocks_live_or_in_one_batch_equals_one_pass_over_the_signal():
    rate = 4000.0
    rng = np.random.default_rng(1)
    signal = 9.81 + rng.standard_normal(20000)
    sizes = rng.integers(1, 900, 60)
    sizes = sizes[np.cumsum(sizes) <= signal.size]
    blocks = blocks_of(signal, rate, sizes)
    used = signal[:int(sizes.sum())]
    sos = butter(2, 0.5, 'highpass', fs=rate, output='sos')
    expected, _ = sosfilt(sos, used, zi=sosfilt_zi(sos) * used[:sizes[0]].mean())
    live = filter_blocks(HighPassFilter(), blocks, rate)
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    batch = HighPassFilter().apply(used, np.array([s for s, _ in blocks]), np.full(sizes.size, rate), starts, sizes)
    np.testing.assert_allclose(live, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(batch, expected, rtol=0, atol=1e-12)
    assert abs(expected[4000:].mean()) < 0.01          # gravity gone after the start, with no transient needed


def test_a_gap_restarts_the_imu_high_pass_at_the_new_level_without_a_transient():
    rate = 4000.0
    tone = np.sqrt(2) * np.sin(2 * np.pi * 100.0 * np.arange(8000) / rate)
    before, after = tone[:4000], tone[4000:] + 9.81          # gravity appears while nothing was recorded
    band_filter = HighPassFilter()
    first = filter_blocks(band_filter, blocks_of(before, rate, [400] * 10), rate)
    second = filter_blocks(band_filter, blocks_of(after, rate, [400] * 10, t0=T0 + 5.0), rate)   # 4 s gap
    assert np.sqrt(np.mean(first[400:] ** 2)) == pytest.approx(1.0, rel=1e-3)
    assert np.sqrt(np.mean(second ** 2)) == pytest.approx(1.0, rel=1e-3)    # from the first block on
    joined = filter_blocks(HighPassFilter(), blocks_of(np.concatenate((before, after)), rate, [400] * 20), rate)
    assert np.sqrt(np.mean(joined[4000:4400] ** 2)) > 3.0    # the same step without a gap: a real transient


def test_the_band_keeps_the_bins_inside_it_and_the_same_bins_at_any_rate():
    for rate in (4000.0, 10000.0, 51200.0):
        t = np.arange(int(rate)) / rate                       # one 1 s window: 1 Hz bins
        signal = 9.81 + np.sqrt(2) * np.sin(2 * np.pi * 3.0 * t) + np.sqrt(2) * 0.5 * np.sin(2 * np.pi * 1200.0 * t)
        assert DEFAULT_BAND.resolved(rate).high == 0.4 * rate      # by default the whole band the rate gives
        band = AnalysisBand(high=1600.0)                            # what calibrate --band-high 1600 asks for
        assert band_mean_square(signal, rate, band) == pytest.approx(1.25, rel=1e-9)   # 1 + 0.25, gravity out
        if rate > 4000:
            above = signal + np.sqrt(2) * np.sin(2 * np.pi * 1700.0 * t)            # outside the band
            assert band_mean_square(above, rate, band) == pytest.approx(1.25, rel=1e-9)


def steady_windows(offset, rate, band=DEFAULT_BAND, seconds=8.0, blocks_per_batch=7):
    """Windows of a 30 rad/s, 200 N run whose vibration is a 0.7 m/s^2 RMS mix plus ``offset`` m/s^2."""
    rng = np.random.default_rng(4)
    n = int(seconds * rate)
    t = np.arange(n) / rate
    signal = (0.5 * np.sin(2 * np.pi * 4.77 * t) + 0.6 * np.sin(2 * np.pi * 310.0 * t + 0.3)
              + 0.2 * rng.standard_normal(n)) + offset
    size = int(rate * 0.1)
    builder = WindowBuilder(WindowSettings(band=band), lead=0.005)
    for first in range(0, n // size, blocks_per_batch):
        last = min(first + blocks_per_batch, n // size)
        count = last - first
        builder.add(VibrationBatch(T0 + np.arange(first, last) * 0.1, np.full(count, rate),
                                   np.arange(count + 1, dtype=np.int64) * size,
                                   signal[first * size:last * size].astype(np.float32)))
    stamps = T0 + np.arange(0, seconds, 0.01)
    builder.add(ScrewStateBatch(stamps, 30.0 * (stamps - T0), np.full(stamps.size, 30.0)))
    builder.add(AxialLoadBatch(stamps, np.full(stamps.size, -200.0)))
    windows = builder.pop_closed() + builder.finish()
    return [w for w in windows if w.steady], builder


@pytest.mark.parametrize('rate', [4000.0, 20000.0])
def test_a_dc_offset_leaves_the_window_rms_in_the_band_and_raises_the_raw_one(rate):
    clean, builder = steady_windows(0.0, rate)
    gravity, _ = steady_windows(9.81, rate)
    assert builder.band.high == 0.4 * rate and len(clean) == 8
    for a, b in zip(clean, gravity):
        assert b.vibration_rms == pytest.approx(a.vibration_rms, rel=2e-4)
        assert a.sample_rate == rate
    raw, _ = steady_windows(9.81, rate, band=None)
    assert raw[0].vibration_rms > 9.8                        # what the RMS was without the band


def test_the_band_edge_follows_the_first_rate_and_a_slower_one_is_refused_in_one_line():
    assert DEFAULT_BAND.resolved(51200.0).high == 20480.0
    assert DEFAULT_BAND.resolved(2000.0).high == 800.0
    _, builder = steady_windows(0.0, 2000.0, band=BAND_4K)
    line = ('vibration: sample rate 2000 Hz cannot cover the analysis band 0.5-1600 Hz (needs at least 4000 Hz: '
            'upper edge at most 0.8 x the Nyquist frequency); record faster, or calibrate in a band every recording '
            'covers (prsm-lube calibrate --band-high HZ, at most 800 Hz for this rate; 1600 Hz serves every rate from '
            '4000 Hz up)')
    assert builder.band_refusal == line
    assert builder.take_problems() == [line + '; 7 block(s) left out']
    with pytest.raises(InputError, match='analysis band'):
        AnalysisBand(low=0.0)
    with pytest.raises(InputError, match='high-pass'):
        HighPassFilter(0.0)


def test_a_recording_below_the_band_is_refused_by_the_pipeline(paper_experiment):
    band = AnalysisBand(high=4000.0)           # needs 10 kHz; the paper's recordings are at 4 kHz
    with pytest.raises(InputError) as refused:
        recording_windows(paper_experiment / 'stage_1', lead=0.005, settings=WindowSettings(band=band))
    assert str(refused.value) == (
        f'{paper_experiment / "stage_1"}: vibration: sample rate 4000 Hz cannot cover the analysis band '
        '0.5-4000 Hz (needs at least 10000 Hz: upper edge at most 0.8 x the Nyquist frequency); '
        'record faster, or calibrate in a band every recording covers '
        '(prsm-lube calibrate --band-high HZ, at most 1600 Hz for this rate; '
        '1600 Hz serves every rate from 4000 Hz up)')


def test_spectrum_segments_resolve_the_lowest_order_at_the_lowest_speed():
    assert spectrum_segment(25600.0, 25.0) == 4096                     # 6.25 Hz bins for 25 Hz shaft orders
    assert spectrum_segment(4000.0, 100 / 60, max_samples=4000) == 2048      # capped by the window
    rate = 25600.0
    t = np.arange(int(rate)) / rate
    spectra = {}
    for lowest in (0.0, 25.0):
        builder = WindowBuilder(WindowSettings(spectrum_segment=256, spectrum_lowest_frequency=lowest), lead=0.005)
        signal = np.sin(2 * np.pi * 25.0 * t) + np.sin(2 * np.pi * 50.0 * t)   # orders 1 and 2 at 1500 r/min
        builder.add(VibrationBatch(np.array([T0]), np.array([rate]), np.array([0, t.size]), signal))
        window = builder.finish()[0]
        spectra[lowest] = (window.spectrum, window.spectrum_resolution)
    coarse, fine = spectra[0.0], spectra[25.0]
    assert coarse[1] == 100.0 and fine[1] == 6.25
    psd, df = fine
    at = [int(round(f / df)) for f in (25.0, 37.5, 50.0)]
    assert psd[at[1]] < 0.01 * min(psd[at[0]], psd[at[2]])      # two orders, a trough between them
    assert coarse[0][1] > 0.1 * coarse[0][0]        # 100 Hz bins: both orders in the first two bins
