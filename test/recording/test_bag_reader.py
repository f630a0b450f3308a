# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Reading recordings: every storage format, foreign type names, bad files, and fast == rosbags decoding.

Recordings are written by ``bagfactory`` with closed-form values (see its
docstring); the tests compare what is read with those formulas.
"""

import numpy as np
import pytest


import bagfactory as bf  # noqa: E402
from prsm_lube_ros.recording.reader import bare_read, find_actuators, open_recording  # noqa: E402
from prsm_lube_ros.errors import InputError  # noqa: E402
from prsm_lube_ros.recording.batches import (AxialLoadBatch, ScrewStateBatch, TemperatureBatch,  # noqa: E402
                                             VibrationBatch)

SECONDS = 12.0


def read_all(recording, **kwargs):
    """Concatenated columns per batch type, the problems and the slices."""
    problems, slices = [], []
    for batches in recording.slices(on_problem=problems.append, **kwargs):
        slices.append(batches)
    out = {}
    for cls, names in ((VibrationBatch, ('stamps', 'sample_rates', 'samples')),
                       (ScrewStateBatch, ('stamps', 'angles', 'speeds')),
                       (AxialLoadBatch, ('stamps', 'forces')),
                       (TemperatureBatch, ('stamps', 'temperatures'))):
        batches = [b for s in slices for b in s if isinstance(b, cls)]
        out[cls.__name__] = {name: np.concatenate([getattr(b, name) for b in batches]) if batches
                             else np.empty(0) for name in names}
        if cls is VibrationBatch:
            out[cls.__name__]['block_sizes'] = (np.concatenate([np.diff(b.offsets) for b in batches])
                                                if batches else np.empty(0))
    return out, problems, slices


def check_closed_form(data, seconds=SECONDS, temperature=True):
    """Values against the factory's formulas (independent of the reader)."""
    vib = data['VibrationBatch']
    blocks = int(round(seconds * 10))
    np.testing.assert_allclose(vib['stamps'] - bf.T0_SEC, np.arange(blocks) * 0.1, atol=1e-6)
    assert np.all(vib['sample_rates'] == 4000.0)
    assert np.all(vib['block_sizes'] == 400)
    expected = (np.arange(blocks)[:, None] + np.arange(400) / 1000.0).astype(np.float32).ravel()
    assert vib['samples'].dtype == np.float32
    np.testing.assert_array_equal(vib['samples'], expected)
    screw = data['ScrewStateBatch']
    j = np.arange(int(round(seconds * 100)))
    np.testing.assert_allclose(screw['stamps'] - bf.T0_SEC, j / 100.0, atol=1e-6)
    np.testing.assert_array_equal(screw['angles'], 0.5 * j)
    np.testing.assert_array_equal(screw['speeds'], -0.25 * j)
    load = data['AxialLoadBatch']
    k = np.arange(int(round(seconds * 50)))
    np.testing.assert_allclose(load['stamps'] - bf.T0_SEC, k / 50.0, atol=1e-6)
    np.testing.assert_array_equal(load['forces'], -100.0 - k)
    temp = data['TemperatureBatch']
    m = np.arange(int(seconds)) if temperature else np.arange(0)
    np.testing.assert_array_equal(temp['temperatures'], 20.0 + m)


@pytest.fixture(scope='module')
def entries():
    return bf.contract_entries(SECONDS)


@pytest.fixture(scope='module')
def bags(tmp_path_factory, entries):
    """The same recording in every format."""
    root = tmp_path_factory.mktemp('bags')
    return {
        'bare': bf.write_bare_mcap(root / 'bare.mcap', entries),
        'mcap_dir': bf.write_rosbag2(root / 'mcap_dir', entries, 'mcap'),
        'zstd_dir': bf.write_rosbag2(root / 'zstd_dir', entries, 'mcap', zstd=True),
        'sqlite_dir': bf.write_rosbag2(root / 'sqlite_dir', entries, 'sqlite3'),
        'lz4_small_chunks': bf.write_mcap_library(root / 'lz4.mcap', entries, compression='lz4',
                                                  chunk_size=20000),
        'unchunked': bf.write_mcap_library(root / 'unchunked.mcap', entries, use_chunking=False),
    }


