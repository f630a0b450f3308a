# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Study: does ``diagnose`` name a concealed effect, and stay quiet without one.

Two designs:

* ``--design random`` (default, :mod:`.random_study`): per case the operating
  plan (3-6 speeds x 2-5 loads), the recording set-up (1-20 kHz, 5-200 ms
  blocks, joint states 50-1000 Hz, ...), stamp jitter, repeated stamps, lost
  blocks and the effect's strength and form are drawn at random
  (:mod:`.study_draws`); ``--seeds`` cases per effect, as many without an
  effect and as many with two.  Writes ``confusion.md`` (score per kind,
  confusion per form, every miss) and ``results.json`` to ``--out``.
  ``--quick``: the smallest plan, for a test of the machinery.
* ``--design paper``: the paper's plan with only the effect strengths drawn,
  as the earlier tables (``benchmarks/results/diagnose_study_rig*``,
  ``diagnose_study_synthetic``); writes ``confusion.md`` / ``confusion.csv`` /
  ``results.json``.

For the paper design, every effect ID and no effect get ``--seeds`` recordings
with effect strengths drawn in their physical ranges and runs in random order.

Simulators (paper design):

* ``rig`` — :mod:`prsm_lube_ros.simulation`: bags of vibration blocks, joint
  states, load and temperature, read back through the windowing like any
  recording; two sessions at theta_Oil = 1 with a relubrication between them.
* ``synthetic`` — :mod:`.synthetic`: window tables from an independent
  implementation with its own plan, noise and effect parametrisations.

``--order fixed`` runs the conditions speed-major instead (run order confounded
with speed), to see how often the diagnosis says it cannot tell.

    python -m prsm_lube_ros.experiments.diagnose_study --out benchmarks/results/diagnose_study_random --seeds 30
    python -m prsm_lube_ros.experiments.diagnose_study --design paper --out out/diagnose_study [--seeds 20]
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import csv
import json
from pathlib import Path
import shutil
import sys
import tempfile
import time
from typing import cast, TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence

    from ..diagnosis.fitting import ModelFit
    from ..diagnosis.table import WindowTable

__all__ = ['FORM_SEARCH', 'NONE', 'confusion', 'main', 'run_case', 'write_outputs']

NONE = 'none'
#: Seeds searched per kind for cases of one drawn form (``--form-contains``).
FORM_SEARCH = 5000


def _simulate_rig(effect: str, seed: int, order: str, sessions: int) -> tuple[WindowTable, dict | None]:
    from ..estimation.pipeline import recording_windows
    from ..simulation.recordings import draw_effects, simulate_experiment
    from ..simulation.rig_config import ExperimentPlan
    from ..estimation.windowing import WindowSettings
    from ..diagnosis.table import table_from_windows
    plan = ExperimentPlan(stage_thetas=(1.0,) * sessions)
    effects = draw_effects([] if effect == NONE else [effect], seed=seed, plan=plan)
    folder = Path(tempfile.mkdtemp(prefix='prsm_diag_'))
    try:
        paths = simulate_experiment(folder / 'sim', plan=plan, seed=seed, effects=effects, run_order=order)
        # Raw RMS and 256-sample spectra, as the recorded results of this study were made (issue 16 left them).
        windows = [recording_windows(p, lead=0.005, settings=WindowSettings(spectrum_segment=256, band=None)).windows
                   for p in paths]
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return table_from_windows(windows, sources=[p.name for p in paths]), effects.as_dict().get(effect)


def _simulate_synthetic(effect: str, seed: int, order: str, sessions: int) -> tuple[WindowTable, dict]:
    from .synthetic_tables import SyntheticPlan, synthetic_table
    rng = np.random.default_rng(10_000 + seed)
    plan = SyntheticPlan(repeats=1, sessions=sessions, random_order=order == 'random', spectrum_bins=128,
                         condition_indicators=True)
    table, truth = synthetic_table(rng, None if effect == NONE else effect, plan)
    return table, {k: (list(v) if isinstance(v, tuple) else v) for k, v in truth['params'].items()}


