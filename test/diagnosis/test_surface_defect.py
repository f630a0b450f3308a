# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The surface-defect candidate: its law, its evidence in the condition indicators, and the engine's verdicts."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from prsm_lube_ros.diagnosis.effects import get_effect
from prsm_lube_ros.diagnosis.effects import surface_defect as candidate
from prsm_lube_ros.diagnosis.effects.base import Effect
from prsm_lube_ros.diagnosis.engine import diagnose_table
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
from prsm_lube_ros.physics.effects import surface_defect as law

PARAMS = {'impulsive_rms': 0.3, 'reference_speed': 10.0, 'reference_load': 100.0, 'speed_exponent': 1.0,
          'load_exponent': 0.5, 'growth_per_revolution': 0.0, 'linear': 0.0}


class _Table(SimpleNamespace):
    """A stand-in for a window table with condition-indicator columns (NaN where unknown)."""

    def __len__(self):
        return len(self.speed)


def table_of(kurtosis, defect_db=None, n=40):
    peaks = np.full(n, np.nan) if defect_db is None else np.broadcast_to(np.asarray(defect_db, dtype=float), (n,))
    return _Table(kurtosis=np.broadcast_to(np.asarray(kurtosis, dtype=float), (n,)), defect_db=peaks,
                  defect_order=np.full(n, 6.25), revolutions=np.linspace(0.0, 500.0, n), speed=np.full(n, 10.0),
                  load=np.full(n, 100.0), rms=np.full(n, 0.5), recording=np.zeros(n, dtype=int))


def test_impulsive_power_adds_to_the_contacts_and_is_removed_in_power():
    effect = get_effect('surface_defect')
    windows = SimpleNamespace(speed=np.array([10.0, 20.0]), load=np.array([100.0, 400.0]),
                              revolutions=np.array([0.0, 0.0]))
    # P_imp = 0.3^2 (2)^2 (4)^1 at the second window: 0.3 x 2 x 2 = 1.2 m/s^2 RMS.
    assert effect.power(PARAMS, windows) == pytest.approx([0.09, 1.44])
    ln_a22 = np.log([0.4, 1.6])
    total = np.exp(ln_a22 + effect.log_gain(PARAMS, windows, ln_a22))
    assert total == pytest.approx([0.5, 2.0])
    assert effect.eq22_amplitude(PARAMS, windows, total) == pytest.approx([0.4, 1.6])
    assert effect.assessment_film_factor(PARAMS, windows) == 1.0      # a defect is no lubrication change


def test_growth_counts_the_revolutions_over_the_recordings_in_order():
    revolutions = np.array([0.0, 100.0, 200.0, 0.0, 150.0])
    recording = np.array([0, 0, 0, 1, 1])
    assert law.cumulative_revolutions(revolutions, recording) == pytest.approx([0, 100, 200, 200, 350])
    grown = dict(PARAMS, growth_per_revolution=1 / 350)
    windows = SimpleNamespace(speed=np.full(5, 10.0), load=np.full(5, 100.0), revolutions=revolutions,
                              recording=recording)
    assert get_effect('surface_defect').power(grown, windows)[-1] == pytest.approx(0.09 * math.e ** 2)


def test_without_condition_indicators_the_defect_is_not_testable():
    table = table_of(np.nan)
    assert 'condition indicators' in get_effect('surface_defect').applicable(table)
    assert get_effect('surface_defect').independent_evidence(table, None) == ''
    assert get_effect('surface_defect').contrary_evidence(table, None) == ''
    bare = _Table(**{k: v for k, v in vars(table).items() if k not in ('kurtosis', 'defect_db', 'defect_order')})
    assert candidate.indicators(bare) is None


def test_impulsive_windows_are_evidence_and_gaussian_ones_are_evidence_against():
    effect = get_effect('surface_defect')
    late = np.where(np.arange(40) >= 25, 8.0, 3.0)          # a growing defect: the last 15 windows impulsive
    assert effect.independent_evidence(table_of(late), None).startswith('condition indicators: 38 % of the windows')
    assert effect.contrary_evidence(table_of(late), None) == ''
    peaks = effect.independent_evidence(table_of(3.0, defect_db=18.0), None)
    assert 'envelope peaks 18 dB' in peaks and 'order 6.25' in peaks
    healthy = table_of(3.0 + 0.1 * np.sin(np.arange(40)), defect_db=4.0)
    assert effect.independent_evidence(healthy, None) == ''
    assert 'not impulsive' in effect.contrary_evidence(healthy, None)


