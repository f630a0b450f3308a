# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Study: is each actuator's forecast warn crossing inside its stated interval, against the simulator's truth.

A fleet is simulated (:mod:`prsm_lube_ros.simulation.fleet`: ``--actuators``
actuators, one short recording a day for ``--days`` days, depletion and
relubrications at known times), calibrated on its reference recording,
assessed into a Parquet history (serially, ``--jobs`` processes or
``--scheduler``) and forecast per actuator with relubrications detected from
the recordings.  Each actuator's true warn crossing (its last lubrication
cycle, usage continued past the last day) is compared with the forecast
interval.  ``--backtest DAYS`` (default 3) also forecasts each fleet from
its history cut DAYS before the newest recording and scores the forecast
band and crossing intervals on the later recordings
(:mod:`prsm_lube_ros.fleet.backtest`, as ``prsm-lube trend --backtest``
does).  Writes ``results.json`` and ``coverage.md`` to ``--results``
(default ``--out``); one fleet per seed of ``--seeds``.

    python -m prsm_lube_ros.experiments.fleet_study --out out/fleet_study [--actuators 20] [--days 10]
        [--seeds 0 1 2] [--results DIR] [--jobs N | --scheduler ADDRESS]

``--horizons`` runs the horizon study instead (:func:`horizon_study`): each
fleet's conditions drawn from its seed over wide ranges
(:func:`draw_conditions`: depletion rates, usage scatter, relubrication
habits down past the error level, put-off relubrications, missed recordings,
measurement noise), a rolling backtest (cuts every ``--step`` days up to 30
days before the newest recording) scored at the warn and error levels per
horizon class (3, 7, 14, 30 days) against the measured values and against
the simulator's true theta_Oil, and the count of estimates outside their own
interval.  ``--synthetic`` takes each recording's true theta_Oil plus the
drawn noise instead of simulating and assessing the signals (minutes instead
of hours for a long fleet).
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
import sys
import time
from typing import TYPE_CHECKING
from collections.abc import Iterable, Sequence

if TYPE_CHECKING:
    from ..fleet.forecast import ActuatorForecast, RecordingPoint
    from ..simulation.fleet import FleetPlan
    from ..fleet.backtest import HorizonCoverage

__all__ = ['CONDITION_RANGES', 'backtest_history', 'backtest_summary', 'compare_with_truth', 'coverage_rows',
           'coverage_table', 'draw_conditions', 'horizon_study', 'horizon_table', 'main', 'simulate_and_assess',
           'synthetic_points', 'true_points']

#: the ranges :func:`draw_conditions` draws a fleet's conditions from (uniformly)
CONDITION_RANGES = {
    'days_to_reference_low': (3.0, 15.0),        # d a full lubrication lasts down to 0.85, fastest actuator
    'days_to_reference_spread': (1.5, 4.0),      # slowest over fastest
    'usage_scatter': (0.05, 0.45),               # sigma of the log-normal day-to-day usage factor
    'relubricate_below_low': (0.55, 0.72),       # the laxest operator's level (below 0.70: error reached)
    'relubricate_below_high': (0.72, 0.84),      # the most careful one's
    'relubrication_put_off': (0.0, 0.6),         # chance a due relubrication waits for a later recording
    'recording_missed': (0.0, 0.5),              # chance a day has no recording
    'noise': (0.002, 0.02),                      # one-sigma of a recording's theta_Oil (synthetic points)
}


