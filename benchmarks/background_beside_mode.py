#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A background beside a mode the speeds are past: how strong the draws made it, and what a redraw changes.

The study's pairs of a background and a mode below the band were named 0 of 5
(``docs/diagnosis-studies.md``).  For each recorded case this prints the
background's RMS B over the thread contacts' RMS at the plan's lowest speed and
highest load (theta_Oil = 1): over Eq. 22's bare contacts (what the background
is drawn against, ``FRACTION_RANGE`` 0.5-1.5) and over the contacts as the
case's mode leaves them (the contacts the recording holds).

With ``--redraw`` each case is simulated again with its background drawn from
the same random stream against the contacts as the mode leaves them (so B is
0.5-1.5 times what the recording's contacts make), read as ``prsm-lube
diagnose`` reads it, diagnosed, and its verdict printed with the background's
and the mode's held-out gains alone and the background fit's C_lambda.

Usage: ``python benchmarks/background_beside_mode.py [--seeds 1346,1737,...] [--redraw]
[--name background_beside_mode]`` (after ``source .env-jazzy.sh``); results to
``benchmarks/results/<name>.{json,md}``.
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import json
from pathlib import Path
import shutil
import sys
import tempfile

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from results_files import write_results  # noqa: E402  (beside this file)

#: The recorded pairs of a background and a mode: below the band (missed) and above or inside it (named).
CASES = (1346, 1737, 1760, 1801, 1807, 1706, 1713, 1819)
POSITIONS = 21      # nut positions over the stroke the contacts are averaged over (in power)


def contact_rms(setup, effects=None) -> float:
    """Thread-contact RMS at the plan's lowest speed and highest load, theta 1, over the stroke, m/s^2."""
    from prsm_lube_ros.simulation.rig_acceleration import thread_contact_amplitude
    plan = setup.plan
    positions = np.linspace(0.0, plan.stroke, POSITIONS)
    amplitude = thread_contact_amplitude(min(plan.speeds), max(plan.loads), 1.0, setup.rig, effects,
                                         nut_position=positions)
    return float(np.sqrt(np.mean(np.square(np.broadcast_to(amplitude, positions.shape)))))


def redrawn_background(seed: int, setup, mode_effects):
    """The case's background drawn from its own stream against the contacts as the mode leaves them."""
    from prsm_lube_ros.physics.effects import effect_ids, simulation
    from prsm_lube_ros.simulation.recordings import simulation_context
    streams = np.random.SeedSequence(seed).spawn(len(effect_ids()))
    rng = np.random.default_rng(streams[list(effect_ids()).index('background_vibration')])
    context = replace(simulation_context(setup.rig, setup.plan), reference_amplitude=contact_rms(setup, mode_effects))
    return simulation('background_vibration').draw(rng, context)


def diagnosed(seed: int, setup, effects) -> dict:
    """Simulate the case with ``effects``, read it as ``diagnose`` does, diagnose; the figures of the row."""
    from prsm_lube_ros.diagnosis.engine import diagnose_table
    from prsm_lube_ros.experiments.random_study import _named_effects, case_recordings, case_table
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    folder = Path(tempfile.mkdtemp(prefix='bg_mode_'))
    try:
        paths = simulate_experiment(folder / 'sim', plan=setup.plan, rig=setup.rig, seed=seed, effects=effects,
                                    nuisances=setup.nuisances)
        table = case_table(paths, case_recordings(paths, setup))
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    document = json.loads(json.dumps(diagnose_table(table).as_json(), default=float))
    candidates = {c['effect']: c for c in document['candidates']}
    background, mode = candidates.get('background_vibration', {}), candidates.get('resonance', {})
    return {'named': _named_effects(document), 'background_gain': background.get('gain'),
            'mode_gain': mode.get('gain'), 'background_c_lambda': (background.get('constants') or {}).get('c_lambda')}


def row(seed: int, redraw: bool) -> dict:
    """One case: its forms, B over the bare and the moded contacts, and (``redraw``) the redrawn diagnosis."""
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    from prsm_lube_ros.experiments.random_study import draw_case, truth_form
    from prsm_lube_ros.simulation.effects import Effects
    setup, names, effects = draw_case('two', seed, list(candidate_ids()))
    if sorted(names) != ['background_vibration', 'resonance']:
        raise SystemExit(f'seed {seed}: the case holds {names}, not a background and a mode')
    mode = Effects(resonance=effects.resonance)
    moded = contact_rms(setup, mode)
    out = {'seed': seed, 'mode': truth_form('resonance', effects.as_dict()['resonance'], setup.plan.speeds),
           'natural_frequency_hz': effects.resonance.natural_frequency,
           'b_over_bare': effects.background_vibration.rms / contact_rms(setup),
           'b_over_moded': effects.background_vibration.rms / moded}
    if redraw:
        background = redrawn_background(seed, setup, mode)
        out['redrawn_b_over_moded'] = background.rms / moded
        out.update(diagnosed(seed, setup, Effects(resonance=effects.resonance, background_vibration=background)))
    return out


def _number(value, fmt: str) -> str:
    return format(value, fmt) if isinstance(value, (int, float)) else '-'


def main(argv=None) -> int:
    """Print and write the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', default=','.join(str(s) for s in CASES), help='study seeds of kind "two"')
    parser.add_argument('--redraw', action='store_true', help='simulate and diagnose with the background redrawn')
    parser.add_argument('--name', default='background_beside_mode', help='results file name in benchmarks/results')
    args = parser.parse_args(argv)
    rows = []
    for seed in (int(s) for s in args.seeds.split(',')):
        rows.append(row(seed, args.redraw))
        print(json.dumps(rows[-1]), flush=True)
    lines = [f'# A background beside a mode (`python benchmarks/background_beside_mode.py {" ".join(sys.argv[1:])}`)',
             '', 'B over the thread contacts at the lowest speed and highest load, theta 1, in power over the stroke: '
             'Eq. 22 bare (what B is drawn against) and as the mode leaves them. With --redraw: B drawn again '
             'against the moded contacts, the case simulated and diagnosed; gains are held-out, each effect alone.',
             '', '| seed | mode | f_r Hz | B / bare contacts | B / moded contacts | redrawn: B / moded | named |'
             ' background gain | mode gain | background fit C_lambda |', '|---|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        lines.append(f'| {r["seed"]} | {r["mode"]} | {r["natural_frequency_hz"]:.2f} | {r["b_over_bare"]:.2f} | '
                     f'{r["b_over_moded"]:.2f} | {_number(r.get("redrawn_b_over_moded"), ".2f")} | '
                     f'{", ".join(r.get("named", [])) or ("-" if "named" not in r else "none")} | '
                     f'{_number(r.get("background_gain"), ".1%")} | {_number(r.get("mode_gain"), ".1%")} | '
                     f'{_number(r.get("background_c_lambda"), ".2f")} |')
    write_results(args.name, rows, lines, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
