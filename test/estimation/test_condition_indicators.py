# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Condition indicators of one window: Gaussian vibration, tones and defect strikes tell themselves apart."""
import math

import numpy as np
import pytest

from prsm_lube_ros.estimation.condition_indicators import condition_indicators, kurtosis
from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.physics.defect_orders import prsm_defect_orders

ORDERS = prsm_defect_orders(Actuator())
RATE = 8000.0
BAND = (0.5, 3200.0)


def strikes(times, angles, order, mode_hz=1500.0, damping=0.04, scatter=0.3, rng=None):
    """Decaying rings of a mode, one per passing contact (``order`` strikes per screw revolution)."""
    rng = rng or np.random.default_rng(0)
    count = int(angles[-1] / (2 * math.pi) * order)
    hits = np.interp(2 * math.pi * np.arange(1, count + 1) / order, angles, times)
    signal = np.zeros(times.size)
    decay = 2 * math.pi * mode_hz * damping
    for t0, amplitude in zip(hits, np.exp(scatter * rng.standard_normal(hits.size))):
        after = times >= t0
        dt = times[after] - t0
        signal[after] += amplitude * np.exp(-decay * dt) * np.sin(2 * math.pi * mode_hz * dt)
    return signal


def window(speed=20.0, ramp=0.0, rng=None):
    times = np.arange(int(RATE)) / RATE
    speeds = speed * (1 + ramp * (times - 0.5))
    angles = np.cumsum(speeds) / RATE
    return times, speeds, angles


def test_gaussian_vibration_reads_kurtosis_three_and_no_defect_line():
    rng = np.random.default_rng(1)
    found = [condition_indicators(rng.standard_normal(int(RATE)), RATE, 20.0, BAND, ORDERS) for _ in range(20)]
    assert np.median([c.kurtosis for c in found]) == pytest.approx(3.0, abs=0.15)
    assert max(c.crest_factor for c in found) < 5.5
    lines = [c.defect_peak() for c in found]
    assert sum(line is not None and line.db > 12 for line in lines) <= 1


def test_a_tone_reads_kurtosis_one_and_a_half():
    times = np.arange(int(RATE)) / RATE
    assert kurtosis(np.sin(2 * math.pi * 100 * times)) == pytest.approx(1.5, abs=0.01)
    found = condition_indicators(np.sin(2 * math.pi * 100 * times), RATE, 20.0, BAND, ORDERS)
    assert found.crest_factor == pytest.approx(math.sqrt(2), rel=0.02)


@pytest.mark.parametrize('order, component', [(6.25, 'screw raceway'), (3.75, 'nut raceway or roller')])
def test_strikes_at_a_defect_order_are_impulsive_and_labelled(order, component):
    rng = np.random.default_rng(2)
    times, _, angles = window()
    signal = 0.1 * rng.standard_normal(times.size) + strikes(times, angles, order, rng=rng)
    found = condition_indicators(signal, RATE, 20.0, BAND, ORDERS)
    assert found.kurtosis > 5
    line = found.defect_peak()
    assert line is not None and line.component == component
    assert line.order == pytest.approx(order, rel=0.03) and line.db > 10
    assert found.demodulation_band[0] < 1500 < found.demodulation_band[1]   # the band the strikes ring in


def test_order_tracking_keeps_the_line_sharp_while_the_speed_changes():
    rng = np.random.default_rng(3)
    times, speeds, angles = window(speed=60.0, ramp=0.3)
    signal = 0.2 * rng.standard_normal(times.size) + strikes(times, angles, 6.25, rng=rng)
    mean_speed = float(speeds.mean())
    tracked = condition_indicators(signal, RATE, mean_speed, BAND, ORDERS, angle_times=times, angles=angles)
    plain = condition_indicators(signal, RATE, mean_speed, BAND, ORDERS)
    assert tracked.defect_peak() is not None
    assert tracked.defect_peak().db > (plain.defect_peak().db if plain.defect_peak() else 0.0) + 3


def test_too_few_samples_or_no_speed_give_nan_not_an_error():
    assert math.isnan(condition_indicators(np.ones(10), RATE, 20.0, BAND, ORDERS).kurtosis)
    found = condition_indicators(np.random.default_rng(0).standard_normal(4000), RATE, 0.0, BAND, ORDERS)
    assert math.isfinite(found.kurtosis) and found.envelope_peaks == ()
    assert found.as_dict()['envelope_peaks'] == []


