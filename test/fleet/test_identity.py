# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Where an actuator id comes from (issue 37): recording, map, folder with its real path; never two in one."""
from pathlib import Path

import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.fleet.identity import (folder_clash, Identity, name_actuators, read_actuator_map,
                                          recorded_actuator)


def bag_folder(root: Path, name: str, actuator: str | None = None) -> str:
    """A rosbag2 folder whose metadata.yaml carries ``custom_data: {actuator_id: ...}`` when ``actuator`` is given."""
    folder = root / name
    folder.mkdir(parents=True)
    custom = f'\n  custom_data:\n    actuator_id: {actuator}' if actuator else ''
    (folder / 'metadata.yaml').write_text(f'rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: mcap'
                                          f'{custom}\n')
    (folder / f'{folder.name}_0.mcap').write_bytes(b'x')
    return str(folder)


def bare(root: Path, *parts: str) -> str:
    path = root.joinpath(*parts)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(b'x')
    return str(path)


def test_the_recording_names_its_actuator_in_its_metadata(tmp_path):
    said = bag_folder(tmp_path / 'day1', 'rec', 'PUMP-7')
    silent = bag_folder(tmp_path / 'day2', 'rec')
    assert recorded_actuator(said) == 'PUMP-7' and recorded_actuator(silent) is None
    assert recorded_actuator(bare(tmp_path, 'x.mcap')) is None
    # recordings that say who they are need no option, even from several folders
    found = name_actuators([said, bag_folder(tmp_path / 'day2', 'other', 'PUMP-7')])
    assert {identity.actuator for identity in found.values()} == {'PUMP-7'}
    assert all(identity.source.startswith('recording ') for identity in found.values())
    with pytest.raises(InputError, match='names no actuator'):
        name_actuators([silent], given='recording')


def mcap_with_custom_data(path: Path, custom: str) -> str:
    """A bare MCAP file holding only what rosbag2's MCAP storage writes for its metadata (found via the summary)."""
    import struct

    def string(text):
        data = text.encode()
        return struct.pack('<I', len(data)) + data

    def record(opcode, content):
        return bytes([opcode]) + struct.pack('<Q', len(content)) + content

    magic = b'\x89MCAP0\r\n'
    pairs = string('serialized_metadata') + string(f'version: 8\nstorage_identifier: mcap\ncustom_data: {custom}\n')
    metadata = record(0x0C, string('rosbag2') + struct.pack('<I', len(pairs)) + pairs)
    header = record(0x01, string('ros2') + string('test'))
    offset = len(magic) + len(header)
    summary = record(0x0D, struct.pack('<QQ', offset, len(metadata)) + string('rosbag2'))
    summary_start = offset + len(metadata)
    footer = record(0x02, struct.pack('<QQI', summary_start, 0, 0))
    path.write_bytes(magic + header + metadata + summary + footer + magic)
    return str(path)


def test_a_bare_mcap_carries_its_actuator_in_the_rosbag2_metadata_record(tmp_path):
    assert recorded_actuator(mcap_with_custom_data(tmp_path / 'a.mcap', '{actuator_id: EMA-3}')) == 'EMA-3'
    assert recorded_actuator(mcap_with_custom_data(tmp_path / 'b.mcap', '~')) is None
    real = Path(__file__).resolve().parents[1] / 'data' / 'conformance' / 'rosbag2' / 'rosbag2_tests' / 'resources' / \
        'mcap' / 'bag_with_topics_and_service_events' / 'bag_with_topics_and_service_events.mcap'
    assert real.is_file() and recorded_actuator(real) is None    # rosbag2's own file: custom_data ~
    (tmp_path / 'cut.mcap').write_bytes((tmp_path / 'a.mcap').read_bytes()[:-20])
    assert recorded_actuator(tmp_path / 'cut.mcap') is None


def test_a_recording_that_says_another_id_than_the_option_is_refused_naming_both(tmp_path):
    said = bag_folder(tmp_path, 'rec', 'PUMP-7')
    with pytest.raises(InputError) as caught:
        name_actuators([said], given='PUMP-8')
    line = str(caught.value)
    assert said in line and "'PUMP-7'" in line and "'PUMP-8'" in line and '\n' not in line


def test_two_folders_of_one_name_are_refused_in_one_line_naming_both(tmp_path):
    first, second = bare(tmp_path, 's1', 'A01', 'd1.mcap'), bare(tmp_path, 's2', 'A01', 'd1.mcap')
    with pytest.raises(InputError) as caught:
        name_actuators([first, second], given='folder')
    line = str(caught.value)
    assert first in line and second in line and '--actuator-map' in line and '\n' not in line
    # the default refuses any call over several folders, saying how to name them
    with pytest.raises(InputError, match='2 folders.*--actuator-id folder.*--actuator-map'):
        name_actuators([first, bare(tmp_path, 's1', 'A02', 'd1.mcap')])


def test_a_symlinked_folder_keeps_the_real_folders_id(tmp_path):
    real = bare(tmp_path, 'fleet', 'A05', 'd1.mcap')
    (tmp_path / 'PUMP7').symlink_to(tmp_path / 'fleet' / 'A05')
    linked = str(tmp_path / 'PUMP7' / 'd1.mcap')
    by_link, = name_actuators([linked]).values()
    direct, = name_actuators([real]).values()
    assert by_link == direct == Identity('A05', f'folder {(tmp_path / "fleet" / "A05").resolve()}')


def test_an_actuator_map_names_recordings_by_path_or_enclosing_folder(tmp_path):
    first, second = bare(tmp_path, 's1', 'A01', 'd1.mcap'), bare(tmp_path, 's2', 'A01', 'd1.mcap')
    special = bare(tmp_path, 's2', 'A01', 'swapped.mcap')
    table = tmp_path / 'map.csv'
    table.write_text('# path,actuator\ns1/A01,fleet1-A01\ns2/A01, fleet2-A01\ns2/A01/swapped.mcap,fleet2-A09\n')
    found = name_actuators([first, second, special], actuator_map=str(table))
    assert [found[b].actuator for b in (first, second, special)] == ['fleet1-A01', 'fleet2-A01', 'fleet2-A09']
    with pytest.raises(InputError, match='not in --actuator-map'):
        name_actuators([bare(tmp_path, 's3', 'A01', 'd1.mcap')], actuator_map=str(table))
    with pytest.raises(InputError, match='twice'):
        name_actuators([first], given='X', actuator_map=str(table))


@pytest.mark.parametrize('text, message', [('', 'no "PATH,ACTUATOR_ID"'), ('a\n', ':1: expected'),
                                           ('a,X\na,Y\n', ':2: a is actuator')])
def test_a_bad_actuator_map_is_one_line_naming_file_and_line(tmp_path, text, message):
    table = tmp_path / 'map.csv'
    table.write_text(text)
    with pytest.raises(InputError, match=message) as caught:
        read_actuator_map(table)
    assert str(table) in str(caught.value)


def test_a_folder_id_joins_only_its_own_folders_recordings(tmp_path):
    mine = Identity('A01', 'folder /data/s1/A01')
    assert folder_clash(mine, [('/data/s1/A01/d1.mcap', 'folder /data/s1/A01')]) is None
    line = folder_clash(mine, [('/data/s2/A01/d1.mcap', 'folder /data/s2/A01')])
    assert '/data/s1/A01' in line and '/data/s2/A01/d1.mcap' in line
    assert folder_clash(Identity('A01'), [('/data/s2/A01/d1.mcap', 'folder /data/s2/A01')]) is None   # the user's
