# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The ideal test a study's misses are measured against (no ROS graph)."""
import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from prsm_lube_ros.experiments import diagnose_study
from prsm_lube_ros.diagnosis.table import WindowTable
from prsm_lube_ros.experiments.detection_power import (
    chance_of_at_least, ideal_detection, names_on_recording, one_sided_detection, power_markdown)
from prsm_lube_ros.experiments.effect_size import EffectSize, recorded_statistic
from prsm_lube_ros.physics.vibration_model import acceleration_amplitude, ModelConstants


def _size(ratio: float, runs: int) -> EffectSize:
    return EffectSize(between_runs=ratio * 0.03, within_runs=0.0, run_scatter=0.03, runs=runs)


def test_ideal_detection_is_the_chance_a_shifted_normal_clears_the_guard():
    # (Z + sqrt(lambda))^2 >= threshold, computed by hand, and by simulation.
    size = _size(0.59, 30)
    threshold = 10.0 + math.log(30)
    root = math.sqrt(size.noncentrality)
    by_hand = stats.norm.sf(math.sqrt(threshold) - root) + stats.norm.cdf(-math.sqrt(threshold) - root)
    assert size.noncentrality == pytest.approx(30 * 0.59 ** 2)
    assert ideal_detection(size) == pytest.approx(by_hand, rel=1e-6)
    draws = (np.random.default_rng(1).standard_normal(200_000) + root) ** 2
    assert ideal_detection(size) == pytest.approx(np.mean(draws >= threshold), abs=0.005)


def test_the_guard_costs_detection_and_an_absent_effect_is_a_rare_false_name():
    assert ideal_detection(_size(0.59, 30), margin=0.0) > ideal_detection(_size(0.59, 30)) + 0.3
    assert ideal_detection(_size(0.0, 30)) < 1e-3
    assert ideal_detection(_size(0.0, 30)) == pytest.approx(stats.chi2.sf(10.0 + math.log(30), df=1))
    assert ideal_detection(_size(2.0, 30)) > 0.999
    assert ideal_detection(EffectSize(0.01, 0.0, 0.0, 30)) == 1.0     # no run scatter: nothing hides it
    assert ideal_detection(_size(0.66, 40)) > ideal_detection(_size(0.66, 20))


def test_knowing_the_sign_names_more_at_the_same_false_name_rate():
    size, absent = _size(0.59, 30), _size(0.0, 30)
    assert one_sided_detection(absent) == pytest.approx(ideal_detection(absent), rel=1e-6)     # the same rate
    assert ideal_detection(size) < one_sided_detection(size) < ideal_detection(size) + 0.15
    critical = stats.norm.isf(ideal_detection(absent))
    assert one_sided_detection(size) == pytest.approx(stats.norm.sf(critical - math.sqrt(size.noncentrality)))


def test_chance_of_at_least_is_the_binomial_tail_for_equal_chances():
    assert chance_of_at_least([0.9] * 30, 29) == pytest.approx(stats.binom.sf(28, 30, 0.9))
    assert chance_of_at_least([1.0, 1.0, 0.5], 3) == pytest.approx(0.5)
    assert chance_of_at_least([0.2, 0.7], 0) == pytest.approx(1.0)
    assert chance_of_at_least([0.2, 0.7], 3) == 0.0


def test_power_markdown_sets_what_was_named_beside_the_ideal_test():
    records = [{'kind': 'lubricant_depletion', 'seed': 1, 'verdict': 'lubricant_depletion', 'right': True},
               {'kind': 'lubricant_depletion', 'seed': 2, 'verdict': 'adequate', 'right': False},
               {'kind': 'lubricant_depletion', 'seed': 3, 'verdict': 'adequate', 'right': False}]
    sizes = [{'kind': 'lubricant_depletion', 'seed': s, 'size': _size(r, 30).as_json()}
             for s, r in ((1, 2.0), (2, 0.59))]
    sizes.append({'kind': 'lubricant_depletion', 'seed': 3, 'size': None})    # no usable window: left out
    text = power_markdown(records, sizes, 'cmd')
    assert '| lubricant_depletion | 2 | adequate | no | 30 | 0.59 | 10.4 | 33 % | 40 % | 92 % |' in text
    assert '| lubricant_depletion | 2 | 1 | 1.3 | 1.4 | 1.9 |' in text
    assert '(2 or more)' in text


