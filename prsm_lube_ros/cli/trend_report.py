# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The planner's outputs of ``prsm-lube trend``: the short Markdown table, the CSV and the one-page HTML report.

All three show the same rows (:func:`~prsm_lube_ros.fleet.planner.planner_rows`),
most urgent first: the next crossing of either level with its interval and
its probability by the planning date, theta_Oil forecast at the as-of date
with its band, the last recording and the data's age (stale flagged).  The
HTML page is self-contained (the plots inline as PNG data, no script or
style from elsewhere) and its table sorts by any column on a click.
"""
from __future__ import annotations

import base64
import csv
import html
import io
import math
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from ..fleet.planner import PlannedCrossing, PlannerRow

__all__ = ['CSV_COLUMNS', 'PageContext', 'SORT_SCRIPT', 'STYLE', 'csv_text', 'html_page', 'level_name',
           'markdown_table', 'next_text']

#: columns of trend.csv, one row per actuator
CSV_COLUMNS = ('rank', 'actuator', 'next_level', 'next_status', 'next_days_to_go', 'next_days_low',
               'next_days_high', 'next_probability_by', 'theta_as_of', 'theta_as_of_low', 'theta_as_of_high',
               'last_seen_utc', 'data_age_days', 'stale', 'tau_days', 'recordings', 'relubrications',
               'warn_crossing_utc', 'warn_low_utc', 'warn_high_utc', 'warn_status', 'warn_days_to_go',
               'warn_probability_by', 'error_crossing_utc', 'error_low_utc', 'error_high_utc', 'error_status',
               'error_days_to_go', 'error_probability_by', 'reason')


class PageContext:
    """What every output states once: levels, confidence, as-of and planning dates, the stale limit."""

    def __init__(self, levels: tuple[float, float], confidence: float, as_of: float, by: float,
                 stale_days: float) -> None:
        self.levels, self.confidence, self.as_of, self.by, self.stale_days = levels, confidence, as_of, by, stale_days

    @property
    def percent(self) -> str:
        """The confidence as ``95%``."""
        return f'{self.confidence:.0%}'


def _utc(seconds: float | None) -> str:
    from ..fleet.forecast import utc_minutes
    return utc_minutes(seconds) or 'never'


def level_name(level: float, levels: tuple[float, float]) -> str:
    """``warn`` or ``error`` for one of ``levels`` (warn, error), else the level's value."""
    return {levels[0]: 'warn', levels[1]: 'error'}.get(level, f'{level:g}')


def next_text(row: PlannerRow, context: PageContext) -> str:
    """The next crossing in words (``error in 4.0 d (2.1 .. 6.3)``), or why there is none."""
    from ..fleet.planner import planner_text
    forecast = row.forecast
    if forecast.reason:
        return forecast.reason
    if row.next is None:
        return 'no level forecast'
    return f'{level_name(row.next.level, context.levels)} {planner_text(row.next)}'


def _number(value: float | None, digits: str = '.2f') -> str:
    return '–' if value is None or not math.isfinite(value) else format(value, digits)


def _theta_text(row: PlannerRow) -> str:
    centre, low, high = row.theta_as_of
    if not math.isfinite(centre):
        return '–'
    return f'{centre:.3f} ({low:.3f} .. {high:.3f})'


def _age_text(row: PlannerRow) -> str:
    age = _number(row.data_age_days, '.1f')
    return f'{age} STALE' if row.stale else age


def markdown_table(rows: Sequence[PlannerRow], context: PageContext, odometer_cells: Mapping[str, list[str]]) -> str:
    """The Markdown table: rank, actuator, next crossing, its probability, theta_Oil at the as-of date, data age.

    ``odometer_cells`` (actuator to two cells) adds the fit against
    revolutions when not empty.  Every row has as many cells as the header.
    """
    day, by_day = _utc(context.as_of)[:10], _utc(context.by)[:10]
    header = ['#', 'actuator', f'next crossing, days to go as of {day} ({context.percent} interval)',
              f'P(by {by_day})', f'theta_Oil on {day} ({context.percent} band)', 'last seen', 'data age d', 'tau d']
    if odometer_cells:
        header += ['N_d rev', f'warn at odometer rev ({context.percent} interval)']
    lines = ['| ' + ' | '.join(header) + ' |', '|---' * len(header) + '|']
    for row in rows:
        probability = None if row.next is None else row.next.probability_by
        cells = [str(row.rank), row.actuator, next_text(row, context), _number(probability),
                 _theta_text(row), _utc(row.last_seen)[:10], _age_text(row), _number(row.forecast.tau_days, '.3g')]
        if odometer_cells:
            cells += odometer_cells.get(row.actuator, ['–', '–'])
        lines.append('| ' + ' | '.join(cells) + ' |')
    return '\n'.join(lines)


