# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Speed work moves no condition indicator: every window's indicators equal those of the code before, unrounded.

``test/cli/test_assess_reference.py`` compares the assessment JSON, whose
indicators are rounded (kurtosis to 4 digits, dB to 2); here the
:class:`~prsm_lube_ros.estimation.condition_indicators.ConditionIndicators`
of every window of recorded cases are compared as computed, before any
rounding: kurtosis, crest factor, spectral kurtosis, order resolution and each
envelope peak's dB to :data:`RELATIVE`, the demodulation band (Hz), each
peak's order and component and which windows have indicators exactly, and the
envelope on the order grid (float32, what the run screen averages) to
:data:`GRID_RELATIVE` of the window's largest envelope bin.

Cases (:data:`CASES`): simulated endurance recordings of 90 s at 4 kHz, one
healthy and one with a spall (``prsm-lube simulate --endurance 90 --effect
surface_defect``), kept in ``test/data/indicator_reference/``; the simulated
stage with a growing spall of the assessment reference; the FEMTO-ST late
(damaged) and early (healthy) runs at 25.6 kHz with the PRONOSTIA bearing's
defect orders.

The reference was written by the code before the speed work, with that
checkout first on the path::

    git worktree add --detach /tmp/speed39-before main
    PYTHONPATH=/tmp/speed39-before python test/estimation/test_indicator_reference.py --write
"""
from __future__ import annotations

import json
import math
from pathlib import Path
import sys

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / 'test' / 'data'
REFERENCE = DATA / 'indicator_reference'
FEMTO_ACTUATOR = ROOT / 'config' / 'femto_pronostia_bearing.yaml'

#: name: (recording, actuator configuration or None for the default actuator)
CASES = {
    'sim_healthy_endurance': (REFERENCE / 'sim_healthy_endurance', None),
    'sim_spall_endurance': (REFERENCE / 'sim_spall_endurance', None),
    'sim_growing_spall_stage': (DATA / 'assess_reference' / 'sim_surface_defect_stage_2', None),
    'femto_all_late': (DATA / 'realdata' / 'femto' / 'all_late', FEMTO_ACTUATOR),
    'femto_test_early': (DATA / 'realdata' / 'femto' / 'test_early', FEMTO_ACTUATOR),
}

#: Relative tolerance of every indicator number (the FFTs may change their order of summation, not their values).
RELATIVE = 1e-9
#: Tolerance of the float32 envelope on the order grid, relative to the window's largest bin.
GRID_RELATIVE = 1e-6

SCALARS = ('kurtosis', 'crest_factor', 'spectral_kurtosis', 'order_resolution')


def window_indicators(name: str) -> tuple[list[dict], np.ndarray]:
    """Per window of case ``name``: its indicators as numbers (unrounded), and the envelope grids (windows x grid).

    Windows without indicators are listed with ``condition`` None; the grid
    rows are those of the windows with an envelope, in window order.
    """
    from prsm_lube_ros.estimation.pipeline import recording_windows
    from prsm_lube_ros.estimation.windowing import WindowSettings
    from prsm_lube_ros.physics.actuator import load_actuator
    from prsm_lube_ros.physics.defect_orders import defect_orders
    recording, config = CASES[name]
    actuator = load_actuator(str(config) if config else None)
    settings = WindowSettings(defect_orders=defect_orders(actuator))
    windows = recording_windows(recording, lead=actuator.lead, settings=settings).windows
    records, grids = [], []
    for window in windows:
        c = window.condition
        record: dict = {'start': window.start, 'condition': None}
        if c is not None:
            record['condition'] = {**{key: getattr(c, key) for key in SCALARS},
                                   'demodulation_band': list(c.demodulation_band),
                                   'envelope_peaks': [[p.order, p.db, p.component] for p in c.envelope_peaks],
                                   'envelope': c.envelope is not None}
            if c.envelope is not None:
                grids.append(c.envelope)
        records.append(record)
    grid = np.vstack(grids).astype(np.float32) if grids else np.zeros((0, 0), np.float32)
    return records, grid


def write_reference() -> None:
    """Write each case's reference with the ``prsm_lube_ros`` first on the path (the code before)."""
    import prsm_lube_ros
    REFERENCE.mkdir(parents=True, exist_ok=True)
    for name in CASES:
        records, grid = window_indicators(name)
        (REFERENCE / f'{name}.json').write_text(json.dumps(records, indent=0, allow_nan=True) + '\n')
        np.save(REFERENCE / f'{name}_envelope.npy', grid)
        print(f'{name}: {len(records)} windows, {grid.shape[0]} envelopes, '
              f'with the code of {Path(prsm_lube_ros.__file__).parent.parent}')


