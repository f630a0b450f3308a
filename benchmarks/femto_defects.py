#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Real bearings (FEMTO-ST PRONOSTIA): is a damaged bearing told from a lubrication change?

With the installed ``prsm-lube`` command, as a user runs it: calibrate on the
6 healthy early runs of ``learn_early`` with the PRONOSTIA bearing's geometry
(``config/femto_pronostia_bearing.yaml``, so envelope lines are labelled with
BPFO, BPFI, BSF), then assess the 11 healthy early runs of ``test_early`` and
the 17 late runs before failure of ``all_late``.  Per run: the run's median
kurtosis and crest factor, its strongest envelope line at a strike order (dB
over the floor), whether a surface defect is suspected, theta_Oil and its z
against 1.  The early runs are other healthy units (none should be flagged);
the late runs are what the bearings looked like before they failed.

Writes ``benchmarks/results/femto_defects.md`` and ``.json``::

    python benchmarks/femto_defects.py [--data test/data/realdata/femto]
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
import shutil
import subprocess
import tempfile

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
ACTUATOR = ROOT / 'config' / 'femto_pronostia_bearing.yaml'


def prsm_lube(*args: object) -> subprocess.CompletedProcess:
    """The installed command, whole process."""
    command = shutil.which('prsm-lube')
    if not command:
        raise SystemExit('prsm-lube is not on PATH: source .env-jazzy.sh (tools/setup-env) first')
    result = subprocess.run([command, *map(str, args)], capture_output=True, text=True, timeout=600)
    if result.returncode not in (0,):
        raise SystemExit(f'prsm-lube {" ".join(map(str, args[:2]))} failed: {result.stderr.strip()[-400:]}')
    return result


def strongest_line(run: dict) -> dict | None:
    """The strongest envelope peak of a run that points at a strike component (not carrier or cage)."""
    peaks = [p for p in run['condition_indicators']['envelope_peaks']
             if p['component'] and not any(word in p['component'] for word in ('carrier', 'cage'))]
    return max(peaks, key=lambda p: p['db']) if peaks else None


def main() -> int:
    """Calibrate, assess, tabulate."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--data', type=Path, default=ROOT / 'test' / 'data' / 'realdata' / 'femto')
    args = parser.parse_args()
    spans = json.loads((args.data / 'runs.json').read_text())
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        calibration = Path(folder) / 'calibration.yaml'
        prsm_lube('calibrate', args.data / 'learn_early', '--out', calibration, '--actuator', ACTUATOR)
        for subset in ('test_early', 'all_late'):
            out = Path(folder) / f'{subset}.json'
            prsm_lube('assess', args.data / subset, '--calibration', calibration, '--actuator', ACTUATOR,
                      '--json', out)
            for run in json.loads(out.read_text())['runs']:
                name = next((item['name'] for item in spans[subset]
                             if item['start'] - 1.0 <= run['start'] <= item['end']), '?')
                line = strongest_line(run)
                indicators = run['condition_indicators']
                rows.append({'subset': subset, 'bearing': name.rsplit('_', 1)[0].replace('Bearing', ''),
                             'kurtosis': indicators['kurtosis'], 'crest_factor': indicators['crest_factor'],
                             'line': line, 'defect_suspected': run['defect_suspected'],
                             'evidence': run['defect_evidence'], 'theta_oil': run['theta_oil'],
                             'theta_oil_std': run['theta_oil_std']})
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'femto_defects.json').write_text(json.dumps(rows, indent=1))
    lines = ['# Real bearings: surface defect told from lubrication (FEMTO-ST PRONOSTIA)', '',
             'Command: `python benchmarks/femto_defects.py` (calibrated on `learn_early`, 6 healthy runs, with '
             '`--actuator config/femto_pronostia_bearing.yaml`).', '',
             '| subset | bearing | kurtosis | crest | strongest strike-order line | defect suspected | theta_Oil |'
             ' z vs 1 |', '|---|---|---|---|---|---|---|---|']
    for row in sorted(rows, key=lambda r: (r['subset'] != 'test_early', r['bearing'])):
        line = row['line']
        text = f'{line["order"]:.2f}x {line["component"]}, {line["db"]:.1f} dB' if line else '-'
        z = ((row['theta_oil'] - 1) / row['theta_oil_std'] if row['theta_oil_std'] else math.nan)
        lines.append(f'| {row["subset"]} | {row["bearing"]} | {row["kurtosis"]:.2f} | {row["crest_factor"]:.1f} | '
                     f'{text} | {"**yes**" if row["defect_suspected"] else "no"} | {row["theta_oil"]:.3f} +/- '
                     f'{row["theta_oil_std"]:.3f} | {z:+.1f} |')
    for subset in ('test_early', 'all_late'):
        chosen = [r for r in rows if r['subset'] == subset]
        lines.append('')
        lines.append(f'{subset}: {sum(r["defect_suspected"] for r in chosen)} of {len(chosen)} runs flagged')
    (RESULTS / 'femto_defects.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