@pytest.mark.parametrize('kind', ['bare', 'mcap_dir', 'zstd_dir', 'sqlite_dir', 'lz4_small_chunks', 'unchunked'])
def test_every_format_reads_the_closed_form_values(bags, kind):
    recording = open_recording(bags[kind])
    assert recording.topics['/prsm/vibration'].message_count == 120
    assert recording.topics['/prsm/joint_states'].message_count == 1200
    assert recording.topics['/prsm/axial_load'].message_count == 600
    assert recording.topics['/prsm/temperature'].message_count == 12
    assert recording.actuators == ['/prsm']
    # log times are the stamps + 2 ms: first vibration block at 0, last joint state at 11.99 s
    assert recording.start_time - bf.T0_SEC == pytest.approx(0.002, abs=1e-6)
    assert recording.end_time - bf.T0_SEC == pytest.approx(11.992, abs=1e-6)
    data, problems, _ = read_all(recording)
    assert problems == []
    check_closed_form(data)
    assert bare_read(bags[kind]) == 120 + 1200 + 600 + 12


@pytest.mark.parametrize('kind', ['bare', 'mcap_dir', 'sqlite_dir', 'lz4_small_chunks'])
def test_fast_path_equals_rosbags_deserializer(bags, kind):
    fast, _, fast_slices = read_all(open_recording(bags[kind]), engine='fast')
    slow, _, slow_slices = read_all(open_recording(bags[kind]), engine='rosbags')
    assert len(fast_slices) == len(slow_slices)
    for batch_type, columns in fast.items():
        for name, values in columns.items():
            assert values.dtype == slow[batch_type][name].dtype
            np.testing.assert_array_equal(values, slow[batch_type][name], err_msg=f'{batch_type}.{name}')


def test_slices_are_bounded_time_spans_in_order(bags):
    _, _, slices = read_all(open_recording(bags['bare']), slice_seconds=2.0)
    # 12 s of log time from 0.002 s on a 2 s grid: 6 slices, each within 2 s of header stamps
    assert len(slices) == 6
    previous_end = -np.inf
    for batches in slices:
        stamps = np.concatenate([b.stamps for b in batches])
        assert stamps.max() - stamps.min() < 2.0
        assert stamps.min() >= previous_end - 0.01   # log time = stamp + 2 ms
        previous_end = stamps.max()
        assert {type(b) for b in batches} >= {VibrationBatch, ScrewStateBatch, AxialLoadBatch}


def test_vibration_block_under_another_package_name(tmp_path):
    store = bf.foreign_typestore('acme_msgs/msg/VibrationBlock', bf.VIBRATION_MSG)
    entries = bf.contract_entries(SECONDS, vibration_type='acme_msgs/msg/VibrationBlock', store=store)
    path = bf.write_bare_mcap(tmp_path / 'acme.mcap', entries, store=store)
    recording = open_recording(path)
    assert recording.topics['/prsm/vibration'].msgtype == 'acme_msgs/msg/VibrationBlock'
    assert find_actuators(path) == ['/prsm']
    data, problems, _ = read_all(recording)
    assert problems == []
    check_closed_form(data)


def test_vibration_topic_with_another_layout_is_rejected(tmp_path):
    definition = 'std_msgs/Header header\nfloat64 sample_rate\nfloat64[] samples\n'
    store = bf.foreign_typestore('acme_msgs/msg/VibrationBlock', definition)
    entries = bf.contract_entries(2.0, vibration_type='acme_msgs/msg/VibrationBlock', store=store)
    for entry in entries:
        if entry[0] == '/prsm/vibration':
            entry[3].samples = entry[3].samples.astype(np.float64)
    path = bf.write_bare_mcap(tmp_path / 'other_layout.mcap', entries, store=store)
    with pytest.raises(InputError) as error:
        open_recording(path)
    line = str(error.value)
    assert '\n' not in line and str(path) in line and '/prsm/vibration' in line and 'float64[]' in line
    assert find_actuators(path) == []


