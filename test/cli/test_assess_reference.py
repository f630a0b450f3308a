# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Speed work moves no theta_oil, sigma, indicator or verdict: ``assess`` JSON equals the reference to 1e-9.

The reference JSON in ``test/data/assess_reference/`` was written by the code
before the speed work (``python scripts/assess_reference.py --code <worktree
of main>``, see that script) on real and simulated recordings; here the code
under test assesses the same recordings and every number must agree to 1e-9
relative, every flag, verdict and label exactly.  Keys added since are
allowed; where a recording lies (``bag``, the paths in ``problems``) is
compared by its name only.
"""
import json
import math
from pathlib import Path
import sys

import pytest

from prsm_lube_ros.cli import main

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / 'scripts'))
from assess_reference import assess_command, CASES, REFERENCE  # noqa: E402  (the script that wrote the reference)

RELATIVE = 1e-9


def differences(expected, actual, where='$'):
    """Where ``actual`` departs from ``expected`` (numbers to RELATIVE, the rest exactly); keys added are allowed."""
    if isinstance(expected, dict):
        if not isinstance(actual, dict):
            return [f'{where}: {actual!r} is not an object']
        found = []
        for key, value in expected.items():
            if key not in actual:
                found.append(f'{where}.{key}: missing')
            elif key == 'bag':
                if Path(value).name != Path(str(actual[key])).name:
                    found.append(f'{where}.bag: {actual[key]!r} is not {value!r}')
            else:
                found += differences(value, actual[key], f'{where}.{key}')
        return found
    if isinstance(expected, list):
        if not isinstance(actual, list) or len(actual) != len(expected):
            return [f'{where}: {len(actual) if isinstance(actual, list) else actual!r} items, '
                    f'{len(expected)} expected']
        return [line for k, (e, a) in enumerate(zip(expected, actual)) for line in differences(e, a, f'{where}[{k}]')]
    if isinstance(expected, float) and not isinstance(actual, bool) and isinstance(actual, (int, float)):
        if math.isclose(expected, actual, rel_tol=RELATIVE, abs_tol=1e-300):
            return []
        return [f'{where}: {actual!r}, {expected!r} expected']
    if expected != actual:
        return [f'{where}: {actual!r}, {expected!r} expected']
    return []


def without_paths(lines):
    """Problem lines with the recording's folder left out (``PATH: what``)."""
    return [line.split(': ', 1)[-1] for line in lines]


@pytest.mark.parametrize('name', sorted(CASES))
def test_assessment_equals_the_reference_of_the_code_before(name, tmp_path, capsys):
    reference = json.loads((REFERENCE / f'{name}.json').read_text())
    out = tmp_path / f'{name}.json'
    assert main(assess_command(name, out)) == 0, capsys.readouterr().err
    document = json.loads(out.read_text())
    reference['problems'] = without_paths(reference['problems'])
    document['problems'] = without_paths(document['problems'])
    found = differences(reference, document)
    assert not found, f'{len(found)} differences, first: ' + '; '.join(found[:5])
    # The cases hold what is compared: assessed runs, and the indicators of the windows (flags on the late runs).
    assert len(document['windows']) > 50 and any(run['theta_oil'] is not None for run in document['runs'])
    assert any(window['condition_indicators']['envelope_peaks'] for window in document['windows'])
    assert any(run['defect_suspected'] for run in document['runs']) == (name == 'femto_all_late')


def test_the_comparison_sees_a_changed_theta_and_a_changed_flag():
    """The comparison fails where a number moves by more than 1e-9 or a flag turns."""
    reference = json.loads((REFERENCE / 'femto_all_late.json').read_text())
    changed = json.loads(json.dumps(reference))
    run = next(run for run in changed['runs'] if run['theta_oil'] is not None)
    run['theta_oil'] *= 1 + 1e-8
    changed['runs'][0]['defect_suspected'] = not changed['runs'][0]['defect_suspected']
    found = differences(reference, changed)
    assert len(found) == 2 and all('theta_oil' in line or 'defect_suspected' in line for line in found)
    assert differences(reference, json.loads(json.dumps(reference))) == []