def _level_cells(planned: PlannedCrossing | None, crossing_time: tuple) -> list:
    """CSV cells of one level: crossing time, interval, status, days to go, probability by the planning date."""
    from ..fleet.forecast import utc_minutes
    if planned is None:
        return [''] * 6
    return [*(utc_minutes(v) or '' for v in crossing_time), planned.status.value,
            _csv_number(planned.days_to_go), _csv_number(planned.probability_by)]


def _csv_number(value: float | None) -> str:
    return '' if value is None or not math.isfinite(value) else f'{value:.6g}'


def csv_text(rows: Sequence[PlannerRow], context: PageContext) -> str:
    """trend.csv: :data:`CSV_COLUMNS`, one line per actuator, most urgent first (empty cells where unknown)."""
    from ..fleet.forecast import utc_minutes
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator='\n')
    writer.writerow(CSV_COLUMNS)
    for row in rows:
        forecast, item = row.forecast, row.next
        levels: list = []
        for level in context.levels:
            planned = next((p for p in row.planned if math.isclose(p.level, level)), None)
            crossing = forecast.crossing(level)
            times = (None, None, None) if crossing is None else (crossing.time, crossing.low, crossing.high)
            levels += _level_cells(planned, times)
        writer.writerow([row.rank, row.actuator, '' if item is None else level_name(item.level, context.levels),
                         '' if item is None else item.status.value,
                         *(_csv_number(None if item is None else v) for v in
                           ((item.days_to_go, item.days_low, item.days_high, item.probability_by) if item else
                            (None,) * 4)),
                         *(_csv_number(v) for v in row.theta_as_of), utc_minutes(row.last_seen) or '',
                         _csv_number(row.data_age_days), 'yes' if row.stale else 'no',
                         _csv_number(forecast.tau_days), len(forecast.points), len(forecast.relubrications),
                         *levels, forecast.reason])
    return buffer.getvalue()


STYLE = """body{font-family:sans-serif;margin:1.5em;max-width:1100px}table{border-collapse:collapse;font-size:90%}
th,td{border:1px solid #bbb;padding:3px 6px;text-align:left}th{background:#eee;cursor:pointer;user-select:none}
th[aria-sort=ascending]::after{content:" \\25B2"}th[aria-sort=descending]::after{content:" \\25BC"}
tr.stale td{background:#fff3cd}img{max-width:100%;height:auto}section{margin-top:2em}.note{color:#555}"""

SORT_SCRIPT = """document.querySelectorAll('table.sortable th').forEach(function (th, column) {
  th.addEventListener('click', function () {
    var table = th.closest('table'), body = table.tBodies[0];
    var ascending = th.getAttribute('aria-sort') !== 'ascending';
    table.querySelectorAll('th').forEach(function (other) { other.removeAttribute('aria-sort'); });
    th.setAttribute('aria-sort', ascending ? 'ascending' : 'descending');
    var rows = Array.prototype.slice.call(body.rows);
    rows.sort(function (a, b) {
      var x = a.cells[column].getAttribute('data-sort'), y = b.cells[column].getAttribute('data-sort');
      var nx = parseFloat(x), ny = parseFloat(y);
      var order = (!isNaN(nx) && !isNaN(ny)) ? nx - ny : x.localeCompare(y);
      return ascending ? order : -order;
    });
    rows.forEach(function (row) { body.appendChild(row); });
  });
});"""


def _cell(text: str, sort: float | str) -> str:
    """A table cell with its sort value (numbers: unknown sorts last)."""
    if isinstance(sort, float):
        sort = f'{sort:.9g}' if math.isfinite(sort) else '1e300'
    return f'<td data-sort="{html.escape(str(sort), quote=True)}">{html.escape(text)}</td>'


def _image(path: Path, alt: str) -> str:
    """An <img> with the PNG inline (data URI): the page needs no other file."""
    if not path.is_file():
        return f'<p class="note">(no plot: {html.escape(path.name)} was not written)</p>'
    data = base64.b64encode(path.read_bytes()).decode('ascii')
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt, quote=True)}">'


