# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The diagnosis' rules as one typed policy: every threshold a verdict depends on, and where each comes from.

:class:`DiagnosisRules` is frozen; :func:`~.engine.diagnose_table` takes one
(``rules=``, default :data:`DEFAULT_RULES`) and every rule of the engine, the
adequacy test and the covariate tests of :func:`~.locate.locate` reads its
threshold from it, so a stricter or looser policy is one value::

    from dataclasses import replace
    strict = replace(DEFAULT_RULES, bic_margin=20.0)
    diagnose_table(table, rules=strict)

Each field carries its *source* (a statistical principle, or the study cases
that set it) in its metadata (:func:`rule_source`); ``docs/diagnosis-rules.md``
lists them with the test of each (:func:`rules_markdown` writes that table, and
``test/diagnosis/test_rules.py`` checks the page holds it).

The thresholds of the spectral evidence (what counts as a fixed line, a mode
band, a changing spectral shape) are :class:`SpectralRules`, the defaults of
:mod:`.locate`'s spectral measurements; they are listed here beside the others
but are properties of the measurement, not arguments of
:func:`~.engine.diagnose_table` (the effect plug-ins measure with them).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
import math
from typing import Any

__all__ = ['DEFAULT_RULES', 'DEFAULT_SPECTRAL_RULES', 'DiagnosisRules', 'SpectralRules', 'rule_source',
           'rules_markdown']

_KASS_RAFTERY = 'Kass & Raftery (1995), Bayes factors, JASA 90: 773-795'


def _rule(default: Any, source: str, test: str = '') -> Any:
    """A policy field: its default, where the value comes from and the test that pins the rule."""
    return field(default=default, metadata={'source': source, 'test': test})


