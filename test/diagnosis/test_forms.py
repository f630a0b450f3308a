# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every physical form of each effect is named with its form; two effects at once are named together."""
import json
import math

import numpy as np
import pytest

from prsm_lube_ros.diagnosis import diagnose_table
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table

PLAN = SyntheticPlan(spectrum_bins=128)
TOP = 200 * math.pi / 30
#: Short rests and three repeats: nut and oil warm by about 30 K, enough to show a curved viscosity law.
WARM = SyntheticPlan(rest=5.0, repeats=3)


def diagnose(effect, params, seed=3, plan=PLAN):
    table, _ = synthetic_table(np.random.default_rng(seed), effect, plan, params=params)
    result = diagnose_table(table)
    document = json.loads(json.dumps(result.as_json(), allow_nan=False))
    return result, document


@pytest.mark.parametrize('arrangement, form', [
    ('fixed-free', 'fixed-free, fixed bearing beyond the stroke end'),
    ('free-fixed', 'fixed-free, fixed bearing before the stroke start'),
])
def test_fixed_free_shaft_is_named_with_the_end_of_its_fixed_bearing(arrangement, form):
    params = {'arrangement': arrangement, 'bearing_before': 0.03, 'bearing_after': 0.03, 'contact_ratio': 1.2}
    result, document = diagnose('position_dependent_stiffness', params)
    assert document['verdict'] == 'position_dependent_stiffness'
    assert document['best']['form'] == form and document['effects'][0]['form'] == form
    # Every arrangement was fitted; the fixed bearing at the other end fits far worse (fixed-fixed with one
    # bearing far away comes close to fixed-free, but has a parameter more).
    forms = {f['form']: f['delta_bic'] for f in document['candidates'][0]['forms']}
    other = next(k for k in forms if k.startswith('fixed-free') and k != form)
    assert len(forms) == 3 and forms[other] > 50 and forms['fixed-fixed'] > 0
    assert result.chosen.fit.params['contact_over_ea'] == pytest.approx(1.2, rel=0.3)


@pytest.mark.parametrize('top_ratio, band', [(0.6, 'above'), (1.4, 'inside'), (3.5, 'below')])
def test_resonance_is_placed_above_inside_or_below_the_speed_band(top_ratio, band):
    params = {'top_ratio': top_ratio, 'damping_ratio': 0.05, 'top_speed': TOP}
    result, document = diagnose('resonance', params)
    assert document['verdict'] == 'resonance'
    assert document['best']['form'].startswith(f'mode {band} the speed band')
    # The resonant speed (whatever the order that excites the mode) on the named side of the band.
    resonant, bottom = result.chosen.fit.params['resonant_speed'], TOP / 2
    assert {'above': resonant > TOP, 'inside': bottom < resonant < TOP, 'below': resonant < bottom}[band]
    if band == 'inside':
        assert resonant == pytest.approx(TOP / top_ratio, rel=0.1)
    assert 'order 2' in document['best']['explanation']


@pytest.mark.parametrize('form', ['fixed-frequency lines', 'broadband floor', 'lines and broadband floor'])
def test_background_is_named_as_lines_or_floor_from_the_spectrum(form):
    params = {'fraction': 0.8, 'tones': (480.0, 870.0), 'form': form}
    _, document = diagnose('background_vibration', params)
    assert document['verdict'] == 'background_vibration'
    assert document['best']['form'] == form


def test_curved_viscosity_law_is_preferred_to_the_exponential_when_the_oil_warms_enough():
    vogel = {'rise': 45.0, 'tau': 120.0, 'beta': 0.035, 'law': 'vogel', 'shape': 60.0}
    _, document = diagnose('thermal_viscosity', vogel, plan=WARM)
    assert document['verdict'] == 'thermal_viscosity'
    assert document['best']['form'] == 'Vogel'
    assert document['best']['params']['vogel_distance'] == pytest.approx(60.0, rel=0.3)
    walther = {'rise': 45.0, 'tau': 120.0, 'beta': 0.035, 'law': 'walther', 'shape': 30.0}
    _, document = diagnose('thermal_viscosity', walther, plan=WARM)
    # Over 30 K Walther and Vogel draw the same curve: both are named, the exponential law is not.
    assert 'Walther' in document['best']['form'] and 'exponential' not in document['best']['form']
    thermal = next(c for c in document['candidates'] if c['effect'] == 'thermal_viscosity')
    assert {f['form']: f['delta_bic'] for f in thermal['forms']}['exponential (Reynolds)'] > 6


