# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube assess``: theta_Oil for every steady window and run of recordings."""
from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from .common import add_recording_options, EXIT_USER_ERROR

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable, Sequence

    from ..diagnosis.condition_report import ConditionReport
    from ..estimation.calibration import Calibration
    from ..estimation.pipeline import RecordingAssessment
    from ..estimation.windowing import WindowSettings
    from ..fleet.parallel import BagOutcome
    from ..physics.actuator import Actuator


__all__ = ['add_command', 'run']


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``assess`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'assess', help='theta_oil for every steady window and run',
        description='Assess theta_oil for every steady window and every run of the recordings.')
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    parser.add_argument('--calibration', required=True, metavar='CALIB.yaml')
    parser.add_argument('--json', metavar='OUT.json', help='write runs and windows as JSON (compact, one line)')
    parser.add_argument('--indent', type=int, default=None, metavar='N',
                        help='indent the --json output by N spaces a level, for people (default: compact)')
    add_recording_options(parser)
    parser.add_argument('--report', metavar='DIR',
                        help='write DIR/index.html with the condition figures of every recording: order and envelope '
                        'spectra with the defect orders, waterfalls, indicator trends and theta_oil per run')
    parser.add_argument('--history', metavar='DIR',
                        help='add runs and windows to this Parquet history (re-assessed recordings replace theirs)')
    parser.add_argument('--actuator-id', default=None, metavar='ID',
                        help='actuator the recordings belong to in the history: an id; "folder" for the name of '
                        'the real folder holding each recording (symlinks resolved; two folders of one name are '
                        'refused); "recording" for the id each bag carries (custom_data actuator_id in its '
                        'metadata.yaml). Default: the id the bag carries, else its folder\'s, refused when the '
                        'recordings lie in more than one folder')
    parser.add_argument('--actuator-map', default=None, metavar='FILE',
                        help='actuator of each recording from FILE: lines "PATH,ID" (a recording or a folder '
                        'holding recordings, relative to FILE); a recording it does not cover is refused')
    parser.add_argument('--jobs', type=int, default=1, metavar='N',
                        help='assess N recordings at a time in local processes (default 1)')
    parser.add_argument('--scheduler', default=None, metavar='ADDRESS',
                        help='assess on a Dask distributed cluster at ADDRESS, or "local" for a local cluster '
                        'of --jobs workers; a tcp:// address that sends no Dask handshake, or a scheduler without a '
                        'worker, within --scheduler-timeout is refused')
    parser.add_argument('--scheduler-timeout', type=float, default=None, metavar='S',
                        help='s to wait on --scheduler: to connect, for a first worker, and without any worker while '
                        'recordings are left (default 10)')
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """theta_Oil for every steady window and run; table on stdout, JSON and history if asked.

    A recording that cannot be assessed is one line on stderr; the others are
    assessed, and the status is non-zero at the end.  Windows are made in the
    calibration's band (:mod:`..estimation.conditioning`); a recording whose
    sample rate cannot cover it is such a line.  The table is printed only when
    some recording was assessed; ``!`` marks a theta_oil outside its physical
    range, ``~`` a run outside the calibration's domain (extrapolated), ``D`` a
    run whose vibration shows a surface defect (:mod:`..estimation.defect_screen`):
    its theta_oil is then no lubrication measure.
    """
    from ..estimation.calibration_file import load_calibration
    from ..fleet.parallel import assess_bags, BagJob
    from ..physics.actuator import load_actuator
    from .common import progress_bar, warn
    calibration = load_calibration(args.calibration)
    actuator = load_actuator(args.actuator)
    settings = _window_settings(args, calibration, actuator)
    _indent(args.indent)        # refused before the work, not after it
    report = _condition_report(calibration, settings, args.bags) if args.report else None
    job = BagJob(calibration, actuator.lead, settings, args.namespace,
                 hash_content=bool(args.history))
    to_history = _history_writer(args, calibration) if args.history else None
    bar = progress_bar(len(args.bags), 'assessing', unit='recording')
    refused = []

    def done(outcome: BagOutcome) -> None:
        """Write each finished recording into the history at once (this process), so a killed run keeps it."""
        if to_history is not None:
            refused.append(to_history(outcome))
        if report is not None and outcome.assessment is not None:
            report.add(outcome.assessment)      # summarised now, the windows' spectra let go
        bar.update(1)

    try:
        outcomes = assess_bags(args.bags, job, jobs=args.jobs, scheduler=args.scheduler, on_done=done,
                               timeout=_scheduler_timeout(args))
    finally:
        bar.close()
    results = [outcome.assessment for outcome in outcomes if outcome.assessment is not None]
    for outcome in outcomes:
        for line in (outcome.assessment.problems if outcome.assessment else []):
            warn(line)
        if outcome.error:
            print(f'prsm-lube assess: error: {outcome.error}', file=sys.stderr)
    refused = [line for line in refused if line]
    for line in refused:
        print(f'prsm-lube assess: error: {line}', file=sys.stderr)
    if not results:
        return EXIT_USER_ERROR
    _print_table(results, calibration, args.calibration)
    _write_outputs(args, results, calibration, report, len(results) - len(refused))
    return EXIT_USER_ERROR if len(results) < len(outcomes) or refused else 0


def _history_writer(args: argparse.Namespace, calibration: Calibration) -> Callable[[BagOutcome], str]:
    """The writer of ``args.history``, each recording's actuator named first (refused in one line if it cannot be)."""
    from ..fleet.history import history_writer
    from ..fleet.identity import name_actuators
    identities = name_actuators(args.bags, given=args.actuator_id, actuator_map=args.actuator_map,
                                namespace=args.namespace)
    return history_writer(args.history, args.calibration, calibration, identities=identities,
                          namespace=args.namespace)


def _window_settings(args: argparse.Namespace, calibration: Calibration, actuator: Actuator) -> WindowSettings:
    """Windows in the calibration's band, envelope lines labelled by the actuator; spectra kept for ``--report``."""
    from ..estimation.conditioning import LOWEST_ORDER_FREQUENCY
    from ..estimation.windowing import WindowSettings
    from ..physics.defect_orders import defect_orders
    from ..validation import require_positive
    return WindowSettings(window_length=require_positive('--window', args.window), band=calibration.band,
                          defect_orders=defect_orders(actuator),
                          spectrum_lowest_frequency=LOWEST_ORDER_FREQUENCY if args.report else 0.0)


def _write_outputs(args: argparse.Namespace, results: Sequence[RecordingAssessment], calibration: Calibration,
                   report: ConditionReport | None, added: int) -> None:
    """The history's count, the JSON and the condition report, each said in one line."""
    from ..estimation.pipeline import assessment_json
    from .common import write_json
    if args.history:
        print(f'history {args.history}: {added} recordings added or replaced')
    if args.json:
        document = assessment_json(results, calibration)
        write_json(args.json, document, indent=_indent(args.indent))
        print(f'wrote {args.json}: {len(document["runs"])} runs, {len(document["windows"])} windows')
    if report is not None:
        print(f'wrote {report.write(args.report)}: condition figures of {len(report.runs)} runs')


def _indent(spaces: int | None) -> int | None:
    """``--indent``: None (compact) or spaces >= 0; a negative count is refused in one line."""
    from ..errors import InputError
    if spaces is not None and spaces < 0:
        raise InputError(f'--indent {spaces}: give a number of spaces >= 0')
    return spaces


def _print_table(results: Sequence[RecordingAssessment], calibration: Calibration, calibration_path: str) -> None:
    """The calibration's band and flags, then one line per run; ``!``, ``~`` and ``D`` runs explained below it."""
    import math
    from pathlib import Path
    from ..estimation.calibration_file import band_note, baseline_note
    for flag in calibration.flags:
        print(f'warning: calibration {calibration_path}: {flag}')
    if baseline_note(calibration):
        print(f'warning: calibration {calibration_path}: {baseline_note(calibration)}')
    print(f'calibration {calibration_path}: {band_note(calibration)}'
          + (f'; domain {calibration.domain.text}' if calibration.domain is not None else ''))
    print(f'{"recording":<28} {"run":>4} {"speed r/min":>11} {"load N":>8} {"RMS m/s^2":>10} '
          f'{"kurtosis":>8} {"theta_oil":>9} {"+/-":>6}')
    flagged, extrapolated, defects = [], [], []
    for rec in results:
        for run_result in rec.runs:
            theta = (f'{run_result.theta_oil:9.3f} {run_result.theta_oil_std:6.3f}' if not run_result.reason
                     else f'{"NaN":>9}  {run_result.reason}')
            if run_result.flag:
                flagged.append((Path(rec.path).name, run_result.run_index, run_result.flag))
                theta += ' !'
            if run_result.domain_flag:
                extrapolated.append((Path(rec.path).name, run_result.run_index, run_result.domain_flag))
                theta += ' ~'
            if run_result.defect.suspected:
                defects.append((Path(rec.path).name, run_result.run_index, run_result.defect.evidence))
                theta += ' D'
            kurtosis = run_result.condition.kurtosis if run_result.condition is not None else math.nan
            print(f'{Path(rec.path).name[:28]:<28} {run_result.run_index:>4} '
                  f'{run_result.screw_speed * 60 / (2 * math.pi):>11.1f} '
                  f'{run_result.axial_load:>8.1f} {run_result.vibration_rms:>10.4f} {kurtosis:>8.2f} {theta}')
    for name, run_index, flag in flagged:
        print(f'! {name} run {run_index}: {flag}')
    for name, run_index, flag in extrapolated:
        print(f'~ {name} run {run_index}: {flag}')
    for name, run_index, evidence in defects:
        print(f'D {name} run {run_index}: surface defect suspected: {evidence}; theta_oil is not a lubrication '
              'measure while it lasts')


def _condition_report(calibration: Calibration, settings: WindowSettings, bags: Sequence[str]) -> ConditionReport:
    """The ``--report`` page's collector, with the calibration's band, baseline and flags; recordings as given."""
    from ..diagnosis.condition_report import ConditionReport
    from ..estimation.calibration_file import band_note, baseline_note
    band = calibration.band
    return ConditionReport(settings.defect_orders, band=(band.low, band.high) if band is not None else None,
                           baseline=calibration.condition_baseline,
                           notes=[f'Calibration: {band_note(calibration)}'
                                  + (f'; domain {calibration.domain.text}' if calibration.domain is not None else '')
                                  + ''.join(f'; {note}' for note in (*calibration.flags, baseline_note(calibration))
                                            if note) + '.'], paths=bags)


def _scheduler_timeout(args: argparse.Namespace) -> float:
    """``--scheduler-timeout``, checked (a positive number of seconds)."""
    from ..fleet.scheduler import CONNECT_TIMEOUT
    from ..validation import require_positive
    return CONNECT_TIMEOUT if args.scheduler_timeout is None else require_positive('--scheduler-timeout',
                                                                                   args.scheduler_timeout)
