# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The random-case study's machinery (not its score): draws, one quick run end to end, the tables."""
import json

import numpy as np

from prsm_lube_ros.experiments import diagnose_study
from prsm_lube_ros.experiments.random_study import case_rng, confusion_markdown, summarise
from prsm_lube_ros.experiments.study_draws import draw_setup, recording_pairs


def test_draws_cover_the_contract_rates_and_are_reproducible():
    setups = [draw_setup(case_rng('none', seed)) for seed in range(40)]
    rates = {s.rig.vibration_rate for s in setups}
    assert min(rates) < 2500 and max(rates) > 10000
    for setup in setups:
        assert 3 <= len(setup.plan.speeds) <= 6 and 2 <= len(setup.plan.loads) <= 5
        assert 0.005 <= setup.rig.vibration_block <= 0.2
        assert 50 <= setup.rig.joint_state_rate <= 1000
        assert setup.rig.block_size == setup.rig.vibration_rate * setup.rig.vibration_block
        assert setup.rig.contact_mode_frequency < 0.45 * setup.rig.vibration_rate
    assert draw_setup(case_rng('resonance', 3)) == draw_setup(case_rng('resonance', 3))
    assert draw_setup(case_rng('resonance', 3)) != draw_setup(case_rng('none', 3))
    assert all(abs(r * b - round(r * b)) < 1e-6 for r, b in recording_pairs())


def test_quick_study_runs_cases_in_two_processes_and_writes_tables(tmp_path):
    out = tmp_path / 'study'
    assert diagnose_study.main(['--quick', '--out', str(out), '--jobs', '2',
                                '--effects', 'background_vibration', 'resonance']) == 0
    document = json.loads((out / 'results.json').read_text())
    kinds = sorted(case['kind'] for case in document['cases'])
    assert kinds == ['background_vibration', 'none', 'resonance', 'two']
    two = next(case for case in document['cases'] if case['kind'] == 'two')
    assert sorted(two['effects']) == ['background_vibration', 'resonance']
    for case in document['cases']:
        assert not case['verdict'].startswith('failed'), case['verdict']
        assert isinstance(case['right'], bool) and case['setup']['sample_rate'] > 0
    text = (out / 'confusion.md').read_text()
    assert '## Confusion per form' in text and '## Misses' in text
    assert document['summary']['cases'] == 4
    assert all(case['candidates'] and {'effect', 'status', 'reason', 'gain', 'delta_bic'} <= set(case['candidates'][0])
               for case in document['cases'])
    assert diagnose_study.main(['--out', str(out), '--margins']) == 0
    assert '## Margin 8' in (out / 'margins.md').read_text()
    # The case is simulated again as the quick study drew it: the same runs.
    assert diagnose_study.main(['--out', str(out), '--power', 'resonance', '--jobs', '1']) == 0
    resonance = next(case for case in document['cases'] if case['kind'] == 'resonance')
    rows = [line.split(' | ') for line in (out / 'power.md').read_text().splitlines()
            if line.startswith('| resonance | 0 |')]
    assert len(rows) == 1 and rows[0][2] == resonance['verdict'] and int(rows[0][4]) == resonance['runs']
    # A case marked missed is run again on this engine: the same recording, so the same verdict. Its record
    # without effects (a case that crashed in the study) takes them from the rerun.
    resonance['right'] = False
    resonance['effects'] = []
    (out / 'results.json').write_text(json.dumps(document))
    assert diagnose_study.main(['--out', str(out), '--rerun-misses', '--jobs', '1']) == 0
    rows = [line.split(' | ') for line in (out / 'rerun.md').read_text().splitlines()
            if line.startswith('| resonance | 0 |')]
    assert len(rows) == 1 and rows[0][3] == rows[0][4] == resonance['verdict'] and rows[0][2] == 'resonance'
    missed = sum(not case['right'] for case in document['cases'])
    assert f'of the {missed} cases the study missed are right now' in (out / 'rerun.md').read_text()


