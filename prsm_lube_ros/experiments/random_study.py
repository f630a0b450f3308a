# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The diagnosis study on randomly drawn cases: run one case, tabulate many.

A case is a kind (an effect ID, ``none`` or ``two`` effects) and a seed.  From
them :mod:`.study_draws` draws the operating plan, the recording set-up and its
nuisances, and :func:`~prsm_lube_ros.simulation.recordings.draw_effects` the
effects (their strengths and, where the draw functions offer several, their
physical form).  The rig simulator writes the bags, they are read back through
the windowing like any recording, and :func:`~prsm_lube_ros.diagnosis.engine.diagnose_table`
gives the verdict.  Nothing of the truth reaches the diagnosis.

Scored per case: whether the verdict is right (the concealed effect named;
``adequate`` without one; both named, or at least one, with two), the held-out
gain of the chosen model against the paper's (``1 - cv_rmse / cv_rmse_paper``)
and the run-level lack-of-fit test of the paper's model (condition means against
replicate runs, :mod:`~prsm_lube_ros.diagnosis.adequacy`): a case whose test
finds a lack of fit must never be called ``adequate``.
"""
from __future__ import annotations

import json
import math
from pathlib import Path
import shutil
import tempfile
import time
from typing import cast, TYPE_CHECKING
import zlib
from collections.abc import Iterable, Sequence

import numpy as np
from scipy import stats

from ..physics.effects import simulation

if TYPE_CHECKING:
    from ..diagnosis.fitting import ModelFit
    from ..diagnosis.table import WindowTable
    from ..estimation.pipeline import RecordingWindows
    from ..simulation.effects import Effects
    from .study_draws import CaseSetup

__all__ = ['COOL_DOWN', 'NONE', 'OTHER_VERDICTS', 'OUTSIDE_KINDS', 'RETURN_LOG_FACTOR', 'STEP_AT', 'STEP_SIZE',
           'TARGET_GAIN', 'THERMAL_FREE', 'TWO', 'WARM_START', 'case_effect_forms', 'case_forms', 'case_recordings',
           'case_rng',
           'case_table', 'draw_case',
           'confusion_markdown', 'explain_miss', 'misses_markdown', 'run_random_case', 'simulate_case', 'summarise',
           'truth_form', 'write_random_outputs']

NONE, TWO = 'none', 'two'
#: Kinds with physics outside the diagnosis catalogue, and the covariate diagnose must locate for each: a step of
#: the amplitude in time (the sensor re-seated) and a factor on the loaded return traverses (direction of travel).
OUTSIDE_KINDS = {'step_in_time': 'time', 'direction_factor': 'direction'}
#: Thermal viscosity with a temperature that does not follow the revolutions (warm start, cool-down pauses).
THERMAL_FREE = 'thermal_free'
#: Ranges of those kinds: |step| (fraction), where it happens (fraction of the traverses), |ln return factor|,
#: initial offset of the nut temperature (times the running rise), cool-down pause (times the time constant).
STEP_SIZE = (0.15, 0.40)
STEP_AT = (0.3, 0.7)
RETURN_LOG_FACTOR = (0.12, 0.35)
WARM_START = (1.0, 2.0)
COOL_DOWN = (0.7, 1.5)
#: Verdict columns besides effect IDs.
OTHER_VERDICTS = ('adequate', 'ambiguous', 'unexplained', 'cannot tell')
#: Held-out gain an effect must bring when it is named (the issue's target).
TARGET_GAIN = 0.30


def case_rng(kind: str, seed: int) -> np.random.Generator:
    """The case's generator: the same for (kind, seed) in every process (crc32, not Python's salted hash)."""
    return np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(kind.encode())]))


def _forms(params: dict | None) -> str:
    """A drawn law's form: its text-valued parameters joined (``''`` for a law with one form)."""
    if not params:
        return ''
    return ','.join(str(v) for k, v in sorted(params.items()) if isinstance(v, str))


