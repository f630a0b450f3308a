# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``assess --report`` and ``diagnose --report``: the figures a vibration analyst expects (issue 34, item 5).

FEMTO-like recordings (test/support/bearing_bags.py: a bearing shaft at the
PRONOSTIA conditions, 25.6 kHz, healthy or with an outer-race spall ringing a
mode) go through the installed ``prsm-lube`` command with the PRONOSTIA
bearing's geometry; simulated PRSM recordings through ``main``.  Each figure
the page shows must exist and be a PNG, and the page must say the resolution
and the defect orders in words.
"""
import json
from pathlib import Path
import re
import shutil
import subprocess

import numpy as np
import pytest

import browser
from bearing_bags import BPFO, write_bearing_recording

ROOT = Path(__file__).resolve().parents[2]
FEMTO_ACTUATOR = ROOT / 'config' / 'femto_pronostia_bearing.yaml'
PNG = b'\x89PNG\r\n\x1a\n'


def prsm_lube(*args):
    command = shutil.which('prsm-lube')
    assert command, 'the installed prsm-lube command is not on PATH'
    return subprocess.run([command, *map(str, args)], capture_output=True, text=True, timeout=600)


def page_figures(page):
    """The figures an HTML page shows, each checked: the file exists beside the page and is a PNG."""
    sources = re.findall(r'<img src="([^"]+)"', page.read_text())
    for source in sources:
        data = (page.parent / source).read_bytes()
        assert data[:8] == PNG and len(data) > 5000, source
    return sources


@pytest.fixture(scope='module')
def femto_like(tmp_path_factory):
    """Calibrated on one healthy bearing, a second healthy one and a spalled one assessed with --report."""
    folder = tmp_path_factory.mktemp('femto_like')
    write_bearing_recording(folder / 'healthy_a', seed=1)
    write_bearing_recording(folder / 'healthy_b', seed=2, start=1.7e9 + 100)
    write_bearing_recording(folder / 'spalled', seed=3, start=1.7e9 + 200, defect_order=BPFO, growth=0.5)
    made = prsm_lube('calibrate', folder / 'healthy_a', '--out', folder / 'cal.yaml', '--actuator', FEMTO_ACTUATOR)
    assert made.returncode == 0, made.stderr
    result = prsm_lube('assess', folder / 'healthy_b', folder / 'spalled', '--calibration', folder / 'cal.yaml',
                       '--actuator', FEMTO_ACTUATOR, '--json', folder / 'out.json', '--report', folder / 'report')
    return folder, result


def test_assess_report_shows_every_figure_kind_and_says_resolution_and_defect_orders(femto_like):
    folder, result = femto_like
    assert result.returncode == 0, result.stderr
    page = folder / 'report' / 'index.html'
    assert f'wrote {page}: condition figures of 6 runs' in result.stdout
    sources = page_figures(page)
    for kind in ('trends_all.png', 'order_spectrum.png', 'waterfall_envelope.png', 'waterfall_order.png',
                 'trends.png', 'envelope_run'):
        assert any(kind in source for source in sources), kind
    text = page.read_text()
    # The resolution, in words: Hz and orders per bin, the demodulation band.
    assert re.search(r'Welch PSD of each steady window, [\d.]+ Hz per bin = [\d.]+ orders per bin at 1800 r/min', text)
    assert re.search(r'Envelope spectrum resolution:</b> [\d.]+-[\d.]+ orders per bin', text)
    assert re.search(r'Demodulation band</b> \(chosen per window by spectral kurtosis\): \d+-\d+ Hz', text)
    assert 'Analysis band 0.5-10240 Hz' in text
    # Every defect order of the configured bearing, named by component.
    for words in ('5.611x support bearing outer race', '7.389x support bearing inner race',
                  '3.589x support bearing rolling element', '0.4316x support bearing cage (modulates, not screened)'):
        assert words in text, words
    assert not list((folder / 'report').glob('.*.tmp'))


def test_assess_report_points_at_the_spall_and_not_at_the_healthy_bearing(femto_like):
    folder, _ = femto_like
    runs = json.loads((folder / 'out.json').read_text())['runs']
    assert [run['defect_suspected'] for run in runs] == [False] * 3 + [True] * 3
    text = (folder / 'report' / 'index.html').read_text()
    assert '6 runs in 2 recordings; defect suspected in 3' in text
    spalled = text[text.index('spalled</h3>'):]
    assert spalled.count('support bearing outer race defect suspected') >= 3       # per drawn run, with the line
    healthy = text[text.index('healthy_b</h3>'):text.index('spalled</h3>')]
    assert 'no defect suspected' in healthy and 'defect suspected:' not in healthy


def test_the_report_changes_no_number_of_the_assessment(femto_like):
    """Spectra are kept for the report only: the JSON is the same without --report."""
    folder, _ = femto_like
    plain = prsm_lube('assess', folder / 'healthy_b', folder / 'spalled', '--calibration', folder / 'cal.yaml',
                      '--actuator', FEMTO_ACTUATOR, '--json', folder / 'plain.json')
    assert plain.returncode == 0, plain.stderr
    assert json.loads((folder / 'plain.json').read_text()) == json.loads((folder / 'out.json').read_text())


def test_the_report_is_the_same_from_worker_processes(femto_like):
    """With --jobs the recordings are summarised in the main process as they come back: the same page."""
    folder, _ = femto_like
    result = prsm_lube('assess', folder / 'healthy_b', folder / 'spalled', '--calibration', folder / 'cal.yaml',
                       '--actuator', FEMTO_ACTUATOR, '--jobs', '2', '--report', folder / 'report_jobs')
    assert result.returncode == 0, result.stderr
    assert (folder / 'report_jobs' / 'index.md').read_text() == (folder / 'report' / 'index.md').read_text()


def test_assess_report_loads_every_figure_in_chromium(femto_like, tmp_path):
    if browser.chromium() is None:
        pytest.skip('chromium is not installed: run tools/install-browser to check the report in a real browser')
    folder, _ = femto_like
    page = folder / 'report' / 'index.html'
    widths = browser.image_widths(page, tmp_path / 'profile')
    assert sorted(widths) == sorted(page_figures(page))
    assert not [src for src, width in widths.items() if width <= 0], widths


def test_a_report_folder_that_cannot_be_made_is_one_line(femto_like):
    folder, _ = femto_like
    blocker = folder / 'a_file'
    blocker.write_text('not a folder')
    result = prsm_lube('assess', folder / 'healthy_b', '--calibration', folder / 'cal.yaml', '--actuator',
                       FEMTO_ACTUATOR, '--report', blocker)
    assert result.returncode != 0
    assert 'Traceback' not in result.stderr and f'{blocker}: cannot create report folder' in result.stderr


def test_assess_report_on_simulated_prsm_recordings(tmp_path, capsys):
    """The simulator's rig (default actuator: 6.25x screw raceway; nut raceway and roller share 3.75x)."""
    from prsm_lube_ros.cli import main
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    from prsm_lube_ros.simulation.rig_config import ExperimentPlan
    bags = simulate_experiment(tmp_path / 'sim', plan=ExperimentPlan(stage_thetas=(1.0, 0.8)), seed=4)
    assert main(['calibrate', str(bags[0]), '--out', str(tmp_path / 'cal.yaml')]) == 0
    assert main(['assess', str(bags[1]), '--calibration', str(tmp_path / 'cal.yaml'),
                 '--report', str(tmp_path / 'report')]) == 0
    page = tmp_path / 'report' / 'index.html'
    assert len(page_figures(page)) >= 5
    text = page.read_text()
    assert '0.375x carrier (modulates, not screened); 3.75x nut raceway or roller; 6.25x screw raceway' in text
    assert 'x roller' not in text.replace('raceway or roller', '')            # a shared order is said once
    assert re.search(r'[\d.]+ Hz per bin = [\d.]+ orders per bin at \d+ r/min to [\d.]+ at \d+ r/min', text)
    assert 'wrote' in capsys.readouterr().out


