# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The diagnosis' rules as one typed policy (issue 35, item 2), driven through the public API."""
from dataclasses import FrozenInstanceError, fields, replace
import json
from pathlib import Path
import re

import numpy as np
import pytest

from prsm_lube_ros.diagnosis import DEFAULT_RULES, diagnose_table, DiagnosisRules, Verdict
from prsm_lube_ros.diagnosis.engine import Decision, OUTCOMES, Status
from prsm_lube_ros.diagnosis.rules import rules_markdown, SpectralRules
from prsm_lube_ros.experiments.synthetic_tables import SyntheticPlan, synthetic_table

ROOT = Path(__file__).resolve().parents[2]
PLAN = SyntheticPlan(spectrum_bins=128, sessions=2)


@pytest.fixture(scope='module')
def depletion_table():
    """Depletion drawn in its range by the window-table simulator: no spectral signature, named by BIC alone."""
    table, _ = synthetic_table(np.random.default_rng(5), 'lubricant_depletion', PLAN)
    return table


def test_the_default_policy_names_the_concealed_effect(depletion_table):
    result = diagnose_table(depletion_table)
    assert result.verdict == 'lubricant_depletion' and result.verdict.names_an_effect
    assert isinstance(result.verdict, Verdict) and result.rules is DEFAULT_RULES
    depletion = next(c for c in result.candidates if c.effect.id == 'lubricant_depletion')
    assert depletion.status == Status.EARNS and depletion.decisions[0].rule == 'bic_margin'


def test_a_stricter_bic_margin_changes_the_verdict(depletion_table):
    """The same table under a policy asking a BIC drop no effect reaches: the effect is no longer named."""
    strict = replace(DEFAULT_RULES, bic_margin=1e6, located_law_bic=1e6)
    result = diagnose_table(depletion_table, rules=strict)
    assert result.verdict != 'lubricant_depletion' and not result.verdict.names_an_effect
    assert result.verdict in OUTCOMES and result.rules is strict
    depletion = next(c for c in result.candidates if c.effect.id == 'lubricant_depletion')
    assert depletion.status == Status.REJECTED
    assert depletion.decisions[-1].rule == 'bic_margin' and 'does not earn' in depletion.reason


def test_a_larger_min_gain_names_nothing(depletion_table):
    result = diagnose_table(depletion_table, rules=replace(DEFAULT_RULES, min_gain=0.999))
    assert not result.verdict.names_an_effect
    assert all(c.status != Status.EARNS for c in result.candidates)


def test_a_stricter_lack_of_fit_level_is_what_the_adequacy_test_reports():
    """The run-level test is judged by the policy's level: the JSON's limit and the verdict follow it."""
    table, _ = synthetic_table(np.random.default_rng(3), None, PLAN)
    default = diagnose_table(table)
    assert default.verdict == 'adequate'
    loose = diagnose_table(table, rules=replace(DEFAULT_RULES, setup_scatter=1e-4))
    assert loose.baseline_fit_test.as_json()['setup_scatter_limit'] == 1e-4
    assert loose.baseline_fit_test.excess_scatter and loose.verdict != 'adequate'


def test_the_policy_is_frozen_and_refuses_thresholds_no_rule_can_use():
    with pytest.raises(FrozenInstanceError):
        DEFAULT_RULES.bic_margin = 3.0      # type: ignore[misc]
    for bad in (-1.0, float('nan'), float('inf')):
        with pytest.raises(ValueError, match='bic_margin'):
            DiagnosisRules(bic_margin=bad)


def test_decisions_are_immutable_values_and_the_reason_is_their_words(depletion_table):
    result = diagnose_table(depletion_table)
    for candidate in result.candidates:
        assert candidate.decisions and all(isinstance(d, Decision) for d in candidate.decisions)
        with pytest.raises(FrozenInstanceError):
            candidate.decisions[0].text = 'changed'     # type: ignore[misc]
        assert candidate.status == candidate.decisions[-1].status
        assert candidate.decisions[-1].text in candidate.reason
    document = json.loads(json.dumps(result.as_json(), default=float))
    assert all(entry['decisions'] and {'rule', 'status', 'text'} <= set(entry['decisions'][0])
               for entry in document['candidates'])


def _test_exists(reference: str) -> bool:
    """``file.py`` or ``file.py::test_name`` under test/diagnosis (or test/) names a test that exists."""
    name, _, function = reference.partition('::')
    path = next((p for p in (ROOT / 'test' / 'diagnosis' / name, ROOT / 'test' / name) if p.is_file()), None)
    if path is None:
        return False
    return not function or re.search(rf'^def {re.escape(function)}\(', path.read_text(), re.M) is not None


@pytest.mark.parametrize('policy', [DiagnosisRules, SpectralRules])
def test_every_rule_says_where_its_value_comes_from_and_which_test_pins_it(policy):
    for item in fields(policy):
        source, test = item.metadata['source'], item.metadata['test']
        assert re.match(r'(principle|study|convention|measured|physics): ', source), (item.name, source)
        assert _test_exists(test), (item.name, test)


def test_the_rules_page_lists_every_rule_with_its_default_source_and_test():
    page = (ROOT / 'docs' / 'diagnosis-rules.md').read_text()
    assert rules_markdown() in page, 'docs/diagnosis-rules.md: paste the output of rules_markdown() again'
    assert '```mermaid' in page