def test_envelope_lines_at_one_speed_of_several_are_no_defect_evidence():
    # a band fixed in Hz (a mode ringing) meets a defect order at one speed only; strikes keep their order
    effect = get_effect('surface_defect')
    speeds = np.repeat([10.0, 15.0, 22.0], 14)[:40]
    one_speed = table_of(3.0, defect_db=np.where(speeds == 10.0, 15.0, 4.0))
    one_speed.speed = speeds
    assert effect.independent_evidence(one_speed, None) == ''
    two_speeds = table_of(3.0, defect_db=np.where(speeds < 20.0, 15.0, 4.0))
    two_speeds.speed = speeds
    assert 'envelope peaks 15 dB' in effect.independent_evidence(two_speeds, None)


def test_run_lines_below_the_runs_unexplained_lines_are_no_evidence_for_a_defect_nor_against_it():
    # study two 1757: a mode and thermal thinning, lines of 12 dB at the roller-pass order in every run beside
    # lines of 15 dB at orders no component explains; the defect's evidence is not there, and nothing impulsive is
    effect = get_effect('surface_defect')
    speeds = np.repeat([10.0, 15.0, 22.0], 14)[:40]
    crowded = table_of(3.0, defect_db=12.0)
    crowded.speed, crowded.run_defect_db, crowded.run_unexplained_db = speeds, np.full(40, 12.0), np.full(40, 15.0)
    assert candidate.unspecific_lines(candidate.indicators(crowded)).all()
    assert effect.independent_evidence(crowded, None) == ''
    assert effect.contrary_evidence(crowded, None) == ''     # lines at a defect order are there: none against
    # the same lines as high as the runs' unexplained ones are evidence, as are those of a table built before
    # the column (NaN: nothing to judge them against)
    clear = table_of(3.0, defect_db=12.0)
    clear.speed, clear.run_defect_db, clear.run_unexplained_db = speeds, np.full(40, 12.0), np.full(40, 12.0)
    assert 'envelope peaks 12 dB' in effect.independent_evidence(clear, None)
    clear.run_unexplained_db = np.full(40, np.nan)
    assert 'envelope peaks 12 dB' in effect.independent_evidence(clear, None)


def test_beside_a_defect_a_spectral_shape_change_is_no_background_evidence():
    background = get_effect('background_vibration')
    location = SimpleNamespace(spectrum=None, shape=SimpleNamespace(floor_added=True, note='the shape changes'))
    table = table_of(3.0)
    assert background.spectral_evidence(table, location) == 'spectrum: the shape changes'
    assert background.spectral_evidence(table, location, beside=get_effect('surface_defect')) == ''


def _verdict(kind, seed):
    table, truth = synthetic_table(np.random.default_rng(seed), kind,
                                   plan=SyntheticPlan(condition_indicators=True, sessions=2))
    return diagnose_table(table), truth


def test_the_engine_names_a_growing_defect_where_the_windows_are_impulsive_not_depletion():
    diagnosis, truth = _verdict('surface_defect', 2)
    assert truth['params']['law']['growth'] != 'steady'
    assert diagnosis.verdict == 'surface_defect'
    depletion = next(c for c in diagnosis.candidates if c.effect.id == 'lubricant_depletion')
    assert depletion.status.value != 'earns' or diagnosis.verdict != 'lubricant_depletion'


@pytest.mark.parametrize('seed, form', [(6, 'growing linearly with revolutions'), (2, 'growing with revolutions')])
def test_a_defect_growing_linearly_is_fitted_in_its_linear_form(seed, form):
    """The simulator grows a spall exponentially or linearly; the candidate has both forms, and each is chosen where
    it was drawn (seed 6: linear, N_g 287 revolutions; seed 2: exponential, N_g 323)."""
    diagnosis, truth = _verdict('surface_defect', seed)
    assert truth['params']['law']['growth'] == ('linear' if 'linearly' in form else 'exponential')
    assert diagnosis.verdict == 'surface_defect' and diagnosis.chosen.form == form
    assert diagnosis.chosen.fit.params['linear'] == (1.0 if 'linearly' in form else 0.0)


