# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The laws of each effect's physical forms: what each equation promises."""
import math

import numpy as np
import pytest

from prsm_lube_ros.errors import ConfigError
from prsm_lube_ros.physics.effects import background_vibration as background
from prsm_lube_ros.physics.effects import lubricant_depletion as depletion
from prsm_lube_ros.physics.effects import position_dependent_stiffness as stiffness
from prsm_lube_ros.physics.effects import resonance
from prsm_lube_ros.physics.effects import thermal_viscosity as thermal

T = np.linspace(20.0, 80.0, 61)


@pytest.mark.parametrize('law, shape', [('exponential', math.nan), ('vogel', 110.0), ('walther', 68.0)])
def test_every_viscosity_law_has_slope_beta_at_the_reference_temperature(law, shape):
    ratio = thermal.law_viscosity_ratio(law, T, 20.0, 0.03, shape)
    assert ratio[0] == pytest.approx(1.0)
    assert np.all(np.diff(ratio) < 0)
    slope = (math.log(thermal.law_viscosity_ratio(law, 20.01, 20.0, 0.03, shape))
             - math.log(thermal.law_viscosity_ratio(law, 19.99, 20.0, 0.03, shape))) / 0.02
    assert slope == pytest.approx(-0.03, rel=1e-3)


def test_vogel_is_convex_in_ln_eta_and_exp_b_over_t_minus_tv():
    ratio = thermal.vogel_viscosity_ratio(T, 20.0, 0.03, 110.0)
    # ln eta = b / (T - T_V) + const with b = beta D^2, T_V = T_ref - D.
    b, vogel_temperature = 0.03 * 110.0 ** 2, 20.0 - 110.0
    assert np.log(ratio) == pytest.approx(b / (T - vogel_temperature) - b / 110.0)
    assert np.all(np.diff(np.log(ratio), 2) > 0)


def test_walther_is_a_straight_line_in_astm_d341_coordinates():
    nu_ref = 68.0
    nu = nu_ref * thermal.walther_viscosity_ratio(T, 40.0, 0.03, nu_ref)
    z = np.log10(np.log10(nu + 0.7))
    line = np.polyfit(np.log10(T + 273.15), z, 1)
    assert np.max(np.abs(np.polyval(line, np.log10(T + 273.15)) - z)) < 1e-9
    assert -line[0] == pytest.approx(thermal.walther_slope(0.03, 40.0, nu_ref))
    # An ISO VG 68 mineral oil: B about 3.5-4 for beta about 0.045 1/K at 40 degC.
    assert 3.0 < thermal.walther_slope(0.045, 40.0, nu_ref) < 4.5


def test_thermal_law_rejects_an_unknown_viscosity_law():
    with pytest.raises(ConfigError, match='viscosity_law'):
        thermal.ThermalViscosityLaw(10.0, 300.0, 0.03, viscosity_law='arrhenius')


def test_linear_depletion_falls_by_equal_steps_and_stops_at_a_residual_film():
    factor = depletion.theta_factor(np.array([0.0, 100.0, 200.0, 5000.0]), 1e-3, 'linear')
    assert factor[:3] == pytest.approx([1.0, 0.9, 0.8])
    assert factor[3] == depletion.MIN_SUPPLY
    exponential = depletion.theta_factor(np.array([100.0, 200.0]), 1e-3)
    assert exponential[1] == pytest.approx(exponential[0] ** 2)


def test_loss_recovers_at_rest_only():
    # Two runs of 10 windows (1 s, 1 rev/s), a 60 s standstill between them.
    time = np.r_[np.arange(1, 11), 70 + np.arange(1, 11)].astype(float)
    revolutions = np.r_[np.arange(1, 11), 10 + np.arange(1, 11)].astype(float)
    speed = np.full(20, 2 * math.pi)
    rest = depletion.rest_durations(revolutions, time, speed)
    assert rest[10] == pytest.approx(60.0) and np.count_nonzero(rest) == 1
    effective = depletion.effective_revolutions(revolutions, rest, 1 / 60.0, time=time)
    assert effective[:10] == pytest.approx(revolutions[:10])
    assert effective[10] == pytest.approx(10 * math.exp(-1.0) + 1)
    # Shuffled windows give the same answer per window; without recovery N_eff is N_rev.
    order = np.random.default_rng(1).permutation(20)
    again = depletion.effective_revolutions(revolutions[order], rest[order], 1 / 60.0, time=time[order])
    assert again == pytest.approx(effective[order])
    assert depletion.effective_revolutions(revolutions, rest, 0.0) == pytest.approx(revolutions)


