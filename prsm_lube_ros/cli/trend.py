# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend``: theta_Oil history per actuator, depletion fit and when it crosses warn and error.

For the people who plan maintenance: every figure is stated as of a date
(``--as-of``, default now): days to go with their interval (``--level``),
overdue, "may have crossed" with its probability, and the probability of
crossing by a chosen date (``--by``).  Actuators are ranked by the next
crossing of either level, each with its last recording, the data's age
(stale beyond ``--stale-days``) and theta_Oil forecast at the as-of date;
trend.md, trend.csv and the one-page trend.html show that
(:mod:`.trend_report`).  ``--backtest DAYS`` forecasts from the
history cut DAYS earlier and scores it against what was measured since.

An actuator whose history holds a run the defect screen flagged (from the
first such run on: the damage does not heal, :mod:`~prsm_lube_ros.fleet.defects`)
gets no lubrication forecast: its row, JSON entry and plot say since when and
which component, and it comes first (it needs an inspection, not oil).

Bad input never stops the report for the others: an unreadable file of the
history, a stray file in it, an odometer that goes backwards or names an
actuator the history does not have are each one line on stderr (``file`` or
``file:line``), the rest is reported, and the status is non-zero.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .common import EXIT_USER_ERROR

if TYPE_CHECKING:
    import argparse
    from collections.abc import Mapping, Sequence
    from pathlib import Path

    import numpy.typing as npt

    from ..fleet.forecast import ActuatorForecast, FleetRecords, RecordingPoint
    from ..fleet.planner import PlannerRow

    #: Each actuator's recording points.
    _Points = Mapping[str, Sequence[RecordingPoint]]
    #: Relubrications per actuator, s since the epoch (None: found as jumps up).
    _Relubrications = dict[str, list[float]] | None
    #: Odometers per actuator: (times s since the epoch, cumulative revolutions).
    _Odometers = dict[str, tuple[list[float], list[float]]] | None

__all__ = ['BY_DAYS', 'STALE_DAYS', 'TrendOptions', 'add_command', 'run']

