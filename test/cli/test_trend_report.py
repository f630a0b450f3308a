# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube trend --report``: the planner's table (Markdown, CSV), one self-contained HTML page checked in
headless Chromium, and plots whose legends leave the data free."""
import csv
import json
import re
import subprocess

import pytest

import browser
from trend_command import actuators, table_rows, trend

SORT_PROBE = """<!DOCTYPE html><html><body><pre id="out">pending</pre><iframe id="page" src="{page}"></iframe><script>
document.getElementById('page').addEventListener('load', function () {{
  var found = [];
  try {{
    var doc = this.contentDocument, table = doc.getElementById('planner');
    var widths = Array.prototype.map.call(doc.images, function (image) {{
      return image.complete ? image.naturalWidth : -1;
    }});
    var names = function () {{
      return Array.prototype.map.call(table.tBodies[0].rows, function (row) {{ return row.cells[1].textContent; }});
    }};
    found.push(names().join(','));
    var header = table.tHead.rows[0].cells;
    header[1].click();
    found.push(names().join(','));
    header[1].click();
    found.push(names().join(','));
    header[0].click();
    found.push(names().join(','));
    document.getElementById('out').textContent = 'WIDTHS ' + widths.join(',') + ' ORDERS ' + found.join(';');
  }} catch (error) {{
    document.getElementById('out').textContent = 'ERROR ' + error;
  }}
}});
</script></body></html>
"""


def _need_chromium():
    if browser.chromium() is None:
        pytest.skip('chromium is not installed: run tools/install-browser (apt-get install chromium) to check the '
                    'trend page in a real browser')


@pytest.fixture(scope='module')
def report(small_fleet, tmp_path_factory):
    """trend as of the fleet's newest recording day + 20 d (every actuator stale at --stale-days 10)."""
    folder = tmp_path_factory.mktemp('trend_report')
    fresh, stale = folder / 'fresh', folder / 'stale'
    for out, extra in ((fresh, ['--as-of', '2026-01-07']), (stale, ['--as-of', '2026-01-27', '--stale-days', '10'])):
        result = trend(small_fleet['history'], '--report', out, *extra)
        assert result.returncode == 0, result.stderr
    return fresh, stale


def test_the_markdown_rows_are_short_and_say_the_next_crossing_and_data_age(report):
    fresh, stale = report
    rows = table_rows((fresh / 'trend.md').read_text())
    assert len(rows) == 2 + 4 and max(len(row) for row in rows[2:]) < 160
    assert 'next crossing, days to go as of 2026-01-07' in rows[0] and 'last seen' in rows[0]
    assert all(re.match(r'\| \d \| A0\d \| (warn|error) ', row) for row in rows[2:]), rows
    assert 'STALE' not in '\n'.join(rows)
    assert sum('STALE' in row for row in table_rows((stale / 'trend.md').read_text())) == 4


def test_the_csv_holds_one_ranked_row_per_actuator_with_the_as_of_band(report):
    from prsm_lube_ros.cli.trend_report import CSV_COLUMNS
    fresh, stale = report
    with open(fresh / 'trend.csv', newline='') as handle:
        rows = list(csv.DictReader(handle))
    assert tuple(rows[0]) == CSV_COLUMNS and [int(r['rank']) for r in rows] == [1, 2, 3, 4]
    document = json.loads((fresh / 'trend.json').read_text())
    assert [r['actuator'] for r in rows] == [a['actuator'] for a in document['actuators']]
    for row in rows:
        assert float(row['theta_as_of_low']) <= float(row['theta_as_of']) <= float(row['theta_as_of_high'])
        assert row['stale'] == 'no' and row['next_level'] in ('warn', 'error')
        assert 0.0 <= float(row['next_probability_by']) <= 1.0
    with open(stale / 'trend.csv', newline='') as handle:
        later = {r['actuator']: r for r in csv.DictReader(handle)}
    for row in rows:
        old = later[row['actuator']]
        assert old['stale'] == 'yes' and float(old['data_age_days']) > 19.0
        assert old['last_seen_utc'] == row['last_seen_utc']
        assert float(old['theta_as_of']) < float(row['theta_as_of'])       # 20 more days of depletion


