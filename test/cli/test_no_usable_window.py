# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A recording with messages on the contract topics but no usable window is one line and a non-zero status."""

import numpy as np
import pytest

import bagfactory as bf
from prsm_lube_ros.cli import main
from prsm_lube_ros.estimation.calibration import Calibration
from prsm_lube_ros.estimation.calibration_file import save_calibration
from prsm_lube_ros.physics.vibration_model import ModelConstants


def standstill(entries):
    """``entries`` with every JointState replaced by the screw standing still."""
    store = bf.typestore()
    out = []
    for index, (topic, msgtype, log_time, message) in enumerate(entries):
        if topic.endswith('/joint_states'):
            message = store.types['sensor_msgs/msg/JointState'](
                header=message.header, name=['screw'], position=np.array([1.0]), velocity=np.array([0.0]),
                effort=np.zeros(0))
        out.append((topic, msgtype, log_time, message))
    return out


@pytest.mark.parametrize('case, needle', [('standstill', 'standstill'), ('accelerating', 'steady speed')])
def test_no_usable_window_says_why_in_one_line(tmp_path, capsys, case, needle):
    entries = bf.contract_entries(seconds=6.0)
    if case == 'standstill':
        entries = standstill(entries)
    bag = bf.write_rosbag2(tmp_path / case, entries)
    status = main(['calibrate', str(bag), '--out', str(tmp_path / 'c.yaml')])
    err = capsys.readouterr().err
    assert status != 0 and 'Traceback' not in err
    last = err.strip().splitlines()[-1]
    assert 'no usable window' in last and needle in last and str(bag) in last
    assert not (tmp_path / 'c.yaml').exists()


def test_assess_of_a_standstill_recording_is_not_zero_runs_with_status_zero(tmp_path, capsys):
    calibration = tmp_path / 'c.yaml'
    save_calibration(Calibration(ModelConstants(1e-3, 1e-3, 0.5), np.eye(3) * 1e-4, 0.01, 0.01, 10, 1.0),
                     calibration)
    bag = bf.write_rosbag2(tmp_path / 'still', standstill(bf.contract_entries(seconds=6.0)))
    status = main(['assess', str(bag), '--calibration', str(calibration), '--json', str(tmp_path / 'a.json')])
    captured = capsys.readouterr()
    assert status != 0 and '0 runs' not in captured.out
    last = captured.err.strip().splitlines()[-1]
    assert 'no usable window' in last and 'standstill' in last and str(bag) in last
    assert not (tmp_path / 'a.json').exists()


@pytest.mark.parametrize('case', ['standstill', 'accelerating'])
def test_the_calibrate_service_says_it_in_the_commands_words(tmp_path, capsys, case):
    """One answer to "which recording has no usable window, and why": the node's request and the CLI agree."""
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.estimation.pipeline import analysis_settings
    from prsm_lube_ros.estimation.windowing import MIN_AXIAL_LOAD
    from prsm_lube_ros.nodes.calibration_request import calibrate_from_request
    from prsm_lube_ros.physics.actuator import load_actuator
    entries = bf.contract_entries(seconds=6.0)
    bag = bf.write_rosbag2(tmp_path / case, standstill(entries) if case == 'standstill' else entries)
    main(['calibrate', str(bag), '--out', str(tmp_path / 'c.yaml')])
    command_line = capsys.readouterr().err.strip().splitlines()[-1]
    with pytest.raises(InputError) as refused:
        calibrate_from_request([case], 1.0, folder=tmp_path, lead=load_actuator(None).lead, namespace='/prsm',
                               settings=analysis_settings(), min_axial_load=MIN_AXIAL_LOAD)
    because = command_line[command_line.index('no usable window'):]
    assert str(refused.value) == f'calibrate: {bag}: {because} (topics under /prsm)'
