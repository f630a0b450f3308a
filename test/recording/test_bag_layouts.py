# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Bags laid out in other ways: a bare .db3, a split bag (intact and with its last file cut), no metadata.yaml."""

import shutil
import sqlite3

import pytest
import yaml

import bagfactory as bf
from prsm_lube_ros.errors import RecordingError
from prsm_lube_ros.recording.reader import open_recording


def test_a_bare_db3_file_reads_like_its_bag(tmp_path):
    bag = bf.write_rosbag2(tmp_path / 'bag', bf.contract_entries(seconds=3.0), storage='sqlite3')
    (db3,) = bag.glob('*.db3')
    bf.assert_same_slices(list(open_recording(bag).slices(slice_seconds=1.0)),
                          list(open_recording(db3).slices(slice_seconds=1.0)))


def test_a_sqlite3_file_that_is_not_a_bag_is_refused_in_one_line(tmp_path):
    path = tmp_path / 'other.db3'
    connection = sqlite3.connect(path)
    connection.execute('CREATE TABLE things (x INTEGER)')
    connection.commit()
    connection.close()
    with pytest.raises(RecordingError, match='not a rosbag2 sqlite3 database') as raised:
        open_recording(path)
    assert '\n' not in str(raised.value) and str(path) in str(raised.value)


def write_split_bag(tmp_path, storage, seconds=4.0):
    """One recording as a bag of two storage files, ``split_0`` and ``split_1``, and the plain bag."""
    entries = bf.contract_entries(seconds=seconds)
    half = len(entries) // 2
    plain = bf.write_rosbag2(tmp_path / f'plain_{storage}', entries, storage=storage)
    split = tmp_path / 'split'
    split.mkdir()
    suffix = '.mcap' if storage == 'mcap' else '.db3'
    for index, part in enumerate((entries[:half], entries[half:])):
        target = split / f'split_{index}{suffix}'
        if storage == 'mcap':     # small chunks, several to a file
            bf.write_mcap_library(target, part, compression='none', chunk_size=64 * 1024)
        else:
            bag = bf.write_rosbag2(tmp_path / f'part{index}', part, storage=storage)
            shutil.move(str(next(bag.glob('*' + suffix))), target)
    metadata = yaml.safe_load((plain / 'metadata.yaml').read_text())
    metadata['rosbag2_bagfile_information']['relative_file_paths'] = [f'split_0{suffix}', f'split_1{suffix}']
    (split / 'metadata.yaml').write_text(yaml.safe_dump(metadata))
    return plain, split


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_a_split_bag_reads_like_the_plain_one_with_or_without_metadata(tmp_path, storage):
    plain, split = write_split_bag(tmp_path, storage)
    want = list(open_recording(plain).slices(slice_seconds=1.0))
    bf.assert_same_slices(want, list(open_recording(split).slices(slice_seconds=1.0)))
    (split / 'metadata.yaml').unlink()
    bf.assert_same_slices(want, list(open_recording(split).slices(slice_seconds=1.0)))


def test_a_cut_last_file_of_a_split_bag_is_reported_against_that_file(tmp_path):
    _, split = write_split_bag(tmp_path, 'mcap')
    last = split / 'split_1.mcap'
    data = last.read_bytes()
    last.write_bytes(data[:len(data) * 2 // 3])
    recording = open_recording(split)
    problems = []
    slices = list(recording.slices(on_problem=problems.append, slice_seconds=1.0))
    assert slices
    cut = [line for line in problems + recording.problems if 'truncated' in line]
    assert cut and all(line.startswith(f'{last}: ') and '\n' not in line for line in cut)


def test_a_split_bag_whose_files_go_back_in_time_reads_like_the_plain_one_while_streaming(tmp_path, monkeypatch):
    plain, split = write_split_bag(tmp_path, 'mcap', seconds=20.0)
    first, second = split / 'split_0.mcap', split / 'split_1.mcap'
    swap = split / 'swap.mcap'
    first.rename(swap)
    second.rename(first)
    swap.rename(second)                          # split_0 now holds the later half
    expected = list(open_recording(plain).slices(slice_seconds=1.0))
    splits = bf.count_chunk_splits(monkeypatch)
    seen_at, got = [], []
    for batches in open_recording(split).slices(slice_seconds=1.0):
        seen_at.append(splits[0])
        got.append(batches)
    bf.assert_same_slices(expected, got, at_least=6)
    assert splits[0] > 4 and seen_at[len(seen_at) // 4] < 0.5 * splits[0]   # the earlier file streams first


def test_reading_a_sqlite3_bag_leaves_its_folder_as_it_was(tmp_path):
    bag = bf.write_rosbag2(tmp_path / 'bag', bf.contract_entries(seconds=2.0), storage='sqlite3')
    before = sorted(p.name for p in bag.iterdir())
    list(open_recording(bag).slices())
    assert sorted(p.name for p in bag.iterdir()) == before


@pytest.mark.parametrize('mode', ['message', 'file'])
def test_a_zstd_compressed_sqlite3_bag_reads_like_the_plain_one(tmp_path, mode):
    entries = bf.contract_entries(seconds=3.0)
    plain = bf.write_rosbag2(tmp_path / 'plain', entries, storage='sqlite3')
    compressed = bf.write_rosbag2(tmp_path / mode, entries, storage='sqlite3', zstd=True, zstd_mode=mode)
    problems = []
    got = list(open_recording(compressed).slices(on_problem=problems.append, slice_seconds=1.0))
    assert problems == []
    bf.assert_same_slices(list(open_recording(plain).slices(slice_seconds=1.0)), got, at_least=3)


def test_a_corrupt_file_compressed_sqlite3_bag_is_refused_in_one_line(tmp_path):
    bag = bf.write_rosbag2(tmp_path / 'bag', bf.contract_entries(seconds=1.0), storage='sqlite3', zstd=True,
                           zstd_mode='file')
    (storage_file,) = bag.glob('*.zstd')
    storage_file.write_bytes(b'\x28\xb5\x2f\xfd' + b'\xff' * 64)
    with pytest.raises(RecordingError, match='zstd') as raised:
        open_recording(bag)
    assert '\n' not in str(raised.value) and str(storage_file) in str(raised.value)
