# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every rosbag2 test bag (test/data/conformance/rosbag2) streams the messages the reference readers give.

The references: the ``mcap`` package's reader for MCAP storage files, and a plain SQL query joining
``messages`` to ``topics`` by id for sqlite3 files (rosbags' Reader streams nothing from 8 of these bags,
whose metadata.yaml does not match the storage exactly, and refuses 2, so it cannot be the reference here).
"""

from pathlib import Path
import shutil
import sqlite3

from mcap.reader import make_reader
import pytest

from prsm_lube_ros.errors import RecordingError
from prsm_lube_ros.recording.reader import list_topics, topic_messages

ROSBAG2 = Path(__file__).resolve().parents[1] / 'data' / 'conformance' / 'rosbag2'
BAGS = sorted(p.parent for p in ROSBAG2.rglob('metadata.yaml')) if ROSBAG2.is_dir() else []
REINDEX = sorted(ROSBAG2.rglob('reindex_test_bags/multiple_files'))
SINGLE_FILES = sorted(ROSBAG2.rglob('bags/*.mcap')) + sorted(ROSBAG2.rglob('bags/*.db3'))


def _split_order(path):
    stem, _, number = path.stem.rpartition('_')
    return int(number) if number.isdigit() else -1


def reference_messages(files):
    """topic -> sorted [(log_time, data)] from the reference readers, over the storage files of one bag."""
    messages = {}
    for file in files:
        if file.suffix == '.mcap':
            with open(file, 'rb') as stream:
                for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
                    messages.setdefault(channel.topic, []).append((message.log_time, bytes(message.data)))
        else:
            connection = sqlite3.connect(f'{file.resolve().as_uri()}?immutable=1', uri=True)   # no -wal/-shm left
            rows = connection.execute('SELECT topics.name, messages.timestamp, messages.data FROM messages '
                                      'JOIN topics ON topics.id = messages.topic_id')
            for topic, log_time, data in rows:
                messages.setdefault(topic, []).append((log_time, bytes(data)))
            connection.close()
    return {topic: sorted(values) for topic, values in messages.items()}


def our_messages(path):
    problems = []
    messages = {}
    for topic, log_time, data in topic_messages(path, problems.append):
        messages.setdefault(topic, []).append((log_time, data))
    return {topic: sorted(values) for topic, values in messages.items()}, problems


def storage_files(bag):
    return sorted((p for p in bag.iterdir() if p.suffix in ('.mcap', '.db3')), key=_split_order)


def test_the_rosbag2_test_bags_are_in_the_repository():
    assert len(BAGS) >= 20 and REINDEX and len(SINGLE_FILES) >= 4


@pytest.mark.parametrize('bag', BAGS + REINDEX + SINGLE_FILES, ids=lambda p: str(p.relative_to(ROSBAG2)))
def test_a_test_bag_streams_the_reference_messages_per_topic(bag):
    files = [bag] if bag.is_file() else storage_files(bag)
    expected = reference_messages(files)
    got, problems = our_messages(bag)
    assert problems == []
    assert {t: len(v) for t, v in got.items()} == {t: len(v) for t, v in expected.items()}
    assert got == expected
    listed = {name: info.message_count for name, info in list_topics(bag).items() if info.message_count}
    assert listed == {t: len(v) for t, v in expected.items()}


def test_the_talker_bag_whose_qos_differs_from_its_metadata_streams_all_its_messages():
    """rosbag2's talker bag: metadata.yaml and the .db3 disagree on QoS; the .db3 and .mcap copies agree."""
    sqlite_bag = next(b for b in BAGS if b.name == 'talker' and b.parent.name == 'sqlite3')
    mcap_bag = next(b for b in BAGS if b.name == 'talker' and b.parent.name == 'mcap')
    got, problems = our_messages(sqlite_bag)
    assert problems == []
    assert {t: len(v) for t, v in got.items()} == {'/topic': 10, '/rosout': 10}
    assert got['/topic'] == our_messages(mcap_bag)[0]['/topic']


def test_a_folder_of_unrelated_recordings_is_refused_in_one_line():
    folder = SINGLE_FILES[0].parent
    with pytest.raises(RecordingError, match='not the parts of one split bag') as raised:
        list_topics(folder)
    assert '\n' not in str(raised.value) and str(folder) in str(raised.value)


def test_where_rosbags_streams_fewer_messages_than_listed_it_says_so_per_topic(tmp_path):
    """Compressed bags and the reference engine read through rosbags, which drops the talker bag's messages."""
    from prsm_lube_ros.recording.reader import _RosbagsSource
    bag = next(b for b in BAGS if b.name == 'talker' and b.parent.name == 'sqlite3')
    bag = Path(shutil.copytree(bag, tmp_path / 'talker'))     # rosbags leaves -wal/-shm files beside the .db3
    source = _RosbagsSource(bag)
    problems = []
    for _ in source.raw_chunks(list(source.topics), problems.append):
        pass
    assert sorted(line.split(':')[0] for line in problems) == ['/rosout', '/topic']
    assert all('10 message(s) listed, 0 streamed' in line for line in problems)
