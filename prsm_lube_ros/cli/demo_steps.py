# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Steps 2 to 4 of ``prsm-lube demo``, each checked against the simulator's truth.

2. Live graph (:mod:`prsm_lube_ros.nodes.live_demo`): ``prsm-lube run`` with
   the bridge playing stage 1 of step 1 (true theta_Oil ``stages[0]``) and the
   estimator started from a calibration made on stage 2 taken for fully
   lubricated (a wrong reference state, so theta_Oil reads high); the
   calibrate service is called on stage 3 (theta_Oil = 1).  Check: the
   service succeeds, the estimator's status arrives on ``/diagnostics``, and
   the median theta_Oil of the windows after the calibration lies within
   ``LIVE_TOLERANCE`` of the truth.
3. Concealed physics: one effect of
   :func:`~prsm_lube_ros.physics.effects.effect_ids`, drawn from the seed with
   its strength, hidden in two sessions of the paper's plan at theta_Oil = 1
   (runs in random order); ``prsm-lube diagnose`` locates, names and models it
   and writes its report.  Check: the verdict names the concealed effect.
4. A small fleet (:mod:`prsm_lube_ros.simulation.fleet`): ``prsm-lube
   calibrate`` on its reference recording, ``prsm-lube assess --history``,
   ``prsm-lube trend``.  Check: for the most urgent actuators (the trend's
   first rows) the true warn crossing lies inside the forecast's 95 % interval.