def truth_form(name: str, params: dict | None, speeds: Sequence[float]) -> str:
    """The physical form of a drawn law, in words, for the per-form rows.

    Text-valued parameters (bearing arrangement, viscosity law, depletion form,
    defect component and growth) name it; besides, the effect's simulation hook
    adds its own words (``Simulation.form_words``: a resonance placed against
    the plan's ``speeds`` in rad/s, a background's lines or floor, ...).
    """
    params = params or {}
    words = [_forms(params)] if _forms(params) else []
    return ', '.join(words + simulation(name).form_words(params, speeds))


def _named_effects(document: dict) -> list[str | None]:
    """Effect IDs a ``diagnose`` JSON document names: its ``effects`` list if any, else the verdict's effect."""
    listed = document.get('effects')
    if isinstance(listed, list) and listed:
        return [item.get('effect') if isinstance(item, dict) else str(item) for item in listed]
    verdict = document.get('verdict')
    return [verdict] if verdict not in OTHER_VERDICTS else []


def _chosen_form(document: dict) -> str:
    best = document.get('best') or {}
    if best.get('effect') != document.get('verdict'):
        return ''
    form = best.get('form')
    return str(form) if form else _forms(best.get('params') or {})


def draw_case(kind: str, seed: int, effect_pool: list[str], *,
              quick: bool = False) -> tuple[CaseSetup, list[str], Effects]:
    """The set-up, effect names and drawn effects of one case, nothing simulated yet."""
    from ..simulation.recordings import draw_effects
    from .study_draws import draw_setup
    rng = case_rng(kind, seed)
    setup = draw_setup(rng, quick=quick)
    names: list[str]
    if kind == NONE or kind in OUTSIDE_KINDS:
        names = []
    elif kind == TWO:
        names = sorted(rng.choice(effect_pool, size=2, replace=False).tolist())
    elif kind == THERMAL_FREE:
        names = ['thermal_viscosity']
    else:
        names = [kind]
    effects = draw_effects(names, seed=seed, rig=setup.rig, plan=setup.plan)
    return _outside_catalogue(kind, rng, setup, effects), names, effects


def case_forms(kind: str, seed: int, effect_pool: list[str], *, quick: bool = False) -> list[str]:
    """The drawn forms of a case's effects in words (:func:`truth_form`), without simulating it."""
    return [form for _, form in case_effect_forms(kind, seed, effect_pool, quick=quick)]


def case_effect_forms(kind: str, seed: int, effect_pool: list[str], *,
                      quick: bool = False) -> list[tuple[str, str]]:
    """(effect ID, drawn form in words) of each of a case's effects, without simulating it."""
    setup, names, effects = draw_case(kind, seed, effect_pool, quick=quick)
    truth = effects.as_dict()
    return [(name, truth_form(name, truth.get(name), setup.plan.speeds)) for name in names]


def simulate_case(kind: str, seed: int, effect_pool: list[str], *, quick: bool = False,
                  folder: Path) -> tuple[list[Path], CaseSetup, list[str], dict[str, dict | None]]:
    """Bags of one case in ``folder``; returns (paths, setup, effect names, truth of each effect)."""
    from ..simulation.recordings import simulate_experiment
    setup, names, effects = draw_case(kind, seed, effect_pool, quick=quick)
    paths = simulate_experiment(folder / 'sim', plan=setup.plan, rig=setup.rig, seed=seed, effects=effects,
                                nuisances=setup.nuisances)
    truth = effects.as_dict()
    return paths, setup, names, {name: truth.get(name) for name in names}