def test_the_engine_keeps_naming_depletion_where_nothing_is_impulsive():
    diagnosis, _ = _verdict('lubricant_depletion', 2)
    assert diagnosis.verdict == 'lubricant_depletion'
    defect = next(c for c in diagnosis.candidates if c.effect.id == 'surface_defect')
    assert defect.status.value != 'earns'


def test_window_indicators_leave_the_other_columns_of_a_synthetic_table_as_they_were():
    plain, _ = synthetic_table(np.random.default_rng(4), 'lubricant_depletion', plan=SyntheticPlan(sessions=2))
    marked, _ = synthetic_table(np.random.default_rng(4), 'lubricant_depletion',
                                plan=SyntheticPlan(sessions=2, condition_indicators=True))
    assert np.array_equal(plain.rms, marked.rms) and np.array_equal(plain.speed, marked.speed)
    assert not plain.has_indicators and marked.has_indicators
    assert abs(np.median(marked.kurtosis) - 3.0) < 0.05          # Gaussian contact vibration


def test_the_window_level_simulator_measures_the_gaussian_part_without_the_strikes():
    plain, _ = synthetic_table(np.random.default_rng(4), 'lubricant_depletion',
                               plan=SyntheticPlan(sessions=2, condition_indicators=True))
    assert np.median(plain.gaussian_rms / plain.rms) == pytest.approx(1.0, abs=0.01)
    struck, truth = synthetic_table(np.random.default_rng(2), 'surface_defect',
                                    plan=SyntheticPlan(sessions=2, condition_indicators=True))
    share = (struck.gaussian_rms / struck.rms) ** 2
    impulsive = struck.kurtosis > 4.5
    assert impulsive.any() and np.median(share[impulsive]) < 0.9 < np.median(share[~impulsive])


def test_a_shape_change_does_not_tie_background_with_a_defect(tmp_path):
    """A steady roller spall (study case surface_defect 1307) against a background that only the shape supports.

    Both fit the amplitudes alike and both have evidence alone: the defect its
    impulsive windows and envelope lines at the roller order, the background a
    spectral shape change, which the strikes give by themselves.  Counted
    beside each other, only the defect's holds, so it is named (it was
    ``ambiguous`` before).  That is the case without a standstill recorded; with
    it, the background's fit is refuted before any tie: the accelerometer reads
    far less than B with the screw still (rule ``measured_against``).
    """
    import dataclasses
    from prsm_lube_ros.diagnosis.effects import candidate_ids
    from prsm_lube_ros.diagnosis.engine import Status
    from prsm_lube_ros.experiments.random_study import case_recordings, case_table, simulate_case, truth_form
    paths, setup, names, truth = simulate_case('surface_defect', 1307, list(candidate_ids()), folder=tmp_path)
    assert truth_form('surface_defect', truth['surface_defect'], setup.plan.speeds) == 'roller,steady'
    table = case_table(paths, case_recordings(paths, setup))
    assert table.rest_windows >= 3
    for rest_recorded in (True, False):
        tried = table if rest_recorded else dataclasses.replace(table, rest_rms=math.nan, rest_windows=0)
        result = diagnose_table(tried)
        background, = [c for c in result.candidates if c.effect.id == 'background_vibration']
        assert background.evidence.startswith('spectrum: the spectral shape changes')   # evidence alone ...
        assert (result.verdict, result.confident) == ('surface_defect', True)      # ... that does not tie
        if rest_recorded:
            assert background.status == Status.REJECTED and background.decisions[-1].rule == 'measured_against'
        else:
            assert any('decided by evidence from outside the fit: surface_defect' in n for n in result.notes)


def _depletion_struck(share, seed=2):
    """A depletion table whose band kurtosis is impulsive in ``share`` of the windows (strikes too small for the RMS).

    The amplitudes are depletion's alone: a spall whose power is a small share
    of the RMS (study case two 1336 of block 1330) leaves nothing for its
    amplitude law beside depletion, only its impulsiveness.
    """
    from dataclasses import replace
    table, _ = synthetic_table(np.random.default_rng(seed), 'lubricant_depletion',
                               plan=SyntheticPlan(condition_indicators=True, sessions=2))
    struck = np.random.default_rng(seed + 100).random(len(table)) < share
    return replace(table, kurtosis=np.where(struck, 9.0, table.kurtosis))


