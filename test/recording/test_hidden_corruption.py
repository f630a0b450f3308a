# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Damage that used to pass in silence: each is now one line naming the file, and what can be read is read.

The cases of the independent trial (issue 18): a record length inside a chunk
(the rest of the chunk was dropped without a word), a DataEnd or Footer opcode
in the middle of the data (reading ended there), index times that disagree
with the messages' own (a phantom run), a chunk whose opcode became a user
opcode, a header stamp or a sample rate changed in one message, a sqlite3
row moved to another topic id.  The ``mcap`` library's stream reader refuses an
end record in the middle and reads the other cases in silence, with the
messages read here.
"""
from pathlib import Path
import sqlite3
import struct
import zlib

from mcap.reader import NonSeekingReader
import pytest

import bagfactory as bf
from fuzzing import _clear_crc, _data_records, _rate_positions, _uncompressed_chunks
from prsm_lube_ros.estimation.pipeline import recording_windows
from prsm_lube_ros.recording.reader import raw_messages, topic_messages

CONFORMANCE = Path(__file__).resolve().parents[1] / 'data' / 'conformance' / 'mcap'


def windows_and_problems(path):
    problems = []
    windows = recording_windows(path, lead=0.005, on_problem=problems.append).windows
    return [(w.start, w.reason_kind, w.run_index, w.vibration_rms, w.screw_speed) for w in windows], problems


def reference_count(path):
    """Messages the ``mcap`` library reads from the file start to end, CRCs checked (None: it refuses)."""
    try:
        with open(path, 'rb') as stream:
            return len(list(NonSeekingReader(stream, validate_crcs=True).iter_messages()))
    except Exception:
        return None


@pytest.fixture(scope='module')
def entries():
    return bf.contract_entries(seconds=2.0, block=100)


@pytest.fixture
def plain(tmp_path, entries):
    """A bare MCAP file as rosbags (and the rig simulator) write it: uncompressed chunks with CRC 0."""
    return bf.write_bare_mcap(tmp_path / 'plain.mcap', entries)


def test_a_record_length_inside_a_chunk_is_one_line_with_the_bytes_lost(plain):
    clean, _ = windows_and_problems(plain)
    data = bytearray(plain.read_bytes())
    chunk_pos, start, stop, records = _uncompressed_chunks(data)[0]
    assert struct.unpack_from('<I', data, chunk_pos + 9 + 24)[0] == 0      # no CRC to catch it
    pos, _, length = records[len(records) // 2]
    data[pos + 1:pos + 9] = struct.pack('<Q', length + 5000)
    plain.write_bytes(bytes(data))
    windows, problems = windows_and_problems(plain)
    assert any(str(plain) in line and 'runs past the chunk' in line and 'bytes are not readable' in line
               for line in problems), problems
    assert any('listed in the summary were not read' in line for line in problems), problems
    assert windows != clean and len(list(raw_messages(plain))) == reference_count(plain)


@pytest.mark.parametrize('opcode', [0x0F, 0x02])
def test_an_end_record_in_the_middle_is_skipped_in_one_line_and_the_rest_is_read(tmp_path, entries, opcode):
    path = bf.write_mcap_library(tmp_path / 'chunks.mcap', entries, compression='lz4', chunk_size=4096)
    clean = list(raw_messages(path))
    data = bytearray(path.read_bytes())
    chunks = [r for r in _data_records(data) if r[1] == 0x06]
    pos = chunks[1][0]
    data[pos] = opcode
    path.write_bytes(bytes(data))
    problems = []
    got = list(raw_messages(path, problems.append))
    assert any('in the middle of the data section' in line for line in problems), problems
    assert len(got) < len(clean) and got[-1] == clean[-1]      # read on past it: only that chunk is lost
    assert reference_count(path) is None


def test_index_times_that_disagree_with_the_messages_are_said_and_the_messages_times_used(tmp_path, entries):
    path = bf.write_mcap_library(tmp_path / 'indexed.mcap', entries, compression='zstd', chunk_size=8192)
    clean, _ = windows_and_problems(path)
    data = bytearray(path.read_bytes())
    index = next(r for r in _data_records(data) if r[1] == 0x07)
    at = index[0] + 15                                          # the first entry's time
    time = struct.unpack_from('<Q', data, at)[0]
    data[at:at + 8] = struct.pack('<Q', time + 3600 * 10**9)    # an hour later: a phantom run
    path.write_bytes(bytes(data))
    windows, problems = windows_and_problems(path)
    assert any('message index time(s) disagree' in line for line in problems), problems
    assert windows == clean


def test_a_chunk_turned_into_a_user_record_is_missed_against_the_summary(tmp_path, entries):
    path = bf.write_mcap_library(tmp_path / 'chunks.mcap', entries, compression='lz4', chunk_size=4096)
    data = bytearray(path.read_bytes())
    data[[r for r in _data_records(data) if r[1] == 0x06][2][0]] = 0x99   # readers skip user opcodes
    path.write_bytes(bytes(data))
    problems = []
    list(topic_messages(path, problems.append))
    assert any('listed in the summary were not read' in line for line in problems), problems
    assert reference_count(path) == len(list(raw_messages(path)))       # the same, in silence


def test_a_stamp_or_a_sample_rate_changed_in_one_message_is_said(plain):
    data = bytearray(plain.read_bytes())
    at = _rate_positions(data)[30]
    data[at:at + 8] = struct.pack('<d', 7000.0)                 # plausible, but not this stream's rate
    plain.write_bytes(bytes(data))
    _, problems = windows_and_problems(plain)
    assert any('sample_rate differs by more than 5% from both neighbours' in line for line in problems), problems
    data = bytearray(plain.read_bytes())
    data[at:at + 8] = struct.pack('<d', 4000.0)
    at = _rate_positions(data)[40]
    assert data[at - 4:at] == b'nut\0'            # header: sec, nanosec, frame_id "nut"; then sample_rate
    stamp_at = at - 16
    struct.pack_into('<i', data, stamp_at, struct.unpack_from('<i', data, stamp_at)[0] - 86400 * 50)
    plain.write_bytes(bytes(data))
    _, problems = windows_and_problems(plain)
    assert any('header stamp that jumps' in line for line in problems), problems


def test_a_sqlite3_row_moved_to_another_topic_is_missed_against_metadata_yaml(tmp_path, entries):
    bag = bf.write_rosbag2(tmp_path / 'bag', entries, storage='sqlite3')
    db = next(bag.glob('*.db3'))
    with sqlite3.connect(db) as connection:
        connection.execute('UPDATE messages SET topic_id = 99 WHERE id = 50')
    _, problems = windows_and_problems(bag)
    assert any('metadata.yaml lists' in line and 'read' in line for line in problems), problems


def test_every_conformance_file_still_reads_without_a_problem_line():
    """The new checks must not cry wolf: 416 valid MCAP files, every writer option, no line at all."""
    noisy = []
    for path in sorted(CONFORMANCE.glob('*/*.mcap')):
        problems = []
        list(raw_messages(path, problems.append))
        list(topic_messages(path, problems.append))
        if problems:
            noisy.append(f'{path.name}: {problems[0]}')
    assert not noisy, noisy[:10]


def test_a_file_cut_at_a_record_boundary_says_it_is_truncated(tmp_path, entries):
    path = bf.write_mcap_library(tmp_path / 'cut.mcap', entries, compression='lz4', chunk_size=4096)
    data = path.read_bytes()
    path.write_bytes(data[:[r for r in _data_records(data) if r[1] == 0x06][3][0]])   # just before a chunk
    problems = []
    got = list(raw_messages(path, problems.append))
    assert got and any('without a DataEnd record or footer (truncated' in line for line in problems), problems


def test_bytes_no_chunk_crc_covers_are_caught_by_the_data_end_crc(tmp_path, entries):
    path = bf.write_mcap_library(tmp_path / 'crc.mcap', entries, compression='lz4', chunk_size=4096)
    data = bytearray(path.read_bytes())
    end = next(r for r in _data_records(data) if r[1] == 0x0F)[0]
    struct.pack_into('<I', data, end + 9, zlib.crc32(data[:end]))   # the python writer states none; Go's does
    path.write_bytes(bytes(data))
    problems = []
    list(raw_messages(path, problems.append))
    assert not problems
    profile_at = data.index(b'ros2', 8)                         # the Header record's profile: no chunk around it
    data[profile_at + 3] = ord('3')
    path.write_bytes(bytes(data))
    list(raw_messages(path, problems.append))
    assert any('does not match the CRC its DataEnd record states' in line for line in problems), problems
    assert reference_count(path) is None


def test_a_chunk_whose_records_do_not_hold_what_its_index_lists_is_said(tmp_path, entries):
    path = bf.write_mcap_library(tmp_path / 'indexed.mcap', entries, compression='none', chunk_size=8192)
    data = bytearray(path.read_bytes())
    chunk_pos, _, _, records = _uncompressed_chunks(data)[0]
    _clear_crc(data, chunk_pos)
    data[records[5][0]] = 0x99                   # a message becomes a user record: its index entry points at it
    path.write_bytes(bytes(data))
    problems = []
    list(raw_messages(path, problems.append))
    assert any('its message index lists' in line for line in problems), problems
