# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``colcon build`` + ``colcon test`` of this package in a fresh workspace, as a ROS user runs them.

The package is built with ``BUILD_TESTING=ON`` (tools/setup-env builds without
it), ``colcon test`` runs the pytest suite through ``ament_add_pytest_test``
(narrowed here with ``PYTEST_ADDOPTS=-k`` to the manifest tests, so the suite
does not run twice), and ``colcon test-result`` reads the JUnit file it wrote.
"""
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Set in the inner colcon test run, so that it does not start another one.
INNER = 'PRSM_INSIDE_COLCON_TEST'

pytestmark = [pytest.mark.timeout(900),
              pytest.mark.skipif(os.environ.get(INNER) == '1', reason='already inside colcon test'),
              pytest.mark.skipif(shutil.which('colcon') is None, reason='colcon is not installed')]


def test_colcon_test_runs_the_suite_and_test_result_reports_it(tmp_path):
    pytest.importorskip('rclpy')
    venv = Path(sys.prefix)
    (tmp_path / 'src').mkdir()
    (tmp_path / 'src' / 'prsm_lube_ros').symlink_to(ROOT)
    env = dict(os.environ, AMENT_PREFIX_PATH=str(venv), CMAKE_PREFIX_PATH=str(venv),
               PATH=f'{venv / "bin"}:{os.environ["PATH"]}')

    def colcon(*args, **extra):
        result = subprocess.run(['colcon', '--log-base', 'log', *args], cwd=tmp_path, capture_output=True,
                                text=True, env=dict(env, **extra), timeout=800)
        assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
        return result.stdout

    colcon('build', '--event-handlers', 'console_cohesion-', '--cmake-args',
           f'-DPython3_EXECUTABLE={sys.executable}', '-DBUILD_TESTING=ON')
    colcon('test', '--event-handlers', 'console_cohesion-',
           PYTEST_ADDOPTS='-p no:cacheprovider -k test_package_manifest', **{INNER: '1'})
    report = colcon('test-result', '--test-result-base', 'build', '--verbose')
    summary = re.search(r'Summary: (\d+) tests?, (\d+) errors?, (\d+) failures?, (\d+) skipped', report)
    assert summary, report
    tests, errors, failures, _ = map(int, summary.groups())
    assert tests >= 3 and errors == 0 and failures == 0, report
    junit = list((tmp_path / 'build' / 'prsm_lube_ros' / 'test_results').rglob('*.xml'))
    assert junit and 'test_every_imported_ros_package_is_declared' in junit[0].read_text()