@pytest.mark.parametrize('arrangement', stiffness.ARRANGEMENTS)
def test_every_arrangement_profile_is_exact(arrangement):
    law = stiffness.PositionDependentStiffnessLaw(contact_stiffness=2e8, reference_load=100.0, youngs_modulus=2.1e11,
                                                  root_diameter=0.02, free_length_at_start=0.2,
                                                  arrangement=arrangement, near_length_at_start=0.04)
    x = np.linspace(0.0, 0.17, 18)
    area = math.pi * 0.02 ** 2 / 4
    ratios = stiffness.arrangement_ratios(arrangement, 2e8 / (2.1e11 * area), 0.17, 0.04, 0.03)
    profile = stiffness.compliance_ratio_profile(x / 0.17, *ratios)
    assert law.amplitude_factor(x, 100.0) == pytest.approx(1 + profile)
    if arrangement == 'fixed-fixed':
        assert 0 < np.argmax(profile) < x.size - 1
    else:
        assert np.all(np.diff(profile) != 0)


def test_background_form_follows_its_power_shares():
    assert background.BackgroundVibrationLaw(1.0).form == 'lines and broadband floor'
    assert background.BackgroundVibrationLaw(1.0, (), (), 1.0).form == 'broadband floor'
    assert background.BackgroundVibrationLaw(1.0, (50.0,), (1.0,), 0.0).form == 'fixed-frequency lines'


def test_resonance_band_position_and_natural_frequency_per_order():
    assert resonance.band_position(5.0, 10.0, 20.0) == 'below the speed band'
    assert resonance.band_position(15.0, 10.0, 20.0) == 'inside the speed band'
    assert resonance.band_position(25.0, 10.0, 20.0) == 'above the speed band'
    assert resonance.natural_frequency(2 * math.pi, 3) == pytest.approx(3.0)


def test_a_mode_below_the_mesh_band_lies_between_the_low_orders_and_the_mesh():
    rng = np.random.default_rng(7)
    top, bottom, mesh = 20.0, 10.0, (3.75, 11.25, 22.5)
    for _ in range(50):
        law = resonance.draw_below_mesh(rng, mesh_orders=mesh, top_speed=top, bottom_speed=bottom)
        assert law is not None and law.order in mesh[1:]      # 3.75 x 10 rad/s lies below 3 x 20 rad/s: no gap
        assert max(resonance.LOW_ORDERS) * top / (2 * math.pi) < law.natural_frequency \
            < law.order * bottom / (2 * math.pi)
        assert law.frequency_ratio(bottom) > 1.0               # every speed past resonance for the mesh order
    # a speed band so wide that every mesh order overlaps the low orders: no such mode
    assert resonance.draw_below_mesh(rng, mesh_orders=(3.75,), top_speed=40.0, bottom_speed=10.0) is None


def test_the_simulation_hook_draws_modes_below_the_mesh_band_too():
    from prsm_lube_ros.physics.effects import simulation, SimulationContext
    from prsm_lube_ros.physics.actuator import Actuator
    context = SimulationContext(actuator=Actuator(), speeds=(10.0, 20.0), loads=(100.0,), stroke=0.1,
                                session_revolutions=100.0, reference_amplitude=1.0, sample_rate=10000.0,
                                band_high=4000.0)
    hook = simulation('resonance')
    words = [hook.form_words(vars(hook.draw(np.random.default_rng(seed), context)), context.speeds)[0]
             for seed in range(80)]
    below_mesh = sum('below the mesh band' in w for w in words)
    assert 0 < below_mesh < len(words)
    assert any(w.startswith('mode above') for w in words) and any(w.startswith('mode inside') for w in words)
