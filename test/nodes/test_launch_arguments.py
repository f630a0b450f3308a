# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The launch file's argument logic (prsm_lube_ros.nodes.launch_arguments), plain Python: no ROS, no launch."""
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.nodes.launch_arguments import bringup_plan, flag, LAUNCH_ARGUMENTS


def test_the_launch_arguments_become_namespace_log_level_parameter_files_and_autostart(tmp_path):
    site = tmp_path / 'site.yaml'
    site.write_text("'/**/lubrication_estimator':\n  ros__parameters:\n    warn_below: 0.9\n")
    names = [a[0] for a in LAUNCH_ARGUMENTS]
    assert names[:5] == ['namespace', 'log_level', 'use_sim_time', 'params_file', 'autostart']
    default = bringup_plan({}, '/share/config')
    assert default.autostart
    assert default.estimator.parameters == ('/share/config/estimator.yaml',
                                            {'use_sim_time': False, 'autostart': True})
    assert default.bridge.parameters == ('/share/config/sensor_bridge.yaml',
                                         {'use_sim_time': False, 'autostart': True})
    assert default.bridge.executable == 'sensor_bridge_managed'
    plan = bringup_plan({'namespace': '/rig/left', 'log_level': 'DEBUG', 'use_sim_time': 'true',
                         'params_file': str(site), 'autostart': 'false'}, '/share/config')
    assert plan.estimator.namespace == '/rig/left' == plan.bridge.namespace and not plan.autostart
    assert plan.bridge.ros_arguments == ('--log-level', 'debug')
    assert plan.estimator.parameters == ('/share/config/estimator.yaml', str(site),
                                         {'use_sim_time': True, 'autostart': False})
    assert bringup_plan({'bridge': 'false'}, '/c').bridge is None


def test_the_default_namespace_is_left_to_the_enclosing_launch():
    """'' (no namespace of the nodes' own): a PushRosNamespace decides, else the nodes' built-in /prsm."""
    default = bringup_plan({}, '/c')
    assert default.estimator.namespace == '' == default.bridge.namespace
    assert {name: default for name, default, _ in LAUNCH_ARGUMENTS}['namespace'] == ''
    assert bringup_plan({'namespace': 'prsm'}, '/c').estimator.namespace == 'prsm'     # relative: below a push
    assert bringup_plan({'namespace': ' /robot/left '}, '/c').bridge.namespace == '/robot/left'


@pytest.mark.parametrize('bad, word', [
    ({'log_level': 'loud'}, 'log_level'), ({'autostart': 'yes please'}, 'autostart'),
    ({'namespace': 'rig left'}, 'namespace'), ({'namespace': '/'}, 'namespace'),
    ({'namespace': '/9rig'}, 'namespace'), ({'use_sim_time': 'maybe'}, 'use_sim_time'), ({'bridge': 'no!'}, 'bridge'),
    ({'params_file': 'NO_FILE'}, 'params_file'),
])
def test_a_bad_argument_is_one_line_naming_it(bad, word, tmp_path):
    if 'params_file' in bad:
        bad = {'params_file': str(tmp_path / 'missing.yaml')}
    with pytest.raises(InputError, match=f'launch argument {word}:=') as raised:
        bringup_plan(bad, '/c')
    assert '\n' not in str(raised.value)


def test_flags_read_as_launch_reads_them():
    assert [flag('x', v) for v in ('true', 'True', '1', ' false ', 'FALSE', '0')] == [True] * 3 + [False] * 3
    with pytest.raises(InputError, match='x:='):
        flag('x', 'on')


def test_own_config_files_replace_the_packages():
    plan = bringup_plan({'estimator_config': '/site/est.yaml', 'bridge_config': '/site/bridge.yaml'}, '/c')
    assert plan.estimator.parameters[0] == '/site/est.yaml' and plan.bridge.parameters[0] == '/site/bridge.yaml'
