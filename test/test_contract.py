# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""One topic-name rule for reader, writer and estimator (they used to disagree on prefixes)."""
import pytest

from prsm_lube_ros.contract import namespace_of, topic_name


@pytest.mark.parametrize('namespace, leaf, topic', [
    ('/prsm', 'vibration', '/prsm/vibration'),
    ('prsm', 'vibration', '/prsm/vibration'),
    ('prsm/', 'vibration', '/prsm/vibration'),
    ('/', 'vibration', '/vibration'),
    ('/rig/left_', 'vibration', '/rig/left_vibration'),
    ('/ema_left/prsm', '/diagnostics', '/diagnostics'),
    ('', 'vibration', 'vibration'),
])
def test_topic_names(namespace, leaf, topic):
    assert topic_name(namespace, leaf) == topic


@pytest.mark.parametrize('namespace', ['/prsm', '/rig/left_', '/a/b/c'])
def test_namespace_of_inverts_topic_name(namespace):
    assert namespace_of(topic_name(namespace, 'vibration')) == namespace


def test_writer_and_reader_agree_on_a_prefix_namespace(tmp_path):
    """A bag written under the prefix /rig/left_ is found by the reader under the same namespace."""
    from prsm_lube_ros.recording.reader import find_actuators
    from prsm_lube_ros.simulation.recordings import simulate_experiment
    from prsm_lube_ros.simulation.rig_config import ExperimentPlan
    import dataclasses
    from prsm_lube_ros.simulation.rig_config import RigConfig
    plan = dataclasses.replace(ExperimentPlan(), speeds=(15.0,), loads=(100.0,), stage_thetas=(1.0,))
    bag = simulate_experiment(tmp_path, plan=plan, rig=RigConfig(namespace='/rig/left_'), seed=1)[0]
    assert find_actuators(bag) == ['/rig/left_']
