# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend``: theta_Oil history per actuator, depletion fit and when it crosses warn and error."""
from __future__ import annotations


def add_command(subparsers) -> None:
    """Add ``trend`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'trend', help='theta_oil history per actuator and the forecast of the warn and error crossings',
        description='Fit theta_oil = a exp(-t/tau) per lubrication cycle to each actuator\'s history (written '
        'by assess --history), relubrications found as jumps up or given, and forecast when theta_oil crosses '
        'the warn and error levels, with a 95 % interval. Table most urgent first, JSON and plots.')
    parser.add_argument('history', metavar='HISTORY', help='history folder written by prsm-lube assess --history')
    parser.add_argument('--actuator', default=None, metavar='ID', help='only this actuator')
    parser.add_argument('--report', required=True, metavar='DIR', help='folder for trend.json, trend.md, plots')
    parser.add_argument('--warn-below', type=float, default=0.85, help='warn level (estimator default 0.85)')
    parser.add_argument('--error-below', type=float, default=0.70, help='error level (estimator default 0.70)')
    parser.add_argument('--relubrications', default=None, metavar='CSV',
                        help='known relubrications, lines "actuator,time" (ISO 8601 or s since the epoch); '
                        'actuators not listed have theirs found as jumps up in theta_oil')
    parser.add_argument('--odometer', default=None, metavar='CSV',
                        help='cumulative screw revolutions, lines "actuator,time,revolutions": adds the fit against '
                        'revolutions (N_d) and the odometer reading at each crossing')
    parser.set_defaults(func=run)


def run(args) -> int:
    """Forecast every actuator of the history; table on stdout, JSON, Markdown and one plot each."""
    from pathlib import Path
    import numpy as np
    from ..estimation.health import HealthThresholds
    from ..figures import history_with_forecast
    from ..errors import ConfigError
    from ..fleet.forecast import DAY, forecast_history
    from .common import write_json
    HealthThresholds(warn_below=args.warn_below, error_below=args.error_below)   # checks the order
    report = Path(args.report)
    if report.exists() and not report.is_dir():
        raise ConfigError(f'--report {report}: exists and is not a folder')
    levels = (args.warn_below, args.error_below)
    from ..fleet.service_log import read_odometer, read_relubrications
    relubrications = read_relubrications(args.relubrications) if args.relubrications else None
    odometers = read_odometer(args.odometer) if args.odometer else None
    forecasts = forecast_history(args.history, actuator=args.actuator, relubrications=relubrications,
                                 levels=levels, odometers=odometers)
    rows = [_row(forecast) for forecast in forecasts]
    header = ('| actuator | recordings | relubrications | tau d | theta now | warn crossing (95 % interval) '
              '| error crossing (95 % interval) |')
    if odometers:
        header += ' N_d rev | warn at odometer rev (95 % interval) |'
    table = '\n'.join([header, '|---' * header.count(' |') + '|'] + rows)
    print(table)
    for forecast in forecasts:
        points = forecast.points
        future = np.linspace(forecast.last_recording, forecast.last_recording + 30 * DAY, 200) \
            if not forecast.reason else np.array([])
        history_with_forecast(report / f'{forecast.actuator}.png', [p.time for p in points],
                              [p.theta_oil for p in points], [p.theta_oil_std for p in points], future,
                              forecast.band(future) if len(future) else ([], [], []),
                              {f'warn {args.warn_below:g}': args.warn_below,
                               f'error {args.error_below:g}': args.error_below},
                              forecast.relubrications, f'{forecast.actuator}: theta_Oil and forecast')
    write_json(report / 'trend.json', {'history': str(args.history),
                                       'levels': {'warn': args.warn_below, 'error': args.error_below},
                                       'actuators': [forecast.as_json() for forecast in forecasts]})
    (report / 'trend.md').write_text(f'# theta_Oil trend, most urgent first\n\n{table}\n')
    print(f'wrote {report}: trend.json, trend.md and {len(forecasts)} plots')
    return 0


def _row(forecast) -> str:
    """One Markdown table row of a forecast."""
    import math
    from ..fleet.forecast import crossing_interval_text
    if forecast.reason:
        return f'| {forecast.actuator} | {len(forecast.points)} | – | – | – | {forecast.reason} | |'
    cells = []
    for crossing in forecast.crossings:
        data = crossing.as_json()
        cells.append(f'{data["time_utc"]} ({crossing_interval_text(crossing)})' if data['time_utc'] else 'never')
    row = (f'| {forecast.actuator} | {len(forecast.points)} | {len(forecast.relubrications)} | '
           f'{forecast.tau_days:.3g} | {forecast.theta_now:.3f} | ' + ' | '.join(cells) + ' |')
    if math.isfinite(forecast.depletion_revolutions):
        crossing = forecast.revolution_crossings[0] if forecast.revolution_crossings else None
        where = 'passed'
        if crossing and crossing.time is not None:
            high = 'never' if crossing.high is None else f'{crossing.high:.0f}'
            where = f'{crossing.time:.0f} ({crossing.low:.0f} .. {high})'
        row += f' {forecast.depletion_revolutions:.3g} | {where} |'
    return row
