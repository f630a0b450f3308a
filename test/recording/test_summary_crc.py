# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The Footer's summary CRC is checked: a corrupted summary is said in one line and the listing comes from the data."""
from pathlib import Path

import bagfactory as bf
from prsm_lube_ros.recording.reader import open_recording


def corrupt_summary_topic(path: Path, target: Path) -> Path:
    """Copy of ``path`` whose summary Channel record says /prsm/vibratiom (still parses; only the CRC tells)."""
    data = bytearray(path.read_bytes())
    at = data.rfind(b'/prsm/vibration')              # the last copy: the summary section's Channel record
    assert at > data.find(b'/prsm/vibration') > 0
    data[at + len('/prsm/vibratio')] = ord('m')
    target.write_bytes(bytes(data))
    return target


def test_a_corrupted_summary_is_reported_and_the_listing_rebuilt_from_the_data(tmp_path):
    plain = bf.write_mcap_library(tmp_path / 'plain.mcap', bf.contract_entries(seconds=4.0), compression='none')
    damaged = corrupt_summary_topic(plain, tmp_path / 'damaged.mcap')
    recording = open_recording(damaged)
    assert any('summary section does not match its CRC' in line for line in recording.problems)
    assert '/prsm/vibration' in recording.topics and '/prsm/vibratiom' not in recording.topics
    bf.assert_same_slices(list(open_recording(plain).slices()), list(recording.slices()))


def test_an_intact_summary_is_used_without_a_problem(tmp_path):
    plain = bf.write_mcap_library(tmp_path / 'plain.mcap', bf.contract_entries(seconds=4.0), compression='none')
    recording = open_recording(plain)
    assert not any('CRC' in line for line in recording.problems)
