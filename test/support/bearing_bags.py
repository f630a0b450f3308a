# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Small FEMTO-like recordings: a bearing shaft at 1500-1800 r/min, 25.6 kHz, healthy or with a race defect.

Like the converted PRONOSTIA recordings (../shared/realdata/femto): the shaft
speed is the ``screw`` joint, the radial load the axial load, runs at the
three PRONOSTIA conditions separated by standstill.  Healthy vibration is
Gaussian, its RMS growing with speed; a defect adds strikes at ``defect_order``
times the shaft frequency (1 % timing jitter, 25 % amplitude scatter), each
ringing a structural mode at ``mode_hz``, with amplitude growing run by run
when ``growth`` > 0 (a spall growing with the revolutions run).
"""
import math

import numpy as np

from prsm_lube_ros.recording.writer import ContractBagWriter

#: (r/min, N) of the PRONOSTIA conditions.
CONDITIONS = ((1800.0, 4000.0), (1650.0, 4200.0), (1500.0, 5000.0))
#: BPFO of the PRONOSTIA bearing (config/femto_pronostia_bearing.yaml).
BPFO = 5.61


def write_bearing_recording(path, *, conditions=CONDITIONS, seconds=4.0, rest=1.0, rate=25600.0, block=2560,
                            defect_order=None, strike=6.0, growth=0.0, mode_hz=4000.0, seed=0, start=1.7e9):
    """Write a recording of one run per condition at ``path``; returns the path."""
    rng = np.random.default_rng(seed)
    per_run = rest + seconds
    total = len(conditions) * per_run + rest
    n = int(round(total * rate / block)) * block
    t = np.arange(n) / rate
    speed = np.zeros(n)
    load = np.zeros(n)
    for k, (rpm, force) in enumerate(conditions):
        on = (t >= rest + k * per_run) & (t < rest + k * per_run + seconds)
        speed[on] = rpm * math.pi / 30.0
        load[on] = force
    signal = 0.05 * rng.standard_normal(n) + 2.0e-3 * speed * rng.standard_normal(n)
    if defect_order is not None:
        ring = np.arange(int(0.004 * rate)) / rate
        kernel = np.exp(-ring * 1200.0) * np.sin(2 * math.pi * mode_hz * ring)
        pulses = np.zeros(n)
        for k, (rpm, _) in enumerate(conditions):
            shaft_hz = rpm / 60.0
            period = 1.0 / (defect_order * shaft_hz)
            first = rest + k * per_run
            times = np.arange(first, first + seconds, period)
            times = times + 0.01 * period * rng.standard_normal(times.size)
            index = np.clip(np.round(times * rate).astype(int), 0, n - 1)
            np.add.at(pulses, index, strike * (1.0 + growth * k) * (1.0 + 0.25 * rng.standard_normal(index.size)))
        signal = signal + np.convolve(pulses, kernel)[:n]
    angle = np.cumsum(speed) / rate
    blocks = signal.reshape(-1, block)
    stamps = (start * 1e9 + np.arange(blocks.shape[0]) * block / rate * 1e9).astype(np.int64)
    joint_rate = 200.0
    joint_index = np.arange(0, n, int(rate / joint_rate))
    joint_stamps = (start * 1e9 + joint_index / rate * 1e9).astype(np.int64)
    with ContractBagWriter(path) as writer:
        writer.add_vibration(stamps, stamps + int(block / rate * 1e9), rate, blocks)
        writer.add_joint_states(joint_stamps, joint_stamps, angle[joint_index], speed[joint_index])
        writer.add_axial_loads(joint_stamps[::4], joint_stamps[::4], load[joint_index][::4])
    return path