def test_missing_vibration_topic_names_the_topics_present(tmp_path):
    entries = [e for e in bf.contract_entries(2.0) if not e[0].endswith('vibration')]
    path = bf.write_bare_mcap(tmp_path / 'novib.mcap', entries)
    with pytest.raises(InputError) as error:
        open_recording(path)
    line = str(error.value)
    assert str(path) in line and 'no /prsm/vibration topic' in line and '/prsm/joint_states' in line


@pytest.mark.parametrize('make', ['missing', 'text', 'empty_file', 'dir_without_metadata', 'bad_metadata'])
def test_paths_that_are_not_recordings(tmp_path, make):
    path = tmp_path / 'thing'
    if make == 'text':
        path.write_text('hello\n')
    elif make == 'empty_file':
        path.write_bytes(b'')
    elif make == 'dir_without_metadata':
        path.mkdir()
    elif make == 'bad_metadata':
        path.mkdir()
        (path / 'metadata.yaml').write_text('just: [a, list')
    with pytest.raises(InputError) as error:
        open_recording(path)
    assert '\n' not in str(error.value) and 'thing' in str(error.value)


def test_empty_bag(tmp_path):
    path = tmp_path / 'empty'
    bf.write_rosbag2(path, [])
    with pytest.raises(InputError, match='holds no topics'):
        open_recording(path)
    # topics registered but never written
    from rosbags.rosbag2 import StoragePlugin, Writer
    path = tmp_path / 'silent'
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        writer.add_connection('/prsm/vibration', 'prsm_lube_ros/msg/VibrationBlock', typestore=bf.typestore())
    with pytest.raises(InputError, match='no messages on /prsm/vibration'):
        open_recording(path)


def test_joint_states_with_other_joints_and_missing_screw(tmp_path):
    store = bf.typestore()
    entries = []
    for topic, msgtype, log_time, message in bf.contract_entries(4.0, temperature=False):
        if topic.endswith('joint_states'):
            j = int(round((log_time - bf.T0_SEC * 10**9) / 1e7))   # 10 ms per joint state, +2 ms delay
            names = [('motor', 'screw', 'nut'), ('screw',), ('a', 'bb', 'screw'), ('motor', 'nut')][j % 4]
            message = bf.joint_message(store, j, names=names)
        entries.append((topic, msgtype, log_time, message))
    path = bf.write_bare_mcap(tmp_path / 'joints.mcap', entries)
    data, problems, _ = read_all(open_recording(path))
    j = np.arange(400)
    j = j[j % 4 != 3]                              # every 4th message has no screw entry
    np.testing.assert_array_equal(data['ScrewStateBatch']['angles'], 0.5 * j)
    np.testing.assert_array_equal(data['ScrewStateBatch']['speeds'], -0.25 * j)
    np.testing.assert_allclose(data['ScrewStateBatch']['stamps'] - bf.T0_SEC, j / 100.0, atol=1e-6)
    assert problems == ['/prsm/joint_states: 100 JointState message(s) without a "screw" entry skipped']


def test_undecodable_and_big_endian_messages(tmp_path):
    store = bf.typestore()
    entries = []
    for n, (topic, msgtype, log_time, message) in enumerate(bf.contract_entries(3.0, temperature=False)):
        if topic.endswith('vibration') and n % 7 == 0:
            message = bytes(store.serialize_cdr(message, msgtype))[:30]          # cut short: undecodable
        elif topic.endswith('axial_load') and n % 3 == 0:
            message = bytes(store.serialize_cdr(message, msgtype, little_endian=False))
        entries.append((topic, msgtype, log_time, message))
    cut = sum(1 for n, e in enumerate(entries) if e[0].endswith('vibration') and n % 7 == 0)
    path = bf.write_bare_mcap(tmp_path / 'mixed.mcap', entries)
    data, problems, _ = read_all(open_recording(path))
    assert problems == [f'/prsm/vibration: {cut} message(s) could not be decoded and were skipped']
    assert data['VibrationBatch']['stamps'].size == 30 - cut
    k = np.arange(150)                              # all loads, big-endian ones included, in order
    np.testing.assert_array_equal(data['AxialLoadBatch']['forces'], -100.0 - k)


