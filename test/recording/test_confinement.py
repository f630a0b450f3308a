# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Every file opened on a request is confined and a regular file of bounded size (issue 36, item 1).

Links inside a bag folder that lead out of the allowed root, FIFOs, devices and
oversized files are refused in one line, before anything is read from them
(a FIFO with no writer would block a reader for good), and the line never
repeats what the link's target holds.
"""
import os
from pathlib import Path
import shutil
import subprocess
import sys
import threading

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import bagfactory as bf
from prsm_lube_ros import input_file
from prsm_lube_ros.config_file import read_yaml
from prsm_lube_ros.errors import ConfigError, InputError, RecordingError
from prsm_lube_ros.recording.reader import open_recording

SECRET = 'root:x:0:0:secret-content-never-echoed:/root:/bin/bash\n'


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    """A valid rosbag2 folder (mcap storage) of the contract's topics."""
    folder = tmp_path_factory.mktemp('bags')
    return bf.write_rosbag2(folder / 'bag', bf.contract_entries(seconds=2.0, block=100))


def within(seconds, work):
    """``work()``'s result or exception, failing the test if it takes longer than ``seconds`` (a hang)."""
    box = {}

    def run():
        try:
            box['result'] = work()
        except BaseException as exc:   # handed to the test
            box['error'] = exc
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f'still blocked after {seconds} s'
    if 'error' in box:
        raise box['error']
    return box['result']


def copy_bag(bag, target):
    shutil.copytree(bag, target)
    return target, next(target.glob('*.mcap'))


def test_a_metadata_link_out_of_the_bag_is_refused_without_its_content(bag, tmp_path):
    secret = tmp_path / 'passwd'
    secret.write_text(SECRET)
    folder, _ = copy_bag(bag, tmp_path / 'inside' / 'bag')
    (folder / 'metadata.yaml').unlink()
    (folder / 'metadata.yaml').symlink_to(secret)
    with pytest.raises(RecordingError) as raised:
        open_recording(folder)
    text = str(raised.value)
    assert 'leads outside' in text and 'metadata.yaml' in text
    assert 'secret' not in text and 'root:x' not in text and '\n' not in text


def test_a_storage_file_linked_from_outside_is_not_read(bag, tmp_path):
    """The issue's escape: a storage file linked to a recording outside the allowed root."""
    outside = tmp_path / 'outside.mcap'
    folder, storage = copy_bag(bag, tmp_path / 'recordings' / 'bag')
    shutil.move(storage, outside)
    storage.symlink_to(outside)
    with pytest.raises(RecordingError, match='leads outside'):
        open_recording(folder)                                   # the command line: the folder is the root
    with pytest.raises(RecordingError, match='leads outside'):
        open_recording(folder, root=tmp_path / 'recordings')     # the service: recordings_dir is the root
    # A link that stays inside the root is a recording like any other.
    inside = tmp_path / 'recordings' / 'kept.mcap'
    shutil.move(outside, inside)
    storage.unlink()
    storage.symlink_to(inside)
    assert open_recording(folder, root=tmp_path / 'recordings').topics


def test_a_fifo_as_storage_or_metadata_is_refused_at_once(bag, tmp_path):
    folder, storage = copy_bag(bag, tmp_path / 'bag')
    storage.unlink()
    os.mkfifo(storage)
    with pytest.raises(RecordingError, match='FIFO'):
        within(10, lambda: open_recording(folder))
    metadata = folder / 'metadata.yaml'
    metadata.unlink()
    os.mkfifo(metadata)
    with pytest.raises(RecordingError, match='FIFO'):
        within(10, lambda: open_recording(folder))
    bare = tmp_path / 'bare.mcap'
    os.mkfifo(bare)
    with pytest.raises(RecordingError, match='FIFO'):
        within(10, lambda: open_recording(bare))


def test_a_device_as_storage_is_refused(bag, tmp_path):
    folder, storage = copy_bag(bag, tmp_path / 'recordings' / 'bag')
    storage.unlink()
    storage.symlink_to('/dev/zero')
    with pytest.raises(RecordingError, match='character device|leads outside'):
        within(10, lambda: open_recording(folder, root='/'))


def test_metadata_over_its_bound_is_refused_before_it_is_parsed(bag, tmp_path, monkeypatch):
    folder, _ = copy_bag(bag, tmp_path / 'bag')
    monkeypatch.setattr(input_file, 'MAX_METADATA_BYTES', 100)
    monkeypatch.setattr('prsm_lube_ros.recording.reader.MAX_METADATA_BYTES', 100)
    with pytest.raises(RecordingError, match='more than 100'):
        open_recording(folder)


@pytest.mark.parametrize('special', ['/dev/zero', '/dev/urandom', 'fifo', 'folder'])
def test_yaml_files_are_regular_files_only(special, tmp_path):
    if special == 'fifo':
        special = tmp_path / 'fifo.yaml'
        os.mkfifo(special)
    elif special == 'folder':
        special = tmp_path
    with pytest.raises(ConfigError) as raised:
        within(10, lambda: read_yaml(special, 'calibration file'))
    assert str(special) in str(raised.value)