def simulate_and_assess(out: Path, *, actuators: int, days: int, seed: int = 0, jobs: int = 1,
                        scheduler: str | None = None, storage: str = 'mcap', fleet: FleetPlan | None = None) -> dict:
    """Simulate the fleet into ``out/fleet``, calibrate, assess into ``out/history``; return timings and counts.

    ``fleet`` replaces the default plan of ``actuators`` x ``days``.
    """
    from ..estimation.calibration_file import save_calibration
    from ..estimation.pipeline import calibrate_recordings, recording_windows
    from ..fleet.history import history_writer
    from ..fleet.parallel import assess_bags, BagJob
    from ..physics.actuator import load_actuator
    from ..recording.writer import bag_path
    from ..simulation.fleet import FleetPlan, simulate_fleet
    fleet_dir, history = out / 'fleet', out / 'history'
    started = time.perf_counter()
    paths = simulate_fleet(fleet_dir, fleet=fleet or FleetPlan(actuators=actuators, days=days), seed=seed,
                           storage=storage)
    simulated = time.perf_counter()
    lead = load_actuator(None).lead
    calibration = calibrate_recordings([recording_windows(bag_path(fleet_dir, 'reference', storage), lead=lead)])
    calibration_path = save_calibration(calibration, out / 'calibration.yaml')
    outcomes = assess_bags(paths, BagJob(calibration, lead, hash_content=True), jobs=jobs, scheduler=scheduler,
                           on_done=history_writer(history, calibration_path, calibration, actuator_id='folder'))
    failed = [o.error for o in outcomes if o.error]
    return {'recordings': len(paths), 'failed': failed, 'simulate_s': simulated - started,
            'assess_s': time.perf_counter() - simulated}


def compare_with_truth(history: Path, truth_path: Path, level: float | None = None) -> list[dict]:
    """Per actuator: the forecast crossing of ``level`` (default the truth's first threshold) against the truth.

    With ``odometer.csv`` beside the truth, each row also has the fitted N_d
    (``depletion_revolutions``, its one-sigma) and the true one.
    """
    from ..fleet.service_log import read_odometer
    from ..fleet.forecast import forecast_history
    truth = json.loads(Path(truth_path).read_text())
    level = truth['thresholds'][0] if level is None else level
    odometer = Path(truth_path).parent / 'odometer.csv'
    forecasts = forecast_history(history, levels=(level,),
                                 odometers=read_odometer(odometer) if odometer.exists() else None)
    rows = coverage_rows(forecasts, truth, level)
    by_name = {f.actuator: f for f in forecasts}
    for row, actuator in zip(rows, truth['actuators']):
        forecast = by_name.get(row['actuator'])
        row['depletion_revolutions'] = forecast.depletion_revolutions if forecast else None
        row['depletion_revolutions_std'] = forecast.depletion_revolutions_std if forecast else None
        row['true_depletion_revolutions'] = actuator['depletion_revolutions']
    return rows


def _days(value: float | None, origin: float) -> str:
    """Days of ``value`` (s since the epoch) since ``origin``, or 'never'."""
    return f'{(value - origin) / 86400.0:7.2f}' if value is not None else '  never'


def coverage_table(rows: list[dict], origin: float) -> str:
    """Markdown: one line per actuator (days since the fleet's epoch) and the coverage."""
    lines = ['| actuator | true crossing d | forecast d | interval d | inside | ahead of data | relubrications '
             'true/found |', '|---|---|---|---|---|---|---|']
    for row in rows:
        lines.append(f'| {row["actuator"]} | {_days(row["true"], origin)} | {_days(row["forecast"], origin)} | '
                     f'{_days(row["low"], origin)} .. {_days(row["high"], origin)} | '
                     f'{"yes" if row["inside"] else "NO"} | {"yes" if row["ahead"] else "no"} | '
                     f'{row["true_relubrications"]}/{row["found_relubrications"]} |')
    return '\n'.join(lines)


