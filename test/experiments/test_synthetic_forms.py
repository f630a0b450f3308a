# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The window-table simulator makes each effect form and several effects at once."""
import numpy as np
import pytest

from prsm_lube_ros.physics.effects.background_vibration import draw as draw_background_vibration
from prsm_lube_ros.physics.effects.lubricant_depletion import draw as draw_lubricant_depletion
from prsm_lube_ros.physics.effects.resonance import draw as draw_resonance
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table

PLAN = SyntheticPlan(random_order=False)


def test_two_effects_at_once_both_act():
    params = {'lubricant_depletion': {'fall': 0.2},
              'position_dependent_stiffness': {'arrangement': 'fixed-fixed', 'bearing_before': 0.02,
                                               'bearing_after': 0.02, 'contact_ratio': 4.7}}
    table, truth = synthetic_table(np.random.default_rng(1), tuple(params), PLAN, params=params)
    alone, _ = synthetic_table(np.random.default_rng(1), 'lubricant_depletion', PLAN,
                               params=params['lubricant_depletion'])
    assert truth['params'] == params
    assert truth['theta_effective'][-1] == pytest.approx(0.8, rel=0.02)
    # The arch raises the amplitude mid-travel on top of the depletion.
    ratio = table.rms / alone.rms
    middle = np.abs(table.position - 0.085) < 0.02
    assert ratio[middle].mean() > 1.05 * ratio[~middle].mean()


def test_depletion_recovers_over_rests_and_linear_form_falls_linearly():
    _, recovering = synthetic_table(np.random.default_rng(2), 'lubricant_depletion', PLAN,
                                    params={'fall': 0.2, 'recovery_time': 30.0})
    _, plain = synthetic_table(np.random.default_rng(2), 'lubricant_depletion', PLAN, params={'fall': 0.2})
    assert recovering['theta_effective'][-1] > plain['theta_effective'][-1] + 0.05
    _, linear = synthetic_table(np.random.default_rng(2), 'lubricant_depletion', PLAN,
                                params={'fall': 0.2, 'form': 'linear'})
    assert linear['theta_effective'][-1] == pytest.approx(0.8, rel=0.02)


def test_draws_take_the_form_asked_for():
    rng = np.random.default_rng(3)
    assert draw_background_vibration(rng, reference_amplitude=1.0, form='broadband floor').tone_frequencies == ()
    assert draw_lubricant_depletion(rng, session_revolutions=1000.0, form='linear').form == 'linear'
    mode = draw_resonance(rng, order=3.0, top_speed=20.0, bottom_speed=10.0, band='below')
    assert 2 * np.pi * mode.natural_frequency / mode.order < 10.0
    # Without a bottom speed the mode stays above the band, as before.
    mode = draw_resonance(rng, order=3.0, top_speed=20.0)
    assert 2 * np.pi * mode.natural_frequency / mode.order > 20.0