Each step returns a :class:`StepResult` for the summary page
(:mod:`.demo_page`); the commands run in this process with their output
kept in ``<step folder>/*.log``.
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
import io
import json
import math
from pathlib import Path
import shutil
import time
from collections.abc import Callable, Sequence

import numpy as np

__all__ = ['LIVE_TOLERANCE', 'StepResult', 'URGENT', 'concealed_effect', 'diagnosis_step', 'fleet_step', 'live_step',
           'run_command']

#: Largest distance of the live median theta_Oil after the calibration from the truth.
LIVE_TOLERANCE = 0.03
#: Actuators of the trend's table whose true crossing is checked against their interval.
URGENT = 3


@dataclass
class StepResult:
    """One step for the summary page: what it showed, its checks and the files it wrote."""

    number: int
    title: str
    shows: str
    lines: list = field(default_factory=list)          # printed lines (without the indent)
    checks: list = field(default_factory=list)         # (text, passed)
    figures: list = field(default_factory=list)        # (path, caption)
    tables: list = field(default_factory=list)         # (caption, header, rows)
    links: list = field(default_factory=list)          # (path, text)
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        """Whether every check passed; False when there was none."""
        return bool(self.checks) and all(ok for _, ok in self.checks)


def run_command(argv: list, log: Path) -> tuple[int, str]:
    """``prsm-lube <argv>`` in this process; its stdout and stderr go to ``log``; returns (status, text)."""
    from . import main
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer), contextlib.redirect_stderr(buffer):
        try:
            status = main([str(a) for a in argv])
        except SystemExit as exc:          # argparse refusing the line
            status = exc.code if isinstance(exc.code, int) else 2
    text = buffer.getvalue()
    log.parent.mkdir(parents=True, exist_ok=True)
    with open(log, 'a') as stream:
        stream.write('$ prsm-lube ' + ' '.join(str(a) for a in argv) + '\n' + text + '\n')
    return status, text


def _check(step: StepResult, say: Callable[[str], None], text: str, passed: bool) -> None:
    """Record one check of ``step`` and print its outcome."""
    step.checks.append((text, bool(passed)))
    say(f'    check: {text}: {"PASS" if passed else "FAIL"}')


# -- step 2 ----------------------------------------------------------------------------------------
def _live_inputs(out: Path, bags_dir: Path, stages: Sequence[float], *, playback_rate: float, window: float,
                 storage: str) -> tuple[Path, Path, Path, Path, Path]:
    """The live step's folder (emptied), its bags (played, wrongly calibrated on, reference), its parameter file.

    The estimator's calibration file is made on stage 2 taken for theta_Oil = 1.
    """
    from ..estimation.calibration_file import save_calibration
    from ..estimation.pipeline import calibrate_recordings, recording_windows
    from ..nodes.live_demo import write_parameters
    from ..physics.actuator import Actuator
    from ..recording.writer import bag_path
    folder = out / 'live'
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    played, wrong, reference = (bag_path(bags_dir, f'stage_{n}', storage) for n in (1, 2, len(stages)))
    wrong_calibration = calibrate_recordings([recording_windows(wrong, lead=Actuator().lead)], theta=1.0)
    save_calibration(wrong_calibration, folder / 'calibration_prsm.yaml')
    parameters = write_parameters(folder / 'parameters.yaml', bag=played, playback_rate=playback_rate,
                                  calibration_pattern=folder / 'calibration_{actuator}.yaml',
                                  recordings_dir=bags_dir, window_length=window)
    return folder, played, wrong, reference, parameters


def live_step(out: Path, bags_dir: Path, stages: Sequence[float], *, playback_rate: float, windows: int,
              say: Callable[[str], None], window: float = 1.0, storage: str = 'mcap',
              timeout: float = 120.0) -> StepResult:
    """Both nodes live on stage 1's recording; calibrate service on stage 3; theta before and after."""
    from ..figures import live_theta
    step = StepResult(2, 'Live graph: bridge, estimator, calibrate service',
                      'the sensor bridge replays stage 1 on /prsm/*, the estimator publishes theta_Oil and '
                      '/diagnostics; the estimator starts from a calibration made on stage 2 taken for '
                      'theta_Oil = 1, then /prsm/calibrate is called on stage 3 (the true reference)')
    started = time.perf_counter()
    try:
        from ..nodes.live_demo import run_live_graph
    except ImportError as exc:           # prsm-lube installed with pip, without ROS 2
        _check(step, say, f'ROS 2 and the package\'s interfaces importable ({exc}; source the workspace, e.g. '
               '.env-jazzy.sh, or run tools/demo)', False)
        return step
    folder, played, wrong, reference, parameters = _live_inputs(out, bags_dir, stages, playback_rate=playback_rate,
                                                                window=window, storage=storage)
    truth = float(stages[0])
    say(f'    bridge: playback of {played.name} (true theta_Oil {truth:.2f}) at {playback_rate:g} x real time; '
        f'estimator calibration: {wrong.name} taken for theta_Oil = 1 (wrong: true {stages[1]:.2f})')
    result = run_live_graph(folder, parameters, reference_bags=[reference.name], reference_theta=1.0,
                            windows_wanted=windows, settle=2.0 * window / playback_rate + 1.0, timeout=timeout,
                            say=say)
    before = np.array([w[1] for w in result.windows_before])
    after = np.array([w[1] for w in result.windows_after])
    median_before = float(np.median(before)) if before.size else math.nan
    median_after = float(np.median(after)) if after.size else math.nan
    response = result.response
    if response is not None and response.success:
        say(f'    answer: success, C_sys {response.c_sys:.4g} +/- {response.c_sys_std:.2g}, '
            f'C_F {response.c_f:.4g} 1/N, C_lambda {response.c_lambda:.4g}, fit RMS error '
            f'{100 * response.fit_rmse:.2f} % on {response.windows_used} windows; written to '
            f'{response.calibration_file}')
    say(f'    theta_Oil before: median {median_before:.3f} of {before.size} windows; after: median '
        f'{median_after:.3f} of {after.size} windows (true {truth:.2f})')
    levels = {0: 'OK', 1: 'WARN', 2: 'ERROR', 3: 'STALE'}
    if result.statuses:
        _, level, message = result.statuses[-1]
        say(f'    /diagnostics: {len(result.statuses)} estimator statuses, last {levels.get(level, level)} '
            f'"{message}"; {result.bridge_statuses} bridge statuses')
    if result.problem:
        say(f'    problem: {result.problem}')
    _check(step, say, 'the calibrate service answered success', response is not None and response.success)
    _check(step, say, 'the estimator\'s status arrived on /diagnostics', bool(result.statuses))
    _check(step, say, f'theta_Oil after the calibration {median_after:.3f} within +/-{LIVE_TOLERANCE:.2f} of '
           f'the truth {truth:.2f}', after.size >= windows and abs(median_after - truth) <= LIVE_TOLERANCE)
    figure = live_theta(folder / 'live_theta.png', result.windows_before + result.windows_after,
                        result.calibrated_at, truth,
                        f'theta_Oil on /prsm/lubrication_state, live ({played.name} at {playback_rate:g} x)')
    step.figures.append((figure, 'theta_Oil per window as the observer received it; the vertical line is the '
                                 'calibrate service\'s answer, dashed the truth'))
    rows = [['before (calibrated on stage 2 as if theta_Oil = 1)', f'{median_before:.3f}', str(before.size)],
            ['after /prsm/calibrate on stage 3', f'{median_after:.3f}', str(after.size)]]
    step.tables.append((f'theta_Oil live, true {truth:.2f}', ['calibration', 'median theta_Oil', 'windows'], rows))
    step.links += [(parameters, 'parameter file of both nodes'), (folder / 'nodes.log', 'log of prsm-lube run')]
    step.seconds = time.perf_counter() - started
    return step


# -- step 3 ----------------------------------------------------------------------------------------
def concealed_effect(seed: int) -> str:
    """The effect hidden in step 3: one of the diagnosis's effect IDs, drawn from ``seed``.

    ``surface_defect`` has its own step (5, :mod:`.demo_defect`), so step 3 draws among the others.
    """
    from ..physics.effects import effect_ids
    ids = sorted(set(effect_ids()) - {'surface_defect'})
    return ids[int(np.random.default_rng([seed, 3]).integers(len(ids)))]


def diagnosis_step(out: Path, seed: int, say: Callable[[str], None]) -> StepResult:
    """Hide an effect drawn from ``seed`` in a simulated recording; ``prsm-lube diagnose`` must name it."""
    from ..simulation.recordings import draw_effects, simulate_experiment
    from ..simulation.rig_config import ExperimentPlan
    step = StepResult(3, 'Concealed physics located, named and modelled',
                      'a recording (two sessions of the paper\'s plan at theta_Oil = 1, runs in random order) '
                      'with one physical effect the paper\'s model leaves out, drawn from the seed; '
                      'prsm-lube diagnose must find which')
    started = time.perf_counter()
    folder = out / 'diagnose'
    if folder.exists():
        shutil.rmtree(folder)
    effect = concealed_effect(seed)
    plan = ExperimentPlan(stage_thetas=(1.0, 1.0))
    effects = draw_effects([effect], seed=seed, plan=plan)
    say(f'    simulating with a concealed effect (seed {seed}; its name is in {folder / "bags" / "truth.json"})')
    bags = simulate_experiment(folder / 'bags', plan=plan, seed=seed, effects=effects, run_order='random')
    report = folder / 'report'
    status, text = run_command(['diagnose', *bags, '--theta', '1', '--json', folder / 'diagnosis.json',
                                '--report', report], folder / 'diagnose.log')
    say(f'    $ prsm-lube diagnose {" ".join(b.name for b in bags)} --theta 1 --json diagnosis.json '
        '--report report')
    for line in text.rstrip().splitlines():
        say(f'    | {line}')
    verdict, gain = None, math.nan
    if status == 0:
        document = json.loads((folder / 'diagnosis.json').read_text())
        verdict = document.get('verdict')
        chosen = next((c for c in document.get('candidates', []) if c.get('effect') == verdict), None)
        gain = (chosen or {}).get('gain', math.nan)
        gain = math.nan if gain is None else float(gain)
    say(f'    concealed: {effect}; named: {verdict}; held-out gain {100 * gain:.1f} % (fall of the held-out '
        'relative RMS error per window against the paper\'s model)')
    _check(step, say, f'diagnose named the concealed effect ({effect})', status == 0 and verdict == effect)
    step.lines = [f'concealed effect: {effect}; verdict: {verdict}; held-out gain {100 * gain:.1f} %']
    for png in sorted(report.glob('*.png')):
        step.figures.append((png, png.stem.replace('_', ' ')))
    if (report / 'index.html').exists():
        step.links.append((report / 'index.html', 'the diagnosis report'))
    step.links += [(folder / 'diagnosis.json', 'diagnosis JSON'), (folder / 'bags' / 'truth.json', 'the truth')]
    step.tables.append(('prsm-lube diagnose', ['output'], [[line] for line in text.rstrip().splitlines()]))
    step.seconds = time.perf_counter() - started
    return step


# -- step 4 ----------------------------------------------------------------------------------------
def _fleet_commands(folder: Path, recordings: Path, seed: int, actuators: int,
                    days: int) -> list[tuple[list | None, str]]:
    """The fleet step's command lines (None: assess, its recordings known once simulated), each as shown."""
    commands = [
        ['simulate', recordings, '--fleet', actuators, '--days', days, '--seed', seed],
        ['calibrate', recordings / 'reference', '--theta', '1', '--out', folder / 'calibration.yaml'],
        None,                                       # assess: the recordings simulate wrote
        ['trend', folder / 'history', '--report', folder / 'trend'],
    ]
    shown = [f'simulate recordings --fleet {actuators} --days {days} --seed {seed}',
             'calibrate recordings/reference --theta 1 --out calibration.yaml',
             'assess recordings/A*/* --calibration calibration.yaml --history history --actuator-id folder',
             'trend history --report trend']
    return list(zip(commands, shown))