def test_margins_list_what_a_lower_bic_margin_would_let_in(tmp_path, capsys):
    from prsm_lube_ros.experiments.margins import margin_entrants, margins_markdown

    def candidate(effect, delta_bic, gain, status='rejected', reason='does not earn its 1 parameter(s)'):
        return {'effect': effect, 'status': status, 'gain': gain, 'delta_bic': delta_bic, 'reason': reason}
    records = [
        {'kind': 'lubricant_depletion', 'seed': 16, 'effects': ['lubricant_depletion'], 'verdict': 'adequate',
         'candidates': [candidate('lubricant_depletion', -8.2, 0.107), candidate('resonance', 8.0, -0.02)]},
        {'kind': 'thermal_viscosity', 'seed': 26, 'effects': ['thermal_viscosity'], 'verdict': 'thermal_viscosity',
         'candidates': [candidate('thermal_viscosity', -80.0, 0.5, status='earns'),
                        candidate('lubricant_depletion', -9.4, 0.113),
                        candidate('background_vibration', -9.0, 0.2, reason='unphysical constants'),
                        candidate('resonance', -7.0, 0.03)]}]
    at_8 = margin_entrants(records, 8.0)
    assert [(e['seed'], e['effect'], e['concealed']) for e in at_8] == [
        (16, 'lubricant_depletion', True), (26, 'lubricant_depletion', False)]
    assert margin_entrants(records, 9.0)[0]['seed'] == 26          # -8.2 does not reach a margin of 9
    assert '## Margin 8: 1 concealed, 1 not concealed' in margins_markdown(records, 'cmd')
    assert 'do not keep the candidates' not in margins_markdown(records, 'cmd')
    del records[0]['candidates'][0]['reason']                        # a study written before reasons were kept
    assert 'do not keep the candidates\' reasons' in margins_markdown(records, 'cmd')
    assert diagnose_study.main(['--out', str(tmp_path / 'absent'), '--margins']) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_tables_report_misses_and_wrong_names():
    records = [
        {'kind': 'resonance', 'seed': 0, 'effects': ['resonance'], 'forms': {'resonance': ''}, 'verdict': 'adequate',
         'named': [], 'right': False, 'gain': None, 'lack_of_fit': True, 'seconds': 1.0},
        {'kind': 'none', 'seed': 0, 'effects': [], 'verdict': 'resonance', 'named': ['resonance'], 'right': False,
         'gain': 0.1, 'lack_of_fit': False, 'seconds': 1.0},
        {'kind': 'two', 'seed': 0, 'effects': ['a', 'b'], 'verdict': 'a', 'named': ['a'], 'right': False,
         'gain': 0.5, 'seconds': 1.0}]
    summary = summarise(records)
    assert summary['right'] == 0 and summary['adequate_with_lack_of_fit'] == 1 and summary['lack_of_fit'] == 1
    assert summary['wrong_effect_named'] == 1 and summary['adequate_on_unaffected'] == 0
    text = confusion_markdown(records, 'cmd', 60.0, 2)
    assert '## Misses (3)' in text and 'one named' in text
    assert np.isclose(summary['kinds']['two']['median_gain'], 0.5)


def test_truth_forms_name_band_lines_and_recovery():
    from prsm_lube_ros.experiments.random_study import truth_form
    speeds = [10.0, 20.0]
    assert truth_form('resonance', {'order': 10.0, 'natural_frequency': 100.0}, speeds).startswith('mode above')
    assert truth_form('resonance', {'order': 10.0, 'natural_frequency': 5.0}, speeds).startswith('mode below')
    assert truth_form('background_vibration', {'tone_frequencies': [], 'broadband_share': 1.0}, speeds) == 'floor'
    assert truth_form('lubricant_depletion', {'form': 'linear', 'recovery_time': 300.0}, speeds) == \
        'linear, recovery at rest'
    assert truth_form('position_dependent_stiffness', {'arrangement': 'fixed-fixed'}, speeds) == 'fixed-fixed'


