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
    # Issue 36: values that loaded silently and changed results.
    'c_f negative': lambda d: scaled(d, 'c_f', -1),
    'c_f zero': lambda d: d['constants'].__setitem__('c_f', 0.0),
    'c_f x 1e5': lambda d: scaled(d, 'c_f', 1e5),
    'c_lambda x 1e-6': lambda d: scaled(d, 'c_lambda', 1e-6),
    'c_lambda x 1e3': lambda d: scaled(d, 'c_lambda', 1e3),
    'covariance diagonal 1e300': lambda d: d['covariance_ln_csys_cf_clambda'][0].__setitem__(0, 1e300),
    'covariance c_lambda variance 1e6': lambda d: d['covariance_ln_csys_cf_clambda'][2].__setitem__(2, 1e6),
    'resonance speed negative': lambda d: d.__setitem__(
        'extension', {'effect': 'resonance', 'params': {'resonant_speed': -1.0, 'damping_ratio': 0.05}}),
    'resonance damping negative': lambda d: d.__setitem__(
        'extension', {'effect': 'resonance', 'params': {'resonant_speed': 30.0, 'damping_ratio': -0.05}}),
    'background negative': lambda d: d.__setitem__(
        'extension', {'effect': 'background_vibration', 'params': {'background_rms': -0.2}}),
    'thermal slope negative': lambda d: d.__setitem__(
        'extension', {'effect': 'thermal_viscosity',
                      'params': {'viscosity_temperature_coefficient': -0.03, 'reference_temperature': 25.0}}),
    'thermal reference below absolute zero': lambda d: d.__setitem__(
        'extension', {'effect': 'thermal_viscosity',
                      'params': {'viscosity_temperature_coefficient': 0.03, 'reference_temperature': -500.0}}),
    'second effect negative': lambda d: d.__setitem__('extension', {
        'effect': 'resonance', 'params': {'resonant_speed': 30.0, 'damping_ratio': 0.05},
        'effects': [{'effect': 'resonance', 'params': {'resonant_speed': 30.0, 'damping_ratio': 0.05}},
                    {'effect': 'background_vibration', 'params': {'background_rms': -1.0}}]}),
    'effects not a list': lambda d: d.__setitem__('extension', {
        'effect': 'resonance', 'params': {'resonant_speed': 30.0, 'damping_ratio': 0.05}, 'effects': 'x'}),
    'domain of one number': lambda d: d.__setitem__('domain', {'speed_rad_s': [10.0], 'load_n': [100.0, 200.0]}),
    'domain empty range': lambda d: d.__setitem__('domain', {'speed_rad_s': [], 'load_n': [100.0, 200.0]}),
    'domain reversed': lambda d: d.__setitem__('domain', {'speed_rad_s': [20.0, 10.0]}),
    'domain text': lambda d: d.__setitem__('domain', {'load_n': ['a', 'b']}),
    'domain a list': lambda d: d.__setitem__('domain', [[1.0]]),
}

#: Words the line of each issue-36 edit holds: the field it names.
FIELDS = {'c_f negative': 'c_f', 'c_f zero': 'c_f', 'c_f x 1e5': 'c_f', 'c_lambda x 1e-6': 'c_lambda',
          'c_lambda x 1e3': 'c_lambda', 'covariance diagonal 1e300': 'covariance',
          'covariance c_lambda variance 1e6': 'covariance', 'resonance speed negative': 'resonant_speed',
          'resonance damping negative': 'damping_ratio', 'background negative': 'background_rms',
          'thermal slope negative': 'viscosity_temperature_coefficient',
          'thermal reference below absolute zero': 'reference_temperature',
          'second effect negative': 'effects[1] parameter background_rms', 'effects not a list': 'effects',
          'domain of one number': 'domain speed_rad_s', 'domain empty range': 'domain speed_rad_s',
          'domain reversed': 'domain speed_rad_s', 'domain text': 'domain load_n', 'domain a list': 'domain'}


@pytest.mark.parametrize('edit', sorted(EDITS))
def test_an_edited_value_is_refused_in_one_line_naming_the_file_without_a_numpy_warning(tmp_path, document, edit):
    EDITS[edit](document)
    path = write(tmp_path, document)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        with pytest.raises(ConfigError) as caught:
            load_calibration(path)
    assert str(path) in str(caught.value) and '\n' not in str(caught.value), str(caught.value)
    assert FIELDS.get(edit, '') in str(caught.value), str(caught.value)


def test_a_negative_c_f_the_fit_itself_flagged_still_loads(tmp_path, document):
    """Real bearings can fit C_F < 0 (FEMTO's test_early); calibrate then says so in fit.flags, and it loads."""
    from prsm_lube_ros.estimation.calibration import sign_flags
    from prsm_lube_ros.physics.vibration_model import ModelConstants
    scaled(document, 'c_f', -0.2)
    document['fit']['flags'] = sign_flags(ModelConstants(**document['constants']))
    assert load_calibration(write(tmp_path, document)).constants.c_f < 0
    document['fit']['flags'] = []
    with pytest.raises(ConfigError, match='fit.flags'):
        load_calibration(write(tmp_path, document))


def test_a_written_calibration_cut_short_anywhere_is_refused(tmp_path):
    """Issue 36: a truncated file was read as an older format; now every cut at a line or inside one is refused."""
    from prsm_lube_ros.estimation.calibration_file import SEAL_HEAD
    data = seed_calibration(tmp_path / 'seed.yaml').read_bytes()
    assert data.startswith(SEAL_HEAD.encode()) and load_calibration(tmp_path / 'seed.yaml')
    lines = {i + 1 for i, byte in enumerate(data) if byte == ord('\n')}
    cuts = sorted(lines | set(range(len(SEAL_HEAD), len(data), 97)))
    loaded = []
    for cut in cuts[:-1]:
        path = tmp_path / 'cut.yaml'
        path.write_bytes(data[:cut])
        try:
            load_calibration(path)
            loaded.append(cut)
        except ConfigError as exc:
            assert str(path) in str(exc) and '\n' not in str(exc)
    assert not loaded, f'cut at {loaded} of {len(data)} bytes loaded'


def test_a_changed_byte_in_a_written_calibration_is_refused_and_older_files_still_load(tmp_path, repo_root):
    path = seed_calibration(tmp_path / 'seed.yaml')
    text = path.read_text()
    path.write_text(text.replace('windows_used: 60', 'windows_used: 61'))
    with pytest.raises(ConfigError, match='changed after it was written'):
        load_calibration(path)
    path.write_text(text.split('\n', 1)[1])            # its first line deleted: loaded unchecked, as older files
    assert load_calibration(path).windows_used == 60
    old = load_calibration(repo_root / 'test' / 'data' / 'calibration' / 'before_band.yaml')
    assert old.constants.c_f > 0


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