def _newest_recording_day(truth: Path) -> str:
    """The UTC day (YYYY-MM-DD) of the newest recording the fleet simulator wrote (its ``truth.json``)."""
    document = json.loads(truth.read_text())
    return max(r['start_utc'] for a in document['actuators'] for r in a['recordings'])[:10]


def _run_fleet_commands(step: StepResult, say: Callable[[str], None], folder: Path, recordings: Path,
                        commands: list[tuple[list | None, str]], log: Path) -> str | None:
    """Run the commands in order, output to ``log``: the last one's output, or None (a failed check) if one fails."""
    text = ''
    for argv, line in commands:
        if argv is None:
            paths = sorted(p for p in recordings.glob('A*/*') if p.name != 'metadata.yaml')
            argv = ['assess', *paths, '--calibration', folder / 'calibration.yaml', '--history',
                    folder / 'history', '--actuator-id', 'folder']
            line = line.replace('recordings/A*/*', f'recordings/A*/* ({len(paths)} recordings)')
        if argv[0] == 'trend':
            # As of the day of the newest recording, not the wall clock: the fleet is simulated in the past.
            day = _newest_recording_day(recordings / 'truth.json')
            argv = [*argv, '--as-of', day]
            line += f' --as-of {day}'
        say(f'    $ prsm-lube {line}')
        status, text = run_command(argv, log)
        if status != 0:
            say(f'    | {text.strip().splitlines()[-1] if text.strip() else ""}')
            _check(step, say, f'prsm-lube {argv[0]} succeeded (see {log})', False)
            return None
    return text