def _study_fleet(folder: Path, seed: int, args: argparse.Namespace) -> tuple[dict, list[dict], dict, str]:
    """One fleet of the study in ``folder``: its run (timings, counts), rows, backtest and Markdown section."""
    run = simulate_and_assess(folder, actuators=args.actuators, days=args.days, seed=seed, jobs=args.jobs,
                              scheduler=args.scheduler)
    truth = json.loads((folder / 'fleet' / 'truth.json').read_text())
    rows = compare_with_truth(folder / 'history', folder / 'fleet' / 'truth.json')
    for row in rows:
        row['seed'] = seed
    backtest = dict(backtest_history(folder / 'history', args.backtest), seed=seed)
    inside, ahead = sum(row['inside'] for row in rows), [row for row in rows if row['ahead']]
    section = (f'## Fleet seed {seed}: {inside}/{len(rows)} inside; ahead of the data '
               f'{sum(row["inside"] for row in ahead)}/{len(ahead)}\n\n'
               f'{run["recordings"]} recordings, {len(run["failed"])} failed; days since '
               f'{truth["actuators"][0]["recordings"][0]["start_utc"][:10]} 00:00 UTC.\n\n'
               + coverage_table(rows, truth['epoch']))
    return dict(run, seed=seed), rows, backtest, section


def draw_conditions(seed: int, actuators: int, days: int) -> tuple[FleetPlan, float]:
    """A fleet plan and a measurement noise drawn from ``seed`` over :data:`CONDITION_RANGES`."""
    import numpy as np
    from ..simulation.fleet import FleetPlan
    rng = np.random.default_rng(np.random.SeedSequence([seed, 37]))

    def draw(name: str) -> float:
        return float(rng.uniform(*CONDITION_RANGES[name]))
    fastest = draw('days_to_reference_low')
    slowest = fastest * draw('days_to_reference_spread')
    plan = FleetPlan(actuators=actuators, days=days, days_to_reference=(fastest / days, slowest / days),
                     usage_scatter=draw('usage_scatter'),
                     relubricate_below_range=(draw('relubricate_below_low'), draw('relubricate_below_high')),
                     relubrication_put_off=draw('relubrication_put_off'), recording_missed=draw('recording_missed'))
    return plan, draw('noise')


def true_points(truth: dict) -> dict[str, list[RecordingPoint]]:
    """Each actuator's recordings at their true theta_Oil (zero one-sigma): the process itself, for scoring."""
    from ..fleet.forecast import RecordingPoint
    return {actuator['actuator_id']: [RecordingPoint(r['start'], r['theta_oil'], 0.0, r['path'])
                                      for r in actuator['recordings']] for actuator in truth['actuators']}


def _fleet_points(folder: Path, seed: int, args: argparse.Namespace) -> tuple[dict, dict, dict]:
    """One fleet of the horizon study: its conditions, measured points and truth."""
    from dataclasses import asdict
    from ..fleet.forecast import history_points
    from ..simulation.fleet import simulate_fleet
    plan, noise = draw_conditions(seed, args.actuators, args.days)
    conditions = {**asdict(plan), 'noise': noise if args.synthetic else 'assessed'}
    if args.synthetic:
        simulate_fleet(folder, fleet=plan, seed=seed, write_recordings=False)
        truth = json.loads((folder / 'truth.json').read_text())
        return conditions, synthetic_points(truth, noise=noise, seed=seed), truth
    run = simulate_and_assess(folder, actuators=args.actuators, days=args.days, seed=seed, jobs=args.jobs,
                              scheduler=args.scheduler, fleet=plan)
    conditions.update(recordings=run['recordings'], failed=len(run['failed']))
    return conditions, history_points(folder / 'history'), json.loads((folder / 'fleet' / 'truth.json').read_text())