def test_impulsiveness_in_most_windows_names_the_defect_beside_the_first_effect():
    """Evidence no other effect makes puts the defect beside depletion even when depletion leaves nothing.

    Before the rule only a candidate with vibration at standstill was tried
    when the first effect left no lack of fit (study case two 1336 of block
    1330: depletion alone, 82 % of the windows impulsive).
    """
    from dataclasses import replace
    from prsm_lube_ros.diagnosis import DEFAULT_RULES
    table = _depletion_struck(0.8)
    diagnosis = diagnose_table(table)
    assert diagnosis.verdict == 'lubricant_depletion'
    second = diagnosis.second
    assert second is not None and second.effect.id == 'surface_defect'
    assert 'impulsive' in second.basis
    assert [e['effect'] for e in diagnosis.as_json()['effects']] == ['lubricant_depletion', 'surface_defect']
    # the rule is one field: asking every window to be struck names depletion alone
    strict = diagnose_table(table, rules=replace(DEFAULT_RULES, exclusive_evidence_share=1.0))
    assert strict.verdict == 'lubricant_depletion' and strict.second is None


def _struck_where(table, where):
    """``table`` with band kurtosis 9 in the windows of the (speed level, load level) conditions ``where``."""
    from dataclasses import replace
    from prsm_lube_ros.estimation.calibration import operating_levels
    speeds, loads = operating_levels(np.abs(table.speed)), operating_levels(np.abs(table.load))
    speed_level = np.argmin(np.abs(np.abs(table.speed)[:, None] - np.array(speeds)[None, :]), axis=1)
    load_level = np.argmin(np.abs(np.abs(table.load)[:, None] - np.array(loads)[None, :]), axis=1)
    struck = np.zeros(len(table), bool)
    for speed, load in where:
        struck |= (speed_level == speed) & (load_level == load)
    return replace(table, kurtosis=np.where(struck, 9.0, table.kurtosis)), struck


def test_a_defect_shown_at_the_fastest_speed_only_counts_by_its_conditions_not_its_windows():
    """A traverse holds windows as 1 / speed, so the fastest conditions hold the fewest windows.

    Study two 1877: every window at the fastest of five speeds impulsive (kurtosis 6-15), none at the slowest;
    18 % of all windows, 27 % of each condition's on average.  Here 3 speeds x 2 loads with 80, 52 and 40
    windows per condition: struck at the fastest speed, 23 % of the windows and a third of the conditions.
    """
    depletion, _ = synthetic_table(np.random.default_rng(2), 'lubricant_depletion',
                                   plan=SyntheticPlan(condition_indicators=True, sessions=2))
    table, struck = _struck_where(depletion, [(2, 0), (2, 1)])
    assert struck.mean() < candidate.IMPULSIVE_SHARE        # by windows no evidence ...
    assert candidate.condition_share(table, struck) == pytest.approx(1 / 3)
    effect = get_effect('surface_defect')
    assert 'impulsive' in effect.independent_evidence(table, None)      # ... by conditions a third
    assert effect.contrary_evidence(table, None) == ''
    assert effect.exclusive_evidence(table, 0.5) == ''
    assert effect.independent_evidence(depletion, None) == ''
    assert effect.contrary_evidence(depletion, None) != ''


def test_a_window_off_the_plan_is_no_condition_of_its_own():
    """One impulsive window at a speed of its own would weigh as a third of a plan of two conditions."""
    kurtosis = np.r_[np.full(80, 3.0), 9.0]
    table = _Table(kurtosis=kurtosis, speed=np.r_[np.full(40, 10.0), np.full(40, 20.0), 30.0], load=np.full(81, 100.0))
    impulsive = kurtosis > candidate.IMPULSIVE_KURTOSIS
    assert candidate.condition_share(table, impulsive) == 0.0
    few = _Table(kurtosis=kurtosis[-4:], speed=np.array([10.0, 20.0, 30.0, 30.0]), load=np.full(4, 100.0))
    assert candidate.condition_share(few, impulsive[-4:]) == 0.25     # no condition of 3 windows: by windows