#: days after the as-of date of the default ``--by`` date
BY_DAYS = 30.0
#: the default of ``--stale-days`` (:data:`~prsm_lube_ros.fleet.planner.STALE_DAYS`, without importing numpy here)
STALE_DAYS = 7.0


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``trend`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'trend', help='theta_oil history per actuator and the forecast of the warn and error crossings',
        description='Fit theta_oil = a exp(-t/tau) per lubrication cycle to each actuator\'s history (written '
        'by assess --history), relubrications found as jumps up or given, and forecast when theta_oil crosses '
        'the warn and error levels, with an interval. Table most urgent first (the next crossing of either level), '
        'CSV, JSON, dated plots and one HTML page, as of a '
        'date; --backtest scores the forecast against later recordings. An actuator with a run the surface '
        'defect screen of assess flagged gets no forecast from then on (theta_oil is no lubrication measure) '
        'and comes first: it needs an inspection.')
    parser.add_argument('history', metavar='HISTORY', help='history folder written by prsm-lube assess --history')
    parser.add_argument('--actuator', default=None, metavar='ID', help='only this actuator')
    parser.add_argument('--report', required=True, metavar='DIR',
                        help='folder for trend.html (one self-contained page), trend.md, trend.csv, trend.json, plots')
    parser.add_argument('--warn-below', type=float, default=0.85, help='warn level (estimator default 0.85)')
    parser.add_argument('--error-below', type=float, default=0.70, help='error level (estimator default 0.70)')
    parser.add_argument('--as-of', default=None, metavar='DATE',
                        help='forecast as of this UTC date or time (ISO 8601; a date means its end), from the '
                        'recordings made by then; days to go count from it (default: now)')
    parser.add_argument('--by', default=None, metavar='DATE',
                        help=f'also give the probability of crossing each level by this date (default: as-of + '
                        f'{BY_DAYS:g} days)')
    parser.add_argument('--level', type=float, default=0.95, metavar='P',
                        help='probability inside the stated intervals and the plotted band (default 0.95: 95 %% '
                        'intervals)')
    parser.add_argument('--backtest', type=float, default=None, metavar='DAYS',
                        help='forecast from the history cut DAYS before its newest recording and score it '
                        'against the recordings after the cut (coverage of band and crossing intervals)')
    parser.add_argument('--relubrications', default=None, metavar='CSV',
                        help='known relubrications, lines "actuator,time" (ISO 8601 or s since the epoch); '
                        'actuators not listed have theirs found as jumps up in theta_oil')
    parser.add_argument('--stale-days', type=float, default=STALE_DAYS, metavar='DAYS',
                        help=f'flag an actuator whose last recording is more than DAYS before the as-of date '
                        f'(default {STALE_DAYS:g})')
    parser.add_argument('--odometer', default=None, metavar='CSV',
                        help='cumulative screw revolutions, lines "actuator,time,revolutions": adds the fit against '
                        'revolutions (N_d) and the odometer reading at each crossing')
    parser.set_defaults(func=run)


@dataclass(frozen=True)
class TrendOptions:
    """The checked options of one ``trend`` run (times in s since the epoch)."""

    levels: tuple[float, float]
    confidence: float
    as_of: float
    by: float
    stale_days: float = STALE_DAYS


def _options(args: argparse.Namespace) -> TrendOptions:
    """Check the levels, ``--level`` and the dates; one-line errors."""
    import datetime
    from ..errors import InputError
    from ..estimation.health import HealthThresholds
    HealthThresholds(warn_below=args.warn_below, error_below=args.error_below)   # checks the order
    if not 0.0 < args.level < 1.0:
        raise InputError(f'--level must lie between 0 and 1 (a probability such as 0.95), got {args.level:g}')
    now = datetime.datetime.now(datetime.UTC).timestamp()
    as_of = _date('--as-of', args.as_of) if args.as_of else now
    by = _date('--by', args.by) if args.by else as_of + BY_DAYS * 86400.0
    stale_days = getattr(args, 'stale_days', STALE_DAYS)
    if not stale_days > 0:
        raise InputError(f'--stale-days must be > 0, got {stale_days:g}')
    return TrendOptions((args.warn_below, args.error_below), args.level, as_of, by, stale_days)


def _date(option: str, text: str) -> float:
    """s since the epoch of an ISO 8601 date (its end) or time (UTC unless it names a zone)."""
    import datetime
    from ..errors import InputError
    try:
        if len(text.strip()) == 10:
            day = datetime.date.fromisoformat(text.strip())
            stamp = datetime.datetime.combine(day, datetime.time.max, datetime.UTC)
        else:
            stamp = datetime.datetime.fromisoformat(text.strip().replace('Z', '+00:00'))
    except ValueError:
        raise InputError(f'{option} {text!r} is not an ISO 8601 date or time (e.g. 2026-03-01)') from None
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=datetime.UTC)
    return stamp.timestamp()


def run(args: argparse.Namespace) -> int:
    """Forecast every actuator of the history; table on stdout, JSON, Markdown and one plot each."""
    from pathlib import Path
    from ..errors import ConfigError
    from ..fleet.forecast import history_records
    from .common import warn
    options = _options(args)
    report = Path(args.report)
    if report.exists() and not report.is_dir():
        raise ConfigError(f'--report {report}: exists and is not a folder')
    problems: list[str] = []
    records = history_records(args.history, on_problem=problems.append, actuator=args.actuator)
    relubrications, odometers, odometer_reasons = _service_logs(args, records.points, problems)
    if args.backtest is not None:
        _backtest(args, options, records, relubrications, report)
    else:
        _forecast(args, options, records, relubrications, odometers, odometer_reasons, report)
    for line in problems:
        warn(line)
    return EXIT_USER_ERROR if problems else 0


def _service_logs(args: argparse.Namespace, points: _Points,
                  problems: list[str]) -> tuple[_Relubrications, _Odometers, dict[str, str]]:
    """Relubrications, odometers without the problem ones, and each problem actuator's reason."""
    from ..fleet.history import actuator_key
    from ..fleet.service_log import odometer_problems, odometer_readings, read_relubrications
    relubrications = read_relubrications(args.relubrications) if args.relubrications else None
    if not args.odometer:
        return relubrications, None, {}
    readings = odometer_readings(args.odometer)
    found = odometer_problems(args.odometer, readings, set(points), key=actuator_key)
    problems.extend(found.values())
    odometers = {name: ([r.time for r in items], [r.revolutions for r in items])
                 for name, items in readings.items() if name not in found}
    return relubrications, odometers, {actuator_key(name): line for name, line in found.items()
                                       if actuator_key(name) in points}


def _forecast(args: argparse.Namespace, options: TrendOptions, records: FleetRecords,
              relubrications: _Relubrications, odometers: _Odometers, odometer_reasons: dict[str, str],
              report: Path) -> None:
    """Forecast, plan, print the table and write trend.json, trend.md and the plots."""
    from ..fleet.forecast import forecast_points
    from ..atomic_file import write_text_atomically
    from ..fleet.planner import planner_rows
    from .common import write_json
    from .trend_report import csv_text, html_page, markdown_table, PageContext
    from ..errors import InputError
    forecasts = forecast_points(records.points, relubrications=relubrications, levels=options.levels,
                                only=args.actuator, odometers=odometers, confidence=options.confidence,
                                as_of=options.as_of, defects=records.defects)
    if not forecasts:
        raise InputError(f'{args.history}: no assessed recording made by --as-of {_utc(options.as_of)}')
    for forecast in forecasts:
        forecast.revolutions_reason = odometer_reasons.get(forecast.actuator, '')
    rows = planner_rows(forecasts, options.as_of, options.by, options.stale_days)
    context = PageContext(options.levels, options.confidence, options.as_of, options.by, options.stale_days)
    odometer = {row.actuator: _odometer_cells(row.forecast) for row in rows
                if not row.forecast.reason} if args.odometer else {}
    parts = (markdown_table(rows, context, odometer), _defect_lines(forecasts), _note_lines(records.notes))
    text = '\n\n'.join(part for part in parts if part)
    print(text)
    plots = {row.actuator: _plot(report, row.forecast, options) for row in rows}
    write_json(report / 'trend.json', _document(args, options, rows, records.notes))
    write_text_atomically(report / 'trend.md', f'# theta_Oil trend as of {_utc(options.as_of)}, most urgent '
                          f'first\n\n{text}\n')
    write_text_atomically(report / 'trend.csv', csv_text(rows, context))
    write_text_atomically(report / 'trend.html', html_page(rows, context, plots, records.notes, str(args.history)))
    print(f'wrote {report}: trend.html, trend.json, trend.md, trend.csv and {len(rows)} plots')


def _defect_lines(forecasts: Sequence[ActuatorForecast]) -> str:
    """The evidence of each suspected surface defect, under the table ('' when there is none)."""
    suspected = [f for f in forecasts if f.defect is not None]
    if not suspected:
        return ''
    lines = ['Surface defect suspected: inspect the screw and its bearings (oil does not mend a spall). theta_Oil '
             'reads the damage as if it were oil loss, so it is no lubrication measure. Suspected from the first '
             'flagged run on: the damage does not heal, so neither a relubrication nor a later run the screen '
             'passes ends it.', '']
    for forecast in suspected:
        defect = forecast.defect
        assert defect is not None  # kept above
        since = sum(p.time >= defect.since_recording for p in forecast.points)
        lines.append(f'- {forecast.actuator}: since {defect.since_utc} ({defect.recording_path}), flagged in '
                     f'{defect.recordings} of {max(since, defect.recordings)} recordings since: '
                     f'{defect.evidence or "no evidence recorded"}')
    return '\n'.join(lines)


def _note_lines(notes: Sequence[str]) -> str:
    """Notes on the history (recordings never screened for a defect), '' without any."""
    return '\n'.join(f'Note: {line}' for line in notes)


def _utc(seconds: float | None) -> str:
    """ISO 8601 UTC to the minute (the forecast's own format), ``never`` for None."""
    from ..fleet.forecast import utc_minutes
    return utc_minutes(seconds) or 'never'


def _document(args: argparse.Namespace, options: TrendOptions, rows: Sequence[PlannerRow],
              notes: Sequence[str]) -> dict:
    """trend.json: options, notes, and per actuator (most urgent first) the forecast with its planner view."""
    actuators = []
    for row in rows:
        entry = row.forecast.as_json()
        entry['planner'] = [item.as_json() for item in row.planned]
        entry.update(row.as_json())
        entry['revolutions']['reason'] = row.forecast.revolutions_reason
        actuators.append(entry)
    return {'history': str(args.history), 'levels': {'warn': options.levels[0], 'error': options.levels[1]},
            'confidence': options.confidence, 'as_of': options.as_of, 'as_of_utc': _utc(options.as_of),
            'by': options.by, 'by_utc': _utc(options.by), 'stale_days': options.stale_days, 'notes': list(notes),
            'actuators': actuators}


def _odometer_cells(forecast: ActuatorForecast) -> list[str]:
    """N_d and the odometer reading of the warn crossing, or why there are none."""
    import math
    if forecast.revolutions_reason:
        return ['–', forecast.revolutions_reason]
    if not math.isfinite(forecast.depletion_revolutions):
        return ['–', 'odometer does not cover the recordings']
    crossing = forecast.revolution_crossings[0] if forecast.revolution_crossings else None
    where = 'passed'
    if crossing and crossing.time is not None:
        high = 'never' if crossing.high is None else f'{crossing.high:.0f}'
        where = f'{crossing.time:.0f} ({crossing.low:.0f} .. {high})'
    return [f'{forecast.depletion_revolutions:.3g}', where]


def _plot(report: Path, forecast: ActuatorForecast, options: TrendOptions) -> Path:
    """One dated plot: recordings, band to the by-date, levels, crossings with intervals, as-of line."""
    import numpy as np
    from ..figures import history_with_forecast
    points = forecast.points
    end = max(options.by, forecast.last_recording + 7 * 86400.0) if not forecast.reason else 0.0
    future = np.linspace(forecast.last_recording, end, 200) if not forecast.reason else np.array([])
    names = ('warn', 'error')
    band: tuple[npt.ArrayLike, npt.ArrayLike, npt.ArrayLike] = ([], [], [])
    if len(future):
        band = forecast.band(future)
    title = f'{forecast.actuator}: theta_Oil and forecast'
    since = None
    if forecast.defect is not None:
        title = (f'{forecast.actuator}: theta_Oil; no lubrication forecast (surface defect suspected since '
                 f'{forecast.defect.since_utc[:10]})')
        since = (f'surface defect suspected ({forecast.defect.component or "impulsive"}): theta_Oil no lubrication '
                 'measure', forecast.defect.since)
    return history_with_forecast(report / f'{forecast.actuator}.png', [p.time for p in points],
                                 [p.theta_oil for p in points], [p.theta_oil_std for p in points], future, band,
                                 {f'{name} {level:g}': level for name, level in zip(names, options.levels)},
                                 forecast.relubrications, title,
                                 crossings=[(f'{name} crossing', c.level, c.time, c.low, c.high)
                                            for name, c in zip(names, forecast.crossings)],
                                 as_of=options.as_of, confidence=options.confidence, marked_since=since)


def _backtest(args: argparse.Namespace, options: TrendOptions, records: FleetRecords,
              relubrications: _Relubrications, report: Path) -> None:
    """Forecast from the history cut ``--backtest`` days earlier; print and write its scores."""
    from ..errors import InputError
    from ..atomic_file import write_text_atomically
    from ..fleet.backtest import backtest
    from .common import write_json
    if not args.backtest > 0:
        raise InputError(f'--backtest DAYS must be > 0, got {args.backtest:g}')
    if not records.points:
        raise InputError(f'{args.history}: no recording with a theta_Oil to backtest')
    result = backtest(records.points, args.backtest, relubrications=relubrications, levels=options.levels,
                      confidence=options.confidence, defects=records.defects)
    document = result.as_json()
    lines = [f'# Backtest: forecast as of {_utc(result.cut)} ({args.backtest:g} d before the newest recording)', '',
             '| actuator | later recordings | inside band | crossings seen | inside interval |',
             '|---|---|---|---|---|']
    for item in result.actuators:
        lines.append(f'| {item.actuator} | {item.later} | {item.inside_band} | {len(item.crossings)} | '
                     f'{sum(c.inside for c in item.crossings)} |' + (f' {item.reason}' if item.reason else ''))
    lines += ['', f'At {options.confidence:.0%}: band coverage {_share(document["band_coverage"])} of '
              f'{document["recordings_scored"]} later recordings; crossing coverage '
              f'{_share(document["crossing_coverage"])} of {document["crossings_scored"]} crossings seen; median '
              f'|error| of the crossing estimate {_days(document["median_abs_crossing_error_days"])}.']
    text = '\n'.join(lines)
    print(text)
    write_json(report / 'backtest.json', document)
    write_text_atomically(report / 'backtest.md', text + '\n')


def _share(value: float | None) -> str:
    return '–' if value is None else f'{value:.1%}'


def _days(value: float | None) -> str:
    return '–' if value is None else f'{value:.2f} d'
