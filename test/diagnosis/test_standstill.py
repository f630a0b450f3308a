# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Vibration recorded with the screw still: what the window table keeps of it."""
import dataclasses
import math

import numpy as np
import pytest

from prsm_lube_ros.diagnosis.table import REST_SPEED, table_from_windows
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
    assert named[1][2]['background_rms'] > 0.5 * floor


@pytest.mark.parametrize('rest', [0.002, 0.6])
def test_vibration_at_standstill_the_running_amplitudes_do_not_carry_names_no_background(rest):
    """A resonance alone, with a sensor's noise at standstill, or vibration there that running does not show (a servo
    dithering to hold position): the fitted floor would be ~0, so the standstill is no evidence for it."""
    from prsm_lube_ros.diagnosis import diagnose_table
    from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table
    plan = SyntheticPlan(spectrum_bins=128)
    table, _ = synthetic_table(np.random.default_rng(1), 'resonance', plan)
    result = diagnose_table(dataclasses.replace(table, rest_rms=rest * _floor_reference(plan), rest_windows=10))
    assert [e[0].id for e in result.named_effects()] == ['resonance']