def test_exponential_viscosity_law_stays_exponential():
    params = {'rise': 45.0, 'tau': 120.0, 'beta': 0.035}
    _, document = diagnose('thermal_viscosity', params, plan=WARM)
    assert document['best']['form'] == 'exponential (Reynolds)'


def test_linear_depletion_is_named_linear():
    _, document = diagnose('lubricant_depletion', {'fall': 0.25, 'form': 'linear'})
    assert document['verdict'] == 'lubricant_depletion'
    assert document['best']['form'] == 'linear in revolutions'
    assert document['best']['params']['linear'] == 1.0


def test_depletion_recovering_at_rest_is_named_with_its_recovery():
    result, document = diagnose('lubricant_depletion', {'fall': 0.25, 'recovery_time': 40.0})
    assert document['verdict'] == 'lubricant_depletion'
    assert 'partial recovery at rest' in document['best']['form']
    assert 1 / result.chosen.fit.params['recovery_rate'] == pytest.approx(40.0, rel=0.5)


@pytest.mark.parametrize('effects, params, forms', [
    (('position_dependent_stiffness', 'lubricant_depletion'),
     {'position_dependent_stiffness': {'arrangement': 'fixed-fixed', 'bearing_before': 0.02, 'bearing_after': 0.02,
                                       'contact_ratio': 4.7},
      'lubricant_depletion': {'fall': 0.2}},
     {'position_dependent_stiffness': 'fixed-fixed', 'lubricant_depletion': 'exponential in revolutions'}),
    (('resonance', 'background_vibration'),
     {'resonance': {'top_ratio': 0.8, 'damping_ratio': 0.05, 'top_speed': TOP},
      'background_vibration': {'fraction': 0.8, 'tones': (480.0, 870.0)}},
     {'resonance': 'mode above the speed band', 'background_vibration': 'fixed-frequency lines'}),
])
def test_two_effects_at_once_are_named_together(effects, params, forms):
    result, document = diagnose(effects, params)
    named = {entry['effect']: entry['form'] for entry in document['effects']}
    assert named == forms
    assert document['verdict'] == document['effects'][0]['effect']
    assert document['confident'] is True and document['adequacy']['chosen']['significant'] is False
    assert result.second.fit.cv_rmse < 0.5 * result.baseline.cv_rmse
    assert any('two effects at once' in note for note in document['notes'])
    stored = result.calibration().extension                   # what diagnose --calibration-out writes
    assert {item['effect'] for item in stored['effects']} == set(effects)
    assert stored['effect'] == document['verdict']


def test_one_effect_is_not_reported_as_two():
    _, document = diagnose('lubricant_depletion', {'fall': 0.2})
    assert [entry['effect'] for entry in document['effects']] == ['lubricant_depletion']


def test_a_jacobian_step_out_of_the_laws_domain_leaves_no_standard_error_and_no_warning(monkeypatch):
    """A forward step of the constants that leaves the law's domain (a mode met at r = 1: two 1346 of block 1330)
    gives C_lambda no standard error, silently: no RuntimeWarning reaches ``diagnose``'s user."""
    import warnings
    from prsm_lube_ros.diagnosis import fitting
    table, _ = synthetic_table(np.random.default_rng(1), 'resonance', SyntheticPlan())
    assert math.isfinite(fitting.fit_model(table, None, folds=[]).c_lambda_std)
    real = fitting.constants_jacobian

    def stepped_out(*args):
        jacobian = real(*args)
        jacobian[0, 0] = np.inf
        return jacobian
    monkeypatch.setattr(fitting, 'constants_jacobian', stepped_out)
    with warnings.catch_warnings():
        warnings.simplefilter('error', RuntimeWarning)
        fit = fitting.fit_model(table, None, folds=[])
    assert math.isnan(fit.c_lambda_std) and np.all(np.isfinite(fit.log_residual))
