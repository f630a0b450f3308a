# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Fixtures shared across the test tree (which mirrors the package: physics/, recording/, ...).

Helpers that tests import by name (``bagfactory``, ``polling``,
``synthetic_inputs``) live in ``test/support/``, put on ``sys.path`` by the
``pythonpath`` setting in ``setup.cfg``.
"""
import os
from pathlib import Path
import sys

import pytest

#: The repository root (package.xml, config/, msg/).
ROOT = Path(__file__).resolve().parents[1]

#: Test modules that start ROS graphs (in this process or in a child) without the ``ros`` marker.
GRAPH_MODULES = ('test/cli/test_demo.py', 'test/cli/test_signals.py')

# Under pytest-xdist (tools/test runs two workers), each worker talks on its own DDS domain, so two
# workers' graphs never see each other's topics; the modules derive theirs from this one.
_WORKER = os.environ.get('PYTEST_XDIST_WORKER', '')
if _WORKER.startswith('gw') and _WORKER[2:].isdigit():
    _base = int(os.environ.get('ROS_DOMAIN_ID', '0') or 0)
    os.environ['ROS_DOMAIN_ID'] = str((_base + 13 * int(_WORKER[2:])) % 100 + 100)


def pytest_collection_modifyitems(config, items):
    """Put every test that runs a ROS graph in one xdist group: they run one after another on one worker.

    Graph tests wait on discovery and timers; two of them at once on a 2-core machine, beside the CPU-bound
    tests, is what makes them late. Without pytest-xdist the mark has no effect.
    """
    for item in items:
        try:
            path = Path(str(item.fspath)).resolve().relative_to(ROOT).as_posix()
        except ValueError:
            path = ''
        if item.get_closest_marker('ros') or path.startswith('test/nodes/') or path in GRAPH_MODULES:
            item.add_marker(pytest.mark.xdist_group('ros_graph'))


@pytest.fixture(scope='session')
def repo_root() -> Path:
    """The repository root."""
    return ROOT


@pytest.fixture(scope='session')
def paper_experiment(tmp_path_factory):
    """The rig simulator's recordings of the paper's experiment (three stages, random run order, seed 11)."""
    from prsm_lube_ros.cli import main
    out = tmp_path_factory.mktemp('experiment')
    assert main(['simulate', str(out), '--seed', '11', '--run-order', 'random']) == 0
    return out


@pytest.fixture
def fake_daq(monkeypatch):
    """The fake nidaqmx (``test/support/fake_nidaqmx.py``) in sys.modules for one test."""
    import fake_nidaqmx
    fake_nidaqmx.FakeTask.instances, fake_nidaqmx.FakeTask.fail_on = [], None
    for name, module in fake_nidaqmx.fake_nidaqmx().items():
        monkeypatch.setitem(sys.modules, name, module)
    return fake_nidaqmx.FakeTask


@pytest.fixture(scope='session')
def small_fleet(tmp_path_factory):
    """A simulated fleet (4 actuators, 6 days, bare .mcap files), calibrated and assessed into a history.

    A dict with ``root`` (recordings, ``truth.json``), ``calibration``, ``history`` and ``bags``.
    """
    from prsm_lube_ros.cli import main
    root = tmp_path_factory.mktemp('fleet')
    assert main(['simulate', str(root / 'fleet'), '--fleet', '4', '--days', '6', '--seed', '3',
                 '--storage', 'mcap-file']) == 0
    calibration, history = root / 'calibration.yaml', root / 'history'
    assert main(['calibrate', str(root / 'fleet' / 'reference.mcap'), '--out', str(calibration)]) == 0
    bags = sorted(str(p) for p in (root / 'fleet').glob('A*/*.mcap'))
    assert main(['assess', *bags, '--calibration', str(calibration), '--history', str(history),
                 '--actuator-id', 'folder']) == 0
    return {'root': root / 'fleet', 'calibration': calibration, 'history': history, 'bags': bags}
