# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Raw vibration blocks: the CDR bytes rclpy hands a ``raw=True`` subscription decode to what the message holds."""
import numpy as np
import pytest
from rclpy.serialization import serialize_message

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.nodes.lubrication_estimator import join_batches
from prsm_lube_ros.nodes.raw_inputs import decode_block, join_blocks, raw_vibration_converter
from prsm_lube_ros.nodes.ros_convert import vibration_batch, vibration_block_msg
from prsm_lube_ros.recording.batches import VibrationBatch


@pytest.mark.parametrize('frame_id', ['', 'n', 'nut', 'nut_accel', 'sensor frame with 9+ bytes'])
@pytest.mark.parametrize('count', [0, 1, 3, 400])
def test_a_serialized_block_decodes_to_the_messages_fields(frame_id, count):
    samples = np.random.default_rng(count).normal(size=count).astype(np.float32)
    msg = vibration_block_msg(1_700_000_123.25, 4000.0, samples, frame_id=frame_id)
    block = decode_block(serialize_message(msg))
    expected = vibration_batch(msg)
    assert block.stamp == expected.stamps[0] and block.sample_rate == 4000.0 and block.frame_id == frame_id
    assert block.samples.dtype == np.float32 and np.array_equal(block.samples, samples)


def test_big_endian_cdr_is_read_too():
    samples = np.array([1.5, -2.25, 3.0], np.float32)
    little = serialize_message(vibration_block_msg(1_700_000_000.5, 51200.0, samples, frame_id='nut'))
    body = bytearray(little[:4])
    body[1] = 0
    body += (1_700_000_000).to_bytes(4, 'big') + (500_000_000).to_bytes(4, 'big') + (4).to_bytes(4, 'big') + b'nut\0'
    body += np.array([51200.0], '>f8').tobytes() + (3).to_bytes(4, 'big') + samples.astype('>f4').tobytes()
    block = decode_block(bytes(body))
    assert (block.stamp, block.sample_rate, block.frame_id) == (1_700_000_000.5, 51200.0, 'nut')
    assert block.samples.dtype.isnative and np.array_equal(block.samples, samples)


@pytest.mark.parametrize('cut', [0, 3, 10, 17, 30, -1])
def test_a_short_or_foreign_buffer_is_one_input_error_naming_the_topic(cut):
    data = serialize_message(vibration_block_msg(1_700_000_000.0, 4000.0, np.ones(8, np.float32), frame_id='nut'))
    with pytest.raises(InputError, match='^/a/vibration: .*left out'):
        decode_block(data[:cut] if cut >= 0 else b'\x01\x07' + data[2:], '/a/vibration')


def test_a_zero_stamp_is_refused_as_for_a_message():
    data = serialize_message(vibration_block_msg(0.0, 4000.0, np.ones(8, np.float32)))
    with pytest.raises(InputError, match='stamp is zero'):
        decode_block(data)


def test_blocks_joined_keep_each_blocks_samples_and_the_converter_reports_the_frame():
    frames = []
    convert = raw_vibration_converter('/a/vibration', frames.append)
    messages = [vibration_block_msg(100.0 + 0.1 * k, 4000.0, np.full(k + 2, k, np.float32), frame_id=f'f{k}')
                for k in range(3)]
    batches = [convert(serialize_message(msg)) for msg in messages]
    joined = join_batches(batches)
    assert isinstance(joined, VibrationBatch) and np.array_equal(join_blocks(batches).samples, joined.samples)
    assert frames == ['f0', 'f1', 'f2']
    assert joined.offsets.tolist() == [0, 2, 5, 9] and joined.stamps.tolist() == [100.0, 100.1, 100.2]
    for k in range(3):
        assert np.array_equal(joined.samples[joined.offsets[k]:joined.offsets[k + 1]], np.full(k + 2, k))


def joint_state(names, positions, velocities, efforts=(), frame_id='', stamp=1_700_000_000.375):
    from sensor_msgs.msg import JointState
    from prsm_lube_ros.nodes.ros_convert import time_msg
    msg = JointState(name=list(names), position=list(positions), velocity=list(velocities), effort=list(efforts))
    msg.header.stamp, msg.header.frame_id = time_msg(stamp), frame_id
    return msg