def test_power_option_takes_single_effects_only(tmp_path, capsys):
    assert diagnose_study.main(['--out', str(tmp_path / 'absent'), '--power', 'resonance']) == 2
    assert 'cannot read the cases' in capsys.readouterr().err
    (tmp_path / 'results.json').write_text('{"cases": []}')
    assert diagnose_study.main(['--out', str(tmp_path), '--power', 'two']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'not two' in err[0]


def _recording(rng, strength, run_scatter=0.03, window_scatter=0.02, per_run=12):
    """Three speeds x two loads, five times over; amplitude rising by ``strength`` (ln) over the revolutions."""
    conditions = [(w, f) for w in (20.0, 40.0, 80.0) for f in (2000.0, 4000.0)] * 5
    run = np.repeat(np.arange(len(conditions)), per_run)
    speed = np.array([conditions[r][0] for r in run])
    load = np.array([conditions[r][1] for r in run])
    revolutions = np.cumsum(speed) / (2 * math.pi)
    form = revolutions / revolutions[-1]
    constants = ModelConstants(c_sys=1e-9, c_f=1e-5, c_lambda=0.05)
    run_factor = run_scatter * rng.standard_normal(len(conditions))[run]
    log_rms = (np.log(acceleration_amplitude(speed, load, 1.0, constants)) + strength * form + run_factor
               + window_scatter * rng.standard_normal(run.size))
    n = run.size
    table = WindowTable(speed=speed, load=load, rms=np.exp(log_rms), position=np.zeros(n), revolutions=revolutions,
                        time=np.arange(n, dtype=float), temperature=np.full(n, np.nan), run=run,
                        recording=np.zeros(n, dtype=int))
    return table, form


def test_the_recorded_statistic_is_chi2_with_the_noncentrality_of_the_effect_size():
    rng = np.random.default_rng(7)
    null = [recorded_statistic(*_recording(rng, 0.0), 0.03) for _ in range(300)]
    assert np.mean(null) == pytest.approx(1.0, abs=0.25)          # chi^2 with one degree of freedom
    assert np.mean(np.array(null) >= stats.chi2.isf(0.05, df=1)) == pytest.approx(0.05, abs=0.035)
    table, form = _recording(rng, 0.0)
    # The form's change beyond the constants, as effect_size measures it: noncentrality runs * ratio^2.
    means = table.run_means(0.06 * form)
    design = np.column_stack([np.ones(table.runs.size), table.run_means(table.load),
                              table.run_means(-table.film_term)])
    left = means - design @ np.linalg.lstsq(design, means, rcond=None)[0]
    run_variance = 0.03 ** 2 + 0.02 ** 2 / 12
    noncentrality = float(left @ left) / run_variance
    shifted = [recorded_statistic(*_recording(rng, 0.06), 0.03) for _ in range(300)]
    assert np.mean(shifted) == pytest.approx(1.0 + noncentrality, rel=0.15)
    assert noncentrality > 5.0


def test_the_recorded_statistic_skips_windows_without_an_amplitude():
    table, form = _recording(np.random.default_rng(3), 0.04)
    whole = recorded_statistic(table, form, 0.03)
    # Lost windows (NaN RMS) are left out, not counted: the same as the table without them.
    lost = np.zeros(len(table), dtype=bool)
    lost[5::7] = True
    gappy = dataclasses.replace(table, rms=np.where(lost, np.nan, table.rms))
    kept = table.subset(~lost)
    assert recorded_statistic(gappy, form, 0.03) == pytest.approx(recorded_statistic(kept, form[~lost], 0.03))
    assert recorded_statistic(gappy, form, 0.03) != pytest.approx(whole)


def test_names_on_recording_holds_the_statistic_to_the_guard_plus_ln_runs():
    threshold = 10.0 + math.log(30)
    below = EffectSize(0.02, 0.0, 0.03, 30, recorded_statistic=threshold - 0.1)
    above = EffectSize(0.02, 0.0, 0.03, 30, recorded_statistic=threshold + 0.1)
    assert names_on_recording(below) is False and names_on_recording(above) is True
    assert names_on_recording(_size(0.5, 30)) is None
    assert EffectSize.from_json(above.as_json()).recorded_statistic == pytest.approx(threshold + 0.1, abs=1e-3)
    assert math.isnan(EffectSize.from_json({k: v for k, v in above.as_json().items()
                                            if k != 'recorded_statistic'}).recorded_statistic)