def html_page(rows: Sequence[PlannerRow], context: PageContext, plots: Mapping[str, Path], notes: Sequence[str],
              history: str) -> str:
    """One self-contained HTML page: the sortable table and each actuator's plot with its crossings."""
    day = _utc(context.as_of)[:10]
    header = ['#', 'actuator', 'next crossing', f'days to go as of {day}', f'P(by {_utc(context.by)[:10]})',
              f'theta_Oil on {day}', 'last seen', 'data age d', 'tau d', 'recordings', 'relubrications']
    body = []
    for row in rows:
        item = row.next
        days = math.inf if item is None or item.days_to_go is None else item.days_to_go
        probability = math.nan if item is None or item.probability_by is None else item.probability_by
        name = html.escape(row.actuator, quote=True)
        cells = [_cell(str(row.rank), float(row.rank)),
                 f'<td data-sort="{name}"><a href="#actuator-{name}">{name}</a></td>',
                 _cell(next_text(row, context), 'zz' if item is None else level_name(item.level, context.levels)),
                 _cell(_number(None if item is None else item.days_to_go, '.1f'), float(days)),
                 _cell(_number(probability), float(-probability if math.isfinite(probability) else math.inf)),
                 _cell(_theta_text(row), float(row.theta_as_of[0])),
                 _cell(_utc(row.last_seen), float(row.last_seen)),
                 _cell(_age_text(row), float(row.data_age_days)),
                 _cell(_number(row.forecast.tau_days, '.3g'), float(row.forecast.tau_days)),
                 _cell(str(len(row.forecast.points)), float(len(row.forecast.points))),
                 _cell(str(len(row.forecast.relubrications)), float(len(row.forecast.relubrications)))]
        body.append(f'<tr class="{"stale" if row.stale else ""}">' + ''.join(cells) + '</tr>')
    sections = [_section(row, context, plots.get(row.actuator)) for row in rows]
    lines = [f'<p class="note">Note: {html.escape(line)}</p>' for line in notes]
    title = f'theta_Oil trend as of {_utc(context.as_of)}'
    return ('<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
            f'<title>{html.escape(title)}</title><style>{STYLE}</style></head><body>'
            f'<h1>{html.escape(title)}</h1>'
            f'<p>History {html.escape(history)}; levels warn {context.levels[0]:g}, error {context.levels[1]:g}; '
            f'{context.percent} intervals; planning date {html.escape(_utc(context.by))}; data older than '
            f'{context.stale_days:g} d on the as-of date flagged STALE (shaded). Most urgent first: the next '
            'crossing of either level (error once warn is overdue), then the probability of it by the planning '
            'date. Click a column header to sort.</p>' + ''.join(lines)
            + '<table class="sortable" id="planner"><thead><tr>'
            + ''.join(f'<th scope="col">{html.escape(h)}</th>' for h in header)
            + '</tr></thead><tbody>' + ''.join(body) + '</tbody></table>'
            + ''.join(sections) + f'<script>{SORT_SCRIPT}</script></body></html>\n')


def _section(row: PlannerRow, context: PageContext, plot: Path | None) -> str:
    """One actuator: its crossings per level in words and its plot."""
    from ..fleet.forecast_summary import crossing_interval_text
    from ..fleet.planner import planner_text
    forecast = row.forecast
    items = []
    for planned in row.planned:
        crossing = forecast.crossing(planned.level)
        when = '' if crossing is None else f'; crossing {_utc(crossing.time)} ({crossing_interval_text(crossing)})'
        probability = '' if planned.probability_by is None else f'; P(by planning date) {planned.probability_by:.2f}'
        items.append(f'<li>{level_name(planned.level, context.levels)} {planned.level:g}: '
                     f'{html.escape(planner_text(planned) + when + probability)}</li>')
    if forecast.reason:
        items.append(f'<li>{html.escape(forecast.reason)}</li>')
    stale = (f' <strong>STALE: no recording for {row.data_age_days:.1f} d</strong>' if row.stale else '')
    image = _image(plot, f'{forecast.actuator}: theta_Oil history and forecast') if plot is not None else ''
    return (f'<section id="actuator-{html.escape(forecast.actuator, quote=True)}"><h2>#{row.rank} '
            f'{html.escape(forecast.actuator)}</h2><p>Last seen {html.escape(_utc(row.last_seen))}.{stale} theta_Oil '
            f'on the as-of date: {html.escape(_theta_text(row))}.</p><ul>' + ''.join(items) + f'</ul>{image}</section>')
