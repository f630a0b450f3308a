# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""prsm-lube diagnose end to end on small recordings of the rig simulator."""
import json
import re

import pytest

from prsm_lube_ros.cli import main
from prsm_lube_ros.experiments.diagnose_study import run_case
from prsm_lube_ros.simulation.recordings import draw_effects, simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan


def test_diagnose_command_writes_json_report_and_calibration(tmp_path, capsys):
    plan = ExperimentPlan(stage_thetas=(1.0, 1.0))
    effects = draw_effects(['position_dependent_stiffness'], seed=2, plan=plan)
    bags = simulate_experiment(tmp_path / 'sim', plan=plan, seed=2, effects=effects, run_order='random')
    out = tmp_path / 'diag.json'
    status = main(['diagnose', *map(str, bags), '--json', str(out), '--report', str(tmp_path / 'report'),
                   '--calibration-out', str(tmp_path / 'calib.yaml')])
    assert status == 0
    document = json.loads(out.read_text())
    assert document['verdict'] == 'position_dependent_stiffness'
    assert document['best']['cv_rmse'] < 0.7 * document['baseline']['cv_rmse']
    assert (tmp_path / 'report' / 'index.html').is_file()
    assert (tmp_path / 'report' / 'residual.png').stat().st_size > 1000
    assert 'position_dependent_stiffness' in (tmp_path / 'calib.yaml').read_text()
    printed = capsys.readouterr().out
    assert 'verdict: position_dependent_stiffness' in printed
    # Stiffness changes along the stroke: located inside runs, whatever the run-level lack-of-fit test says.
    assert 'lack of fit: ' in printed and 'located: the mismatch follows position' in printed
    assert document['location']['located'] == 'position' and document['adequacy']['baseline']['testable']
    # The rests between runs are read too: with the screw still the accelerometer gives its noise (0.003 m/s^2).
    assert document['data']['standstill_windows'] >= 3 and 0.001 < document['data']['standstill_rms'] < 0.006
    page = (tmp_path / 'report' / 'index.html').read_text()
    assert 'Lack of fit, paper' in page
    # The condition section (issue 34, item 5): every figure shown is a PNG beside the page; orders and resolution said.
    assert 'Condition indicators: is it lubrication or a surface defect?' in page
    assert '3.75x nut raceway or roller; 6.25x screw raceway' in page and 'only its absolute limits apply' in page
    assert 'orders per bin' in page and 'Hz per bin' in page and 'Demodulation band' in page
    sources = re.findall(r'<img src="([^"]+)"', page)
    assert all((tmp_path / 'report' / src).read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' for src in sources)
    for kind in ('condition_trends_all', 'order_spectrum', 'waterfall_envelope', 'waterfall_order', 'envelope_run'):
        assert any(kind in src for src in sources), kind


def test_diagnose_missing_bag_is_one_line_error(tmp_path, capsys):
    status = main(['diagnose', str(tmp_path / 'nothing.mcap'), '--json', str(tmp_path / 'x.json')])
    assert status != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and 'nothing.mcap' in err


@pytest.mark.parametrize('effect', ['none', 'resonance', 'thermal_viscosity', 'lubricant_depletion',
                                    'background_vibration'])
def test_rig_recordings_with_one_concealed_effect(effect):
    record = run_case(('rig', effect, 5, 'random', 2))
    assert record['verdict'] == (effect if effect != 'none' else 'adequate')


def test_a_candidate_refuted_by_a_measurement_says_why_in_the_terminal_table():
    """A floor the standstill does not show fits best yet is rejected: its row gives the reason, not only scores."""
    import dataclasses

    import numpy as np

    from prsm_lube_ros.cli.diagnose import candidate_lines
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    table, _ = synthetic_table(np.random.default_rng(3), 'background_vibration', SyntheticPlan(spectrum_bins=128),
                               params={'form': 'broadband floor', 'fraction': 0.6})
    result = diagnose_table(dataclasses.replace(table, rest_rms=1e-4, rest_windows=10))
    lines = candidate_lines(result.candidates)
    background, = [line for line in lines if line.startswith('background_vibration')]
    assert 'rejected' in background and '% ' in background
    assert background.endswith('which vibration from elsewhere would keep there)')
    assert '(the fit contradicts a measurement: standstill: with the screw still' in background
    # Rows rejected by their scores keep the compact form.
    by_scores = [c.effect.id for c in result.candidates if c.fit is not None and c.decisions[-1].rule == 'bic_margin'
                 and c.effect.id != 'background_vibration']
    assert by_scores
    for effect_id in by_scores:
        line, = [line for line in lines if line.startswith(effect_id + ' ')]
        assert '(' not in line


def test_a_candidate_named_against_the_paper_model_held_physical_says_so_in_the_terminal_table():
    """Its scores against the free fit are poor (BIC about 0): the row carries the reason with the null's scores."""
    import dataclasses

    import numpy as np

    from prsm_lube_ros.cli.diagnose import candidate_lines
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    plan = dataclasses.replace(SyntheticPlan(spectrum_bins=128), window_noise=0.2, run_noise=0.02,
                               speeds_rpm=(100.0, 125.0, 150.0, 175.0))
    table, _ = synthetic_table(np.random.default_rng(1), 'resonance', plan,
                               params={'top_ratio': 0.8, 'damping_ratio': 0.1, 'top_speed': 175 * np.pi / 30})
    result = diagnose_table(table)
    assert result.verdict == 'resonance'
    resonance, = [line for line in candidate_lines(result.candidates) if line.startswith('resonance ')]
    assert 'earns' in resonance and "against it held physical, held-out error" in resonance
