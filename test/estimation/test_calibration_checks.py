# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A calibration file is untrusted input: every bad value or structure is one line naming the file."""
import json
import math
import time
import warnings

import pytest
import yaml

from fuzzing import seed_calibration
from prsm_lube_ros.cli.common import write_json
from prsm_lube_ros.errors import ConfigError
from prsm_lube_ros.estimation.calibration_file import load_calibration


@pytest.fixture
def document(tmp_path):
    return yaml.safe_load(seed_calibration(tmp_path / 'seed.yaml').read_text())


def write(tmp_path, data, name='edited.yaml'):
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def scaled(data, key, factor):
    data['constants'][key] = data['constants'][key] * factor
    return data


EDITS = {
    'nan covariance': lambda d: d['covariance_ln_csys_cf_clambda'][1].__setitem__(1, math.nan),
    'inf covariance': lambda d: d['covariance_ln_csys_cf_clambda'][0].__setitem__(2, math.inf),
    'not positive definite': lambda d: d['covariance_ln_csys_cf_clambda'][0].__setitem__(
        2, 10 * math.sqrt(d['covariance_ln_csys_cf_clambda'][0][0] * d['covariance_ln_csys_cf_clambda'][2][2])),
    'not symmetric': lambda d: d['covariance_ln_csys_cf_clambda'][0].__setitem__(1, 1.0),
    'zero variance': lambda d: d['covariance_ln_csys_cf_clambda'][2].__setitem__(2, 0.0),
    'c_sys x 1e-6': lambda d: scaled(d, 'c_sys', 1e-6),
    'c_sys x 1e9': lambda d: scaled(d, 'c_sys', 1e9),
    'c_sys inf': lambda d: d['constants'].__setitem__('c_sys', math.inf),
    'c_sys negative': lambda d: d['constants'].__setitem__('c_sys', -0.08),
    'c_lambda negative': lambda d: scaled(d, 'c_lambda', -1),
    'c_f nan': lambda d: d['constants'].__setitem__('c_f', math.nan),
    'residual std inf': lambda d: d['fit'].__setitem__('residual_std_ln', math.inf),
    'residual std negative': lambda d: d['fit'].__setitem__('residual_std_ln', -0.1),
    'reference theta 0': lambda d: d['fit'].__setitem__('reference_theta', 0.0),
    'speed level negative': lambda d: d['fit']['speed_levels_rad_s'].__setitem__(0, -10.0),
    'load level 1e12': lambda d: d['fit']['load_levels_n'].__setitem__(0, 1e12),
    'windows used inf': lambda d: d['fit'].__setitem__('windows_used', math.inf),
    'extension parameter inf': lambda d: d.__setitem__(
        'extension', {'effect': 'thermal_viscosity', 'params': {'viscosity_slope': math.inf}}),
    'extension unknown effect': lambda d: d.__setitem__('extension', {'effect': 'no_such_effect', 'params': {}}),
    'extension params a list': lambda d: d.__setitem__('extension', {'effect': 'resonance', 'params': [1, 2]}),
    'covariance 2x2': lambda d: d.__setitem__('covariance_ln_csys_cf_clambda', [[1.0, 0.0], [0.0, 1.0]]),
    'constants a list': lambda d: d.__setitem__('constants', [1, 2, 3]),
}


@pytest.mark.parametrize('edit', sorted(EDITS))
def test_an_edited_value_is_refused_in_one_line_naming_the_file_without_a_numpy_warning(tmp_path, document, edit):
    EDITS[edit](document)
    path = write(tmp_path, document)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        with pytest.raises(ConfigError) as caught:
            load_calibration(path)
    assert str(path) in str(caught.value) and '\n' not in str(caught.value), str(caught.value)


def test_the_seed_and_a_fitted_calibration_still_load(tmp_path, document):
    calibration = load_calibration(write(tmp_path, document))
    assert calibration.constants.c_sys > 0 and calibration.c_lambda_std > 0


@pytest.mark.parametrize('text', [
    '[' * 1000 + ']' * 1000,
    'a:\n' + ''.join(' ' * (2 * i) + f'k{i}:\n' for i in range(1, 200)),
    '&a [' + ','.join(['x'] * 10) + ']\n',
])
def test_deep_nesting_is_one_line_not_a_recursion_error(tmp_path, text):
    path = tmp_path / 'deep.yaml'
    path.write_text(text)
    with pytest.raises(ConfigError, match=str(path)):
        load_calibration(path)


def test_aliases_that_would_expand_to_a_billion_nodes_cost_no_time(tmp_path):
    lines = ['a0: &a0 [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]']
    lines += [f'a{i}: &a{i} [' + ', '.join([f'*a{i - 1}'] * 10) + ']' for i in range(1, 9)]
    path = tmp_path / 'laughs.yaml'
    path.write_text('\n'.join(lines) + '\nformat: prsm_lube_ros/calibration\n')
    start = time.process_time()
    with pytest.raises(ConfigError, match=str(path)):
        load_calibration(path)
    assert time.process_time() - start < 10      # a walk of the expansion would take hours


def test_a_file_over_the_size_bound_is_refused_before_it_is_parsed(tmp_path):
    path = tmp_path / 'huge.yaml'
    with open(path, 'w') as stream:
        stream.write('sources:\n')
        stream.write('- x\n' * (3 << 20))
    with pytest.raises(ConfigError, match='bytes, more than'):
        load_calibration(path)


def test_write_json_writes_null_for_a_nan_that_reached_the_document(tmp_path):
    path = tmp_path / 'out.json'
    write_json(path, {'runs': [{'sigma': math.nan, 'theta': 0.9}], 'inf': [math.inf]})
    assert json.loads(path.read_text()) == {'runs': [{'sigma': None, 'theta': 0.9}], 'inf': [None]}