def _outside_catalogue(kind: str, rng: np.random.Generator, setup: CaseSetup, effects: Effects) -> CaseSetup:
    """The set-up of the kinds that are not one catalogue effect (drawn after everything else of the case)."""
    from dataclasses import replace
    from .study_draws import CaseSetup
    sign = 1.0 if rng.integers(2) else -1.0
    if kind == 'step_in_time':
        rig = replace(setup.rig, mount_step=sign * float(rng.uniform(*STEP_SIZE)),
                      mount_step_at=float(rng.uniform(*STEP_AT)))
        return CaseSetup(setup.plan, rig, setup.nuisances)
    if kind == 'direction_factor':
        rig = replace(setup.rig, return_factor=float(math.exp(sign * rng.uniform(*RETURN_LOG_FACTOR))))
        return CaseSetup(replace(setup.plan, return_under_load=True), rig, setup.nuisances)
    if kind == THERMAL_FREE:
        law = effects.thermal_viscosity
        runs = len(setup.plan.conditions)
        plan = replace(setup.plan, cool_down_pause=float(rng.uniform(*COOL_DOWN) * law.time_constant),
                       cool_down_every=max(3, runs // 2))
        rig = replace(setup.rig, initial_temperature_offset=float(rng.uniform(*WARM_START) * law.temperature_rise))
        return CaseSetup(plan, rig, setup.nuisances)
    return setup


def case_recordings(paths: Sequence[Path], setup: CaseSetup) -> list[RecordingWindows]:
    """What ``prsm-lube diagnose`` reads of a case's bags: the analysis band, spectra resolving the lowest orders."""
    from ..estimation.pipeline import analysis_settings, recording_windows
    return [recording_windows(p, lead=setup.rig.actuator.lead, settings=analysis_settings(spectra=True))
            for p in paths]


def case_table(paths: Sequence[Path], recordings: Sequence[RecordingWindows]) -> WindowTable:
    """The window table ``prsm-lube diagnose`` builds of a case's recordings (InputError when none is usable)."""
    from ..diagnosis.table import band_high_of, table_from_windows
    return table_from_windows([r.windows for r in recordings], sources=[p.name for p in paths],
                              band_high=band_high_of(recordings))


def explain_miss(case: tuple) -> dict:
    """The concealed effects' size against the scatter (:mod:`.effect_size`) for one (kind, seed, pool, quick) case.

    The case is simulated again from its seed, exactly as the study drew it.
    Returns ``{'kind', 'seed', 'size'}`` (``size`` None without a concealed
    catalogue effect or without a usable window).
    """
    kind, seed, effect_pool, quick = case
    from ..errors import InputError
    from ..simulation.effects import Effects
    from .effect_size import effect_size
    folder = Path(tempfile.mkdtemp(prefix='prsm_study_'))
    try:
        paths, setup, names, truth = simulate_case(kind, seed, list(effect_pool), quick=quick, folder=folder)
        recordings = case_recordings(paths, setup)
        try:
            table = case_table(paths, recordings)
        except InputError:
            return {'kind': kind, 'seed': seed, 'size': None}
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if not names:
        return {'kind': kind, 'seed': seed, 'size': None}
    size = effect_size(table, setup.rig, Effects.from_dict(truth))
    return {'kind': kind, 'seed': seed, 'size': size.as_json()}


def run_random_case(case: tuple) -> dict:
    """Simulate, read and diagnose one (kind, seed, effect pool, quick) case; the case's record."""
    kind, seed, effect_pool, quick = case
    from ..diagnosis.engine import diagnose_table
    from ..errors import InputError
    start = time.time()
    folder = Path(tempfile.mkdtemp(prefix='prsm_study_'))
    record = {'kind': kind, 'seed': seed}
    try:
        paths, setup, names, truth = simulate_case(kind, seed, list(effect_pool), quick=quick, folder=folder)
        record.update({'effects': names, 'truth': truth,
                       'forms': {n: truth_form(n, truth[n], setup.plan.speeds) for n in names},
                       'setup': setup.as_dict()})
        recordings = case_recordings(paths, setup)
        record['problems'] = sum(len(r.problems) for r in recordings)
        try:
            table = case_table(paths, recordings)
            result = diagnose_table(table)
        except InputError as exc:      # diagnose refuses the data: what a user would see
            record.update({'verdict': 'cannot tell', 'named': [], 'error': str(exc)})
            result = None
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if result is None:
        record['seconds'] = round(time.time() - start, 2)
        record['right'] = _right(record)
        return record
    document = json.loads(json.dumps(result.as_json(), default=float))
    test = result.baseline_fit_test
    chosen = result.chosen
    record.update({
        'verdict': result.verdict, 'confident': result.confident, 'named': _named_effects(document),
        'chosen_form': _chosen_form(document), 'tied': list(result.tied),
        'windows': len(table), 'runs': int(table.runs.size),
        'baseline_cv_rmse': result.baseline.cv_rmse,
        'chosen_cv_rmse': cast('ModelFit', chosen.fit).cv_rmse if chosen is not None else None,
        'gain': chosen.gain if chosen is not None else None,
        'located': result.location.located,
        'empirical': document.get('empirical'),
        'temperature_revolutions_correlation': document.get('temperature_revolutions_correlation'),
        'baseline_rms': test.residual_rms if test else None,
        'pure_error_rms': test.pure_error_rms if test else None,
        'lack_of_fit': bool(test.lack_of_fit) if test else None,
        'lack_of_fit_excess_rms': test.excess_rms if test else None,
        # every candidate's scores against the paper's model, each fitted alone (its evidence too, even where
        # the engine did not count it beside another effect): what a change of the margins would do
        'candidates': [{key: c.get(key) for key in ('effect', 'status', 'reason', 'gain', 'delta_bic', 'evidence')}
                       for c in document.get('candidates', [])],
        # the engine's own account (ties, second effects and why): which cases a change of its rules can reach
        'notes': list(document.get('notes', [])),
        'seconds': round(time.time() - start, 2)})
    record['right'] = _right(record)
    return record


def _right(record: dict) -> bool:
    effects, named = record['effects'], record.get('named', [])
    if record['kind'] in OUTSIDE_KINDS:
        empirical = record.get('empirical') or {}
        return (record['verdict'] == 'unexplained'
                and OUTSIDE_KINDS[record['kind']] in (record.get('located'), empirical.get('covariate')))
    if not effects:
        return record['verdict'] == 'adequate'
    if len(effects) == 1:
        return effects[0] in named
    return set(effects) <= set(named)


def _row_key(record: dict) -> str:
    if record['kind'] == TWO:
        return 'two: ' + ' + '.join(record['effects'])
    if record['kind'] == NONE:
        return NONE
    form = record.get('forms', {}).get(record['kind'], '')
    return record['kind'] + (f' ({form})' if form else '')


def _cell(record: dict) -> str:
    """The confusion-table column of one record."""
    named = record.get('named', [])
    if record['kind'] == TWO:
        hit = len(set(record['effects']) & set(named))
        if hit == 2:
            return 'both named'
        if hit == 1:
            return 'one named'
    if named:
        return named[0] if len(named) == 1 else '+'.join(named)
    return record['verdict']


def _pct(values: Iterable[float | None], fmt: str = '{:.0f} %') -> str:
    """Median of the finite ``values`` in per cent, formatted; '-' without any."""
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return fmt.format(100 * float(np.median(finite))) if finite else '-'


def summarise(records: list[dict]) -> dict:
    """Counts and scores for the JSON summary and the Markdown tables."""
    by_kind: dict[str, list[dict]] = {}
    for record in records:
        by_kind.setdefault(record['kind'], []).append(record)
    kinds = {}
    for kind, group in sorted(by_kind.items()):
        gains = [r['gain'] for r in group if r.get('gain') is not None]
        kinds[kind] = {'cases': len(group), 'right': sum(r['right'] for r in group),
                       'median_gain': float(np.median(gains)) if gains else None,
                       'gain_at_least_target': sum(g >= TARGET_GAIN for g in gains), 'named': len(gains)}
    unaffected = by_kind.get(NONE, [])
    missed = [r for r in records if r.get('lack_of_fit')]
    return {'kinds': kinds, 'cases': len(records), 'right': sum(r['right'] for r in records),
            'adequate_on_unaffected': sum(r['verdict'] == 'adequate' for r in unaffected),
            'unaffected': len(unaffected),
            'lack_of_fit': len(missed),
            'adequate_with_lack_of_fit': sum(r['verdict'] == 'adequate' for r in missed),
            'wrong_effect_named': sum(bool(set(r.get('named', [])) - set(r['effects'])) for r in records),
            'seconds_total_cpu': round(sum(r.get('seconds', 0) for r in records), 1)}


def _confusion(records: list[dict]) -> tuple[dict[str, dict[str, int]], list[str]]:
    """Counts per row (concealed effect and form) and column (what diagnose said), and the columns in order."""
    rows: dict[str, dict[str, int]] = {}
    columns: list[str] = []
    for record in sorted(records, key=lambda r: (r['kind'] == NONE, r['kind'] == TWO, _row_key(r))):
        key, cell = _row_key(record), _cell(record)
        rows.setdefault(key, {})
        rows[key][cell] = rows[key].get(cell, 0) + 1
        if cell not in columns:
            columns.append(cell)
    columns.sort(key=lambda c: (c in OTHER_VERDICTS, c in ('both named', 'one named'), c))
    return rows, columns


def _outside_lines(outside: list[dict]) -> list[str]:
    """Table rows of the cases outside the catalogue or with thermal not following the revolutions."""
    lines = []
    for r in outside:
        s = r.get('setup', {})
        truth = {'step_in_time': f'step x{1 + s.get("mount_step", 0.0):.3f}',
                 'direction_factor': f'return x{s.get("return_factor", 1.0):.3f}'}.get(r['kind'], 'thermal')
        empirical = r.get('empirical') or {}
        where = ('factor by direction' if empirical.get('form') == 'direction'
                 else f'{empirical.get("form")} in {empirical.get("covariate")}')
        term = (f'{where}: {empirical["explanation"]} '
                f'({100 * empirical["gain"]:.0f} %)' if empirical.get('gain') is not None else '-')
        rho = r.get('temperature_revolutions_correlation')
        lines.append(f'| {r["kind"]} | {r["seed"]} | {truth} | {r["verdict"]} | {r.get("located", "-")} | '
                     f'{term} | {"-" if rho is None else f"{rho:+.2f}"} |')
    return lines


def _miss_lines(misses: list[dict]) -> list[str]:
    """Table rows of the cases diagnose got wrong."""
    lines = []
    for r in misses:
        s = r.get('setup', {})
        plan = f'{len(s.get("speeds_rpm", []))} x {len(s.get("loads_n", []))}'
        gain = f'{100 * r["gain"]:.0f} %' if r.get('gain') is not None else '-'
        lines.append(f'| {_row_key(r)} | {r["seed"]} | {r["verdict"]} | {", ".join(r.get("named", [])) or "-"} '
                     f'| {s.get("sample_rate", 0) / 1000:g} | {1000 * s.get("block", 0):g} | {plan} | {gain} |')
    return lines


def confusion_markdown(records: list[dict], command: str, wall_seconds: float, jobs: int,
                       sources: Sequence[str] = ()) -> str:
    """The study's Markdown: summary, confusion per form, misses listed.

    ``sources``: the commands of the studies whose cases ``records`` merges (their wall times summed).
    """
    summary = summarise(records)
    rows, columns = _confusion(records)
    lines = ['# Diagnose study, random cases', '', f'Command: `{command}`', '']
    if sources:
        lines += ['The cases of these studies, merged (wall time: the sum of theirs):', '',
                  *[f'- `{source}`' for source in sources], '']
    lines += [f'{summary["cases"]} cases in {wall_seconds / 60:.1f} min wall time with {jobs} process(es) '
              f'({summary["seconds_total_cpu"] / 60:.1f} min of case time). Plans, recording set-up, nuisances '
              'and effect strengths are drawn at random per case (see `prsm_lube_ros/experiments/study_draws.py`).',
              '', '## Score per kind', '',
              'Interval: the Wilson 95 % confidence interval of the share a kind\'s cases would have right over '
              'many more seeds.', '',
              '| concealed | right | 95 % interval | median held-out gain when named | gain >= 30 % |',
              '|---|---|---|---|---|']
    for kind, row in summary['kinds'].items():
        gain = f'{100 * row["median_gain"]:.0f} %' if row['median_gain'] is not None and kind != NONE else '-'
        at_least = f'{row["gain_at_least_target"]}/{row["named"]}' if kind != NONE else '-'
        low, high = stats.binomtest(row['right'], row['cases']).proportion_ci(method='wilson')
        lines.append(f'| {kind} | {row["right"]}/{row["cases"]} ({100 * row["right"] / row["cases"]:.0f} %) '
                     f'| {100 * low:.0f}-{100 * high:.0f} % | {gain} | {at_least} |')
    lines += ['', f'Unaffected recordings called `adequate`: {summary["adequate_on_unaffected"]}/'
              f'{summary["unaffected"]}. Cases where the lack-of-fit test finds '
              f'the paper\'s model missing (condition means against replicate runs): {summary["lack_of_fit"]}, '
              f'of them called `adequate`: {summary["adequate_with_lack_of_fit"]}. Cases naming an effect that '
              f'was not concealed: {summary["wrong_effect_named"]}.', '',
              '## Confusion per form (rows: concealed effect and its drawn form; columns: what diagnose said)', '',
              '| concealed | ' + ' | '.join(columns) + ' |', '|---|' + '---|' * len(columns)]
    for key, row in rows.items():
        lines.append(f'| {key} | ' + ' | '.join(str(row.get(c, '')) for c in columns) + ' |')
    outside = [r for r in records if r['kind'] in OUTSIDE_KINDS or r['kind'] == THERMAL_FREE]
    if outside:
        lines += ['', '## Outside the catalogue and thermal with temperature not following revolutions', '',
                  '| kind | seed | truth | verdict | located | empirical term (held-out gain) | r(temperature, '
                  'revolutions) |', '|---|---|---|---|---|---|---|']
        lines += _outside_lines(outside)
    misses = [r for r in records if not r['right']]
    lines += ['', f'## Misses ({len(misses)})', '']
    if misses:
        lines += ['| concealed | seed | verdict | named | rate kHz | block ms | speeds x loads | held-out gain |',
                  '|---|---|---|---|---|---|---|---|']
        lines += _miss_lines(misses)
    else:
        lines.append('none')
    lines += ['', '"held-out gain": 1 - cv_rmse(chosen) / cv_rmse(paper\'s model), leave-one-run-out relative RMS '
              'error per window, over the cases where an effect was named. "two" rows are right when both '
              'effects are named.', '']
    return '\n'.join(lines)


def write_random_outputs(out: Path, records: list[dict], command: str, wall_seconds: float, jobs: int,
                         sources: Sequence[str] = ()) -> str:
    """Write ``confusion.md`` and ``results.json`` (summary and every case) to ``out``; return the Markdown.

    ``sources``: as :func:`confusion_markdown` (kept in results.json).
    """
    text = confusion_markdown(records, command, wall_seconds, jobs, sources)
    out.mkdir(parents=True, exist_ok=True)
    (out / 'confusion.md').write_text(text)
    document = {'command': command, 'wall_seconds': round(wall_seconds, 1), 'jobs': jobs,
                **({'sources': list(sources)} if sources else {}), 'summary': summarise(records), 'cases': records}
    (out / 'results.json').write_text(json.dumps(document, indent=1, default=float))
    return text


def misses_markdown(records: Sequence[dict], sizes: Sequence[dict], command: str) -> str:
    """The missed cases with the size of what was concealed (:func:`explain_miss`), as Markdown."""
    from .detection_power import on_recording
    from .effect_size import EffectSize
    size_of = {(item['kind'], item['seed']): item['size'] for item in sizes}
    lines = ['# Missed cases and the size of what was concealed', '', f'Command: `{command}`', '',
             'Size: the concealed effects\' change of ln A per run beyond what the paper\'s constants absorb '
             '(RMS over runs), against the rig\'s run-to-run scatter, and about the run means (see '
             '`prsm_lube_ros/experiments/effect_size.py`). The smaller the ratio, the less the run amplitudes can show '
             'of the effect, whatever method reads them; on two-effect rows the size is both effects together. '
             'Ideal test on this recording: the statistic of a test that knows the effect\'s form and the run '
             'scatter, computed from the recorded run means, against the engine\'s threshold (see '
             '`prsm_lube_ros/experiments/detection_power.py`).', '',
             '| kind | seed | effects | verdict | between runs | run scatter | ratio | within runs | '
             'ideal test on this recording |',
             '|---|---|---|---|---|---|---|---|---|']
    for record in records:
        if record.get('right'):
            continue
        size = size_of.get((record['kind'], record['seed']))
        cells = (['-'] * 5 if size is None else
                 [f'{100 * size["between_runs"]:.1f} %', f'{100 * size["run_scatter"]:.1f} %',
                  f'{size["ratio"]:.2f}', f'{100 * size["within_runs"]:.1f} %',
                  on_recording(EffectSize.from_json(size))])
        lines.append(f'| {record["kind"]} | {record["seed"]} | {", ".join(record.get("effects", [])) or "-"} | '
                     f'{record.get("verdict")} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines) + '\n'