def fleet_step(out: Path, seed: int, say: Callable[[str], None], *, actuators: int, days: int) -> StepResult:
    """A small simulated fleet: history, trend, the most urgent actuators against their true crossing."""
    from ..experiments.fleet_study import compare_with_truth
    step = StepResult(4, 'Fleet: history, trend, forecast',
                      f'{actuators} simulated actuators, one short recording a day for {days} days, oil depleting '
                      'with use and relubricated when low; assessed into a history and forecast')
    started = time.perf_counter()
    folder = out / 'fleet'
    if folder.exists():
        shutil.rmtree(folder)
    recordings = folder / 'recordings'
    log = folder / 'commands.log'
    text = _run_fleet_commands(step, say, folder, recordings,
                               _fleet_commands(folder, recordings, seed, actuators, days), log)
    if text is None:
        step.seconds = time.perf_counter() - started
        return step
    trend = json.loads((folder / 'trend' / 'trend.json').read_text())
    table = [line for line in text.splitlines() if line.startswith('|')]
    for line in table[:2 + URGENT]:
        say(f'    {line}')
    if len(table) > 2 + URGENT:
        say(f'    ({len(table) - 2 - URGENT} more in {folder / "trend" / "trend.md"})')
    compared = compare_with_truth(folder / 'history', recordings / 'truth.json', level=trend['levels']['warn'])
    rows = {row['actuator']: row for row in compared}
    urgent = [a['actuator'] for a in trend['actuators'] if not a.get('reason')][:URGENT]
    truth_rows = []
    for name in urgent:
        row = rows.get(name, {})
        truth_rows.append([name, _utc(row.get('true')), _utc(row.get('forecast')),
                           f'{_utc(row.get("low"))} .. {_utc(row.get("high"))}', 'yes' if row.get('inside') else 'NO'])
        when = 'after the last recording: a forecast' if row.get('ahead') else 'before the last recording'
        say(f'    {name}: true warn crossing {truth_rows[-1][1]} ({when}), forecast {truth_rows[-1][2]} '
            f'(95 % interval {truth_rows[-1][3]}): {"inside" if row.get("inside") else "OUTSIDE"}')
    inside_all = sum(bool(r['inside']) for r in rows.values())
    say(f'    whole fleet: true warn crossing inside the interval for {inside_all}/{len(rows)} actuators')
    _check(step, say, f'the {len(urgent)} most urgent actuators\' true warn crossings lie inside their '
           f'forecast intervals', len(urgent) == min(URGENT, len(rows)) and all(r[-1] == 'yes' for r in truth_rows))
    step.tables.append(('prsm-lube trend, most urgent first', table[0].strip('|').split('|') if table else [],
                        [line.strip('|').split('|') for line in table[2:]]))
    step.tables.append((f'The {len(urgent)} most urgent against the simulator\'s truth (warn level '
                        f'{trend["levels"]["warn"]:g})', ['actuator', 'true crossing', 'forecast', '95 % interval',
                                                          'inside'], truth_rows))
    for name in urgent:
        png = folder / 'trend' / f'{name}.png'
        if png.exists():
            step.figures.append((png, f'{name}: theta_Oil history and forecast'))
    step.links += [(folder / 'trend' / 'trend.md', 'trend table'), (recordings / 'truth.json', 'the truth'),
                   (log, 'the commands\' output')]
    step.seconds = time.perf_counter() - started
    return step


def _utc(seconds: float | None) -> str:
    """'2026-01-09 14:05' (UTC, for reading) or 'never'."""
    from ..validation import utc_or_none
    stamp = utc_or_none(seconds)
    return 'never' if stamp is None else stamp.strftime('%Y-%m-%d %H:%M')