def horizon_study(args: argparse.Namespace, command: str) -> tuple[dict, str]:
    """Rolling backtests of every fleet, scored per level and horizon against measurements and truth."""
    from ..fleet.backtest import horizon_coverage, rolling_backtest
    levels = (0.85, 0.70)
    measured, against_truth, fleets = [], [], []
    for seed in args.seeds:
        conditions, points, truth = _fleet_points(Path(args.out) / f'seed_{seed}', seed, args)
        started = time.perf_counter()
        cuts = rolling_backtest(points, horizons=args.horizons, step_days=args.step, levels=levels)
        truth_cuts = rolling_backtest(points, horizons=args.horizons, step_days=args.step, levels=levels,
                                      truth=true_points(truth))
        measured += cuts
        against_truth += truth_cuts
        tables = {name: [c.as_json() for c in horizon_coverage(found, args.horizons, levels)]
                  for name, found in (('measured', cuts), ('truth', truth_cuts))}
        fleets.append({'seed': seed, 'conditions': conditions, 'cuts': len(cuts), 'coverage': tables,
                       'backtest_s': time.perf_counter() - started})
        print(f'seed {seed}: ' + ', '.join(f'{c["level"]:g}/{c["horizon_days"]:g} d {c["inside"]}/{c["scored"]}'
                                           for c in tables['truth']), file=sys.stderr, flush=True)
    overall = {name: horizon_coverage(found, args.horizons, levels)
               for name, found in (('measured', measured), ('truth', against_truth))}
    outside = sum(c.estimates_outside for c in overall['measured'])
    scored = [c for table in overall.values() for c in table if c.scored]
    worst = min(scored, key=lambda c: c.coverage) if scored else None
    passed = bool(scored) and all(c.coverage >= 0.95 for c in scored) and outside == 0
    summary = (f'{len(args.seeds)} fleets of {args.actuators} actuators x {args.days} days, conditions drawn over wide '
               f'ranges, {"synthetic points" if args.synthetic else "simulated and assessed recordings"}; rolling '
               f'backtest every {args.step:g} d: lowest coverage of the 95 % crossing intervals over both levels and '
               f'the horizons {", ".join(f"{h:g}" for h in args.horizons)} d is '
               + (f'{worst.coverage:.1%} ({worst.level:g} within {worst.horizon_days:g} d, '
                  f'{worst.inside}/{worst.scored})' if worst else 'none scored')
               + f'; {outside} estimates outside their interval; {"PASS" if passed else "FAIL"} (>= 95 % everywhere).')
    document = {'command': command, 'summary': summary, 'pass': passed, 'horizons': list(args.horizons),
                'levels': list(levels), 'estimates_outside': outside,
                'coverage': {name: [c.as_json() for c in table] for name, table in overall.items()},
                'condition_ranges': CONDITION_RANGES, 'fleets': fleets}
    text = (f'# Fleet forecast: coverage per horizon\n\n`{command}`\n\n{summary}\n\n'
            '## Against the measured values (what `trend --backtest` can score)\n\n'
            + horizon_table(overall['measured']) + '\n\n## Against the simulator\'s true theta_Oil\n\n'
            + horizon_table(overall['truth']) + '\n\n## Conditions per fleet\n\n' + _conditions_table(fleets) + '\n')
    return document, text