def _summary(recording, index, rng, suspected=False):
    from prsm_lube_ros.diagnosis.condition_report import ORDER_SPECTRUM_GRID, RunSummary
    from prsm_lube_ros.estimation.condition_indicators import ORDER_GRID
    envelope = rng.normal(0.0, 3.0, ORDER_GRID.size).astype(np.float32)
    if suspected:
        envelope[np.argmin(np.abs(ORDER_GRID - 6.25))] = 25.0
    return RunSummary(recording=recording, run_index=index, start=1.7e9 + 60.0 * index, speed=20.0, load=150.0,
                      windows=5, kurtosis=6.0 if suspected else 3.0, crest=4.0, line_order=6.25,
                      line_db=25.0 if suspected else 4.0, line_component='screw raceway', theta=1.0, theta_std=0.05,
                      theta_flag='', reason='', suspected=suspected, evidence='unit' if suspected else '',
                      finding_order=6.25 if suspected else np.nan, finding_component='screw raceway',
                      envelope_resolution=0.3, spectrum_resolution=2.0, demodulation_bands=((100.0, 200.0),) * 5,
                      envelope_db=envelope, order_psd=rng.lognormal(-6, 1, ORDER_SPECTRUM_GRID.size).astype(np.float32))


def test_many_recordings_are_capped_and_the_page_says_so(tmp_path, monkeypatch):
    from prsm_lube_ros.diagnosis import condition_report
    from prsm_lube_ros.physics.actuator import Actuator
    from prsm_lube_ros.physics.defect_orders import defect_orders
    monkeypatch.setattr(condition_report, 'MAX_SECTIONS', 2)
    monkeypatch.setattr(condition_report, 'MAX_RUN_FIGURES', 3)
    monkeypatch.setattr(condition_report, 'MAX_RUN_FIGURES_PER_SECTION', 2)
    monkeypatch.setattr(condition_report, 'MAX_TABLE_ROWS', 5)
    rng = np.random.default_rng(0)
    report = condition_report.ConditionReport(defect_orders(Actuator()), band=(0.5, 1600.0))
    for k in range(4):
        path = f'/data/rec{k}'
        report.recordings[path] = [_summary(path, i, rng, suspected=(k == 3 and i == 1)) for i in range(3)]
    page = report.write(tmp_path)
    text = page.read_text()
    assert 'Figures drawn for 2 of 4 recordings (those with a defect suspected first); not drawn: rec1, rec2' in text
    assert '/data/rec3</h3>' in text and '/data/rec0</h3>' in text          # the suspected recording is drawn
    assert 'Table cut at 5 of 12 runs' in text
    envelopes = [source for source in page_figures(page) if 'envelope_run' in source]
    assert len(envelopes) == 3 and 'rec3_envelope_run1.png' in envelopes     # the suspected run's spectrum first
    # The budget goes to the suspected recording first: 2 there, the 1 left to rec0.
    rec3 = text[text.index('/data/rec3</h3>'):]
    assert 'Envelope spectra of 2 of 3 runs drawn' in rec3 and 'Envelope spectra of 1 of 3 runs drawn' in text
