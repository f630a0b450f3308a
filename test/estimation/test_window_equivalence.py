# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""WindowBuilder against a straightforward per-sample computation; Assessor's array path against Eq. 23.

The reference below takes each sample and message on its own: it puts it in
window ``floor(t / L)`` by its time, sums with ``math.fsum`` and words the
reasons from the rules in the windowing docs.  Awkward inputs: blocks that
straddle window boundaries, windows shorter than a block, jittered stamps,
NaN and inf samples, several runs in both directions, several sample rates.
The builder is fed live (one message at a time) and as slices of merged
batches cut at times that line up with nothing.  The assessment of all windows (and
runs) at once must give exactly what one window (run) at a time gives.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from prsm_lube_ros.estimation.assessment import Assessor
from prsm_lube_ros.estimation.calibration import Calibration
from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch
from prsm_lube_ros.physics.vibration_model import ModelConstants
from prsm_lube_ros.estimation.windowing import Window, WindowBuilder, WindowSettings

from synthetic_inputs import T0

LEAD = 0.005
RUNS = ((0.8, 6.0, 120.0), (5.2, -14.0, 400.0), (9.6, 22.0, 60.0))   # (start s, speed rad/s, load N)
RAMP, HOLD = 0.4, 2.6
DURATION = 14.0


def screw_speed(t):
    """Signed screw speed, rad/s: trapezoid runs at rest in between."""
    speed = np.zeros_like(t)
    for start, plateau, _ in RUNS:
        up = np.clip((t - start) / RAMP, 0, 1)
        down = np.clip((start + 2 * RAMP + HOLD - t) / RAMP, 0, 1)
        speed += plateau * np.minimum(up, down)
    return speed


def axial_force(t):
    """Axial force, N (negative: compression), each run's load from shortly before it starts."""
    force = np.full_like(t, -2.0)
    for start, _, load in RUNS:
        force = np.where((t >= start - 0.3) & (t < start + 2 * RAMP + HOLD + 0.3), -load, force)
    return force


def _off_boundaries(stamp, rate, count, length):
    """``stamp`` nudged so that no sample lies within 2 us of a window boundary (float stamps are 0.24 us)."""
    while True:
        t = stamp - T0 + np.arange(count) / rate
        distance = np.abs(t - length * np.round(t / length))
        if distance.min() > 2e-6:
            return stamp
        stamp += 7e-6


def scenario(seed, length, rates, block_seconds, jitter, bad_fraction):
    """Input messages of three runs: lists of (stamp, ...) tuples per stream."""
    rng = np.random.default_rng(seed)
    blocks = []
    stamp = T0 + 0.0123
    while stamp < T0 + DURATION:
        rate = float(rng.choice(rates))
        count = max(1, int(round(block_seconds * rate)))
        stamp = _off_boundaries(stamp, rate, count, length)
        t = stamp - T0 + np.arange(count) / rate
        amplitude = 0.3 + 0.05 * np.abs(screw_speed(t))
        samples = (amplitude * rng.standard_normal(count)).astype(np.float32)
        bad = rng.random(count) < bad_fraction
        samples[bad] = rng.choice([np.nan, np.inf, -np.inf], int(bad.sum()))
        blocks.append((stamp, rate, samples))
        stamp += count / rate + rng.uniform(-jitter, jitter)
    tj = np.arange(0.0, DURATION, 0.01) + rng.uniform(-jitter, jitter, 1400)
    speed = screw_speed(tj) * (1 + 1e-4 * rng.standard_normal(tj.size))
    angle = np.concatenate(([0.3], 0.3 + np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(tj))))
    screw = list(zip((T0 + tj).tolist(), angle.tolist(), speed.tolist()))
    tl = np.arange(0.0, DURATION, 0.05) + rng.uniform(-jitter, jitter, 280)
    force = axial_force(tl) * (1 + 1e-3 * rng.standard_normal(tl.size))
    load = list(zip((T0 + tl).tolist(), force.tolist()))
    tt = np.arange(0.3, DURATION, 1.0)
    temperature = list(zip((T0 + tt).tolist(), (30.0 + 0.1 * tt).tolist()))
    return SimpleNamespace(vibration=blocks, screw=screw, load=load, temperature=temperature)


