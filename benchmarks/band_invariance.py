#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""theta_Oil of the same recordings at other sample rates and with a DC offset: the analysis band at work.

The rig simulator records the paper's experiment (3 speeds x 2 loads after
lubrication stages theta_Oil 0.72, 0.83 and 1.0) once at 51.2 kHz.  Each
stage's vibration is then resampled (``scipy.signal.resample_poly``, whose
anti-alias filter is what a slower acquisition would have had) to 4, 10, 20,
25.6 and 51.2 kHz, a DC offset of 0 to 10 m/s^2 added (9.81: gravity on a
DC-coupled vertical axis), and written back as contract bags with the
joint states, load and temperature unchanged.  The constants are fitted on the
20 kHz, zero-offset stage 3 (theta_Oil 1) and every variant's runs are
assessed with them.

Goal: every run's theta_Oil within +/- ``--tolerance`` (0.01) of the same run
at 20 kHz with no offset, with the band of :mod:`prsm_lube_ros.estimation.conditioning`
(``band``).  The same numbers with the raw RMS (``raw``: no high-pass, the
full band of each rate, what calibrations without a band use) show what the
band removes; they are reported, not judged.  Exit status 1 when the goal
fails, with the variants that fail printed.

Results: ``benchmarks/results/band_invariance.{json,md}``.