def test_a_defect_struck_in_half_the_conditions_is_named_beside_depletion():
    """Half the conditions struck (both loads at the fastest speed, one at the middle): 38 % of the windows."""
    depletion, _ = synthetic_table(np.random.default_rng(2), 'lubricant_depletion',
                                   plan=SyntheticPlan(condition_indicators=True, sessions=2))
    table, struck = _struck_where(depletion, [(2, 0), (2, 1), (1, 1)])
    assert struck.mean() < 0.5
    diagnosis = diagnose_table(table)
    assert diagnosis.verdict == 'lubricant_depletion'
    assert diagnosis.second is not None and diagnosis.second.effect.id == 'surface_defect'
    assert 'per operating condition' in diagnosis.second.basis


class _Oversized(candidate.SurfaceDefectCandidate):
    """A defect law that cannot follow small impulsive power: its impulsive RMS is at least the smallest window's."""

    def bounds(self):
        low, high = super().bounds()
        return np.r_[1.0, low[1:]], high

    def starts(self):
        return [np.r_[1.2, start[1:]] for start in super().starts()]

    def variants(self):
        return [self]


def test_a_defect_shown_by_its_evidence_alone_is_named_with_its_share_of_the_rms_unresolved(tmp_path):
    """The amplitude law predicts held-out runs far worse beside depletion; the impulsiveness still names it.

    The model and the calibration stay depletion's alone, and the words (JSON and report page) say the share is
    unresolved.
    """
    from prsm_lube_ros.diagnosis import write_report
    from prsm_lube_ros.diagnosis.effects import registered
    effects = dict(registered(), surface_defect=_Oversized())
    diagnosis = diagnose_table(_depletion_struck(0.8), effects=effects)
    assert diagnosis.verdict == 'lubricant_depletion'
    second = diagnosis.second
    assert second is not None and second.effect.id == 'surface_defect' and second.unresolved
    assert 'which no other effect makes' in second.basis
    assert 'not kept' in second.basis or 'no fit with physical constants' in second.basis
    named = diagnosis.as_json()['effects']
    assert named[1]['share_unresolved'] and named[1]['params'] == {} and 'unresolved' in named[1]['explanation']
    assert [text for _, _, text in diagnosis.named_descriptions()][1] == second.explanation
    assert second.fit is diagnosis.chosen.fit      # the model is the first effect's alone ...
    calibration = diagnosis.calibration().extension
    assert calibration['effect'] == 'lubricant_depletion' and 'effects' not in calibration     # ... and so is theta
    page = write_report(diagnosis, tmp_path).with_suffix('.md').read_text()
    assert 'share of the RMS unresolved' in page and second.explanation in page


def test_impulsiveness_in_few_windows_does_not_name_the_defect_beside_the_first_effect():
    """A third of the windows impulsive is evidence beside a fit, not enough to be tried where nothing is left."""
    diagnosis = diagnose_table(_depletion_struck(0.35))
    defect = next(c for c in diagnosis.candidates if c.effect.id == 'surface_defect')
    assert defect.evidence and not defect.effect.exclusive_evidence(diagnosis.table, 0.5)
    assert diagnosis.verdict == 'lubricant_depletion'
    assert diagnosis.second is None


BIG = dict(PARAMS, impulsive_rms=0.49)      # 0.49^2 / 0.5^2: the fitted strikes carry 96 % of each window's power


def _measured(gaussian_share, n=40):
    """``table_of`` with the band signal's Gaussian part measured at ``gaussian_share`` of each window's power."""
    table = table_of(3.0, n=n)
    table.gaussian_rms = np.sqrt(gaussian_share) * table.rms
    return table


def test_a_fit_that_silences_the_contacts_where_the_windows_measure_them_is_refuted():
    """The fit's Gaussian part (its amplitude, here the RMS, without P_imp) against the measured one."""
    effect = get_effect('surface_defect')
    fitted = np.full(40, 0.5)
    refuted = effect.measured_against(_measured(0.95), BIG, fitted)
    assert 'Gaussian part' in refuted and '4.2 %' in refuted    # 4 % of the power against 95 %: 4.2 % of it
    assert effect.measured_against(_measured(0.3), BIG, fitted) == ''        # 4 % against 30 %: 13 %, within 10 dB
    assert effect.measured_against(_measured(0.95), PARAMS, fitted) == ''    # the fit leaves the contacts 64 %
    assert effect.measured_against(_measured(math.nan), BIG, fitted) == ''   # not measured: not testable
    assert effect.measured_against(_measured(0.95), BIG) == ''               # no fitted amplitude: not testable


