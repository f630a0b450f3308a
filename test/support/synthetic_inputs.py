# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Synthetic input batches with known answers, for tests without recordings."""
import math

import numpy as np

from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch

T0 = 1767225600.0  # 2026-01-01T00:00:00Z


def speed_profile(t, plateau, t_start, ramp, hold):
    """Trapezoid: 0 until t_start, ramp up, hold, ramp down, 0."""
    up = np.clip((t - t_start) / ramp, 0, 1)
    down = np.clip((t_start + ramp + hold + ramp - t) / ramp, 0, 1)
    return plateau * np.minimum(up, down)


def run_streams(plateau=10.0, load=150.0, amplitude=2.0, t_start=1.0, ramp=0.5, hold=10.0,
                tail=2.0, rate=4000.0, block=0.1, joint_rate=100.0, load_rate=20.0, t0=T0):
    """One run as lists of single-message batches: a sine of `amplitude` (RMS amplitude/sqrt 2)."""
    duration = t_start + 2 * ramp + hold + tail
    vib, screw, loads, temps = [], [], [], []
    n = int(round(block * rate))
    for b in range(int(round(duration / block))):
        stamp = t0 + b * block
        t = b * block + np.arange(n) / rate
        vib.append(VibrationBatch.single(stamp, rate, (amplitude * np.sin(2 * math.pi * 97.0 * t))
                                         .astype(np.float32)))
    tj = np.arange(0, duration, 1 / joint_rate)
    w = speed_profile(tj, plateau, t_start, ramp, hold)
    angle = np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) / joint_rate)))
    for t, s, a in zip(tj, w, angle):
        screw.append(ScrewStateBatch(np.array([t0 + t]), np.array([a]), np.array([s])))
    for t in np.arange(0, duration, 1 / load_rate):
        loads.append(AxialLoadBatch(np.array([t0 + t]), np.array([-load])))
    for t in np.arange(0, duration, 1.0):
        temps.append(TemperatureBatch(np.array([t0 + t]), np.array([31.0])))
    return dict(vibration=vib, screw=screw, load=loads, temperature=temps, duration=duration)


def interleave(streams):
    """All single batches of `streams` in stamp order (as a live subscription sees them)."""
    items = []
    for key in ('vibration', 'screw', 'load', 'temperature'):
        items.extend(streams[key])
    items.sort(key=lambda b: float(b.stamps[0]))
    return items


def merge(batches):
    """Concatenate single batches of one kind into one batch (as a bag reader's slice)."""
    first = batches[0]
    if isinstance(first, VibrationBatch):
        samples = np.concatenate([b.samples for b in batches])
        counts = np.array([b.samples.size for b in batches])
        return VibrationBatch(np.concatenate([b.stamps for b in batches]),
                              np.concatenate([b.sample_rates for b in batches]),
                              np.concatenate(([0], np.cumsum(counts))), samples)
    cls = type(first)
    fields = [*first.__dataclass_fields__]
    return cls(*[np.concatenate([getattr(b, f) for b in batches]) for f in fields])


def defect_vibration(t, speed, rms=1.0, strike=0.0, order=6.25, mode=1000.0, decay=0.002, seed=0):
    """Gaussian vibration of ``rms`` at sample times ``t`` (s) plus a spall's strikes: ``order`` per screw revolution.

    The screw turns at ``speed`` rad/s from angle 0 at t = 0; each strike rings a
    structural mode of ``mode`` Hz decaying with time constant ``decay`` s, peak
    ``strike`` m/s^2 (0: healthy), with a strike-to-strike scatter of 20 % in
    amplitude and 2 % of the strike period in time, as a rolling contact gives.
    """
    t = np.asarray(t, dtype=float)
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(t.size) * rms
    if strike > 0 and t.size:
        period = 2 * math.pi / (speed * order)
        first, last = math.floor(t[0] / period) - 1, math.ceil(t[-1] / period)
        for k in range(first, last + 1):
            k_rng = np.random.default_rng([seed, k + 10 ** 6])   # the same strike whichever block holds it
            at = k * period + 0.02 * period * k_rng.standard_normal()
            size = strike * (1 + 0.2 * k_rng.standard_normal())
            lo, hi = np.searchsorted(t, [at, at + 10 * decay])
            dt = t[lo:hi] - at
            x[lo:hi] += size * np.exp(-dt / decay) * np.sin(2 * math.pi * mode * dt)
    return x