def run_case(case: tuple) -> dict:
    """Simulate and diagnose one (simulator, effect, seed, order, sessions); returns the case's record."""
    simulator, effect, seed, order, sessions = case
    from ..diagnosis.engine import diagnose_table
    start = time.time()
    simulate = _simulate_rig if simulator == 'rig' else _simulate_synthetic
    table, truth = simulate(effect, seed, order, sessions)
    result = diagnose_table(table)
    true_candidate = next((c for c in result.candidates if c.effect.id == effect and c.fit is not None), None)
    return {'simulator': simulator, 'effect': effect, 'seed': seed, 'order': order, 'verdict': result.verdict,
            'tied': result.tied, 'baseline_cv_rmse': result.baseline.cv_rmse,
            'best': result.best.effect.id if result.best else None,
            'best_cv_rmse': cast('ModelFit', result.best.fit).cv_rmse if result.best else None,
            'true_effect_gain': true_candidate.gain if true_candidate else None,
            'chosen_gain': result.chosen.gain if result.chosen else None,
            'chosen_run_gain': (1 - cast('ModelFit', result.chosen.fit).cv_run_rmse / result.baseline.cv_run_rmse
                                if result.chosen else None),
            'truth': truth, 'windows': len(table), 'runs': int(table.runs.size),
            'seconds': round(time.time() - start, 2)}


def confusion(records: list[dict], effects: list[str]) -> tuple[list[str], dict]:
    """Verdict columns and counts[true][verdict]."""
    columns = effects + ['adequate', 'ambiguous', 'unexplained']
    counts = {true: {col: 0 for col in columns} for true in effects + [NONE]}
    for record in records:
        counts[record['effect']][record['verdict']] = counts[record['effect']].get(record['verdict'], 0) + 1
    return columns, counts