def close(expected: float, actual: float) -> bool:
    """Equal to :data:`RELATIVE` (NaN equals NaN)."""
    if math.isnan(expected) or math.isnan(actual):
        return math.isnan(expected) and math.isnan(actual)
    return math.isclose(expected, actual, rel_tol=RELATIVE, abs_tol=1e-300)


def differences(expected: list[dict], actual: list[dict]) -> list[str]:
    """Where the windows' indicators depart from the reference."""
    if len(expected) != len(actual):
        return [f'{len(actual)} windows, {len(expected)} expected']
    found = []
    for k, (e, a) in enumerate(zip(expected, actual)):
        where = f'window {k} ({e["start"]})'
        if e['start'] != a['start'] or (e['condition'] is None) != (a['condition'] is None):
            found.append(f'{where}: {a["start"]} with indicators {a["condition"] is not None}')
            continue
        if e['condition'] is None:
            continue
        ec, ac = e['condition'], a['condition']
        found += [f'{where}.{key}: {ac[key]!r}, {ec[key]!r} expected' for key in SCALARS
                  if not close(ec[key], ac[key])]
        if ec['envelope'] != ac['envelope'] or not all(
                (x == y) or (math.isnan(x) and math.isnan(y))
                for x, y in zip(ec['demodulation_band'], ac['demodulation_band'])):
            found.append(f'{where}: band {ac["demodulation_band"]}, {ec["demodulation_band"]} expected')
        peaks_e, peaks_a = ec['envelope_peaks'], ac['envelope_peaks']
        if len(peaks_e) != len(peaks_a) or any(
                pe[0] != pa[0] or pe[2] != pa[2] or not close(pe[1], pa[1]) for pe, pa in zip(peaks_e, peaks_a)):
            found.append(f'{where}: peaks {peaks_a}, {peaks_e} expected')
    return found


def grid_differences(expected: np.ndarray, actual: np.ndarray) -> list[str]:
    """Rows of the envelope grids that depart by more than :data:`GRID_RELATIVE` of their largest bin."""
    if expected.shape != actual.shape:
        return [f'envelope grids {actual.shape}, {expected.shape} expected']
    if not expected.size:
        return []
    e, a = expected.astype(float), actual.astype(float)
    same_nan = np.isnan(e) == np.isnan(a)
    scale = np.nanmax(np.abs(e), axis=1, keepdims=True)
    off = np.where(np.isnan(e) | np.isnan(a), 0.0, np.abs(e - a)) > GRID_RELATIVE * scale
    bad = np.flatnonzero(~same_nan.all(axis=1) | off.any(axis=1))
    return [f'envelope row {k} departs' for k in bad[:5].tolist()]


@pytest.mark.parametrize('name', sorted(CASES))
def test_indicators_equal_those_of_the_code_before(name):
    expected = json.loads((REFERENCE / f'{name}.json').read_text())
    expected_grid = np.load(REFERENCE / f'{name}_envelope.npy')
    records, grid = window_indicators(name)
    found = differences(expected, records) + grid_differences(expected_grid, grid)
    assert not found, f'{len(found)} differences, first: ' + '; '.join(found[:5])
    # The case holds what is compared: windows with envelopes, and lines labelled with a component.
    assert grid.shape[0] > 20
    assert any(peak[2] for r in records if r['condition'] for peak in r['condition']['envelope_peaks'])


def test_the_comparison_sees_a_moved_indicator_a_moved_band_and_a_moved_envelope():
    """A kurtosis moved by 1e-8 relative, a band one bin over, a peak's component or a grid bin: all seen."""
    expected, grid = [json.loads((REFERENCE / 'sim_spall_endurance.json').read_text()),
                      np.load(REFERENCE / 'sim_spall_endurance_envelope.npy')]
    assert not differences(expected, expected) and not grid_differences(grid, grid)
    k = next(k for k, r in enumerate(expected) if r['condition'] and r['condition']['envelope_peaks'])
    for change in ('kurtosis', 'band', 'component', 'db'):
        moved = json.loads(json.dumps(expected))
        c = moved[k]['condition']
        if change == 'kurtosis':
            c['kurtosis'] *= 1 + 1e-8
        elif change == 'band':
            c['demodulation_band'][0] += 1.0
        elif change == 'component':
            c['envelope_peaks'][0][2] = 'elsewhere'
        else:
            c['envelope_peaks'][0][1] *= 1 + 1e-8
        assert differences(expected, moved), change
    moved_grid = grid.copy()
    row = moved_grid[3]
    row[np.nanargmax(row)] *= 1 + 1e-5
    assert grid_differences(grid, moved_grid) == ['envelope row 3 departs']


if __name__ == '__main__':
    if sys.argv[1:] != ['--write']:
        sys.exit('usage: [PYTHONPATH=CHECKOUT] python test/estimation/test_indicator_reference.py --write')
    write_reference()
