# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""MCAP files whose chunks go back in log time (written topic after topic) read like the plain recording."""

import math

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
import numpy as np
import pytest

import bagfactory as bf
from prsm_lube_ros.estimation.pipeline import calibrate_recordings, recording_windows
from prsm_lube_ros.recording import mcap_file
from prsm_lube_ros.recording.reader import open_recording
from prsm_lube_ros.simulation.recordings import simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan

RPM = 2 * math.pi / 60
PLAN = ExperimentPlan(speeds=(100 * RPM, 150 * RPM, 200 * RPM), loads=(100.0, 200.0), stage_thetas=(1.0,),
                      stroke=0.03, ramp_travel=0.004, stage_pause=0.0)


def regroup_by_topic(source, target, chunk_size=64 * 1024, block_ns=None):
    """Rewrite ``source`` with all messages of one topic before the next (chunk start times go back).

    With ``block_ns``, topic after topic within each block of that much log time (a bounded horizon).
    """
    with open(source, 'rb') as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        by_channel = {}
        for _, channel, message in reader.iter_messages(log_time_order=False):
            block = message.log_time // block_ns if block_ns else 0
            by_channel.setdefault((block, channel.id), []).append(message)
    with open(target, 'wb') as stream:
        writer = Writer(stream, chunk_size=chunk_size, compression=CompressionType.NONE)
        writer.start()
        schema_ids = {sid: writer.register_schema(s.name, s.encoding, s.data) for sid, s in summary.schemas.items()}
        new_ids = {}
        for (_, channel_id), messages in sorted(by_channel.items(), key=lambda item: item[0]):
            if channel_id not in new_ids:
                channel = summary.channels[channel_id]
                new_ids[channel_id] = writer.register_channel(channel.topic, channel.message_encoding,
                                                              schema_ids.get(channel.schema_id, 0), channel.metadata)
            for message in messages:
                writer.add_message(new_ids[channel_id], message.log_time, message.data, message.publish_time,
                                   message.sequence)
        writer.finish()


@pytest.fixture(scope='module')
def plain_and_grouped(tmp_path_factory):
    out = tmp_path_factory.mktemp('ooo')
    plain = simulate_experiment(out / 'sim', plan=PLAN, seed=4, storage='mcap-file')[0]
    grouped = out / 'grouped.mcap'
    regroup_by_topic(plain, grouped)
    return plain, grouped


def test_the_grouped_file_really_has_chunks_going_back_in_time(plain_and_grouped):
    with open(plain_and_grouped[1], 'rb') as stream:
        starts = [index.message_start_time for index in make_reader(stream).get_summary().chunk_indexes]
    assert len(starts) > 3 and any(b < a for a, b in zip(starts, starts[1:]))


def test_chunks_going_back_in_time_give_the_same_slices(plain_and_grouped):
    plain, grouped = plain_and_grouped
    expected = list(open_recording(plain).slices(slice_seconds=2.0))
    problems = []
    got = list(open_recording(grouped).slices(on_problem=problems.append, slice_seconds=2.0))
    assert problems == []
    bf.assert_same_slices(expected, got)


def test_chunks_going_back_in_time_give_the_same_windows_and_constants(plain_and_grouped):
    plain, grouped = plain_and_grouped
    expected = recording_windows(plain, lead=0.0, slice_seconds=2.0)
    got = recording_windows(grouped, lead=0.0, slice_seconds=2.0)
    assert got.problems == expected.problems == []
    assert len(got.windows) == len(expected.windows) > 0
    for a, b in zip(expected.windows, got.windows):
        assert a == b or repr(a) == repr(b)
    want, have = calibrate_recordings([expected]), calibrate_recordings([got])
    assert len(have.speed_levels) == len(want.speed_levels) == 3
    assert have.constants == want.constants


def read_counting_chunks(path, monkeypatch, **options):
    """The slices of ``path``, and how many chunks had been split when each was handed out, and in all."""
    splits = bf.count_chunk_splits(monkeypatch)
    got, seen_at = [], []
    for batches in open_recording(path).slices(**options):
        seen_at.append(splits[0])
        got.append(batches)
    return got, seen_at, splits[0]