def reference_windows(inputs, settings):
    """Every window's values and reason, computed sample by sample and message by message."""
    length = settings.window_length
    acc = {}

    def window(k):
        return acc.setdefault(k, SimpleNamespace(squares=[], count=0, rate=0.0, speeds=[], runs=[], travel=[],
                                                 revolutions=math.nan, loads=[], temps=[]))

    for stamp, rate, samples in inputs.vibration:
        keys = np.floor((stamp + np.arange(samples.size) / rate) / length).astype(np.int64)
        for k, x in zip(keys.tolist(), samples.astype(float).tolist()):
            w = window(k)
            w.rate = max(w.rate, rate)
            if math.isfinite(x):
                w.squares.append(x * x)
                w.count += 1
    moving, run, start_angle, last_angle, revolutions = False, 0, math.nan, math.nan, 0.0
    for stamp, angle, speed in inputs.screw:
        speed = abs(speed)
        now_moving = speed >= settings.min_speed
        if now_moving and not moving:
            run, start_angle = run + 1, angle
        if math.isfinite(last_angle):
            revolutions += abs(angle - last_angle) / (2 * math.pi)
        last_angle, moving = angle, now_moving
        w = window(math.floor(stamp / length))
        w.speeds.append(speed)
        w.runs.append(run)
        w.revolutions = revolutions
        if now_moving:
            w.travel.append(LEAD * (angle - start_angle) / (2 * math.pi))
    for stamp, force in inputs.load:
        window(math.floor(stamp / length)).loads.append(abs(force))
    for stamp, temperature in inputs.temperature:
        window(math.floor(stamp / length)).temps.append(temperature)
    return [_reference_window(k, acc[k], settings) for k in sorted(acc)]


def _mean(values):
    return math.fsum(values) / len(values) if values else math.nan


def _reference_window(k, w, settings):
    length = settings.window_length
    coverage = w.count / (length * w.rate) if w.rate > 0 else 0.0
    speed = _mean(w.speeds)
    spread = (max(w.speeds) - min(w.speeds)) / speed if w.speeds and speed > 0 else math.nan
    if w.count == 0:
        reason = 'no vibration samples in the window'
    elif coverage < settings.min_coverage:
        reason = f'vibration covers {100 * coverage:.0f}% of the window (< {100 * settings.min_coverage:.0f}%)'
    elif not w.speeds:
        reason = 'no screw speed in the window'
    elif speed < settings.min_speed:
        reason = f'screw at rest or crawling ({speed:.3g} rad/s'
    elif spread > settings.max_speed_spread:
        reason = f'screw speed not steady (varies {100 * spread:.1f}%'
    elif min(w.runs) != max(w.runs):
        reason = 'window spans the end of one run and the start of the next'
    elif not w.loads:
        reason = 'no axial load in the window'
    else:
        reason = ''
    return SimpleNamespace(start=k * length, sample_count=w.count, coverage=coverage,
                           vibration_rms=math.sqrt(math.fsum(w.squares) / w.count) if w.count else math.nan,
                           screw_speed=speed, speed_spread=spread, axial_load=_mean(w.loads),
                           temperature=_mean(w.temps), nut_position=_mean(w.travel),
                           revolutions=w.revolutions, run_index=max(w.runs) if w.runs else None,
                           reason=reason)


def _messages(inputs):
    """(stamp, kind, payload) of every message."""
    items = [(s, 'vibration', (r, x)) for s, r, x in inputs.vibration]
    items += [(s, 'screw', (a, v)) for s, a, v in inputs.screw]
    items += [(s, 'load', (f,)) for s, f in inputs.load]
    items += [(s, 'temperature', (c,)) for s, c in inputs.temperature]
    return items


def _batch(kind, items):
    """One batch of ``kind`` from (stamp, kind, payload) items."""
    stamps = np.array([s for s, _, _ in items])
    if kind == 'vibration':
        samples = [p[1] for _, _, p in items]
        offsets = np.concatenate(([0], np.cumsum([x.size for x in samples]))).astype(np.int64)
        return VibrationBatch(stamps, np.array([p[0] for _, _, p in items]), offsets, np.concatenate(samples))
    if kind == 'screw':
        return ScrewStateBatch(stamps, np.array([p[0] for _, _, p in items]), np.array([p[1] for _, _, p in items]))
    values = np.array([p[0] for _, _, p in items])
    return AxialLoadBatch(stamps, values) if kind == 'load' else TemperatureBatch(stamps, values)