def test_stdin_as_calibration_is_one_line_and_reads_nothing(tmp_path):
    """``--calibration /dev/stdin`` fed by a pipe: refused before a byte is read, however much waits there."""
    code = ('import sys\nfrom prsm_lube_ros.estimation.calibration_file import load_calibration\n'
            'from prsm_lube_ros.errors import InputError\n'
            'try:\n    load_calibration("/dev/stdin")\nexcept InputError as exc:\n    print(exc)\n'
            '    print(len(sys.stdin.buffer.read()))\n')
    result = subprocess.run([sys.executable, '-c', code], input=b'x' * 100_000, capture_output=True, timeout=60)
    first, left = result.stdout.decode().splitlines()
    assert '/dev/stdin' in first and 'not a regular file' in first
    assert left == '100000'          # nothing consumed


def test_the_command_line_refuses_dev_zero_as_calibration_in_one_line(bag, tmp_path):
    result = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'assess', str(bag), '--calibration',
                             '/dev/zero', '--json', str(tmp_path / 'out.json')], capture_output=True, text=True,
                            timeout=120)
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    assert '/dev/zero' in lines[0] and 'character device' in lines[0]


def test_open_regular_checks_what_it_opened(tmp_path):
    path = tmp_path / 'a.bin'
    path.write_bytes(b'12345')
    with input_file.open_regular(path, 'file', max_bytes=5) as stream:
        assert stream.read() == b'12345'
    with pytest.raises(InputError, match='more than 4'):
        input_file.read_bytes(path, 'file', max_bytes=4)
    with pytest.raises(InputError, match='not found'):
        input_file.read_bytes(tmp_path / 'gone', 'file', max_bytes=4)
    link = tmp_path / 'inner' / 'link'
    link.parent.mkdir()
    link.symlink_to(path)
    with pytest.raises(InputError, match='leads outside'):
        input_file.read_bytes(link, 'file', max_bytes=5, root=link.parent)


def test_history_files_are_bounded_by_their_footer_and_confined(tmp_path, monkeypatch):
    from prsm_lube_ros.fleet import history
    root = tmp_path / 'history' / history.RECORDINGS / 'actuator=a' / f'recording={"0" * 16}'
    root.mkdir(parents=True)
    table = history.SCHEMAS['runs'].empty_table()
    rows = pa.Table.from_pylist([{name: None for name in table.column_names}] * 50, schema=table.schema)
    pq.write_table(rows, root / 'runs.parquet')
    assert history.read_table(tmp_path / 'history').num_rows == 50
    monkeypatch.setattr(history, 'MAX_PARQUET_ROWS', 10)
    problems = []
    assert history.read_table(tmp_path / 'history', on_problem=problems.append).num_rows == 0
    assert len(problems) == 1 and '50 rows in its footer, more than 10' in problems[0]
    with pytest.raises(ConfigError, match='more than 10'):
        history.read_table(tmp_path / 'history')
    # A Parquet file linked in from outside the history is not read.
    monkeypatch.setattr(history, 'MAX_PARQUET_ROWS', 1000)
    outside = tmp_path / 'elsewhere.parquet'
    shutil.move(root / 'runs.parquet', outside)
    (root / 'runs.parquet').symlink_to(outside)
    problems.clear()
    assert history.read_table(tmp_path / 'history', on_problem=problems.append).num_rows == 0
    assert 'leads outside' in problems[0]
    # A FIFO in its place is refused without blocking.
    (root / 'runs.parquet').unlink()
    os.mkfifo(root / 'runs.parquet')
    problems.clear()
    within(10, lambda: history.read_table(tmp_path / 'history', on_problem=problems.append))
    assert 'FIFO' in problems[0]


def test_path_text_keeps_any_name_as_valid_text():
    from prsm_lube_ros.fleet.history import path_text
    name = os.fsdecode(b'/bags/run\xff.mcap')
    assert path_text(name) == '/bags/run\\xff.mcap'
    assert path_text(Path('/bags/plain.mcap')) == '/bags/plain.mcap'


def test_a_fifo_as_a_service_log_is_one_line(tmp_path):
    from prsm_lube_ros.fleet.service_log import read_relubrications
    fifo = tmp_path / 'relubrications.csv'
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match='FIFO'):
        within(10, lambda: read_relubrications(fifo))


def test_metadata_listing_a_storage_file_many_times_is_refused_before_any_is_opened(bag, tmp_path):
    import yaml
    folder, storage = copy_bag(bag, tmp_path / 'bag')
    metadata = yaml.safe_load((folder / 'metadata.yaml').read_text())
    metadata['rosbag2_bagfile_information']['relative_file_paths'] = [storage.name] * 20_000
    (folder / 'metadata.yaml').write_text(yaml.safe_dump(metadata))
    with pytest.raises(RecordingError, match='lists 20000 storage files'):
        within(10, lambda: open_recording(folder))