def test_the_floors_are_nanmedians_of_every_row_whatever_its_nans():
    """The floor's fast path (rows' finite heads at once) gives np.nanmedian's value on every kind of row."""
    import warnings
    from prsm_lube_ros.estimation.condition_indicators import _floors, FLOOR_LOWEST_ORDER, ORDER_GRID
    rng = np.random.default_rng(1)
    grids = rng.exponential(size=(60, ORDER_GRID.size))
    for k in range(50):
        grids[k, ORDER_GRID.size - 7 * k:] = np.nan          # heads of every length, the full row included
    grids[50, 100] = np.nan                                   # a hole
    grids[51, :] = np.nan                                     # nothing
    grids[52, 40:] = np.nan                                   # nothing above the floor's lowest order
    grids[53, 500:510] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        expected = np.nanmedian(grids[:, ORDER_GRID >= FLOOR_LOWEST_ORDER], axis=1)
    assert np.array_equal(_floors(grids), expected, equal_nan=True)
    assert np.isnan(_floors(grids)[51]) and np.isfinite(_floors(grids)[:50]).all()


def test_the_gaussian_part_is_the_whole_rms_of_gaussian_vibration():
    rng = np.random.default_rng(3)
    found = [condition_indicators(0.7 * rng.standard_normal(int(RATE)), RATE, 20.0, BAND, ORDERS)
             for _ in range(10)]
    band_share = math.sqrt((BAND[1] - BAND[0]) / (RATE / 2))     # white noise: the band holds its share of the power
    assert np.median([c.gaussian_rms for c in found]) == pytest.approx(0.7 * band_share, rel=0.02)


def test_sparse_strikes_leave_the_gaussian_part_and_add_to_the_rms():
    """Strikes at roller pass carrying three times the Gaussian power: the RMS doubles, the Gaussian part stays."""
    rng = np.random.default_rng(5)
    times, _, angles = window(speed=6.0)
    rings = strikes(times, angles, ORDERS[0].order, mode_hz=1500.0, damping=0.04, rng=rng)
    contact = rng.standard_normal(times.size)
    rings *= math.sqrt(3.0 * np.mean(contact ** 2) / np.mean(rings ** 2))
    struck = condition_indicators(contact + rings, RATE, 6.0, (0.5, 3999.0), ORDERS)
    plain = condition_indicators(contact, RATE, 6.0, (0.5, 3999.0), ORDERS)
    rms = math.sqrt(np.mean((contact + rings) ** 2))
    assert rms > 1.9 * plain.gaussian_rms
    assert struck.gaussian_rms == pytest.approx(plain.gaussian_rms, rel=0.1)


def test_dense_strikes_raise_the_gaussian_part_less_than_ten_times():
    """Strikes ringing a low, lightly damped mode for most of their period: the median sees them as Gaussian.

    A mode at 200 Hz damped 2 % rings for 40 ms, the strikes come every 50 ms and carry 80 % of the power: the
    measured Gaussian part is far above the contacts' (the estimate's bias), yet under the ten times the surface
    defect's refutation allows (``SILENCED_SHARE``).
    """
    rng = np.random.default_rng(7)
    times, _, angles = window(speed=2 * math.pi * 20 / ORDERS[0].order)     # 20 strikes a second
    rings = strikes(times, angles, ORDERS[0].order, mode_hz=200.0, damping=0.02, rng=rng)
    contact = rng.standard_normal(times.size)
    rings *= math.sqrt(4.0 * np.mean(contact ** 2) / np.mean(rings ** 2))
    speed = 2 * math.pi * 20 / ORDERS[0].order
    struck = condition_indicators(contact + rings, RATE, speed, (0.5, 3999.0), ORDERS)
    plain = condition_indicators(contact, RATE, speed, (0.5, 3999.0), ORDERS)
    from prsm_lube_ros.diagnosis.effects.surface_defect import SILENCED_SHARE
    bias = struck.gaussian_rms ** 2 / plain.gaussian_rms ** 2
    assert 1.5 < bias < 1 / SILENCED_SHARE