def build(inputs, settings, slice_seconds=None):
    """Windows of the builder fed live (``slice_seconds`` None) or in slices of merged batches."""
    builder = WindowBuilder(settings, lead=LEAD)
    messages = sorted(_messages(inputs), key=lambda m: m[0])
    if slice_seconds is None:
        groups = [[m] for m in messages]
    else:
        groups = {}
        for m in messages:
            groups.setdefault(math.floor((m[0] - T0) / slice_seconds), []).append(m)
        groups = [groups[j] for j in sorted(groups)]
    windows = []
    for group in groups:
        for kind in ('vibration', 'screw', 'load', 'temperature'):
            items = [m for m in group if m[1] == kind]
            if items:
                builder.add(_batch(kind, items))
        windows += builder.pop_closed()
    return windows + builder.finish(), builder


SCENARIOS = {
    'blocks straddle 1 s windows, jittered': dict(seed=1, length=1.0, rates=(4000.0,), block_seconds=0.13,
                                                  jitter=2e-4, bad_fraction=0.0),
    'windows shorter than blocks': dict(seed=2, length=0.05, rates=(4000.0,), block_seconds=0.1,
                                        jitter=1e-4, bad_fraction=0.0),
    'NaN and inf samples': dict(seed=3, length=0.5, rates=(4000.0,), block_seconds=0.1, jitter=1e-4,
                                bad_fraction=2e-3),
    'several sample rates': dict(seed=4, length=1.0, rates=(4100.0, 3500.0, 4000.0), block_seconds=0.17,
                                 jitter=3e-4, bad_fraction=5e-4),
}


@pytest.mark.parametrize('name', list(SCENARIOS))
@pytest.mark.parametrize('feeding', [None, 0.7, 60.0], ids=['live', 'slices of 0.7 s', 'one slice'])
def test_windows_match_a_per_sample_reference(name, feeding):
    params = SCENARIOS[name]
    # The raw RMS (no band): the reference sums the samples as they are; the band is test_conditioning's.
    settings = WindowSettings(window_length=params['length'], band=None)
    inputs = scenario(**params)
    expected = reference_windows(inputs, settings)
    windows, builder = build(inputs, settings, feeding)
    assert [w.start for w in windows] == [e.start for e in expected]
    assert len({w.run_index for w in windows if w.steady}) == 3   # every run has steady windows
    for w, e in zip(windows, expected):
        assert w.end == pytest.approx(e.start + settings.window_length, abs=1e-6)
        assert w.sample_count == e.sample_count, w.start - T0
        assert w.coverage == pytest.approx(e.coverage, rel=1e-12)
        assert w.reason.startswith(e.reason), (w.start - T0, w.reason, e.reason)
        assert w.steady == (e.reason == '')
        for field in ('vibration_rms', 'screw_speed', 'axial_load', 'temperature', 'nut_position'):
            assert getattr(w, field) == pytest.approx(getattr(e, field), rel=1e-12, abs=1e-15, nan_ok=True), field
        assert w.speed_spread == pytest.approx(e.speed_spread, rel=1e-9, abs=1e-12, nan_ok=True)
        assert w.revolutions == pytest.approx(e.revolutions, rel=1e-12, nan_ok=True)
        if e.run_index is not None:
            assert w.run_index == e.run_index
    bad = sum(int((~np.isfinite(x)).sum()) for _, _, x in inputs.vibration)
    problems = builder.take_problems()
    if bad:   # reported once, in words, with the count of the first batch that had any
        assert len(problems) == 1 and problems[0].endswith(' NaN or inf sample(s) left out')
        assert builder.problem_summary() == {'vibration-nonfinite': bad}
        if feeding == 60.0:
            assert problems == [f'vibration: {bad} NaN or inf sample(s) left out']
    else:
        assert problems == [] and builder.problem_summary() == {}