@dataclass(frozen=True)
class DiagnosisRules:
    """Every threshold of the diagnosis' decisions (see the module doc and ``docs/diagnosis-rules.md``)."""

    # --- a candidate earns its parameters (engine) ---
    bic_margin: float = _rule(
        10.0, f'principle: a BIC difference of 10 or more is very strong evidence ({_KASS_RAFTERY}); study: at 8 '
        'depletion would also be named in 3 recordings where it was not concealed (margins.md of seeds 0-29)',
        'test_rules.py::test_a_stricter_bic_margin_changes_the_verdict')
    min_gain: float = _rule(
        0.05, 'principle: an effect must predict held-out runs better by a margin a user notices (5 % of the '
        'relative RMS error), so a BIC gain on correlated windows alone names nothing',
        'test_rules.py::test_a_larger_min_gain_names_nothing')
    # --- a second effect beside the first ---
    second_bic_margin: float = _rule(
        5.0, f'principle: BIC 2-6 positive, 6-10 strong evidence ({_KASS_RAFTERY}); the first effect has already '
        'shown that the model misses, so less than a first effect needs',
        'test_engine.py::test_a_second_effect_is_named_by_the_rules_a_single_effect_earns_by')
    located_bic_tolerance: float = _rule(
        2.0, f'principle: a BIC difference under 2 is not worth more than a bare mention ({_KASS_RAFTERY})',
        'test_engine.py::test_a_second_effect_is_named_by_the_rules_a_single_effect_earns_by')
    # --- a law located on its own covariate ---
    located_law_bic: float = _rule(
        2.0, f'principle: a BIC drop of 2 is positive evidence ({_KASS_RAFTERY}), enough once the locate test has '
        'found the structure the margin of 10 guards against inventing; study: depletion 45, stiffness 30 and 59 '
        '(seeds 30-59: BIC -9.9, -6.0, -5.4 with the mismatch located)',
        'test_engine.py::test_a_law_of_the_located_covariate_is_named_with_a_smaller_bic_drop_when_none_earns')
    within_run_share: float = _rule(
        0.5, 'principle: a covariate that varies mostly within runs (position: every run sweeps the stroke) is '
        'scored on the deviations from run means, where set-up scatter between runs is left out; study: '
        'stiffness 214 and 220 of seeds 210-239 (BIC -0.4 and -0.7 counted by runs, -329 and -270 within runs)',
        'test_engine.py::test_a_weak_arch_under_set_up_scatter_is_named_by_what_it_changes_within_runs')
    # --- evidence from outside the amplitude fit ---
    evidence_tolerance: float = _rule(
        0.02, 'principle: k parameters the amplitudes cannot pin down raise a least-squares prediction error by '
        'about k/(2n) on n runs; this is its floor; study: resonance 151 of seeds 150-179 (a mode band on 3 '
        'speeds in 12 runs, 4.6 % worse held out, within its 8.3 %)',
        'test_engine.py::test_the_held_out_tolerance_of_evidence_is_what_estimating_the_parameters_costs')
    exclusive_evidence_share: float = _rule(
        0.5, 'principle: evidence no other effect of the catalogue makes (impulsive strikes: oil loss, a mode, '
        'stiffness and a background vibrate Gaussian, band kurtosis 2.7-3.4 in healthy 1 s windows, never over the '
        'impulsive 4.5) names an effect beside the first whatever its amplitude fit when the median window of an '
        'average condition shows it: half the windows or more, twice the share that counts as evidence beside a '
        'fit (a growing defect shows late), shares taken per operating condition, each weighing alike (a '
        'traverse holds windows as 1 / speed, and a defect stands out where its own speed and load law puts it); '
        'its share of the RMS is then unresolved; study: two 1336 of block 1330 (82 % impulsive, kurtosis '
        'median 11) dropped beside depletion, two 1202 (22 %) weak, two 1842 (envelope lines in 35 % of the '
        'windows, in every window of the 6 fastest of 12 conditions) dropped beside depletion before shares were '
        'per condition',
        'test_surface_defect.py::test_impulsiveness_in_most_windows_names_the_defect_beside_the_first_effect')
    gaussian_part_share: float = _rule(
        0.8, 'convention: beside an impulsive first effect the windows\' Gaussian part is diagnosed alone when this '
        'share of the windows carries it (as the defect\'s indicators must be carried); an effect it names is named '
        'beside the first; study: modes beside a spall named there in 11 of 12 cases the whole RMS missed (two '
        '1001-1020, 1202, 1330, 1415, 1507, 1511, 1532, 1602, 1710), nothing named in the Gaussian part of 20 '
        'spalls alone (surface_defect 1330-1349)',
        'test_surface_defect.py::test_a_mode_beside_a_spall_is_named_in_the_gaussian_part')
    # --- forms of one effect ---
    form_margin: float = _rule(
        6.0, f'principle: BIC 6 is strong evidence ({_KASS_RAFTERY}) for a form with more parameters',
        'test_engine.py::test_an_off_centre_fixed_fixed_arch_still_chooses_the_arched_form')
    form_tie: float = _rule(
        2.0, f'principle: forms within 2 of each other are not told apart by the data ({_KASS_RAFTERY})',
        'test_forms.py::test_curved_viscosity_law_is_preferred_to_the_exponential_when_the_oil_warms_enough')
    # --- ties between candidates ---
    tie_ratio: float = _rule(
        0.5, 'convention: a runner-up with half the leader\'s held-out gain or more is tested against the leader '
        '(both fitted together, each for what it adds)',
        'test_engine.py::test_temperature_tied_to_revolutions_is_ambiguous_not_a_guess')
    confounded: float = _rule(
        0.9, 'convention: |Spearman| over runs of 0.9 or more makes an operating variable and a drift covariate '
        'indistinguishable on the plan (the runs should be recorded in random order)',
        'test_engine.py::test_run_order_confounded_with_speed_is_reported_not_passed_as_adequate')
    collinear: float = _rule(
        0.9, 'convention: |Pearson| over runs of 0.9 or more makes two drift covariates one shape (time and '
        'revolutions over two sessions); study: depletion 201 of seeds 180-209 (r = 0.99)',
        'test_engine.py::test_a_smooth_in_a_covariate_collinear_with_the_named_law_s_does_not_overrule_it')
    pair_pool: int = _rule(
        3, 'study: two effects that only together explain the mismatch (two 199 of seeds 180-209: a resonance '
        'and thermal viscosity, neither earning alone); 3 candidates keep the pairs tried to 3',
        'test_engine.py::test_the_pair_pool_takes_candidates_with_spectral_evidence_first_then_the_largest_gains')
    # --- adequacy: run-level lack of fit (adequacy.py) ---
    lof_p: float = _rule(
        0.01, 'principle: the classic lack-of-fit F test (condition means against the scatter of repeated runs), '
        'at the 1 % level', 'test_adequacy.py')
    lof_tolerance: float = _rule(
        0.01, 'principle: a lack of fit smaller than 1 % per run is not material whatever its p-value',
        'test_adequacy.py::test_unaffected_table_passes_the_lack_of_fit_test_and_is_adequate')
    setup_scatter: float = _rule(
        0.05, 'measured: a rig\'s set-up scatters repeated traverses of one unit by 1-4 %; 5 % with margin',
        'test_adequacy.py::test_pure_error_is_the_scatter_of_repeated_runs')
    # --- where the mismatch lives (locate.py) ---
    significance: float = _rule(
        1e-3, 'principle: a covariate carries the mismatch at p < 0.001 (several covariates and shapes are '
        'tested; a step in time is Bonferroni-corrected over every stretch tried)',
        'test_locate.py::test_pure_noise_locates_nothing')
    min_temperature_span: float = _rule(
        0.5, 'measured: less is the temperature sensor\'s noise, which bins windows by chance; study: none 70 of '
        'seeds 60-89 (a "pattern" over 0.10 K); the thermal candidate needs the same span',
        'test_locate.py::test_temperature_is_a_covariate_only_when_it_spans_more_than_sensor_noise')
    bins: int = _rule(6, 'convention: quantile bins of the any-shape covariate tests',
                      'test_locate.py::test_an_arch_in_nut_position_is_located_with_its_shape')
    min_segment_runs: int = _rule(
        2, 'convention: a step or stretch in time holds two runs or more either side',
        'test_locate.py::test_a_step_between_runs_is_a_shape_in_time')

    def __post_init__(self) -> None:
        """Refuse a policy no rule can work with (a non-finite or negative threshold)."""
        for item in fields(self):
            value = getattr(self, item.name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f'DiagnosisRules.{item.name} = {value!r}: a finite number >= 0 is needed')


