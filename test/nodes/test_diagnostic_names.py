# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The example diagnostic_aggregator configuration matches the status names the nodes publish.

``GenericAnalyzer`` claims a status when its name starts with a ``startswith``
entry, contains a ``contains`` entry, equals a ``name`` entry or matches a
``regex`` entry; every status the nodes publish must be claimed by exactly one
analyzer of ``config/diagnostic_aggregator.yaml``.
"""
from pathlib import Path
import re
from types import SimpleNamespace

import pytest
import yaml

pytest.importorskip('rclpy')
pytest.importorskip('prsm_lube_ros.msg')

from prsm_lube_ros.contract import LUBRICATION_TASK, SOURCE_TASK, status_name, SURFACE_TASK  # noqa: E402
from prsm_lube_ros.nodes.lubrication_estimator import ActuatorChannel, INPUT_KEYS, INPUT_TASK  # noqa: E402

CONFIG = Path(__file__).resolve().parents[2] / 'config' / 'diagnostic_aggregator.yaml'


def analyzers():
    """name -> parameters of each analyzer in the example file."""
    parameters = yaml.safe_load(CONFIG.read_text())['analyzers']['ros__parameters']
    return {key: value for key, value in parameters.items() if isinstance(value, dict)}


def claims(analyzer: dict, name: str) -> bool:
    """Whether a GenericAnalyzer with ``analyzer``'s parameters takes a status called ``name``."""
    return (any(name.startswith(s) for s in analyzer.get('startswith', []))
            or any(s in name for s in analyzer.get('contains', []))
            or name in analyzer.get('name', [])
            or any(re.match(r, name) for r in analyzer.get('regex', [])))


def estimator_status_name(node_name, actuator):
    """The estimator's status name for ``actuator``, from the node's own property."""
    return ActuatorChannel.status_name.fget(SimpleNamespace(node_name=node_name, name=actuator))


def test_every_analyzer_is_a_generic_analyzer_with_a_path():
    found = analyzers()
    assert set(found) == {'lubrication', 'surface_condition', 'sensor_sources', 'inputs'}
    for analyzer in found.values():
        assert analyzer['type'] == 'diagnostic_aggregator/GenericAnalyzer' and analyzer['path']


NAMES = [('lubrication_estimator', '/prsm'), ('lubrication_estimator', '/ema_left'),
         ('estimator_lubrication_rig', '/lubrication/prsm'), ('lube', '/sensor/source'), ('sensor_bridge', '/')]


@pytest.mark.parametrize('node_name, actuator', NAMES)
def test_an_estimator_status_is_claimed_by_the_lubrication_analyzer_only(node_name, actuator):
    name = estimator_status_name(node_name, actuator)
    assert name == status_name(node_name, actuator, LUBRICATION_TASK)
    assert [key for key, a in analyzers().items() if claims(a, name)] == ['lubrication']


@pytest.mark.parametrize('node_name, actuator', NAMES)
def test_a_surface_condition_status_is_claimed_by_the_surface_analyzer_only(node_name, actuator):
    name = ActuatorChannel.surface_status_name.fget(SimpleNamespace(node_name=node_name, name=actuator))
    assert name == status_name(node_name, actuator, SURFACE_TASK)
    assert [key for key, a in analyzers().items() if claims(a, name)] == ['surface_condition']


@pytest.mark.parametrize('node_name, namespace', NAMES)
def test_a_bridge_status_is_claimed_by_the_sensor_analyzer_only(node_name, namespace):
    name = status_name(node_name, namespace, SOURCE_TASK)
    assert [key for key, a in analyzers().items() if claims(a, name)] == ['sensor_sources']


@pytest.mark.parametrize('node_name, actuator', NAMES)
@pytest.mark.parametrize('key', INPUT_KEYS)
def test_an_input_status_is_claimed_by_the_inputs_analyzer_only(node_name, actuator, key):
    name = status_name(node_name, actuator, INPUT_TASK.format(key=key))
    assert [k for k, a in analyzers().items() if claims(a, name)] == ['inputs']
