# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Contract bags written by prsm_lube_ros.recording.writer read back with rosbags' AnyReader."""
from pathlib import Path

import numpy as np
import pytest
from rosbags.highlevel import AnyReader

from prsm_lube_ros import contract
from prsm_lube_ros.recording import typestore as interfaces
from prsm_lube_ros.recording.writer import bag_path, ContractBagWriter, STORAGE_FORMATS, topic_name
from prsm_lube_ros.errors import InputError

T0 = 1_767_225_600 * 10**9   # 2026-01-01T00:00:00Z in ns


def read_messages(path):
    """``{topic: [(log_time_ns, msgtype, message), ...]}`` and the log times in file order."""
    result, order = {}, []
    with AnyReader([Path(path)], default_typestore=interfaces.contract_typestore()) as reader:
        for connection, log_time, raw in reader.messages():
            message = reader.deserialize(raw, connection.msgtype)
            result.setdefault(connection.topic, []).append((log_time, connection.msgtype, message))
            order.append(log_time)
    return result, order


def write_sample_bag(path, storage):
    """Two chunks of closed-form data, the second handed over after a flush."""
    with ContractBagWriter(path, storage=storage, namespace='/rig7') as writer:
        for chunk in range(2):
            blocks = np.arange(2) + 2 * chunk
            stamps = T0 + blocks * 100_000_000                       # 0.1 s blocks
            samples = (blocks[:, None] + np.arange(400)[None, :] / 1000.0).astype(np.float32)
            writer.add_vibration(stamps, stamps + 100_500_000, 4000.0, samples, 'acc')
            joints = np.arange(20) + 20 * chunk
            joint_stamps = T0 + joints * 10_000_000                  # 100 Hz
            writer.add_joint_states(joint_stamps, joint_stamps + 400_000, 0.5 * joints, -0.25 * joints)
            loads = np.arange(10) + 10 * chunk
            load_stamps = T0 + loads * 20_000_000                    # 50 Hz
            writer.add_axial_loads(load_stamps, load_stamps + 300_000, 100.0 + loads, 'cell')
            if chunk == 1:
                writer.add_temperatures([T0 + 10**9], [T0 + 10**9 + 1000], [31.5], 0.0004, 'nut')
            writer.flush(T0 + (chunk + 1) * 200_000_000)
    return path


@pytest.mark.parametrize('storage', STORAGE_FORMATS)
def test_round_trip_in_every_storage_form(tmp_path, storage):
    path = write_sample_bag(bag_path(tmp_path, 'sample', storage), storage)
    if storage == 'mcap-file':
        assert path.is_file() and path.suffix == '.mcap'
        assert sorted(p.name for p in tmp_path.iterdir()) == ['sample.mcap']   # no metadata.yaml, no leftovers
    else:
        assert (path / 'metadata.yaml').is_file()
    topics, order = read_messages(path)
    assert order == sorted(order)                                  # written in log-time order
    assert set(topics) == {'/rig7/vibration', '/rig7/joint_states', '/rig7/axial_load', '/rig7/temperature'}
    assert [len(topics[t]) for t in ('/rig7/vibration', '/rig7/joint_states', '/rig7/axial_load',
                                     '/rig7/temperature')] == [4, 40, 20, 1]

    log_time, msgtype, block = topics['/rig7/vibration'][3]
    assert msgtype == contract.VIBRATION_BLOCK
    assert (block.header.stamp.sec, block.header.stamp.nanosec) == (1_767_225_600, 300_000_000)
    assert log_time == T0 + 300_000_000 + 100_500_000
    assert block.header.frame_id == 'acc' and block.sample_rate == 4000.0
    assert block.samples.dtype == np.float32
    np.testing.assert_array_equal(block.samples, (3 + np.arange(400) / 1000.0).astype(np.float32))

    _, msgtype, joint = topics['/rig7/joint_states'][25]
    assert msgtype == contract.JOINT_STATE
    assert list(joint.name) == ['screw']
    assert joint.position[0] == 12.5 and joint.velocity[0] == -6.25 and len(joint.effort) == 0
    assert joint.header.stamp.nanosec == 250_000_000

    _, msgtype, wrench = topics['/rig7/axial_load'][13]
    assert msgtype == contract.WRENCH_STAMPED
    assert wrench.wrench.force.z == 113.0 and wrench.header.frame_id == 'cell'
    assert wrench.wrench.force.x == wrench.wrench.torque.z == 0.0

    _, msgtype, temperature = topics['/rig7/temperature'][0]
    assert msgtype == contract.TEMPERATURE
    assert temperature.temperature == 31.5 and temperature.variance == pytest.approx(0.0004)
    assert temperature.header.stamp.sec == 1_767_225_601


def test_bag_path_and_topic_names(tmp_path):
    assert bag_path(tmp_path, 'stage_1') == tmp_path / 'stage_1'
    assert bag_path(tmp_path, 'stage_1', 'sqlite3') == tmp_path / 'stage_1'
    assert bag_path(tmp_path, 'stage_1', 'mcap-file') == tmp_path / 'stage_1.mcap'
    assert topic_name('/prsm', 'vibration') == '/prsm/vibration'
    assert topic_name('prsm/', 'vibration') == '/prsm/vibration'
    assert topic_name('/', 'vibration') == '/vibration'


def test_bad_requests_are_one_line_input_errors(tmp_path):
    with pytest.raises(InputError, match='storage must be one of'):
        ContractBagWriter(tmp_path / 'x', storage='bag')
    with pytest.raises(InputError, match=r'must end in \.mcap'):
        ContractBagWriter(tmp_path / 'x.db', storage='mcap-file')
    (tmp_path / 'taken').mkdir()
    with pytest.raises(InputError, match='exists already'):
        ContractBagWriter(tmp_path / 'taken')


def test_failure_inside_the_context_leaves_no_bag(tmp_path):
    for storage in STORAGE_FORMATS:
        path = bag_path(tmp_path, f'broken_{storage}', storage)
        with pytest.raises(RuntimeError):
            with ContractBagWriter(path, storage=storage) as writer:
                writer.add_joint_states([T0], [T0], [0.0], [0.0])
                raise RuntimeError('producer failed')
        assert not path.exists()
    assert list(tmp_path.iterdir()) == []