def horizon_table(table: Sequence[HorizonCoverage]) -> str:
    """Markdown: coverage per level (rows) and horizon class (columns)."""
    horizons = sorted({c.horizon_days for c in table})
    previous = [0.0] + horizons[:-1]
    lines = ['| level | ' + ' | '.join(f'{a:g}-{b:g} d' for a, b in zip(previous, horizons)) + ' |',
             '|---' * (len(horizons) + 1) + '|']
    for level in sorted({c.level for c in table}, reverse=True):
        cells = [f'{c.inside}/{c.scored} ({c.coverage:.1%})' if c.scored else '–'
                 for c in sorted((c for c in table if c.level == level), key=lambda c: c.horizon_days)]
        lines.append(f'| {level:g} | ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def _conditions_table(fleets: Sequence[dict]) -> str:
    """Markdown: the drawn conditions of each fleet."""
    lines = ['| seed | days to 0.85 | usage scatter | relubricate below | put off | missed | noise |',
             '|---|---|---|---|---|---|---|']
    for fleet in fleets:
        c = fleet['conditions']
        low, high = (v * c['days'] for v in c['days_to_reference'])
        noise = c['noise'] if isinstance(c['noise'], str) else f'{c["noise"]:.4f}'
        lines.append(f'| {fleet["seed"]} | {low:.1f}-{high:.1f} | {c["usage_scatter"]:.2f} | '
                     f'{c["relubricate_below_range"][0]:.2f}-{c["relubricate_below_range"][1]:.2f} | '
                     f'{c["relubrication_put_off"]:.2f} | {c["recording_missed"]:.2f} | {noise} |')
    return '\n'.join(lines)


def _parser() -> argparse.ArgumentParser:
    """The study's options."""
    parser = argparse.ArgumentParser(prog='python -m prsm_lube_ros.experiments.fleet_study',
                                     description=__doc__.split('\n')[0])
    parser.add_argument('--out', default='out/fleet_study', help='folder for the fleets and histories')
    parser.add_argument('--results', default=None, help='folder for coverage.md and results.json (default --out)')
    parser.add_argument('--actuators', type=int, default=20)
    parser.add_argument('--days', type=int, default=10)
    parser.add_argument('--seeds', type=int, nargs='+', default=[0], help='one fleet per seed (default 0)')
    parser.add_argument('--jobs', type=int, default=1)
    parser.add_argument('--scheduler', default=None)
    parser.add_argument('--backtest', type=float, default=3.0, metavar='DAYS')
    parser.add_argument('--horizons', type=float, nargs='+', default=None, metavar='DAYS',
                        help='horizon study: conditions drawn per seed, rolling backtest scored per horizon class '
                        '(e.g. 3 7 14 30)')
    parser.add_argument('--step', type=float, default=3.0, metavar='DAYS', help='horizon study: days between cuts')
    parser.add_argument('--synthetic', action='store_true',
                        help='horizon study: true theta_Oil plus drawn noise instead of simulated recordings')
    return parser


def main(argv: list[str] | None = None) -> int:
    """Command line of the study."""
    args = _parser().parse_args(argv)
    out = Path(args.out)
    results = Path(args.results) if args.results else out
    arguments = sys.argv[1:] if argv is None else argv
    command = 'python -m prsm_lube_ros.experiments.fleet_study ' + ' '.join(arguments)
    if args.horizons:
        document, text = horizon_study(args, command)
        results.mkdir(parents=True, exist_ok=True)
        (results / 'coverage.md').write_text(text)
        (results / 'results.json').write_text(json.dumps(document, indent=1))
        print(document['summary'])
        return 0 if document['pass'] else 1
    sections: list[str] = []
    runs: list[dict] = []
    all_rows: list[dict] = []
    backtests: list[dict] = []
    for seed in args.seeds:
        run, rows, backtest, section = _study_fleet(out / f'seed_{seed}', seed, args)
        backtests.append(backtest)
        runs.append(run)
        all_rows += rows
        sections.append(section)
        print(sections[-1].split('\n')[0], file=sys.stderr, flush=True)
    inside = sum(row['inside'] for row in all_rows)
    ahead = [row for row in all_rows if row['ahead']]
    summary = (f'{len(args.seeds)} fleet(s) of {args.actuators} actuators x {args.days} days '
               f'({sum(r["recordings"] for r in runs)} recordings, {sum(len(r["failed"]) for r in runs)} failed): '
               f'the true warn crossing (0.85) lies inside the forecast 95 % interval for {inside}/{len(all_rows)} '
               f'actuators ({100.0 * inside / len(all_rows):.1f} %); for the {len(ahead)} whose crossing comes '
               f'after their last recording (a true forecast): {sum(row["inside"] for row in ahead)}/{len(ahead)}.')
    fitted = [row for row in all_rows if row['depletion_revolutions'] is not None
              and math.isfinite(row['depletion_revolutions'])]
    if fitted:
        errors = [abs(row['depletion_revolutions'] / row['true_depletion_revolutions'] - 1.0) for row in fitted]
        within = sum(abs(row['depletion_revolutions'] - row['true_depletion_revolutions'])
                     <= 2.0 * row['depletion_revolutions_std'] for row in fitted)
        median = 100.0 * sorted(errors)[len(errors) // 2]
        summary += (f' Against the odometer, N_d of the depletion law came out within {median:.1f} % of the truth '
                    f'(median), within two stated one-sigmas for {within}/{len(fitted)} actuators.')
    summary += ' ' + backtest_summary(backtests, args.backtest)
    text = (f'# Fleet forecast against the simulator\'s truth\n\n`{command}`\n\n{summary}\n\n'
            + '\n\n'.join(sections) + '\n')
    results.mkdir(parents=True, exist_ok=True)
    (results / 'coverage.md').write_text(text)
    (results / 'results.json').write_text(json.dumps({'command': command, 'summary': summary, 'runs': runs,
                                                      'rows': all_rows, 'inside': inside,
                                                      'backtests': backtests,
                                                      'actuators': len(all_rows)}, indent=1))
    print(summary)
    return 0


def backtest_history(history: Path, days: float, confidence: float = 0.95) -> dict:
    """:func:`~prsm_lube_ros.fleet.backtest.backtest` of a history at the estimator's warn and error levels."""
    from ..fleet.backtest import backtest
    from ..fleet.forecast import history_points
    return backtest(history_points(history), days, levels=(0.85, 0.70), confidence=confidence).as_json()


def backtest_summary(backtests: list[dict], days: float) -> str:
    """One sentence: band and crossing coverage over all fleets' backtests."""
    recordings = sum(b['recordings_scored'] for b in backtests)
    inside = sum(a['inside_band'] for b in backtests for a in b['actuators'])
    crossings = [c for b in backtests for a in b['actuators'] for c in a['crossings']]
    hits = sum(c['inside'] for c in crossings)
    return (f'Backtest (forecast from the history cut {days:g} d before its newest recording, scored on the '
            f'later ones): {inside}/{recordings} later recordings inside the 95 % band '
            f'({100.0 * inside / max(recordings, 1):.1f} %), {hits}/{len(crossings)} crossings seen after the cut '
            f'inside their 95 % interval.')


def synthetic_points(truth: dict, *, noise: float = 0.0045, seed: int = 0) -> dict:
    """Recording points from the truth alone: each recording's true theta_Oil plus normal noise ``noise``.

    What assessment gives for the fleet's recordings (one-sigma about 0.0045
    with the default rig), without simulating and reading the signals.
    """
    import numpy as np
    from ..fleet.forecast import RecordingPoint
    rng = np.random.default_rng(seed)
    return {actuator['actuator_id']: [RecordingPoint(r['start'], r['theta_oil'] + noise * rng.standard_normal(),
                                                     noise, r['path']) for r in actuator['recordings']]
            for actuator in truth['actuators']}


def coverage_rows(forecasts: Iterable[ActuatorForecast], truth: dict, level: float) -> list[dict]:
    """Per actuator of the truth: the forecast crossing of ``level`` against the true one."""
    by_name = {f.actuator: f for f in forecasts}
    rows = []
    for actuator in truth['actuators']:
        forecast = by_name.get(actuator['actuator_id'])
        true_time = actuator['crossings'][f'{level:g}']['time']
        crossing = forecast.crossing(level) if forecast is not None and not forecast.reason else None
        low = crossing.low if crossing else None
        high = crossing.high if crossing else None
        inside = (crossing is not None and true_time is not None and low is not None
                  and low <= true_time <= (high if high is not None else math.inf))
        last = forecast.last_recording if forecast is not None else math.nan
        rows.append({'actuator': actuator['actuator_id'], 'true': true_time,
                     'forecast': crossing.time if crossing else None, 'low': low, 'high': high,
                     'inside': bool(inside), 'ahead': true_time is not None and true_time > last,
                     'true_relubrications': len(actuator['relubrications']),
                     'found_relubrications': len(forecast.relubrications) if forecast else 0,
                     'reason': forecast.reason if forecast else 'not in the history'})
    return rows


if __name__ == '__main__':
    sys.exit(main())
