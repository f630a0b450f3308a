#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Is each effect named with the right physical form, and are two effects named together?

Window tables from the window-table simulator
(:mod:`prsm_lube_ros.experiments.synthetic_tables`), two sessions of the six
conditions in random order each; for every form of each effect ``--seeds``
cases, the strength drawn by the simulator over its physical ranges, diagnosed
with :func:`prsm_lube_ros.diagnosis.diagnose_table`.  Per true form: how often
the verdict names the effect, how often the named form is the true one
(``form right``: the first-named form; ``form among named``: the true form is
among those named when the data fit several equally well).  Thermal cases run
twice: on the default plan and on a plan with short rests between runs
(nut and oil warm more).  ``--seeds`` cases with no effect: how often the
verdict is ``adequate``.  Every pair of two effects: how often both are named.
Results go to ``benchmarks/results/diagnose_forms.{json,md}``.

Usage: ``python benchmarks/diagnose_forms.py [--seeds 3] [--pair-seeds 3] [--jobs 2]``
"""
from __future__ import annotations

import argparse
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from itertools import combinations
import json
from pathlib import Path
import time

import numpy as np

from prsm_lube_ros.diagnosis import diagnose_table
from prsm_lube_ros.diagnosis.effects import registered
from prsm_lube_ros.physics.effects.background_vibration import FORMS as BACKGROUND_FORMS
from prsm_lube_ros.experiments.synthetic_tables import _draw_effect, SyntheticPlan, synthetic_table

ROOT = Path(__file__).resolve().parents[1]
#: Two sessions (relubricated between them) as the diagnose study records: within one session temperature and
#: revolutions rise together and the film effects cannot be told apart.
PLAN = SyntheticPlan(spectrum_bins=128, sessions=2)
WARM = SyntheticPlan(spectrum_bins=128, sessions=2, rest=5.0)
EFFECTS = ('position_dependent_stiffness', 'resonance', 'thermal_viscosity', 'lubricant_depletion',
           'background_vibration')
PAIRS = tuple(combinations(EFFECTS, 2))
#: The diagnosis' forms of each effect, by the names it reports (background: the law's forms, one fitted model).
FORMS = {**{effect: tuple(sorted(form.form for form in registered()[effect].variants()))
            for effect in EFFECTS if effect != 'background_vibration'},
         'background_vibration': BACKGROUND_FORMS}
ARRANGEMENT_FORMS = {form.arrangement: form.form for form in registered()['position_dependent_stiffness'].variants()}
LAW_FORMS = {'exponential': 'exponential (Reynolds)', 'vogel': 'Vogel', 'walther': 'Walther (ASTM D341)'}


def true_form(effect: str, params: dict) -> str:
    """The diagnosis' name of the form the simulator drew."""
    if effect == 'position_dependent_stiffness':
        return ARRANGEMENT_FORMS[params['arrangement']]
    if effect == 'resonance':
        return f'mode {params["band"]} the speed band'
    if effect == 'thermal_viscosity':
        return LAW_FORMS[params.get('law', 'exponential')]
    if effect == 'lubricant_depletion':
        form = f'{params.get("form", "exponential")} in revolutions'
        return form + (', partial recovery at rest' if params.get('recovery_time') else '')
    return params['form']


def drawn_params(effect: str, form: str, seed: int, plan: SyntheticPlan) -> dict:
    """Parameters the simulator draws for ``effect`` (its own ranges), the first draw from ``seed`` on in ``form``."""
    for attempt in range(1000):
        params = _draw_effect(effect, np.random.default_rng(1000 * seed + attempt), plan)
        if true_form(effect, params) == form:
            return params
    raise RuntimeError(f'{effect}: no {form} drawn')


def run_single(effect: str | None, form: str, seed: int, plan: SyntheticPlan) -> dict:
    """One case of ``effect`` in ``form`` (``effect`` None: no effect, right when ``adequate``)."""
    params = drawn_params(effect, form, seed, plan) if effect else None
    table, truth = synthetic_table(np.random.default_rng(seed), effect, plan, params=params)
    document = diagnose_table(table).as_json()
    if effect is None:
        return {'effect': 'none', 'form': '', 'seed': seed, 'verdict': document['verdict'], 'named_form': '',
                'form_right': document['verdict'] == 'adequate', 'form_among_named': document['verdict'] == 'adequate',
                'named_effects': [e['effect'] for e in document['effects']]}
    named = document['effects'][0]['form'] if document['verdict'] == effect and document['effects'] else ''
    form = true_form(effect, truth['params'])
    return {'effect': effect, 'form': form, 'seed': seed, 'verdict': document['verdict'], 'named_form': named,
            'form_right': named.split(' or ')[0].split(' (the data')[0] == form,
            'form_among_named': form in named,
            'named_effects': [e['effect'] for e in document['effects']]}