def write_outputs(out: Path, records: list[dict], effects: list[str], command: str) -> str:
    """Write confusion.md, confusion.csv and results.json; return the Markdown."""
    columns, counts = confusion(records, effects)
    short = {e: e.replace('position_dependent_stiffness', 'position').replace('_vibration', '')
             .replace('lubricant_', '').replace('thermal_viscosity', 'thermal') for e in columns}
    lines = ['# Diagnose study', '', f'Command: `{command}`', '',
             '| true effect | ' + ' | '.join(short[c] for c in columns) + ' | right | median gain | run gain |',
             '|---|' + '---|' * (len(columns) + 3)]
    for true, row in counts.items():
        total = sum(row.values())
        right = row.get(true if true != NONE else 'adequate', 0)
        gains = [r['chosen_gain'] for r in records if r['effect'] == true and r['chosen_gain'] is not None]
        gain = f'{100 * np.median(gains):.0f} %' if gains and true != NONE else '-'
        run_gains = [r['chosen_run_gain'] for r in records if r['effect'] == true and r.get('chosen_run_gain')
                     is not None]
        run_gain = f'{100 * np.median(run_gains):.0f} %' if run_gains and true != NONE else '-'
        lines.append(f'| {true} | ' + ' | '.join(str(row[c]) for c in columns)
                     + f' | {right}/{total} ({100 * right / max(total, 1):.0f} %) | {gain} | {run_gain} |')
    lines += ['', '"median gain": median fall of the held-out relative RMS error per window (cv_rmse), chosen '
              'model vs the paper\'s, over the cases where the verdict named an effect; "run gain": the same '
              'for run amplitudes (cv_run_rmse), where the window-to-window scatter averages out.', '']
    weak = [r for r in records if r['effect'] != NONE and r['verdict'] == r['effect']
            and (r['chosen_gain'] or 0) < 0.3]
    if weak:
        lines.append(f'{len(weak)} right verdict(s) with a held-out gain below 30 % '
                     f'({", ".join(sorted({r["effect"] for r in weak}))}): the effect is real but small '
                     'against the window-to-window scatter.')
    text = '\n'.join(lines) + '\n'
    out.mkdir(parents=True, exist_ok=True)
    (out / 'confusion.md').write_text(text)
    with open(out / 'confusion.csv', 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(['true_effect'] + columns)
        for true, row in counts.items():
            writer.writerow([true] + [row[c] for c in columns])
    (out / 'results.json').write_text(json.dumps(records, indent=1, default=float))
    return text


def _safe_random_case(case: tuple) -> dict:
    """:func:`.random_study.run_random_case`, an unexpected failure recorded as the case's verdict."""
    from .random_study import run_random_case
    try:
        return run_random_case(case)
    except Exception as exc:  # noqa: BLE001 - one broken case must not lose the study
        kind, seed = case[0], case[1]
        return {'kind': kind, 'seed': seed, 'effects': [], 'verdict': f'failed: {type(exc).__name__}: {exc}',
                'named': [], 'right': False, 'seconds': 0.0}


def _run_random(args: argparse.Namespace, effects: list[str], command: str) -> int:
    """Cases seed-major (a stopped run is a balanced subset), results rewritten every ``--save-every`` cases."""
    from concurrent.futures import as_completed
    from .random_study import NONE, OUTSIDE_KINDS, THERMAL_FREE, TWO, write_random_outputs
    kinds = effects + [NONE] + ([TWO] if len(effects) >= 2 else []) + list(OUTSIDE_KINDS) + [THERMAL_FREE]
    if args.kinds:
        unknown = sorted(set(args.kinds) - set(kinds))
        if unknown:
            print(f'diagnose_study: unknown kind(s) {", ".join(unknown)}; known: {", ".join(kinds)}', file=sys.stderr)
            return 2
        kinds = list(args.kinds)
    elif args.effects:      # effects chosen by name: those, none and two; the other kinds only when asked
        kinds = [kind for kind in kinds if kind not in OUTSIDE_KINDS and kind != THERMAL_FREE]
    if args.form_contains:
        cases = _cases_of_form(kinds, effects, args)
    else:
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        cases = [(kind, seed, tuple(effects), args.quick) for seed in seeds for kind in kinds]
    records, start = [], time.time()
    with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        futures = [pool.submit(_safe_random_case, case) for case in cases]
        for future in as_completed(futures):
            record = future.result()
            records.append(record)
            print(f'{record["kind"]:<30} seed {record["seed"]:>3} -> {record["verdict"]:<30} '
                  f'{"right" if record["right"] else "MISS "} ({record["seconds"]:.1f} s)', file=sys.stderr, flush=True)
            if len(records) % max(args.save_every, 1) == 0 and len(records) < len(cases):
                write_random_outputs(Path(args.out), sorted(records, key=lambda r: (r['kind'], r['seed'])),
                                     command + f'  (partial: {len(records)} of {len(cases)} cases)',
                                     time.time() - start, args.jobs)
    records.sort(key=lambda r: (r['kind'], r['seed']))
    print(write_random_outputs(Path(args.out), records, command, time.time() - start, args.jobs))
    return 0


def _cases_of_form(kinds: Sequence[str], effects: list[str], args: argparse.Namespace) -> list[tuple]:
    """``--seeds`` cases per kind whose drawn form has ``--form-contains`` in its words, seeds from ``--first-seed``.

    ``--form-contains`` may also be an effect ID (``surface_defect``): the
    cases holding that effect, whatever its form (the form words never name
    the effect, so without this a pair holding a defect of any form could
    not be chosen in one block). The draws are those of every case (nothing
    is drawn differently): the seeds whose drawn effects do not match are
    skipped, up to :data:`FORM_SEARCH` seeds a kind.
    """
    from .random_study import case_effect_forms
    cases = []
    for kind in kinds:
        found = 0
        for seed in range(args.first_seed, args.first_seed + FORM_SEARCH):
            if found == args.seeds:
                break
            drawn = case_effect_forms(kind, seed, effects, quick=args.quick)
            if any(args.form_contains == name or args.form_contains in form for name, form in drawn):
                cases.append((kind, seed, tuple(effects), args.quick))
                found += 1
    return sorted(cases, key=lambda case: (case[1], case[0]))


def _study_cases(out: Path) -> tuple[list[dict], bool] | None:
    """The cases of ``out``/results.json and whether the study ran ``--quick``; None (one line on stderr) if unread."""
    try:
        document = json.loads((out / 'results.json').read_text())
        return list(document['cases']), '--quick' in str(document.get('command', '')).split()
    except (OSError, ValueError, KeyError, TypeError) as exc:
        _cannot_read(out, exc)
        return None


def _cannot_read(folder: Path, exc: Exception) -> None:
    """The one line for a study's results.json that cannot be read."""
    print(f'diagnose_study: cannot read the cases of {folder / "results.json"}: {exc!r}', file=sys.stderr)


def _combine(out: Path, folders: Sequence[Path], command: str) -> int:
    """``--combine``: the cases of several studies' results.json (no case twice) as one study in ``out``."""
    from .random_study import write_random_outputs
    records: list[dict] = []
    wall, jobs, commands = 0.0, 1, []
    for folder in folders:
        try:
            document = json.loads((folder / 'results.json').read_text())
            cases, seconds = list(document['cases']), float(document['wall_seconds'])
        except (OSError, ValueError, KeyError, TypeError) as exc:
            _cannot_read(folder, exc)
            return 2
        seen = {(r['kind'], r['seed']) for r in records}
        twice = sorted(f'{r["kind"]} seed {r["seed"]}' for r in cases if (r['kind'], r['seed']) in seen)
        if twice:
            print(f'diagnose_study: {folder / "results.json"} repeats cases of the folders before it '
                  f'({", ".join(twice[:3])}{", ..." if len(twice) > 3 else ""}); combine studies of disjoint seeds',
                  file=sys.stderr)
            return 2
        records += cases
        wall += seconds
        jobs = max(jobs, int(document.get('jobs', 1)))
        commands.append(str(document.get('command', '')))
    records.sort(key=lambda r: (r['kind'], r['seed']))
    print(write_random_outputs(out, records, command, wall, jobs, sources=commands))
    return 0


def _margins(out: Path, command: str) -> int:
    """``--margins``: the candidates a lower BIC margin would name, to ``out``/margins.md."""
    from .margins import margins_markdown
    study = _study_cases(out)
    if study is None:
        return 2
    text = margins_markdown(study[0], command)
    (out / 'margins.md').write_text(text)
    print(text)
    return 0


def _simulate_again(records: list[dict], quick: bool, jobs: int, case_function: Callable[[tuple], dict]) \
        -> list[dict]:
    """``case_function`` on each of ``records``' cases, simulated again from its (kind, seed) as the study drew it."""
    from ..diagnosis.effects import candidate_ids
    pool_effects = tuple(e for e in candidate_ids() if e != NONE)
    cases = [(r['kind'], r['seed'], pool_effects, quick) for r in records]
    with ProcessPoolExecutor(max_workers=max(jobs, 1)) as pool:
        return list(pool.map(case_function, cases))


def _effect_sizes(records: list[dict], quick: bool, jobs: int) -> list[dict]:
    """The concealed effects' sizes (:func:`.random_study.explain_miss`) of ``records``, simulated again."""
    from .random_study import explain_miss
    return _simulate_again(records, quick, jobs, explain_miss)


def _explain_misses(out: Path, jobs: int, command: str) -> int:
    """``--explain-misses``: the size of what each missed case concealed, to ``out``/misses.md."""
    from .random_study import misses_markdown
    study = _study_cases(out)
    if study is None:
        return 2
    records, quick = study
    sizes = _effect_sizes([r for r in records if not r.get('right')], quick, jobs)
    text = misses_markdown(records, sizes, command)
    (out / 'misses.md').write_text(text)
    print(text)
    return 0


def _rerun_misses(out: Path, jobs: int, command: str) -> int:
    """``--rerun-misses``: the missed cases of ``out``/results.json run again on this engine, to ``out``/rerun.md."""
    from .random_study import run_random_case
    study = _study_cases(out)
    if study is None:
        return 2
    records, quick = study
    missed = [r for r in records if not r.get('right')]
    again = _simulate_again(missed, quick, jobs, run_random_case)
    lines = ['# Missed cases run again on the current engine', '', f'Command: `{command}`', '',
             f'{sum(r["right"] for r in again)} of the {len(missed)} cases the study missed are right now. '
             'These seeds are not fresh for the engine that ran them again: a rerun says what a change did to '
             'the cases it was made for, not how it generalises.', '',
             '| kind | seed | concealed | verdict in the study | verdict now | named now | right now |',
             '|---|---|---|---|---|---|---|']
    for before, now in zip(missed, again):
        # A case that crashed in the study has no effects in its record; the rerun simulated the same ones.
        concealed = before.get('effects') or now.get('effects') or []
        lines.append(f'| {before["kind"]} | {before["seed"]} | {", ".join(concealed) or "-"} | '
                     f'{before["verdict"]} | {now["verdict"]} | {", ".join(now.get("named", [])) or "-"} | '
                     f'{"yes" if now["right"] else "no"} |')
    text = '\n'.join(lines) + '\n'
    (out / 'rerun.md').write_text(text)
    print(text)
    return 0


def _power(out: Path, kinds: Sequence[str], jobs: int, command: str) -> int:
    """``--power``: every case of ``kinds`` against what an ideal test would name, to ``out``/power.md."""
    from ..diagnosis.effects import candidate_ids
    from .detection_power import power_markdown
    study = _study_cases(out)
    if study is None:
        return 2
    records, quick = study
    single = set(candidate_ids()) - {NONE}
    wrong = sorted(set(kinds) - single)
    if wrong:
        print(f'diagnose_study: --power takes single catalogue effects, not {", ".join(wrong)}; '
              f'known: {", ".join(sorted(single))}', file=sys.stderr)
        return 2
    chosen = [r for r in records if r['kind'] in kinds]
    text = power_markdown(chosen, _effect_sizes(chosen, quick, jobs), command)
    (out / 'power.md').write_text(text)
    print(text)
    return 0


def _parser() -> argparse.ArgumentParser:
    """The study's command-line options."""
    parser = argparse.ArgumentParser(prog='python -m prsm_lube_ros.experiments.diagnose_study',
                                     description=__doc__.split('\n')[0])
    parser.add_argument('--out', default='out/diagnose_study')
    parser.add_argument('--design', choices=('random', 'paper'), default='random',
                        help='random plans, set-ups, nuisances and effects (default) or the paper\'s plan')
    parser.add_argument('--seeds', type=int, default=None, help='cases per kind (default 30 random, 20 paper)')
    parser.add_argument('--quick', action='store_true', help='random design: smallest plans, 1 seed unless --seeds')
    parser.add_argument('--simulator', choices=('rig', 'synthetic'), default='rig', help='paper design only')
    parser.add_argument('--order', choices=('random', 'fixed'), default='random', help='paper design only')
    parser.add_argument('--sessions', type=int, default=2, help='paper design: sessions (bags) at theta 1 per case')
    parser.add_argument('--effects', nargs='*', default=None, help='effect IDs (default: all and none)')
    parser.add_argument('--kinds', nargs='*', default=None,
                        help='random design: the kinds to run (default: every effect, none, two, step_in_time, '
                             'direction_factor, thermal_free)')
    parser.add_argument('--first-seed', type=int, default=0, help='random design: seeds from this one on')
    parser.add_argument('--form-contains', default=None, metavar='WORDS',
                        help='random design: per kind the first --seeds seeds (from --first-seed) whose drawn effect '
                             'form has these words, e.g. "below the mesh band", or that draw this effect ID, e.g. '
                             'surface_defect; the other seeds are skipped')
    parser.add_argument('--jobs', type=int, default=2)
    parser.add_argument('--save-every', type=int, default=10, help='random design: rewrite the results every N cases')
    parser.add_argument('--explain-misses', action='store_true',
                        help='random design: simulate the missed cases of --out/results.json again and write '
                             'misses.md with the size of what was concealed against the scatter')
    parser.add_argument('--rerun-misses', action='store_true',
                        help='random design: run the missed cases of --out/results.json again on this engine and '
                             'write rerun.md with what it says now')
    parser.add_argument('--margins', action='store_true',
                        help='random design: write margins.md from --out/results.json, the candidates a lower BIC '
                             'margin would name (no case is run again)')
    parser.add_argument('--combine', nargs='+', default=None, metavar='DIR',
                        help='random design: merge the results.json of these study folders (disjoint seeds, each '
                             'from --first-seed) into --out: one confusion.md and results.json over all their cases')
    parser.add_argument('--power', nargs='+', default=None, metavar='EFFECT',
                        help='random design: simulate every case of these effects in --out/results.json again and '
                             'write power.md, the chance an ideal test would name each')
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Command line of the study."""
    from ..diagnosis.effects import candidate_ids
    args = _parser().parse_args(argv)
    if args.seeds is None:
        args.seeds = 1 if args.quick else (30 if args.design == 'random' else 20)
    effects = list(args.effects) if args.effects else list(candidate_ids())
    command = ('python -m prsm_lube_ros.experiments.diagnose_study '
               + ' '.join(argv if argv is not None else sys.argv[1:]))
    if args.design == 'random' and args.explain_misses:
        return _explain_misses(Path(args.out), args.jobs, command)
    if args.design == 'random' and args.rerun_misses:
        return _rerun_misses(Path(args.out), args.jobs, command)
    if args.design == 'random' and args.combine:
        return _combine(Path(args.out), [Path(d) for d in args.combine], command)
    if args.design == 'random' and args.margins:
        return _margins(Path(args.out), command)
    if args.design == 'random' and args.power:
        return _power(Path(args.out), args.power, args.jobs, command)
    if args.design == 'random':
        return _run_random(args, [e for e in effects if e != NONE], command)
    classes = [e for e in effects if e != NONE] + [NONE]
    cases = [(args.simulator, e, seed, args.order, args.sessions) for e in classes for seed in range(args.seeds)]
    records = []
    with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        for record in pool.map(run_case, cases):
            records.append(record)
            print(f'{record["effect"]:<30} seed {record["seed"]:>3} -> {record["verdict"]:<30} '
                  f'({record["seconds"]:.1f} s)', file=sys.stderr, flush=True)
    print(write_outputs(Path(args.out), records, [e for e in classes if e != NONE], command))
    return 0


if __name__ == '__main__':
    sys.exit(main())