def _window(speed, load, rms, steady=True, reason='', run=1, count=4000):
    return Window(start=0.0, end=1.0, vibration_rms=rms, sample_count=count, coverage=1.0, screw_speed=speed,
                  speed_spread=0.0, axial_load=load, temperature=30.0 + run, nut_position=0.05, revolutions=3.0,
                  run_index=run, reason_kind='' if steady else 'at_rest', reason=reason)


def _calibration():
    covariance = np.array([[4e-4, 1e-7, 2e-5], [1e-7, 1e-9, 3e-8], [2e-5, 3e-8, 9e-5]])
    return Calibration(constants=ModelConstants(c_sys=0.08, c_f=1e-3, c_lambda=0.30), covariance=covariance,
                       fit_rmse=0.02, residual_std=0.02, windows_used=60, reference_theta=1.0)


def _eq23(rms, speed, load, c):
    """Eq. 23 by hand with the math module."""
    return ((c.c_f * load - math.log(rms / (c.c_sys * speed ** 2 * load ** (-1 / 3))))
            / (c.c_lambda * speed ** 0.68 * load ** -0.073))


def _bits(assessment):
    """theta, its std (NaN as None, so NaN equals NaN) and the reason of an assessment."""
    return tuple(None if v != v else v for v in (assessment.theta_oil, assessment.theta_oil_std)) + \
        (assessment.reason,)


def test_all_windows_at_once_give_exactly_what_each_window_alone_gives():
    rng = np.random.default_rng(7)
    windows = [_window(float(s), float(f), float(a), run=int(r)) for s, f, a, r in
               zip(rng.uniform(5, 25, 300), rng.uniform(50, 400, 300), rng.uniform(0.5, 20, 300),
                   rng.integers(1, 6, 300))]
    windows += [_window(0.5, 100.0, 1.0, steady=False, reason='screw at rest or crawling'),
                _window(10.0, 2.0, 1.0), _window(10.0, 100.0, 0.0), _window(10.0, 100.0, math.nan),
                _window(10.0, 100.0, 1e-300)]   # the last: Eq. 23 far outside any sensible range, still finite
    assessor = Assessor(_calibration())
    together = assessor.assess_windows(windows)
    alone = [assessor.assess_window(w) for w in windows]
    assert [_bits(a) for a in together] == [_bits(a) for a in alone]
    for w, a in zip(windows[:300], together):
        assert a.theta_oil == pytest.approx(_eq23(w.vibration_rms, w.screw_speed, w.axial_load,
                                                  assessor.calibration.constants), rel=1e-12)
        assert a.theta_oil_std > 0
    assert [a.reason.split(':')[0] for a in together[300:]] == [
        'screw at rest or crawling', 'axial load 2 N is below 5 N', 'no vibration', 'no vibration', '']


def test_runs_at_once_give_eq23_of_each_runs_pooled_values():
    rng = np.random.default_rng(8)
    runs = {r: [_window(10.0 * r, 100.0 + r, float(a), run=r, count=int(n)) for a, n in
                zip(rng.uniform(1, 3, r + 1), rng.integers(3000, 4001, r + 1))] for r in range(1, 6)}
    assessor = Assessor(_calibration())
    everything = [w for r in sorted(runs) for w in runs[r]]
    results = assessor.assess_runs(assessor.assess_windows(everything))
    assert [r.run_index for r in results] == [1, 2, 3, 4, 5]
    for result in results:
        windows = runs[result.run_index]
        counts = [w.sample_count for w in windows]
        rms = math.sqrt(math.fsum(n * w.vibration_rms ** 2 for n, w in zip(counts, windows)) / sum(counts))
        assert result.windows == len(windows)
        assert result.vibration_rms == pytest.approx(rms, rel=1e-13)
        assert result.temperature == 30.0 + result.run_index
        assert result.theta_oil == pytest.approx(_eq23(rms, 10.0 * result.run_index, 100.0 + result.run_index,
                                                       assessor.calibration.constants), rel=1e-12)
        alone = assessor.assess_run(windows)
        assert (alone.theta_oil, alone.theta_oil_std) == (result.theta_oil, result.theta_oil_std)