def run_pair(pair: tuple, seed: int) -> dict:
    table, truth = synthetic_table(np.random.default_rng(seed), pair, PLAN)
    document = diagnose_table(table).as_json()
    named = [e['effect'] for e in document['effects']]
    return {'pair': list(pair), 'seed': seed, 'verdict': document['verdict'], 'named_effects': named,
            'both': set(named) == set(pair)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=3)
    parser.add_argument('--pair-seeds', type=int, default=3)
    parser.add_argument('--out', type=Path, default=ROOT / 'benchmarks' / 'results')
    parser.add_argument('--jobs', type=int, default=1, help='processes (cases are independent)')
    args = parser.parse_args(argv)
    started = time.time()
    single_cases = [(effect, form, seed, PLAN, 'default') for effect in EFFECTS for form in FORMS[effect]
                    for seed in range(args.seeds)]
    single_cases += [('thermal_viscosity', form, seed, WARM, 'warm') for form in FORMS['thermal_viscosity']
                     for seed in range(args.seeds)]
    single_cases += [(None, '', seed, PLAN, 'default') for seed in range(args.seeds)]
    pair_cases = [(pair, 100 + seed) for pair in PAIRS for seed in range(args.pair_seeds)]
    with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        single_futures = [pool.submit(run_single, *case[:4]) for case in single_cases]
        pair_futures = [pool.submit(run_pair, *case) for case in pair_cases]
        singles = []
        for case, future in zip(single_cases, single_futures):
            singles.append({**future.result(), 'plan': case[4]})
            print(singles[-1], flush=True)
        pairs = []
        for future in pair_futures:
            pairs.append(future.result())
            print(pairs[-1], flush=True)
    rows = defaultdict(lambda: [0, 0, 0, 0])
    for case in singles:
        key = (case['effect'], case['form'], case['plan'])
        row = rows[key]
        row[0] += 1
        row[1] += case['verdict'] == (case['effect'] if case['effect'] != 'none' else 'adequate')
        row[2] += case['form_right']
        row[3] += case['form_among_named']
    lines = ['# Diagnose: each form of each effect, and two effects at once', '',
             f'Command: `python benchmarks/diagnose_forms.py --seeds {args.seeds} --pair-seeds {args.pair_seeds} '
             f'--jobs {args.jobs}` ({time.time() - started:.0f} s wall). Window tables of the window-table simulator, '
             'form and strength drawn per seed in its physical range, two sessions per case; "warm": 5 s rests '
             'between runs, not 30 s. "none" rows: no effect, "effect named" counts `adequate` verdicts.',
             '',
             '| effect | true form | plan | cases | effect named | form right | form among named |',
             '|---|---|---|---|---|---|---|']
    for (effect, form, plan), (n, named, right, among) in sorted(rows.items()):
        lines.append(f'| {effect} | {form} | {plan} | {n} | {named} | {right} | {among} |')
    effect_cases = [c for c in singles if c['effect'] != 'none']
    unaffected = [c for c in singles if c['effect'] == 'none']
    lines += ['', f'Totals: effect named in {sum(c["verdict"] == c["effect"] for c in effect_cases)} of '
              f'{len(effect_cases)} single-effect cases; `adequate` on '
              f'{sum(c["verdict"] == "adequate" for c in unaffected)} of {len(unaffected)} unaffected cases; '
              f'both effects named in {sum(c["both"] for c in pairs)} of '
              f'{len(pairs)} two-effect cases.']
    lines += ['', '| pair | cases | both named | verdicts |', '|---|---|---|---|']
    for pair in PAIRS:
        cases = [c for c in pairs if tuple(c['pair']) == pair]
        verdicts = ', '.join(sorted({'+'.join(c['named_effects']) or c['verdict'] for c in cases}))
        lines.append(f'| {" + ".join(pair)} | {len(cases)} | {sum(c["both"] for c in cases)} | {verdicts} |')
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / 'diagnose_forms.md').write_text('\n'.join(lines) + '\n')
    (args.out / 'diagnose_forms.json').write_text(json.dumps({'singles': singles, 'pairs': pairs}, indent=1))
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