@pytest.mark.parametrize('share, refuted', [(0.2, False), (0.3, True)])
def test_the_gaussian_part_refutes_a_fit_that_silences_the_contacts_in_a_quarter_of_the_windows(share, refuted):
    """The fitted strikes take the whole power only at the highest load; below it the fit leaves the contacts most."""
    table = _measured(0.95)
    high = np.arange(len(table)) < share * len(table)
    table.load = np.where(high, 100.0, 25.0)     # load exponent 0.5: a quarter of the strikes' power at 25 N
    assert bool(get_effect('surface_defect').measured_against(table, BIG, np.full(40, 0.5))) is refuted


def test_a_pair_answers_for_what_a_measurement_says_against_either_of_its_effects():
    from prsm_lube_ros.diagnosis.combined import CombinedEffect
    both = CombinedEffect(get_effect('lubricant_depletion'), get_effect('surface_defect'))
    params = {'first': {}, 'second': {}}
    params['first' if both.first.id == 'surface_defect' else 'second'] = BIG
    assert 'Gaussian part' in both.measured_against(_measured(0.95), params, np.full(40, 0.5))
    assert both.measured_against(_measured(0.3), params, np.full(40, 0.5)) == ''


class _LoadGain(Effect):
    """A law linear in load, ``ln A += g F / F_max``: it trades g against C_F, and a measurement caps g at 0.5."""

    id = 'load_gain'
    title = 'load gain'
    form = 'linear in load'
    parameter_names = ('gain',)
    covariate = 'load'
    trades_load_excitation = True

    def scales(self, table):
        return {'load_scale': float(np.max(np.abs(table.load)))}

    def bounds(self):
        return np.array([0.0]), np.array([5.0])

    def starts(self):
        return [np.array([2.0])]

    def to_params(self, p, scales):
        return {'gain': float(p[0]), **scales}

    def log_gain(self, params, covariates, ln_a22):
        return params['gain'] * np.abs(np.asarray(covariates.load, dtype=float)) / params['load_scale']

    def measured_against(self, table, params, predicted=None):
        return f'measured: the gain is 0.5 at most, fitted {params["gain"]:.2f}' if params['gain'] > 0.5 else ''


def test_a_fit_a_measurement_contradicts_is_fitted_again_with_the_load_excitation_held_physical():
    """Free, the law's g = 2 (its start) and C_F goes below 0 to pay for it; held at C_F >= 0, g fits under 0.5.

    The rig's own C_F is 1e-3 1/N (0.2 at its 200 N): g + C_F F_max is what the amplitudes fix.
    """
    from prsm_lube_ros.diagnosis.fitting import fit_model
    from prsm_lube_ros.physics.vibration_model import ModelConstants
    table, _ = synthetic_table(np.random.default_rng(3), None,
                               plan=SyntheticPlan(sessions=2, constants=ModelConstants(0.02, 1.0e-3, 0.33)))
    free = fit_model(table, _LoadGain(), folds=[])
    assert free.params['gain'] > 1.0 and free.vector[1] < 0.0
    assert _LoadGain().measured_against(table, free.params)
    diagnosis = diagnose_table(table, effects={'load_gain': _LoadGain()})
    candidate_fit = diagnosis.candidates[0].fit
    assert candidate_fit.excitation and candidate_fit.vector[1] >= 0.0 and candidate_fit.params['gain'] <= 0.5
    assert all(d.rule != 'measured_against' for d in diagnosis.candidates[0].decisions)


def test_a_mode_beside_a_spall_is_named_in_the_gaussian_part():
    """A mode below the band the orders sweep, beside a spall: the whole RMS names the spall alone.

    The spall's free exponents and the constants take the mode's fall with
    speed; the windows' Gaussian part (the strikes left out) shows the mode
    alone, and the engine names it there (study cases two 1710, 1532 ...).
    With the rule off (a share no table reaches) the mode goes unnamed.
    """
    from dataclasses import replace
    from prsm_lube_ros.diagnosis import DEFAULT_RULES
    table, truth = synthetic_table(np.random.default_rng(0), ('resonance', 'surface_defect'),
                                   plan=SyntheticPlan(condition_indicators=True, sessions=2))
    assert truth['params']['resonance']['top_ratio'] > 1.0      # the mode is below the band at the top speed
    diagnosis = diagnose_table(table)
    assert diagnosis.verdict == 'surface_defect'
    second = diagnosis.second
    assert second is not None and second.effect.id == 'resonance' and second.route == 5
    assert "Gaussian part" in second.basis
    assert [e['effect'] for e in diagnosis.as_json()['effects']] == ['surface_defect', 'resonance']
    off = diagnose_table(table, rules=replace(DEFAULT_RULES, gaussian_part_share=1.01))
    assert off.verdict == 'surface_defect' and off.second is None