def test_several_namespaces_and_prefixes(tmp_path):
    entries = (bf.contract_entries(3.0, '/left', temperature=False)
               + bf.contract_entries(5.0, '/rig/right', temperature=False)
               + [(t.replace('/prsm/', '/rig/aux_'), *rest) for t, *rest in bf.contract_entries(2.0)])
    entries.sort(key=lambda e: e[2])
    path = bf.write_bare_mcap(tmp_path / 'multi.mcap', entries)
    assert find_actuators(path) == ['/left', '/rig/aux_', '/rig/right']
    with pytest.raises(InputError) as error:
        open_recording(path)
    assert 'actuators found: /left, /rig/aux_, /rig/right' in str(error.value)
    data, problems, _ = read_all(open_recording(path, namespace='/rig/right'))
    assert problems == []
    check_closed_form(data, seconds=5.0, temperature=False)
    data, _, _ = read_all(open_recording(path, namespace='/rig/aux_'))
    check_closed_form(data, seconds=2.0)


@pytest.fixture(scope='module')
def truncation_source(tmp_path_factory):
    """A bare mcap of 60 s in small chunks (so cuts fall inside and between chunks)."""
    root = tmp_path_factory.mktemp('cut')
    entries = bf.contract_entries(60.0)
    return (bf.write_bare_mcap(root / 'whole.mcap', entries),
            bf.write_mcap_library(root / 'whole_zstd.mcap', entries, compression='zstd', chunk_size=100_000))


@pytest.mark.timeout(60)
@pytest.mark.parametrize('which', [0, 1])
def test_truncated_mcap_yields_what_it_can_then_one_line(tmp_path, truncation_source, which):
    source = truncation_source[which]
    whole = source.read_bytes()
    full, _, _ = read_all(open_recording(source))
    full_stamps = full['VibrationBatch']['stamps']
    offsets = [0, 5, 8, 9, 40, 300, 1000, len(whole) // 7, len(whole) // 3, len(whole) // 2 + 13,
               len(whole) - 3000, len(whole) - 200, len(whole) - 40, len(whole) - 1]
    opened = 0
    for offset in offsets:
        path = tmp_path / f'cut_{offset}.mcap'
        path.write_bytes(whole[:offset])
        try:
            recording = open_recording(path)
        except InputError as error:
            assert '\n' not in str(error) and str(path) in str(error)
            continue
        opened += 1
        data, problems, _ = read_all(recording)
        stamps = data['VibrationBatch']['stamps']
        # what was read is the start of the whole recording, sample for sample
        np.testing.assert_array_equal(stamps, full_stamps[:stamps.size])
        samples = data['VibrationBatch']['samples']
        np.testing.assert_array_equal(samples, full['VibrationBatch']['samples'][:samples.size])
        assert all('\n' not in line for line in problems)
        if stamps.size < full_stamps.size:
            assert len(problems) == 1 and 'truncated or corrupt' in problems[0], problems
    assert opened >= 5


@pytest.mark.timeout(60)
def test_corrupted_bytes_never_escape_as_tracebacks(tmp_path, truncation_source):
    whole = bytearray(truncation_source[1].read_bytes())
    rng = np.random.default_rng(7)
    for trial in range(12):
        damaged = bytearray(whole)
        for position in rng.integers(8, len(whole), size=3):
            damaged[position:position + 8] = rng.bytes(8)
        path = tmp_path / f'damaged_{trial}.mcap'
        path.write_bytes(bytes(damaged))
        problems = []
        try:
            recording = open_recording(path)
            for _ in recording.slices(on_problem=problems.append):
                pass
        except InputError as error:
            assert '\n' not in str(error)
        assert all('\n' not in line for line in problems)


def test_describe_lists_topics(bags):
    text = open_recording(bags['bare']).describe()
    assert '/prsm/vibration: prsm_lube_ros/msg/VibrationBlock, 120 messages <- vibration' in text
