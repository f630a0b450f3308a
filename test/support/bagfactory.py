# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Write small recordings of the contract's topics with rosbags, for tests and benchmarks.

Values follow closed forms so tests can check decoded data against them:

* vibration block ``b`` (stamp ``t0 + b * block_seconds``) holds samples
  ``b + i / 1000`` for ``i = 0..block-1`` (exact in float32 for small ``b``);
* joint state ``j`` (stamp ``t0 + j / joint_rate``): screw angle ``0.5 * j``, speed ``-0.25 * j``;
* axial load ``k`` (stamp ``t0 + k / load_rate``): ``wrench.force.z = -100 - k``;
* temperature ``m`` (stamp ``t0 + m``): ``20 + m`` degC.

Log times equal the header stamps plus ``log_delay`` (so tests can tell them apart).
"""
from __future__ import annotations

from pathlib import Path
import shutil
import tempfile

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

from prsm_lube_ros import contract
from prsm_lube_ros.recording import typestore as interfaces

T0_SEC = 1767225600          # 2026-01-01T00:00:00Z


def typestore():
    """The contract typestore."""
    return interfaces.contract_typestore()


def foreign_typestore(msgtype: str, definition: str):
    """A fresh typestore with the standard types plus ``msgtype`` defined by ``definition`` (.msg text)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    store.register(get_types_from_msg(definition, msgtype))
    return store


VIBRATION_MSG = 'std_msgs/Header header\nfloat64 sample_rate\nfloat32[] samples\n'


def stamp(store, seconds: float):
    """builtin_interfaces/Time of ``seconds`` after T0_SEC (rounded to ns)."""
    ns = int(round(seconds * 1e9))
    return store.types['builtin_interfaces/msg/Time'](sec=T0_SEC + ns // 10**9, nanosec=ns % 10**9)


def header(store, seconds: float, frame_id: str = 'nut'):
    """std_msgs/Header at ``seconds`` after T0_SEC."""
    return store.types['std_msgs/msg/Header'](stamp=stamp(store, seconds), frame_id=frame_id)


def vibration_message(store, msgtype: str, index: int, block: int = 400, rate: float = 4000.0):
    """VibrationBlock ``index`` of the closed form above."""
    samples = (index + np.arange(block) / 1000.0).astype(np.float32)
    return store.types[msgtype](header=header(store, index * block / rate), sample_rate=rate,
                                samples=samples)


def joint_message(store, index: int, rate: float = 100.0, names=('screw',)):
    """JointState ``index``; the ``screw`` entry holds the closed form, other joints hold 99."""
    names = list(names)
    position = np.full(len(names), 99.0)
    velocity = np.full(len(names), 99.0)
    if 'screw' in names:
        position[names.index('screw')] = 0.5 * index
        velocity[names.index('screw')] = -0.25 * index
    return store.types['sensor_msgs/msg/JointState'](
        header=header(store, index / rate, 'screw_link'), name=names, position=position,
        velocity=velocity, effort=np.zeros(0))


def wrench_message(store, index: int, rate: float = 50.0):
    """WrenchStamped ``index`` with force.z = -100 - index."""
    vector = store.types['geometry_msgs/msg/Vector3']
    wrench = store.types['geometry_msgs/msg/Wrench'](
        force=vector(x=1.0, y=2.0, z=-100.0 - index), torque=vector(x=3.0, y=4.0, z=5.0))
    return store.types['geometry_msgs/msg/WrenchStamped'](header=header(store, index / rate, 'load_cell'),
                                                          wrench=wrench)


def temperature_message(store, index: int):
    """Temperature ``index``: 20 + index degC."""
    return store.types['sensor_msgs/msg/Temperature'](header=header(store, float(index), 'oil'),
                                                      temperature=20.0 + index, variance=0.0)


def contract_entries(seconds: float = 20.0, namespace: str = '/prsm', *, block: int = 400, rate: float = 4000.0,
                     joint_rate: float = 100.0, load_rate: float = 50.0, temperature: bool = True,
                     joint_names=('screw',), vibration_type: str = contract.VIBRATION_BLOCK,
                     store=None, log_delay: float = 0.002):
    """``(topic, msgtype, log_time_ns, message)`` of all topics for ``seconds``, in log time order."""
    store = store or typestore()
    entries = []

    def add(topic, msgtype, seconds_after, message):
        log_time = T0_SEC * 10**9 + int(round((seconds_after + log_delay) * 1e9))
        entries.append((f'{namespace}/{topic}', msgtype, log_time, message))

    for b in range(int(round(seconds * rate / block))):
        add('vibration', vibration_type, b * block / rate, vibration_message(store, vibration_type, b, block, rate))
    for j in range(int(round(seconds * joint_rate))):
        add('joint_states', 'sensor_msgs/msg/JointState', j / joint_rate,
            joint_message(store, j, joint_rate, joint_names))
    for k in range(int(round(seconds * load_rate))):
        add('axial_load', 'geometry_msgs/msg/WrenchStamped', k / load_rate, wrench_message(store, k, load_rate))
    if temperature:
        for m in range(int(seconds)):
            add('temperature', 'sensor_msgs/msg/Temperature', float(m), temperature_message(store, m))
    entries.sort(key=lambda entry: entry[2])
    return entries


def write_rosbag2(path, entries, storage: str = 'mcap', store=None, zstd: bool = False, zstd_mode: str = 'storage'):
    """Write ``entries`` to a rosbag2 directory at ``path``; returns the path.

    Messages given as bytes are written as they are.  Topics are registered in
    order of first appearance with ``store`` (default: contract); ``zstd``
    compresses the MCAP chunks (``zstd_mode='storage'``), every message
    (``'message'``) or every storage file (``'file'``).
    """
    store = store or typestore()
    path = Path(path)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    connections = {}
    writer = Writer(path, version=9, storage_plugin=plugin)
    if zstd:
        writer.set_compression(CompressionMode[zstd_mode.upper()], CompressionFormat.ZSTD)
    with writer:
        for topic, msgtype, _, _ in entries:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=store)
        for topic, msgtype, log_time, message in entries:
            data = message if isinstance(message, (bytes, memoryview)) else store.serialize_cdr(message, msgtype)
            writer.write(connections[topic], log_time, data)
    return path


