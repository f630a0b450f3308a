# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Vibration recorded with the screw still: what the window table keeps of it."""
import dataclasses
import math

import numpy as np
import pytest

from prsm_lube_ros.diagnosis.table import REST_SPEED, table_from_windows, WindowTable
from prsm_lube_ros.estimation.windowing import AT_REST, Window


def window(start, rms, speed, *, run=1, reason_kind=''):
    return Window(start=float(start), end=float(start) + 1.0, vibration_rms=rms, sample_count=4000, coverage=1.0,
                  screw_speed=speed, speed_spread=0.0, axial_load=2000.0, temperature=math.nan,
                  nut_position=0.01 * start, revolutions=float(start), run_index=run, reason_kind=reason_kind,
                  reason='at rest' if reason_kind else '')


def running(count=12):
    return [window(t, 1.0 + 0.1 * (t % 3), 10.0 + 5.0 * (t % 3), run=1 + t // 4) for t in range(count)]


def test_the_table_keeps_the_median_rms_of_windows_at_standstill_and_leaves_out_those_still_turning():
    still = [window(100 + i, rms, 0.0, run=0, reason_kind=AT_REST) for i, rms in enumerate([0.30, 0.32, 0.34])]
    slowing = [window(110 + i, 0.9, 0.5, run=0, reason_kind=AT_REST) for i in range(5)]   # end of a deceleration
    holding = window(120, 0.31, 0.5 * REST_SPEED, run=0, reason_kind=AT_REST)             # servo jitter
    table = table_from_windows([running() + still[:2] + slowing, [holding, still[2]] + running()])
    assert table.rest_windows == 4
    assert math.isclose(table.rest_rms, np.median([0.30, 0.32, 0.31, 0.34]))
    # Rows are the running windows only, so subsets (held-out folds) keep the standstill figure.
    assert len(table) == 24 and math.isclose(table.subset(np.arange(5)).rest_rms, table.rest_rms)


def test_too_few_windows_at_standstill_give_no_figure():
    table = table_from_windows([running() + [window(100, 0.3, 0.0, run=0, reason_kind=AT_REST)] * 2])
    assert table.rest_windows == 2 and math.isnan(table.rest_rms)


def _floor_reference(plan):
    """The synthetic tables' floor unit: Eq. 22's amplitude at the slowest speed and largest load, m/s^2."""
    from prsm_lube_ros.physics.vibration_model import acceleration_amplitude
    return float(acceleration_amplitude(min(plan.speeds_rpm) * math.pi / 30, max(plan.loads), plan.theta,
                                        plan.constants))


def test_a_floor_a_resonance_absorbed_is_named_beside_it_from_the_vibration_at_standstill():
    """A floor of 0.6 units under a mode inside the band: the resonance's fit takes it, nothing is left to locate
    (random-study two-effect seed 27), and only the floor measured at standstill names it."""
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    plan = SyntheticPlan(spectrum_bins=128)
    table, truth = synthetic_table(np.random.default_rng(1), ('resonance', 'background_vibration'), plan,
                                   params={'background_vibration': {'form': 'broadband floor', 'fraction': 0.6}})
    assert truth['params']['resonance']['band'] == 'inside'
    named = [e[0].id for e in diagnose_table(table).named_effects()]
    assert named == ['resonance']
    floor = 0.6 * _floor_reference(plan)
    named = diagnose_table(dataclasses.replace(table, rest_rms=floor, rest_windows=10)).named_effects()
    assert [e[0].id for e in named] == ['resonance', 'background_vibration']
    params = named[1][2]
    assert params['rest_rms'] == floor and floor <= params['background_rms'] < 1.3 * floor


@pytest.mark.parametrize('rest', [0.002, 0.6])
def test_vibration_at_standstill_the_running_amplitudes_do_not_carry_names_no_background(rest):
    """A resonance alone, with a sensor's noise at standstill, or vibration there that running does not show (a servo
    dithering to hold position): a floor at least what was measured at standstill makes the fit worse, and no
    background is named (before B was held to it, one was, at B = 4e-9 m/s^2)."""
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    plan = SyntheticPlan(spectrum_bins=128)
    table, _ = synthetic_table(np.random.default_rng(1), 'resonance', plan)
    result = diagnose_table(dataclasses.replace(table, rest_rms=rest * _floor_reference(plan), rest_windows=10))
    assert [e[0].id for e in result.named_effects()] == ['resonance']


def test_b_is_never_fitted_below_what_standstill_or_fixed_lines_measured():
    from prsm_lube_ros.diagnosis.effects import get_effect
    background = get_effect('background_vibration')
    quiet = np.r_[np.full(20, 0.5), np.full(80, 2.0)]
    for rest, counted in ((0.3, 0.3), (0.05, 0.0), (math.nan, 0.0)):     # 36 %, 1 % of the quiet power, none
        n = quiet.size
        table = WindowTable(speed=np.full(n, 10.0), load=np.full(n, 2000.0), rms=quiet, position=np.zeros(n),
                            revolutions=np.arange(n), time=np.arange(n), temperature=np.full(n, np.nan),
                            run=np.arange(n) // 10, recording=np.zeros(n), rest_rms=rest, rest_windows=10)
        scales = background.scales(table)
        assert scales['rest_rms'] == counted
        for lines in (0.0, 0.2, 0.4):
            params = background.to_params(np.array([0.0]), {**scales, 'line_rms': lines})
            assert math.isclose(params['background_rms'], max(lines, counted))
        params = background.to_params(np.array([0.4]), {**scales, 'line_rms': 0.1})
        assert math.isclose(params['background_rms'], math.hypot(max(0.1, counted), 0.4 * 0.5))


def test_vibration_at_standstill_makes_no_law_of_speed_and_load_testable_on_too_few_conditions():
    """Three conditions for three constants and B: the standstill measures a floor but tests no law, fixed lines do."""
    from types import SimpleNamespace
    from prsm_lube_ros.diagnosis.effects import get_effect
    from prsm_lube_ros.diagnosis.engine import _too_few_conditions
    from prsm_lube_ros.diagnosis.locate import Location, SpectralLines
    background = get_effect('background_vibration')
    table = SimpleNamespace(speed=np.repeat([10.0, 20.0, 30.0], 10), load=np.full(30, 2000.0),
                            rms=np.repeat([0.5, 1.0, 2.0], 10), rest_rms=0.3, rest_windows=10, spectra=None)
    nothing = Location([], SpectralLines(testable=True), 'none', '', None)
    assert background.independent_evidence(table, nothing).startswith('standstill:')
    assert 'cannot be tested on so few conditions' in _too_few_conditions(table, background, nothing)
    lines = Location([], SpectralLines(testable=True, frequencies=[480.0], share_at_lowest_speed=0.2, note='a line'),
                     'none', '', None)
    assert _too_few_conditions(table, background, lines) == ''


def test_a_background_the_standstill_does_not_show_is_refuted_by_that_measurement():
    """B more than twice the RMS read with the screw still is power the recording shows is not there: not named."""
    from prsm_lube_ros.diagnosis.effects import get_effect
    from prsm_lube_ros.diagnosis.effects.background_vibration import STANDSTILL_CONTRARY_SHARE
    background = get_effect('background_vibration')
    n = 40
    base = dict(speed=np.full(n, 10.0), load=np.full(n, 2000.0), rms=np.full(n, 1.0), position=np.zeros(n),
                revolutions=np.arange(n), time=np.arange(n), temperature=np.full(n, np.nan),
                run=np.arange(n) // 10, recording=np.zeros(n))
    b = 0.5
    edge = math.sqrt(STANDSTILL_CONTRARY_SHARE) * b
    for rest, windows, refuted in ((math.nan, 0, False), (0.01, 10, True), (0.99 * edge, 10, True),
                                   (1.01 * edge, 10, False), (0.6, 10, False)):
        table = WindowTable(**base, rest_rms=rest, rest_windows=windows)
        text = background.measured_against(table, {'background_rms': b})
        assert bool(text) == refuted, (rest, text)
        if refuted:
            assert text.startswith('standstill:') and f'{rest:.3g} m/s^2' in text
    # No other candidate is refuted by the standstill: it measures what the contact law puts at zero.
    table = WindowTable(**base, rest_rms=0.0, rest_windows=10)
    for effect_id in ('resonance', 'lubricant_depletion', 'thermal_viscosity', 'position_dependent_stiffness'):
        assert get_effect(effect_id).measured_against(table, {}) == ''


@pytest.mark.parametrize('rest_share, named', [(0.01, False), (1.0, True)])
def test_a_floor_is_named_only_where_the_standstill_shows_it(rest_share, named):
    """A broadband floor of 0.6 units: with the standstill reading a sensor's noise (1 % of the floor's RMS) the
    fitted background is refuted (rule ``measured_against``); with the standstill reading the floor it is named."""
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.diagnosis.engine import Status
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    plan = SyntheticPlan(spectrum_bins=128)
    table, _ = synthetic_table(np.random.default_rng(3), 'background_vibration', plan,
                               params={'form': 'broadband floor', 'fraction': 0.6})
    floor = 0.6 * _floor_reference(plan)
    result = diagnose_table(dataclasses.replace(table, rest_rms=rest_share * floor, rest_windows=10))
    assert ('background_vibration' in [e[0].id for e in result.named_effects()]) == named
    candidate, = [c for c in result.candidates if c.effect.id == 'background_vibration']
    if named:
        assert candidate.status == Status.EARNS
    else:
        assert candidate.status == Status.REJECTED and candidate.decisions[-1].rule == 'measured_against'
        assert 'the fit contradicts a measurement: standstill' in candidate.reason