@pytest.mark.parametrize('frame_id', ['', 'b', 'base_link', 'a frame of 17 ch'])
@pytest.mark.parametrize('names, positions, velocities, efforts', [
    (['screw'], [1.5], [20.0], []),
    (['motor', 'screw', 'x'], [0.1, 2.5, 0.3], [1.0, -19.5, 3.0], [0.5, 0.25, 0.0]),
    (['screw', 'motor'], [3.0], [], [1.0]),         # shorter arrays: NaN
    (['s', 'screw'], [], [], []),
])
def test_a_raw_joint_state_reads_as_the_message_does(frame_id, names, positions, velocities, efforts):
    from prsm_lube_ros.nodes.raw_inputs import _screw, raw_screw_converter
    from prsm_lube_ros.nodes.ros_convert import screw_batch
    msg = joint_state(names, positions, velocities, efforts, frame_id)
    data = serialize_message(msg)
    assert _screw(data, b'screw') is not None          # read here, not by the typed fallback
    raw, typed = raw_screw_converter('/a/joint_states', 'screw')(data), screw_batch(msg, '/a/joint_states')
    for field in ('stamps', 'angles', 'speeds'):
        assert np.array_equal(getattr(raw, field), getattr(typed, field), equal_nan=True)


def test_a_raw_joint_state_without_the_screw_or_a_stamp_is_the_typed_paths_input_error():
    from prsm_lube_ros.nodes.raw_inputs import raw_screw_converter
    convert = raw_screw_converter('/a/joint_states', 'screw')
    with pytest.raises(InputError, match="^/a/joint_states: JointState without the 'screw' entry"):
        convert(serialize_message(joint_state(['motor'], [1.0], [2.0])))
    with pytest.raises(InputError, match='stamp is zero'):
        convert(serialize_message(joint_state(['screw'], [1.0], [2.0], stamp=0.0)))
    data = serialize_message(joint_state(['screw'], [1.0], [2.0]))
    with pytest.raises(Exception):
        convert(data[:30])                              # cut bytes: neither path reads them


@pytest.mark.parametrize('frame_id', ['', 'load_cell', 'x' * 9])
def test_a_raw_wrench_reads_as_the_message_does(frame_id):
    from geometry_msgs.msg import WrenchStamped
    from prsm_lube_ros.nodes.raw_inputs import _load, raw_load_converter
    from prsm_lube_ros.nodes.ros_convert import load_batch, time_msg
    msg = WrenchStamped()
    msg.header.stamp, msg.header.frame_id = time_msg(1_700_000_001.5), frame_id
    msg.wrench.force.x, msg.wrench.force.z, msg.wrench.torque.z = 3.0, -151.25, 7.0
    data = serialize_message(msg)
    assert _load(data) is not None
    raw, typed = raw_load_converter('/a/axial_load')(data), load_batch(msg)
    assert raw.stamps.tolist() == typed.stamps.tolist() and raw.forces.tolist() == typed.forces.tolist() == [-151.25]


@pytest.mark.parametrize('frame_id', ['', 'base_link'])
@pytest.mark.parametrize('names, positions, velocities, efforts', [
    (['screw'], [1.5], [20.0], []),
    (['motor', 'screw', 'x'], [0.1, 2.5, 0.3], [1.0, -19.5, 3.0], [0.5, 0.25, 0.0]),
])
def test_a_drained_queue_of_joint_states_reads_at_once_as_one_at_a_time(frame_id, names, positions, velocities,
                                                                        efforts):
    from prsm_lube_ros.nodes.lubrication_estimator import join_batches
    from prsm_lube_ros.nodes.raw_inputs import raw_screw_converter
    rng = np.random.default_rng(len(names))
    queue = []
    for k in range(12):
        shifted = [p + rng.normal() for p in positions]
        queue.append(serialize_message(joint_state(names, shifted, [v * rng.uniform(0.5, 2) for v in velocities],
                                                   efforts, frame_id, stamp=1_700_000_000.0 + 0.0101 * k)))
    convert = raw_screw_converter('/a/joint_states', 'screw')
    assert convert.many(queue) is None                      # nothing learnt yet: one at a time
    one_by_one = join_batches([convert(data) for data in queue])
    at_once = convert.many(queue)
    assert at_once is not None
    for field in ('stamps', 'angles', 'speeds'):
        assert np.array_equal(getattr(at_once, field), getattr(one_by_one, field))
        assert getattr(at_once, field).dtype == np.float64