def test_the_json_ranks_by_the_next_crossing_of_either_level(report):
    from prsm_lube_ros.fleet.planner import planner_rank, PlannedCrossing, CrossingStatus
    fresh, _ = report
    found = actuators(fresh)
    assert sorted(a['rank'] for a in found.values()) == [1, 2, 3, 4]
    keys = []
    for name, entry in sorted(found.items(), key=lambda item: item[1]['rank']):
        item = entry['next']
        assert item is not None and entry['data_age_days'] >= 0 and entry['last_seen'] == entry['last_recording']
        status = CrossingStatus(item['status'])
        planned = [PlannedCrossing(p['level'], CrossingStatus(p['status']), p['days_to_go'], p['days_low'],
                                   p['days_high'], p['probability_crossed'], p['probability_by'])
                   for p in entry['planner']]
        assert status in {p.status for p in planned}

        class Forecast:
            actuator, defect, reason = name, None, ''
        keys.append(planner_rank(Forecast, planned))
    assert keys == sorted(keys)


def test_the_page_is_one_self_contained_file(report):
    fresh, _ = report
    page = (fresh / 'trend.html').read_text()
    assert page.count('<img src="data:image/png;base64,') == 4
    assert not re.search(r'(src|href)="(?!data:|#)', page)                # nothing from elsewhere
    assert '<table class="sortable" id="planner">' in page and page.count('<tr class=') == 4
    for name in ('A01', 'A02', 'A03', 'A04'):
        assert f'id="actuator-{name}"' in page


def _probe(page, profile):
    """The page's image widths and its table's actuator orders (as loaded, then after clicks) in Chromium."""
    probe = page.parent / '.sort_probe.html'
    probe.write_text(SORT_PROBE.format(page=page.name))
    try:
        result = subprocess.run([browser.chromium(), *browser.FLAGS, f'--user-data-dir={profile}', probe.as_uri()],
                                capture_output=True, text=True, timeout=120)
    finally:
        probe.unlink()
    match = re.search(r'<pre id="out">WIDTHS (.*?) ORDERS (.*?)</pre>', result.stdout, re.S)
    assert match, result.stdout[-2000:] + result.stderr[-2000:]
    return [int(w) for w in match.group(1).split(',')], [order.split(',') for order in match.group(2).split(';')]


def test_the_page_shows_every_plot_and_sorts_on_a_click_in_chromium(report, tmp_path):
    _need_chromium()
    fresh, _ = report
    widths, orders = _probe(fresh / 'trend.html', tmp_path / 'profile')
    assert len(widths) == 4 and all(width > 500 for width in widths), widths
    ranked, ascending, descending, by_rank = orders
    assert ascending == ['A01', 'A02', 'A03', 'A04'] and descending == ascending[::-1]
    assert by_rank == ranked and sorted(ranked) == ascending


def test_the_browser_check_sees_a_plot_that_does_not_load(report, tmp_path):
    """The check above can fail: a page whose first plot is broken PNG data reports width 0 for it."""
    _need_chromium()
    fresh, _ = report
    broken = tmp_path / 'trend.html'
    broken.write_text(re.sub(r'data:image/png;base64,[^"]{40}', 'data:image/png;base64,AAAA',
                             (fresh / 'trend.html').read_text(), count=1))
    widths, _ = _probe(broken, tmp_path / 'profile')
    assert widths[0] == 0 and all(width > 500 for width in widths[1:]), widths


def test_the_legend_of_a_trend_plot_lies_beside_the_data(monkeypatch, tmp_path):
    """The legend's box and the axes' box do not overlap (it used to sit over the recordings)."""
    import numpy as np
    from prsm_lube_ros import figures
    seen = []
    monkeypatch.setattr(figures, 'save_figure', lambda fig, path: seen.append(fig) or fig.savefig(path))
    times = np.arange(10) * 86400.0 + 1.7e9
    figures.history_with_forecast(tmp_path / 'a.png', times, np.linspace(0.95, 0.8, 10), np.full(10, 0.01),
                                  times[-1] + np.arange(20) * 86400.0, (np.full(20, 0.75),) * 3,
                                  {'warn 0.85': 0.85, 'error 0.7': 0.7}, [times[3]], 'title',
                                  crossings=[('warn crossing', 0.85, times[-1], times[-2], times[-1] + 86400.0)],
                                  as_of=times[-1])
    fig, = seen
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    canvas = FigureCanvasAgg(fig)                 # the figure was closed: draw it on a canvas of its own
    canvas.draw()
    renderer = canvas.get_renderer()
    ax = fig.axes[0]
    legend, frame = ax.get_legend().get_window_extent(renderer), ax.get_window_extent(renderer)
    assert legend.x0 >= frame.x1 and legend.x1 <= fig.bbox.x1 + 1
    assert len(ax.get_legend().get_texts()) >= 7
