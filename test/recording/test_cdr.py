# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Bulk CDR decoding of the contract's messages against rosbags' own deserializer, and the layout check."""
import numpy as np
import pytest

from prsm_lube_ros.contract import JOINT_STATE, VIBRATION_BLOCK
from prsm_lube_ros.recording.cdr import check_layout, decode_messages
from prsm_lube_ros.recording.typestore import contract_typestore, message_definition


def serialized(messages, msgtype):
    """One buffer with the CDR of each message, its offsets and lengths."""
    store = contract_typestore()
    raw = [bytes(store.serialize_cdr(m, msgtype)) for m in messages]
    lengths = np.array([len(r) for r in raw], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    return np.frombuffer(b''.join(raw), dtype=np.uint8), offsets, lengths, raw


def vibration(store, k, n):
    T = store.types
    header = T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=1_700_000_000 + k, nanosec=k * 7),
                                      frame_id='nut' if k % 2 else '')
    return T[VIBRATION_BLOCK](header=header, sample_rate=4000.0 + k,
                              samples=np.linspace(-1, 1, n).astype(np.float32) * (k + 1))


@pytest.mark.parametrize('vectorised', [True, False])
def test_vibration_blocks_decode_as_rosbags_reads_them(vectorised):
    store = contract_typestore()
    messages = [vibration(store, k, n) for k, n in enumerate([400, 400, 400, 13, 0, 400])]
    buffer, offsets, lengths, raw = serialized(messages, VIBRATION_BLOCK)
    decoded = decode_messages('vibration', buffer, offsets, lengths, np.arange(len(messages), dtype=np.int64),
                              vectorised=vectorised)
    assert decoded.undecodable == 0
    reference = [store.deserialize_cdr(r, VIBRATION_BLOCK) for r in raw]
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in reference]
    assert decoded.columns['stamps'].tolist() == stamps
    assert decoded.columns['sample_rates'].tolist() == [m.sample_rate for m in reference]
    for k, message in enumerate(reference):
        block = decoded.samples[decoded.offsets[k]:decoded.offsets[k + 1]]
        assert np.array_equal(block, message.samples)


def test_joint_states_take_the_screw_entry_wherever_it_stands():
    store = contract_typestore()
    T = store.types
    header = T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=5, nanosec=0), frame_id='')
    messages = [T[JOINT_STATE](header=header, name=names, position=np.arange(len(names), dtype=float) + 1,
                               velocity=-np.arange(len(names), dtype=float) - 1, effort=np.zeros(0))
                for names in (['screw'], ['motor', 'screw'], ['motor'])]
    buffer, offsets, lengths, _ = serialized(messages, JOINT_STATE)
    decoded = decode_messages('joint_states', buffer, offsets, lengths, np.arange(3, dtype=np.int64))
    assert decoded.columns['angles'].tolist()[:2] == [1.0, 2.0]
    assert decoded.columns['speeds'].tolist()[:2] == [-1.0, -2.0]
    assert decoded.without_screw == 1


def test_layout_check_accepts_the_contract_under_any_package_and_names_what_differs():
    text = message_definition('VibrationBlock')
    assert check_layout('vibration', 'other_stack/msg/VibrationBlock', 'ros2msg', text) is None
    wrong = text.replace('float32[] samples', 'float64[] samples')
    reason = check_layout('vibration', 'other_stack/msg/VibrationBlock', 'ros2msg', wrong)
    assert reason and 'samples float64[]' in reason and '\n' not in reason
    assert 'does not parse' in check_layout('vibration', 'x/msg/VibrationBlock', 'ros2msg', 'float64[ samples')