@dataclass(frozen=True)
class SpectralRules:
    """What counts as spectral evidence (:mod:`.locate`'s measurements; see the module doc)."""

    line_prominence: float = _rule(
        4.0, 'study: resonance with two background lines, seed 102 of diagnose_forms (a line stood out by 2.9 where '
        '4 was asked at both of the two lowest speeds): 4 at any two speeds', 'test_locate.py')
    line_measurable: float = _rule(2.0, 'convention: a line\'s power is measured where it stands at twice the floor',
                                   'test_locate.py')
    floor_half_width: int = _rule(8, 'convention: neighbourhood, bins, a spectral line is compared with',
                                  'test_locate.py::test_fixed_tones_are_found_and_rotation_orders_are_not')
    line_constancy: float = _rule(
        2.5, 'convention: fixed lines count as constant when their power varies by less than this factor between '
        'speeds', 'test_locate.py::test_a_fixed_line_of_constant_power_is_background_not_a_mode')
    power_spread: float = _rule(
        1.5, 'convention: fixed lines count as constant while the total power varies by more than this factor',
        'test_locate.py')
    mode_floor_half_width: int = _rule(32, 'convention: neighbourhood, bins, a mode band is compared with',
                                       'test_locate.py')
    mode_broad_prominence: float = _rule(
        2.5, 'physics: a mode\'s ringing over its excitation peaks at 1/(4 zeta^2), 6.25 at zeta 0.2; study: '
        'resonances 30, 33, 41, 57 of seeds 30-59 (wide bands)', 'test_locate.py')
    mode_max_order: float = _rule(
        50.0, 'physics: rollers times thread starts stay below order 50; study: the rig\'s contact mode at '
        '1200 Hz (seeds 0-59, commit 8a6cb66); a band whose order at the fitted resonant speed is above it is '
        'no evidence for that mode (a spall\'s ring at orders 63-102 named a mode beside surface_defect 1905, 1339 '
        'and two 1333; test_effects.py::test_a_mode_band_counts_for_a_resonance_only_where_an_order_the_screw_'
        'makes_meets_it)', 'test_locate.py')
    mode_ring_ratio: float = _rule(0.4, 'physics: |H|^2 >= 1.2 from a frequency ratio of 0.4 on',
                                   'test_locate.py')
    mode_upper_skirt: float = _rule(
        math.sqrt(2.0), 'physics: a mode damped 20 % falls back to the floor about half an octave above f_r; '
        'study: background 198 and resonance 208 of seeds 180-209 (a "band" at 396 Hz sampled at 1 kHz)',
        'test_locate.py')
    shape_min_bins: int = _rule(8, 'convention: third-octave bands of the shape test hold 8 bins at least',
                                'test_locate.py')
    shape_noise_factor: float = _rule(
        3.0, 'convention: a shape changes when its distance is 3 times that between halves of one speed\'s runs',
        'test_locate.py')
    shape_min_distance: float = _rule(0.03, 'convention: and by a total variation of 0.03 at least',
                                      'test_locate.py')
    shape_added_bands: int = _rule(3, 'convention: bands compared between speeds', 'test_locate.py')
    mode_min_speeds: int = _rule(3, 'principle: a band fixed in Hz while the orders move needs 3 speeds',
                                 'test_locate.py')
    mode_share_spread: float = _rule(2.0, 'convention: a mode band\'s share varies by 2x between speeds',
                                     'test_locate.py')
    mode_min_share: float = _rule(0.02, 'convention: a mode band carries 2 % of the mean square somewhere',
                                  'test_locate.py')
    mode_order_shift_bins: int = _rule(
        3, 'study: six speeds 9 % apart must not hide a 13 Hz mode (an order must move 3 bins)', 'test_locate.py')
    struck_band_z: float = _rule(
        3.09, 'principle: a band whose power over its neighbours rises and falls with the windows\' strike power '
        '(rms^2 less the Gaussian part\'s) within each operating condition and run, the Gaussian part\'s power '
        'partialled out, beyond chance (pooled Fisher z, one-sided p < 0.001) is rung by impulses, not by an order '
        '(which holds a mode\'s response as the speed and the contacts\' vibration set it); study: surface_defect '
        '1961 (a spall\'s ring at 252 Hz named a mode beside it: z = 10.2; the rings of pairs two 1877 and 1746: '
        '8.2 and 25.6; the modes of pairs 1836 and 1878 beside spalls: 1.7 and 1.2)',
        'test_resonance_evidence.py::test_a_band_that_follows_the_strikes_is_no_evidence_for_a_mode')
    mode_order_tolerance: float = _rule(
        0.15, 'convention: a band\'s frequency f at the fitted resonant speed omega_r implies the order 2 pi f / '
        'omega_r, which must lie within 15 % of an order that excites the mode (omega_r from amplitudes is that '
        'uncertain; the order-tracked check had 15 % before the rules were typed)',
        'test_resonance_evidence.py::test_a_band_at_every_speed_is_evidence_when_it_implies_an_exciting_order')


DEFAULT_RULES = DiagnosisRules()
DEFAULT_SPECTRAL_RULES = SpectralRules()


def rule_source(policy: type, name: str) -> str:
    """Where the value of ``policy``'s field ``name`` comes from."""
    return str(next(item for item in fields(policy) if item.name == name).metadata['source'])


def rules_markdown() -> str:
    """The table of every rule: name, default, source and test (``docs/diagnosis-rules.md`` holds it)."""
    lines = []
    for policy, default in ((DiagnosisRules, DEFAULT_RULES), (SpectralRules, DEFAULT_SPECTRAL_RULES)):
        lines += [f'| `{policy.__name__}` field | default | where the value comes from | test |', '|---|---|---|---|']
        for item in fields(policy):
            value = getattr(default, item.name)
            shown = f'{value:g}' if isinstance(value, float) else str(value)
            lines.append(f'| `{item.name}` | {shown} | {item.metadata["source"]} | `{item.metadata["test"]}` |')
        lines.append('')
    return '\n'.join(lines)