def test_a_bounded_horizon_keeps_streaming(plain_and_grouped, tmp_path, monkeypatch):
    """Chunks going back at most 2 s: same slices, and they are handed out while the file is still being read."""
    plain = plain_and_grouped[0]
    blocked = tmp_path / 'blocked.mcap'
    regroup_by_topic(plain, blocked, chunk_size=16 * 1024, block_ns=2 * 10**9)
    with open(blocked, 'rb') as stream:
        starts = [index.message_start_time for index in make_reader(stream).get_summary().chunk_indexes]
    assert any(b < a for a, b in zip(starts, starts[1:]))
    expected = list(open_recording(plain).slices(slice_seconds=1.0))
    got, seen_at, chunks = read_counting_chunks(blocked, monkeypatch, slice_seconds=1.0)
    bf.assert_same_slices(expected, got, at_least=5)
    assert seen_at[len(seen_at) // 2] < 0.7 * chunks     # not everything held until the end


def test_a_chunk_stating_a_later_start_than_its_messages_is_reported_in_one_line(plain_and_grouped, tmp_path):
    small = tmp_path / 'small_chunks.mcap'
    regroup_by_topic(plain_and_grouped[0], small, chunk_size=16 * 1024, block_ns=10**6)   # in time order
    data = bytearray(small.read_bytes())
    with open(small, 'rb') as stream:
        chunks = make_reader(stream).get_summary().chunk_indexes
    assert len(chunks) > 3
    at = chunks[len(chunks) // 2].chunk_start_offset + 9                   # its message_start_time field
    end = int.from_bytes(data[at + 8:at + 16], 'little')
    data[at:at + 8] = (end + 1).to_bytes(8, 'little')                      # claims to start after its last message
    lying = tmp_path / 'lying.mcap'
    lying.write_bytes(bytes(data))
    problems = []
    list(open_recording(lying).slices(on_problem=problems.append, slice_seconds=0.25))
    late = [line for line in problems if 'later start time than its messages' in line]
    assert late and len(late) == len(set(late)) and all('\n' not in line for line in late)


@pytest.mark.parametrize('order', ['reversed', 'shuffled'])
def test_chunks_in_any_order_give_the_same_slices_while_streaming(plain_and_grouped, tmp_path, order, monkeypatch):
    """Read by seeking in order of chunk start: same slices, handed out long before the end of the file."""
    small = tmp_path / 'small_chunks.mcap'
    regroup_by_topic(plain_and_grouped[0], small, chunk_size=16 * 1024, block_ns=10**6)   # in time order
    moved = tmp_path / f'{order}.mcap'
    rng = np.random.default_rng(3)
    bf.reorder_chunks(small, moved, (lambda n: range(n)[::-1]) if order == 'reversed' else rng.permutation)
    with open(moved, 'rb') as stream:
        assert sum(1 for _ in make_reader(stream).iter_messages()) > 0      # still valid for the reference
    starts = [*mcap_file.data_layout(moved, moved.stat().st_size).times]
    assert sum(b < a for a, b in zip(starts, starts[1:])) > len(starts) // 3
    expected = list(open_recording(small).slices(slice_seconds=1.0))
    problems = []
    got, seen_at, chunks = read_counting_chunks(moved, monkeypatch, on_problem=problems.append, slice_seconds=1.0)
    assert problems == []
    bf.assert_same_slices(expected, got, at_least=5)
    assert chunks > 8 and seen_at[len(seen_at) // 2] < 0.7 * chunks     # streamed, not held until the last chunk


def test_a_damaged_file_whose_chunks_go_far_back_says_it_held_them_in_one_line(tmp_path):
    """Without an intact data section the chunks are read in file order: same data, and one line on memory."""
    plain = bf.write_mcap_library(tmp_path / 'plain.mcap', bf.contract_entries(seconds=70.0, temperature=False),
                                  compression='none', chunk_size=64 * 1024)
    reversed_file = bf.reorder_chunks(plain, tmp_path / 'reversed.mcap', lambda n: range(n)[::-1])
    data = reversed_file.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[:data.rindex(bytes([mcap_file.OP_DATA_END]) + (4).to_bytes(8, 'little'))])
    problems = []
    got = list(open_recording(cut).slices(on_problem=problems.append, slice_seconds=10.0))
    held = [line for line in problems if 'held in memory' in line]
    assert len(held) == 1 and '\n' not in held[0]
    want = list(open_recording(plain).slices(slice_seconds=10.0))
    bf.assert_same_slices(want, got, at_least=6)
