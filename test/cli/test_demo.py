# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube demo`` at a small size: five steps checked against the truth, and its page in a real browser.

The demo runs once per module as a user runs it (a child process on a private
ROS domain, localhost discovery); the page test opens ``index.html`` in headless
Chromium (``tools/install-browser``) and checks every figure loaded.
"""
import os
from pathlib import Path
import re
import subprocess
import sys

import pytest

import browser

pytestmark = [pytest.mark.slow, pytest.mark.timeout(1200)]
STEPS = 5


def _need_chromium():
    if browser.chromium() is None:
        pytest.skip('chromium is not installed: run tools/install-browser (apt-get install chromium) to check the '
                    'demo page in a real browser')


@pytest.fixture(scope='module')
def demo(tmp_path_factory):
    """The demo at a small size: (exit status, printed text, output folder)."""
    pytest.importorskip('rclpy')
    pytest.importorskip('prsm_lube_ros.srv')
    out = tmp_path_factory.mktemp('demo')
    # Its own domain, 50 past the worker's (conftest: workers 13 apart), so no other graph can reach it: both
    # workers run this fixture (pytest-xdist 3.8 does not keep the conftest's ros_graph group on one worker
    # here) and a random draw once gave the two the same domain, where each demo read the other's inputs.
    worker_domain = int(os.environ.get('ROS_DOMAIN_ID', '100') or 100)
    env = dict(os.environ, ROS_DOMAIN_ID=str((worker_domain + 50) % 100 + 100),
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', MPLBACKEND='Agg')
    result = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'demo', '--out', str(out), '--seed', '5',
                             '--actuators', '3', '--days', '6', '--live-windows', '6', '--playback-rate', '15'],
                            capture_output=True, text=True, timeout=1100, env=env)
    return result.returncode, result.stdout + result.stderr, out


def test_every_step_runs_and_passes_its_check_against_the_truth(demo):
    status, text, out = demo
    assert status == 0, text[-4000:]
    for number in range(1, STEPS + 1):
        assert f'=== Step {number}/{STEPS}:' in text
        assert re.search(rf'^step {number} PASS \(\d+ s\)', text, re.M), text[-3000:]
    assert f'DEMO: PASS - {STEPS}/{STEPS} steps' in text
    assert 'theta_Oil before: median' in text and 'after: median' in text          # step 2
    assert 'concealed:' in text and 'held-out gain' in text                        # step 3
    assert 'forecast' in text and 'inside' in text                                 # step 4
    assert 'runs of the defect recording marked defect_suspected' in text           # step 5
    assert 'verdict surface_defect' in text
    # The fleet is simulated in the past: days to go as of its newest recording's day, never "overdue by 300 d".
    as_of = re.search(r'trend history --report trend --as-of (\d{4}-\d{2}-\d{2})', text)
    assert as_of and f'days to go as of {as_of.group(1)}' in text, text[-3000:]
    checks = [line for line in text.splitlines() if line.strip().startswith('check: ')]
    assert len(checks) >= 5 and all(line.endswith(': PASS') for line in checks), checks
    assert 'FAIL' not in text
    assert (out / 'index.html').is_file() and (out / 'diagnose' / 'report' / 'index.html').is_file()


def test_the_page_shows_every_figure_in_chromium(demo, tmp_path):
    _need_chromium()
    _, text, out = demo
    page = out / 'index.html'
    widths = browser.image_widths(page, tmp_path / 'profile')
    sources = re.findall(r'<img src="([^"]+)"', page.read_text())
    assert sorted(widths) == sorted(sources)
    assert len(sources) >= 2 + 1 + 1 + 1           # Fig. 5a/b, live theta, a diagnosis figure, a trend plot
    assert not [src for src, width in widths.items() if width <= 0], widths
    for step in ('fig5b_theta.png', 'live/live_theta.png', 'diagnose/report/', 'fleet/trend/'):
        assert any(step in src for src in sources), step


def test_the_browser_check_sees_a_figure_that_does_not_load(tmp_path):
    """The check above can fail: a page with a missing PNG reports width 0 for it."""
    _need_chromium()
    from prsm_lube_ros.cli.demo_page import write_page
    from prsm_lube_ros.cli.demo_steps import StepResult
    from prsm_lube_ros.figures import live_theta
    good = live_theta(tmp_path / 'good.png', [(0.0, 0.7), (1.0, 0.72)], 0.5, 0.72, 'a figure')
    step = StepResult(1, 'one step', 'what it shows', checks=[('a check', True)],
                      figures=[(good, 'loads'), (tmp_path / 'missing.png', 'does not load')])
    widths = browser.image_widths(write_page(tmp_path, [step], 'test'), tmp_path / 'profile')
    assert widths['good.png'] > 0 and widths['missing.png'] == 0


def test_a_failed_check_fails_the_demo(tmp_path, monkeypatch, capsys):
    """Exit status 1 and FAIL on the page when one step's check fails (the steps replaced by fixed results)."""
    from prsm_lube_ros.cli import demo, demo_defect, demo_steps, main
    from prsm_lube_ros.cli.demo_steps import StepResult

    def step(number, ok):
        return lambda *args, **kwargs: StepResult(number, f'step {number}', 'shows', checks=[('check', ok)])
    monkeypatch.setattr(demo, '_paper_step', step(1, True))
    monkeypatch.setattr(demo_steps, 'live_step', step(2, True))
    monkeypatch.setattr(demo_steps, 'diagnosis_step', step(3, False))
    monkeypatch.setattr(demo_steps, 'fleet_step', step(4, True))
    monkeypatch.setattr(demo_defect, 'defect_step', step(5, True))
    assert main(['demo', '--out', str(tmp_path)]) == 1
    text = capsys.readouterr().out
    assert 'step 3 FAIL' in text and 'DEMO: FAIL - 4/5 steps' in text
    assert '<span class="fail">FAIL</span>' in Path(tmp_path / 'index.html').read_text()