Usage: ``python benchmarks/band_invariance.py [--data DIR] [--tolerance 0.01]``
"""
from __future__ import annotations

import argparse
import json
from math import gcd
from pathlib import Path
import platform
import shutil
import sys
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
SOURCE_RATE = 51200
RATES = (4000, 10000, 20000, 25600, 51200)
OFFSETS = (0.0, 2.0, 5.0, 9.81, 10.0)
REFERENCE = (20000, 0.0)
BLOCK_SECONDS = 0.1


def read_stage(path: Path) -> dict:
    """All batches of one bag, concatenated per kind (the stages are short enough to hold)."""
    from prsm_lube_ros.recording.reader import open_recording
    parts: dict = {}
    for batches in open_recording(path).slices():
        for batch in batches:
            parts.setdefault(type(batch).__name__, []).append(batch)
    stage = {}
    vib = parts['VibrationBatch']
    stage['vibration'] = np.concatenate([np.asarray(b.samples, np.float64) for b in vib])
    stage['vibration_start'] = float(vib[0].stamps[0])
    stage['rate'] = float(vib[0].sample_rates[0])
    screw = parts['ScrewStateBatch']
    stage['joint'] = [np.concatenate([getattr(b, f) for b in screw]) for f in ('stamps', 'angles', 'speeds')]
    load = parts['AxialLoadBatch']
    stage['load'] = [np.concatenate([getattr(b, f) for b in load]) for f in ('stamps', 'forces')]
    temps = parts.get('TemperatureBatch', [])
    stage['temperature'] = ([np.concatenate([getattr(b, f) for b in temps]) for f in ('stamps', 'temperatures')]
                            if temps else None)
    return stage


def write_variant(stage: dict, rate: int, offset: float, path: Path) -> None:
    """``stage`` resampled to ``rate`` Hz with ``offset`` m/s^2 added, as a contract bag at ``path``."""
    from scipy.signal import resample_poly
    from prsm_lube_ros.recording.writer import ContractBagWriter
    source = int(round(stage['rate']))
    common = gcd(rate, source)
    samples = (resample_poly(stage['vibration'], rate // common, source // common) if rate != source
               else stage['vibration'].copy())
    size = int(round(rate * BLOCK_SECONDS))
    blocks = samples[:samples.size // size * size].reshape(-1, size) + offset
    start_ns = int(round(stage['vibration_start'] * 1e9))
    stamps = start_ns + np.arange(blocks.shape[0], dtype=np.int64) * int(round(BLOCK_SECONDS * 1e9))

    def ns(seconds):
        return np.rint(np.asarray(seconds) * 1e9).astype(np.int64)
    with ContractBagWriter(path) as writer:
        writer.add_vibration(stamps, stamps + int(round(BLOCK_SECONDS * 1e9)), float(rate), blocks)
        joint_stamps, angles, speeds = stage['joint']
        writer.add_joint_states(ns(joint_stamps), ns(joint_stamps), angles, speeds)
        load_stamps, forces = stage['load']
        writer.add_axial_loads(ns(load_stamps), ns(load_stamps), forces)
        if stage['temperature'] is not None:
            temp_stamps, temps = stage['temperature']
            writer.add_temperatures(ns(temp_stamps), ns(temp_stamps), temps)


def run_thetas(assessment) -> list:
    """theta_Oil of every assessed run of one recording (NaN for runs not assessed)."""
    return [run.theta_oil if not run.reason else float('nan') for run in assessment.runs]


def main() -> int:
    """Simulate, resample, assess; write the results; non-zero when the goal fails."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--data', type=Path, default=Path('/tmp/prsm_lube_band_bench'))
    parser.add_argument('--tolerance', type=float, default=0.01)
    parser.add_argument('--seed', type=int, default=3)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from prsm_lube_ros.estimation.calibration_file import band_note
    from prsm_lube_ros.estimation.conditioning import AnalysisBand, COMMON_BAND_HIGH
    from prsm_lube_ros.estimation.pipeline import assess_recording, calibrate_recordings, recording_windows
    from prsm_lube_ros.estimation.windowing import WindowSettings
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    from prsm_lube_ros.simulation.rig_config import RigConfig

    started = time.time()
    source = args.data / f'source_{SOURCE_RATE}_seed{args.seed}'
    if not (source / 'truth.json').exists():
        shutil.rmtree(source, ignore_errors=True)
        print(f'simulating the experiment at {SOURCE_RATE} Hz into {source} ...', flush=True)
        simulate_experiment(source, rig=RigConfig(vibration_rate=float(SOURCE_RATE)), seed=args.seed)
    truth = json.loads((source / 'truth.json').read_text())
    stage_paths = [source / stage['path'] for stage in truth['bags']]
    stage_thetas = [stage['theta_oil'] for stage in truth['bags']]
    stages = [read_stage(path) for path in stage_paths]
    work = args.data / 'variants'
    lead = 0.005
    # One calibration for every rate: the band every rate from 4 kHz up covers (calibrate --band-high 1600).
    modes = {'band': WindowSettings(band=AnalysisBand(high=COMMON_BAND_HIGH)), 'raw': WindowSettings(band=None)}
    thetas: dict = {mode: {} for mode in modes}
    calibrations = {}

    def windows_of(rate, offset, mode):
        """Windows of each stage of one variant (bags written once, windowed in both modes)."""
        folder = work / f'{rate}_{offset:g}'
        if not folder.exists():
            for index, stage in enumerate(stages):
                write_variant(stage, rate, offset, folder / f'stage_{index + 1}')
        return [recording_windows(folder / f'stage_{index + 1}', lead=lead, settings=modes[mode])
                for index in range(len(stages))]

    shutil.rmtree(work, ignore_errors=True)
    order = [REFERENCE] + [(r, o) for r in RATES for o in OFFSETS if (r, o) != REFERENCE]
    for rate, offset in order:
        for mode in modes:
            recordings = windows_of(rate, offset, mode)
            if (rate, offset) == REFERENCE:
                calibrations[mode] = calibrate_recordings([recordings[-1]])
            thetas[mode][(rate, offset)] = [run_thetas(assess_recording(rec, calibrations[mode]))
                                            for rec in recordings]
        shutil.rmtree(work / f'{rate}_{offset:g}', ignore_errors=True)
        print(f'{rate} Hz, offset {offset:g} m/s^2: done', flush=True)

    rows, failures = [], []
    for rate, offset in order:
        row = {'sample_rate_hz': rate, 'dc_offset_m_s2': offset}
        for mode in modes:
            reference = np.concatenate([np.asarray(t) for t in thetas[mode][REFERENCE]])
            values = np.concatenate([np.asarray(t) for t in thetas[mode][(rate, offset)]])
            both = np.isfinite(reference) & np.isfinite(values)
            missing = int(np.count_nonzero(np.isfinite(reference) & ~np.isfinite(values)))
            deviation = float(np.max(np.abs(values[both] - reference[both]))) if both.any() else float('nan')
            row[f'{mode}_max_abs_dtheta'] = deviation
            row[f'{mode}_mean_dtheta'] = float(np.mean(values[both] - reference[both])) if both.any() else None
            row[f'{mode}_runs_missing'] = missing
            if mode == 'band' and not (deviation <= args.tolerance and missing == 0):
                failures.append(f'{rate} Hz, offset {offset:g} m/s^2: max |dtheta| {deviation:.4f} '
                                f'(tolerance {args.tolerance}), {missing} run(s) not assessed')
        rows.append(row)
    reference_runs = [[round(t, 4) for t in stage if np.isfinite(t)] for stage in thetas['band'][REFERENCE]]
    document = {'command': 'python benchmarks/band_invariance.py', 'tolerance': args.tolerance,
                'source_rate_hz': SOURCE_RATE, 'seed': args.seed, 'stage_thetas': stage_thetas,
                'band': band_note(calibrations['band']), 'raw': band_note(calibrations['raw']),
                'reference_run_thetas_band': reference_runs, 'rows': rows, 'failures': failures,
                'goal_met': not failures, 'seconds': round(time.time() - started, 1),
                'python': platform.python_version()}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'band_invariance.json').write_text(json.dumps(document, indent=1, allow_nan=False, default=str))
    lines = ['# theta_Oil across sample rates and DC offsets (`python benchmarks/band_invariance.py`)', '',
             f'The paper\'s experiment simulated once at {SOURCE_RATE} Hz (seed {args.seed}; stages theta_Oil '
             f'{", ".join(f"{t:g}" for t in stage_thetas)}), resampled and offset, calibrated on the 20 kHz '
             'zero-offset stage 3 and assessed run by run. Deviation: largest |theta - theta at 20 kHz, no '
             'offset| over the runs of all stages.', '',
             f'- band: {document["band"]}', f'- raw: {document["raw"]}', '',
             '| sample rate Hz | DC offset m/s^2 | band: max abs dtheta | band: mean dtheta | '
             'raw: max abs dtheta | raw: mean dtheta |', '|---|---|---|---|---|---|']
    for row in rows:
        lines.append(f'| {row["sample_rate_hz"]} | {row["dc_offset_m_s2"]:g} | {row["band_max_abs_dtheta"]:.4f} | '
                     f'{row["band_mean_dtheta"]:+.4f} | {row["raw_max_abs_dtheta"]:.4f} | '
                     f'{row["raw_mean_dtheta"]:+.4f} |')
    lines += ['', f'Goal: band max abs dtheta <= {args.tolerance} for every variant: '
              + ('met' if not failures else 'NOT met: ' + '; '.join(failures)), '']
    (RESULTS / 'band_invariance.md').write_text('\n'.join(lines))
    print('\n'.join(lines))
    return 0 if not failures else 1


if __name__ == '__main__':
    sys.exit(main())