def _study_folder(folder, seeds, command):
    records = [{'kind': 'lubricant_depletion', 'seed': seed, 'effects': ['lubricant_depletion'],
                'forms': {'lubricant_depletion': 'linear'},
                'verdict': 'lubricant_depletion' if seed % 2 else 'adequate',
                'named': ['lubricant_depletion'] if seed % 2 else [], 'right': bool(seed % 2), 'gain': 0.3,
                'lack_of_fit': False, 'seconds': 10.0} for seed in seeds]
    folder.mkdir()
    (folder / 'results.json').write_text(json.dumps({'command': command, 'wall_seconds': 60.0, 'jobs': 2,
                                                     'cases': records}))


def test_combine_merges_studies_of_disjoint_seeds_and_refuses_a_case_twice(tmp_path, capsys):
    _study_folder(tmp_path / 'a', range(0, 3), 'study a')
    _study_folder(tmp_path / 'b', range(3, 6), 'study b')
    out = tmp_path / 'all'
    assert diagnose_study.main(['--out', str(out), '--combine', str(tmp_path / 'a'), str(tmp_path / 'b')]) == 0
    document = json.loads((out / 'results.json').read_text())
    assert [case['seed'] for case in document['cases']] == list(range(6))
    assert document['sources'] == ['study a', 'study b'] and document['wall_seconds'] == 120.0
    text = (out / 'confusion.md').read_text()
    assert '- `study a`' in text and '6 cases in 2.0 min' in text
    assert '| lubricant_depletion | 3/6 (50 %) | 19-81 % |' in text          # Wilson interval of 3 in 6
    capsys.readouterr()
    _study_folder(tmp_path / 'c', range(2, 4), 'study c')
    assert diagnose_study.main(['--out', str(tmp_path / 'x'), '--combine', str(tmp_path / 'a'),
                                str(tmp_path / 'c')]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'lubricant_depletion seed 2' in err[0] and not (tmp_path / 'x').exists()


def test_misses_say_what_the_ideal_test_does_on_the_recording():
    from prsm_lube_ros.experiments.effect_size import EffectSize
    from prsm_lube_ros.experiments.random_study import misses_markdown
    records = [{'kind': 'lubricant_depletion', 'seed': 13, 'effects': ['lubricant_depletion'], 'verdict': 'adequate',
                'right': False}]
    size = EffectSize(0.026, 0.0005, 0.039, 40, recorded_statistic=5.75).as_json()
    text = misses_markdown(records, [{'kind': 'lubricant_depletion', 'seed': 13, 'size': size}], 'cmd')
    assert '| 2.6 % | 3.9 % | 0.67 | 0.1 % | 5.8 of 13.7: misses |' in text


def test_cases_of_one_drawn_form_are_chosen_from_the_draws_alone():
    from prsm_lube_ros.experiments.random_study import case_forms
    args = diagnose_study._parser().parse_args(['--kinds', 'resonance', '--seeds', '2', '--first-seed', '50',
                                                '--form-contains', 'below the mesh band'])
    cases = diagnose_study._cases_of_form(['resonance'], ['resonance', 'background_vibration'], args)
    assert len(cases) == 2 and all(seed >= 50 for _, seed, _, _ in cases)
    for kind, seed, pool, quick in cases:
        assert 'below the mesh band' in case_forms(kind, seed, list(pool), quick=quick)[0]
    skipped = [seed for seed in range(50, max(seed for _, seed, _, _ in cases)) if seed not in {c[1] for c in cases}]
    assert all('below the mesh band' not in case_forms('resonance', seed, ['resonance'])[0] for seed in skipped)


def test_cases_holding_one_effect_are_chosen_by_its_id_whatever_its_form():
    from prsm_lube_ros.experiments.random_study import case_effect_forms
    pool = ['lubricant_depletion', 'resonance', 'surface_defect', 'thermal_viscosity']
    args = diagnose_study._parser().parse_args(['--kinds', 'two', '--seeds', '3', '--first-seed', '1500',
                                                '--form-contains', 'surface_defect'])
    cases = diagnose_study._cases_of_form(['two'], pool, args)
    assert len(cases) == 3
    chosen = {seed for _, seed, _, _ in cases}
    for seed in range(1500, max(chosen) + 1):
        drawn = case_effect_forms('two', seed, pool)
        assert ('surface_defect' in [name for name, _ in drawn]) == (seed in chosen)
        assert all('surface_defect' not in form for _, form in drawn)     # the form words never name the effect