def test_a_queue_that_leaves_the_learnt_layout_is_read_one_at_a_time():
    from prsm_lube_ros.nodes.raw_inputs import raw_screw_converter
    convert = raw_screw_converter('/a/joint_states', 'screw')

    def message(k, names=('motor', 'screw'), frame_id='', stamp=None):
        return serialize_message(joint_state(list(names), [0.1 * k, 2.0 * k], [1.0, 20.0], [], frame_id,
                                             stamp=1_700_000_000.0 + 0.01 * k if stamp is None else stamp))
    convert(message(0))
    good = [message(k) for k in range(1, 6)]
    assert convert.many(good) is not None
    padded = bytearray(good[2])
    padded[72] = 0x79              # alignment padding before the velocities (a serializer may leave anything)
    assert convert.many([*good[:2], bytes(padded), *good[3:]]).angles.tolist() == [2.0 * k for k in range(1, 6)]
    for odd in (message(9, names=('screw', 'motor')),      # same size, other order: other bytes shared
                message(9, names=('motor', 'screw', 'x')),  # another size
                message(9, frame_id='base'),
                message(9, stamp=0.0),                      # zero stamp: the typed path's error
                message(9, stamp=1_700_000_000.02)):        # stamp going back
        convert(message(0))                                 # (re)learn
        assert convert.many([*good, odd]) is None, odd


def test_a_drained_queue_of_wrenches_reads_at_once_as_one_at_a_time():
    from geometry_msgs.msg import WrenchStamped
    from prsm_lube_ros.nodes.lubrication_estimator import join_batches
    from prsm_lube_ros.nodes.raw_inputs import raw_load_converter
    from prsm_lube_ros.nodes.ros_convert import time_msg
    queue = []
    for k in range(7):
        msg = WrenchStamped()
        msg.header.stamp, msg.header.frame_id = time_msg(1_700_000_001.5 + 0.02 * k), 'load_cell'
        msg.wrench.force.x, msg.wrench.force.z, msg.wrench.torque.z = 3.0 * k, -151.25 + k, 7.0
        queue.append(serialize_message(msg))
    convert = raw_load_converter('/a/axial_load')
    one_by_one = join_batches([convert(data) for data in queue])
    at_once = convert.many(queue)
    assert at_once is not None
    assert np.array_equal(at_once.stamps, one_by_one.stamps) and np.array_equal(at_once.forces, one_by_one.forces)
    assert at_once.forces.tolist() == [-151.25 + k for k in range(7)]


def test_a_queue_with_a_zero_stamp_anywhere_is_read_one_at_a_time():
    """Stamps rising through zero (before 1970: sec < 0): the message stamped zero is refused one at a time
    (never set by its publisher), so the queue read at once must not take it either."""
    from prsm_lube_ros.nodes.raw_inputs import raw_screw_converter
    convert = raw_screw_converter('/a/joint_states', 'screw')
    queue = []
    for sec, nanosec in ((-1, 980_000_000), (-1, 990_000_000), (0, 0), (0, 10_000_000)):
        msg = joint_state(['screw'], [1.0], [20.0])
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        queue.append(serialize_message(msg))
    convert(queue[0])                                       # learnt
    with pytest.raises(InputError, match='stamp is zero'):
        convert(queue[2])
    assert convert.many(queue) is None


def plain_cdr_joint_state(order, sec, nanosec, names, positions, velocities, frame_id='base', padding=b'\xaa'):
    """A JointState in plain CDR of byte ``order`` ('<' or '>'), alignment padding filled with ``padding``."""
    import struct
    data = bytearray(b'\0' + (b'\1' if order == '<' else b'\0') + b'\0\0')

    def put(code, *values):
        size = struct.calcsize(code[-1])
        while (len(data) - 4) % size:
            data.extend(padding)
        data.extend(struct.pack(order + code, *values))

    def text(value):
        raw = value.encode() + b'\0'
        put('I', len(raw))
        data.extend(raw)

    put('i', sec), put('I', nanosec), text(frame_id), put('I', len(names))
    for name in names:
        text(name)
    for values in (positions, velocities, ()):
        put('I', len(values))
        if values:
            put(f'{len(values)}d', *values)
    return bytes(data)


@pytest.mark.parametrize('order', ['<', '>'])
def test_a_drained_queue_in_either_byte_order_reads_at_once_as_one_at_a_time(order):
    from prsm_lube_ros.nodes.lubrication_estimator import join_batches
    from prsm_lube_ros.nodes.raw_inputs import raw_screw_converter
    queue = [plain_cdr_joint_state(order, 1_700_000_000, 10_000_000 * k, ['m', 'screw'], [0.1 * k, 2.0 * k],
                                   [1.0, 20.0 + k], padding=bytes([k])) for k in range(6)]
    convert = raw_screw_converter('/a/joint_states', 'screw')
    one_by_one = join_batches([convert(data) for data in queue])
    at_once = convert.many(queue)
    assert at_once is not None and at_once.speeds.tolist() == [20.0 + k for k in range(6)]
    for field in ('stamps', 'angles', 'speeds'):
        assert np.array_equal(getattr(at_once, field), getattr(one_by_one, field))
        assert getattr(at_once, field).dtype == np.float64
