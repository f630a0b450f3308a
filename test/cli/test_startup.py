# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Each command imports what it needs: --help loads no numpy, assess loads no diagnosis, scipy.optimize or ROS.

Behaviour, not timing (the times are in benchmarks/assess_throughput.py): which
modules a fresh process has loaded after the command.
"""
import json
import subprocess
import sys

import pytest

HEAVY = ('numpy', 'scipy', 'rclpy', 'rosbags', 'matplotlib', 'yaml', 'prsm_lube_ros.diagnosis',
         'prsm_lube_ros.estimation', 'prsm_lube_ros.simulation')


def loaded_after(code: str) -> list[str]:
    """Names from HEAVY (and their submodules) loaded by ``code`` in a fresh interpreter."""
    probe = (f'import sys, json\n{code}\n'
             f'print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r} '
             f'or m.startswith(("prsm_lube_ros.diagnosis", "prsm_lube_ros.estimation", "prsm_lube_ros.simulation", '
             f'"scipy.optimize", "scipy.stats")))))')
    out = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_building_the_parser_loads_nothing_heavy():
    assert loaded_after('from prsm_lube_ros.cli import build_parser\nbuild_parser()') == []


@pytest.mark.parametrize('command', ['--help', 'assess --help', 'simulate --help', 'diagnose --help'])
def test_help_loads_nothing_heavy(command):
    code = ('from prsm_lube_ros.cli import main\ntry:\n    main(' + repr(command.split()) + ')\n'
            'except SystemExit:\n    pass')
    assert loaded_after(code) == []


def test_assess_loads_neither_the_diagnosis_nor_the_optimiser_nor_ros(paper_experiment, tmp_path):
    from prsm_lube_ros.cli import main
    calibration = tmp_path / 'c.yaml'
    assert main(['calibrate', str(paper_experiment / 'stage_3'), '--out', str(calibration)]) == 0
    code = ('from prsm_lube_ros.cli import main\n'
            f'bag, calibration = {str(paper_experiment / "stage_1")!r}, {str(calibration)!r}\n'
            'assert main(["assess", bag, "--calibration", calibration]) == 0')
    loaded = loaded_after(code)
    assert 'numpy' in loaded and 'prsm_lube_ros.estimation.assessment' in loaded     # it did the work
    for name in ('prsm_lube_ros.diagnosis', 'scipy.optimize', 'scipy.stats', 'rclpy', 'matplotlib',
                 'prsm_lube_ros.simulation'):
        assert name not in loaded, f'assess loaded {name}'


def test_endurance_recording_as_a_bare_mcap_file(tmp_path):
    """prsm-lube simulate --endurance N --storage mcap-file failed ('a bare mcap bag must end in .mcap')."""
    from prsm_lube_ros.cli import main
    assert main(['simulate', str(tmp_path), '--endurance', '20', '--storage', 'mcap-file']) == 0
    assert (tmp_path / 'endurance.mcap').is_file()