def test_the_gaussian_part_of_a_spall_alone_names_nothing_beside_it():
    """Dense strikes raise the measured Gaussian part with speed and load; no effect is named from it."""
    diagnosis, _ = _verdict('surface_defect', 5)
    assert diagnosis.verdict == 'surface_defect' and diagnosis.second is None


def test_the_gaussian_part_is_the_table_without_strikes():
    table, _ = synthetic_table(np.random.default_rng(2), 'surface_defect',
                               plan=SyntheticPlan(sessions=2, condition_indicators=True))
    part = table.gaussian_part()
    assert len(part) == len(table) and np.array_equal(part.rms, table.gaussian_rms)
    from prsm_lube_ros.diagnosis.table import INDICATOR_COLUMNS
    assert part.spectra is None and all(np.isnan(getattr(part, name)).all() for name in INDICATOR_COLUMNS)
    assert np.array_equal(part.speed, table.speed)
    assert part.rest_rms == table.rest_rms or (np.isnan(part.rest_rms) and np.isnan(table.rest_rms))
    gaps = table.gaussian_rms.copy()
    gaps[::4] = np.nan
    from dataclasses import replace
    assert len(replace(table, gaussian_rms=gaps).gaussian_part()) == len(table) - len(gaps[::4])


def test_a_second_named_in_the_gaussian_part_without_a_physical_pair_fit_leaves_its_share_unresolved():
    """The mode shows in the Gaussian part, but no joint fit with the spall on the whole RMS has physical constants.

    The mode is named with its share of the RMS unresolved: the model and the calibration stay the spall's alone,
    and the words say where it was shown.
    """
    table, _ = synthetic_table(np.random.default_rng(7), ('resonance', 'surface_defect'),
                               plan=SyntheticPlan(condition_indicators=True, sessions=2))
    diagnosis = diagnose_table(table)
    second = diagnosis.second
    assert diagnosis.verdict == 'surface_defect'
    assert second is not None and second.route == 5 and second.unresolved and second.combined is None
    assert second.fit is diagnosis.chosen.fit and second.params == {}
    entry = diagnosis.as_json()['effects'][1]
    assert entry['effect'] == 'resonance' and entry['share_unresolved'] and not entry['params']
    assert "in the windows' Gaussian part" in entry['explanation']
    assert 'effects' not in diagnosis.calibration().extension
    assert diagnosis.calibration().extension['effect'] == 'surface_defect'


def test_a_table_of_recorded_windows_carries_each_runs_strike_and_unexplained_lines(paper_experiment):
    from prsm_lube_ros.diagnosis.table import runs_of, table_from_windows
    from prsm_lube_ros.estimation.defect_screen import run_condition, strike_line, unexplained_level
    from prsm_lube_ros.estimation.pipeline import recording_windows
    from prsm_lube_ros.estimation.windowing import DEFAULT_DEFECT_ORDERS as orders
    windows = recording_windows(paper_experiment / 'stage_3', lead=0.005).windows
    table = table_from_windows([windows])
    assert np.isfinite(table.run_unexplained_db).all() and np.isfinite(table.run_defect_db).all()
    assert (table.run_unexplained_db > 0).any()        # healthy runs hold lines no component explains
    checked = 0
    for run, members in runs_of([w for w in windows if w.steady]).items():
        condition = run_condition([w.condition for w in members if w.condition is not None], orders)
        line = strike_line(condition.envelope_peaks, orders, condition.order_resolution)
        rows = np.isin(table.time, [0.5 * (w.start + w.end) - min(x.start for x in windows) for w in members])
        if rows.any():
            assert table.run_unexplained_db[rows] == pytest.approx(unexplained_level(condition.envelope_peaks))
            assert table.run_defect_db[rows] == pytest.approx(line.db if line is not None else 0.0)
            checked += 1
    assert checked >= 6
    assert np.isnan(table.gaussian_part().run_unexplained_db).all()