def write_bare_mcap(path, entries, store=None):
    """Write ``entries`` to a bare ``.mcap`` file at ``path``; returns the path."""
    path = Path(path)
    with tempfile.TemporaryDirectory(dir=path.parent) as scratch:
        bag = write_rosbag2(Path(scratch) / 'bag', entries, 'mcap', store)
        shutil.move(str(bag / 'bag.mcap'), path)
    return path


def write_mcap_library(path, entries, store=None, compression: str = 'zstd', chunk_size: int = 1 << 20,
                       use_chunking: bool = True, schemas=None):
    """Write ``entries`` as a bare ``.mcap`` with the ``mcap`` package's writer (another writer's layout).

    Its chunks may be ``zstd``/``lz4``/uncompressed, or absent (``use_chunking=False``).
    ``schemas`` maps a message type to the ``(encoding, text)`` stored for it (default ``ros2msg``).
    """
    from mcap.writer import CompressionType, Writer as McapWriter
    store = store or typestore()
    path = Path(path)
    with open(path, 'wb') as stream:
        writer = McapWriter(stream, chunk_size=chunk_size, compression=CompressionType[compression.upper()],
                            use_chunking=use_chunking)
        writer.start('ros2', 'bagfactory')
        channels = {}
        for topic, msgtype, log_time, message in entries:
            if topic not in channels:
                encoding, definition = (schemas or {}).get(msgtype) or (
                    'ros2msg', store.generate_msgdef(msgtype, ros_version=2)[0])
                schema = writer.register_schema(msgtype, encoding, definition.encode())
                channels[topic] = writer.register_channel(topic, 'cdr', schema)
            data = message if isinstance(message, (bytes, memoryview)) else store.serialize_cdr(message, msgtype)
            writer.add_message(channels[topic], log_time, bytes(data), log_time)
        writer.finish()
    return path


def reorder_chunks(source, target, order):
    """Rewrite an MCAP file with its chunks (each with its MessageIndex records) in another order.

    ``order(n)`` returns the new order of the ``n`` chunks (e.g. reversed).
    Records before, between and after the chunks keep their place before
    them, and the summary's Schema and Channel records are repeated there
    (a chunk may use a channel defined in a chunk now after it); the summary
    section keeps its Schema, Channel and Statistics
    records, without the ChunkIndex and SummaryOffset records whose offsets
    would be stale; CRCs of the data end and footer are left out (zero).
    """
    import struct
    data = Path(source).read_bytes()
    magic = data[:8]
    footer_at = len(data) - 8 - 9 - 20
    summary_start = struct.unpack_from('<Q', data, footer_at + 9)[0] or footer_at
    records, chunks = [], []
    pos = 8
    while pos < summary_start:
        opcode, length = struct.unpack_from('<BQ', data, pos)
        record = data[pos:pos + 9 + length]
        pos += 9 + length
        if opcode == 0x0F:                      # DataEnd
            break
        if opcode == 0x06:
            chunks.append([record])
        elif opcode == 0x07 and chunks:
            chunks[-1].append(record)
        else:
            records.append(record)
    summary, definitions = [], []
    pos = summary_start
    while pos < footer_at:
        opcode, length = struct.unpack_from('<BQ', data, pos)
        if opcode not in (0x08, 0x0E):          # ChunkIndex, SummaryOffset
            summary.append(data[pos:pos + 9 + length])
        if opcode in (0x03, 0x04):              # Schema, Channel: before every chunk that may use them
            definitions.append(data[pos:pos + 9 + length])
        pos += 9 + length
    body = magic + b''.join(records[:1] + definitions + records[1:])      # the Header record first
    body += b''.join(b''.join(chunks[i]) for i in order(len(chunks)))
    body += struct.pack('<BQI', 0x0F, 4, 0)
    new_summary_start = len(body) if summary else 0
    body += b''.join(summary)
    body += struct.pack('<BQQQI', 0x02, 20, new_summary_start, 0, 0) + magic
    Path(target).write_bytes(body)
    return Path(target)


def assert_same_slices(want, have, at_least: int = 1):
    """Two readings of a recording (lists of slices of batches) hold the same batches, value for value."""
    assert len(want) == len(have) >= at_least
    for want_batches, have_batches in zip(want, have):
        assert [type(b) for b in want_batches] == [type(b) for b in have_batches]
        for a, b in zip(want_batches, have_batches):
            for name, value in vars(a).items():
                np.testing.assert_array_equal(value, vars(b)[name], err_msg=f'{type(a).__name__}.{name}')


def count_chunk_splits(monkeypatch) -> list:
    """Count the chunks the MCAP reader splits from now on: returns a one-item list holding the count.

    A test reading slices notes the count as each slice is handed out, to
    see whether slices stream or wait for the whole file.
    """
    from prsm_lube_ros.recording import mcap_file
    count = [0]
    for name in ('split_indexed', 'split_records'):
        original = getattr(mcap_file, name)

        def counted(*args, original=original, **kwargs):
            count[0] += 1
            return original(*args, **kwargs)
        monkeypatch.setattr(mcap_file, name, counted)
    return count
