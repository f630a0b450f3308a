# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every MCAP conformance file (test/data/conformance) reads as its JSON says, or is refused in one line."""

import json
from pathlib import Path

import pytest

from prsm_lube_ros.errors import RecordingError
from prsm_lube_ros.recording.reader import list_topics, raw_messages

CONFORMANCE = Path(__file__).resolve().parents[1] / 'data' / 'conformance' / 'mcap'
FILES = sorted(CONFORMANCE.glob('*/*.mcap')) if CONFORMANCE.is_dir() else []


def expected(json_path):
    """Topics with message counts, and the messages as (topic, sequence, log_time, data) in file order."""
    records = json.loads(json_path.read_text())['records']
    topics, messages = {}, []
    for record in records:
        fields = dict(record['fields'])
        if record['type'] == 'Channel':
            topics.setdefault(int(fields['id']), fields['topic'])
        elif record['type'] == 'Message':
            messages.append((topics.get(int(fields['channel_id'])), int(fields['sequence']),
                             int(fields['log_time']), bytes(int(b) for b in fields['data'])))
    counts = {}
    for message in messages:
        counts[message[0]] = counts.get(message[0], 0) + 1
    return counts, messages


@pytest.mark.skipif(not FILES, reason='no conformance files')
def test_every_conformance_file_reads_its_messages_or_is_refused_in_one_line():
    wrong = []
    for path in FILES:
        counts, messages = expected(path.with_suffix('.json'))
        try:
            got = list(raw_messages(path))
            topics = list_topics(path)
        except RecordingError as err:
            assert '\n' not in str(err) and str(path) in str(err)
            wrong.append(f'{path.name}: refused: {err}')
            continue
        if got != messages:
            wrong.append(f'{path.name}: {len(got)} messages read, {len(messages)} expected')
        listed = {name: info.message_count for name, info in topics.items() if info.message_count}
        if listed != counts:
            wrong.append(f'{path.name}: listed {listed}, expected {counts}')
    assert not wrong, f'{len(wrong)} of {len(FILES)} files:\n' + '\n'.join(wrong[:20])


def test_the_conformance_files_are_in_the_repository():
    """The test above must not pass by finding nothing: the suite carries its inputs."""
    assert len(FILES) >= 400
