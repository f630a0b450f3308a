#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How often the surface defect screen flags a run with no defect, and how often it finds one that is there.

Per seed, with the installed ``prsm-lube`` command as a user runs it:

* ``simulate --run-order random``: the paper's experiment, oil lost in stages
  (theta_Oil 0.72, 0.83, 1.0), surfaces healthy; calibrate on its last stage;
* ``simulate --endurance``: the six conditions cycled, unloaded return traverses
  at 300 r/min between them (conditions the calibration never saw);
* ``simulate --effect surface_defect``: a spall or pit of drawn component,
  strength, ring, scatter and growth in every stage.

Every run is assessed and then screened again from its pooled indicators in
the JSON with each rule set compared (:class:`DefectRules` variants), so the
sets meet the same runs.  A flagged healthy run is a false alarm; a flagged
run of the defect recordings is a detection (some drawn defects are too weak
for any screen: compare the sets, not the absolute rate).

Writes ``benchmarks/results/defect_false_alarms.md`` and ``.json``::

    python benchmarks/defect_false_alarms.py [--seeds 12] [--first-seed 0] [--endurance 600]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path
import sys
import tempfile

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from prsm_lube_ros.estimation.calibration_file import load_calibration  # noqa: E402
from prsm_lube_ros.estimation.condition_indicators import EnvelopePeak  # noqa: E402
from prsm_lube_ros.estimation.defect_screen import ConditionBaseline, DEFAULT_RULES  # noqa: E402
from prsm_lube_ros.estimation.defect_screen import RunCondition, screen  # noqa: E402
from prsm_lube_ros.estimation.windowing import DEFAULT_DEFECT_ORDERS  # noqa: E402

from femto_defects import prsm_lube  # noqa: E402  (beside this file: the installed command, whole process)

RESULTS = ROOT / 'benchmarks' / 'results'
#: The rule sets compared: this checkout's defaults, and without the unexplained-line requirement.
RULE_SETS = {'default': DEFAULT_RULES,
             'without unexplained-line margin': dataclasses.replace(DEFAULT_RULES, unexplained_margin_db=None)}


def pooled_condition(run: dict) -> RunCondition:
    """A run's pooled indicators as the assessment JSON gives them (no averaged spectrum: the screen needs none)."""
    c = run['condition_indicators']

    def number(name: str) -> float:    # JSON has null where the assessment had NaN
        return float('nan') if c.get(name) is None else c[name]
    peaks = tuple(EnvelopePeak(p['order'], p['db'], p['component']) for p in c['envelope_peaks'])
    return RunCondition(number('kurtosis'), number('crest_factor'), peaks, c.get('windows', 0),
                        number('order_resolution'))


def seed_runs(seed: int, folder: Path, endurance: float) -> tuple[list[dict], ConditionBaseline | None]:
    """Simulate, calibrate and assess one seed's three recordings; each run with its family and pooled condition."""
    healthy, drift, damaged = folder / 'healthy', folder / 'endurance', folder / 'defect'
    prsm_lube('simulate', healthy, '--seed', seed, '--run-order', 'random')
    prsm_lube('simulate', drift, '--seed', seed, '--endurance', endurance)
    prsm_lube('simulate', damaged, '--seed', seed, '--effect', 'surface_defect')
    calibration = folder / 'calibration.yaml'
    prsm_lube('calibrate', healthy / 'stage_3', '--out', calibration)
    truth = json.loads((damaged / 'truth.json').read_text())['effects']['surface_defect']
    rows = []
    for family, bags in (('oil loss, healthy surfaces', [healthy / f'stage_{k}' for k in (1, 2, 3)]),
                         ('endurance, healthy', sorted(p for p in drift.iterdir() if p.is_dir())),
                         ('surface defect', [damaged / f'stage_{k}' for k in (1, 2, 3)])):
        out = folder / f'{family.split(",")[0].replace(" ", "_")}.json'
        prsm_lube('assess', *bags, '--calibration', calibration, '--json', out)
        assessment = json.loads(out.read_text())
        for run in assessment['runs'] + assessment.get('unassessed_runs', []):
            rows.append({'seed': seed, 'family': family, 'condition': pooled_condition(run),
                         'defect': truth if family == 'surface defect' else None,
                         'assessed': bool(run['defect_suspected'])})
    return rows, load_calibration(calibration).condition_baseline


def main() -> int:
    """Simulate, screen with each rule set, tabulate."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=12)
    parser.add_argument('--first-seed', type=int, default=0)
    parser.add_argument('--endurance', type=float, default=600.0, help='seconds of the endurance recording')
    parser.add_argument('--name', default='defect_false_alarms')
    args = parser.parse_args()
    orders = DEFAULT_DEFECT_ORDERS
    counts: dict[tuple[str, str], list[int]] = {}
    flagged_healthy: list[dict] = []
    disagreements = 0     # the default rules on the JSON's rounded indicators against assess's own verdict
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        with tempfile.TemporaryDirectory() as folder:
            rows, baseline = seed_runs(seed, Path(folder), args.endurance)
        for row in rows:
            for name, rules in RULE_SETS.items():
                finding = screen(row['condition'], orders, baseline, rules)
                disagreements += rules is DEFAULT_RULES and finding.suspected != row['assessed']
                tally = counts.setdefault((row['family'], name), [0, 0])
                tally[0] += finding.suspected
                tally[1] += 1
                if finding.suspected and row['defect'] is None:
                    flagged_healthy.append({'seed': seed, 'family': row['family'], 'rules': name,
                                            'evidence': finding.evidence})
        print(f'seed {seed}: ' + ', '.join(f'{f} / {r}: {c[0]}/{c[1]}' for (f, r), c in counts.items()), flush=True)
    command = ' '.join(['python benchmarks/defect_false_alarms.py'] + sys.argv[1:])
    lines = [f'# Surface defect screen: false alarms and detections (`{command}`)', '',
             f'Seeds {args.first_seed}..{args.first_seed + args.seeds - 1}; every run (loaded traverses and unloaded '
             'returns) of each recording, screened with each rule set on the same pooled indicators.', '',
             '| recordings | rules | runs flagged | runs |', '|---|---|---|---|']
    for (family, name), (flagged, total) in counts.items():
        lines.append(f'| {family} | {name} | {flagged} ({100 * flagged / max(total, 1):.1f} %) | {total} |')
    lines += ['', f'Runs where the default rules on the JSON\'s rounded indicators disagree with assess\'s own '
              f'verdict: {disagreements}.', '', 'Healthy runs flagged:', '']
    lines += [f'- seed {f["seed"]}, {f["family"]}, {f["rules"]}: {f["evidence"]}' for f in flagged_healthy]
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f'{args.name}.md').write_text('\n'.join(lines) + '\n')
    (RESULTS / f'{args.name}.json').write_text(json.dumps(
        {'command': command, 'disagreements': disagreements,
         'counts': [{'recordings': f, 'rules': r, 'flagged': c[0], 'runs': c[1]} for (f, r), c in counts.items()],
         'healthy_flagged': flagged_healthy}, indent=1))
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
