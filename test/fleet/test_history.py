# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The Parquet history: a file per recording and table, re-assessment replaces it, a killed writer leaves it sound."""
from concurrent.futures import ProcessPoolExecutor
import datetime
import math
import multiprocessing
import os
from pathlib import Path
import subprocess
import sys

import pyarrow.parquet as pq
import pytest

from prsm_lube_ros.estimation.assessment import RunAssessment
from prsm_lube_ros.fleet.history import add_assessment, actuator_key, content_hash, read_table, STAGING

from fleet_histories import assessment, recording, START


def add(history, path, theta, actuator='/ema_left/prsm', **options):
    return add_assessment(history, assessment(path, theta), actuator_id=actuator, content=content_hash(path),
                          calibration='c0ffee', **options)


def test_rows_land_in_one_folder_per_recording_and_read_back(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    runs_file = add(history, bag, 0.9)
    key = content_hash(bag)[:16]
    assert runs_file.relative_to(history).parts == ('runs', 'actuator=ema_left.prsm', f'{key}.parquet')
    assert (history / 'windows' / 'actuator=ema_left.prsm' / runs_file.name).is_file()
    runs = read_table(history, 'runs')
    assert runs.num_rows == 2 and set(runs.column('actuator').to_pylist()) == {'ema_left.prsm'}
    assert runs.column('theta_oil').to_pylist() == [0.9, 0.9]
    assert runs.column('date').to_pylist() == [datetime.date(2026, 3, 4)] * 2
    assert read_table(history, 'windows', actuator='/ema_left/prsm').num_rows == 6
    assert read_table(history, 'runs', actuator='other').num_rows == 0
    # each file is plain Parquet, readable without this package's reader, and says what it holds
    alone = pq.read_table(runs_file)
    assert alone.num_rows == 2 and str(alone.schema.field('date').type) == 'date32[day]'
    metadata = alone.schema.metadata
    assert metadata[b'prsm_lube_ros.actuator'] == b'/ema_left/prsm' and metadata[b'prsm_lube_ros.table'] == b'runs'
    assert __import__('json').loads(metadata[b'prsm_lube_ros.units'])['screw_speed'] == 'rad/s'
    assert alone.schema.field('axial_load').metadata == {b'unit': b'N'}
    assert alone.column('recording_path').to_pylist() == [str(bag)] * 2      # as given, not resolved


def test_reassessing_a_recording_replaces_its_rows(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    other = recording(tmp_path, 'b.mcap', b'other bytes')
    add(history, bag, 0.9)
    add(history, other, 0.8)
    add(history, bag, 0.7)                       # same recording, new calibration or code: replace
    runs = read_table(history, 'runs')
    by_path = {}
    for path, theta in zip(runs.column('recording_path').to_pylist(), runs.column('theta_oil').to_pylist()):
        by_path.setdefault(Path(path).name, []).append(theta)
    assert by_path == {'a.mcap': [0.7, 0.7], 'b.mcap': [0.8, 0.8]}
    assert len(list(history.glob('runs/*/*.parquet'))) == 2 and len(list(history.glob('windows/*/*.parquet'))) == 2
    # the same content moved to another path is the same recording
    moved = tmp_path / 'moved'
    moved.mkdir()
    os.replace(bag, moved / 'a.mcap')
    add(history, moved / 'a.mcap', 0.6)
    runs = read_table(history, 'runs')
    assert runs.num_rows == 4 and sorted(runs.column('theta_oil').to_pylist()) == [0.6, 0.6, 0.8, 0.8]
    # a recording re-assessed under another actuator id moves partition, without a copy left behind
    add(history, other, 0.5, actuator='B')
    assert sorted(read_table(history, 'runs').column('actuator').to_pylist()) == ['B', 'B', 'ema_left.prsm',
                                                                                  'ema_left.prsm']


def test_an_exception_between_staging_and_commit_leaves_the_old_rows(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)

    def crash(staged):
        assert (staged / 'runs.parquet').exists() and (staged / 'windows.parquet').exists()
        raise RuntimeError('power cut')

    with pytest.raises(RuntimeError):
        add(history, bag, 0.5, before_commit=crash)
    assert read_table(history, 'runs').column('theta_oil').to_pylist() == [0.9, 0.9]
    assert not list((history / STAGING).iterdir())


KILLED = '''
import os, signal, sys
sys.path[:0] = [{here!r}, {support!r}]
from test_history import add
from pathlib import Path
def die(staged):
    os.kill(os.getpid(), signal.SIGKILL)
add(Path({history!r}), Path({bag!r}), 0.1, before_commit=die, actuator={actuator!r})
'''


def killed_writer(history, bag, actuator='/ema_left/prsm'):
    """A writer killed (SIGKILL) with both tables staged, before its commit."""
    script = KILLED.format(here=str(Path(__file__).parent), support=str(Path(__file__).parents[1] / 'support'),
                           history=str(history), bag=str(bag), actuator=actuator)
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, timeout=120)
    assert done.returncode == -9, done.stderr.decode()


def plain_duckdb(history, table='runs'):
    """(recording_path, theta_oil) rows as plain DuckDB reads them, without this package."""
    duckdb = pytest.importorskip('duckdb')
    return sorted(duckdb.sql(f"select recording_path, theta_oil from read_parquet("
                             f"'{history}/{table}/*/*.parquet', hive_partitioning = true)").fetchall())


def test_a_writer_killed_before_its_commit_leaves_the_old_rows_and_the_next_one_cleans_up(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)
    add(history, recording(tmp_path, 'b.mcap', b'b'), 0.8)
    killed_writer(history, bag)
    assert list((history / STAGING).iterdir()), 'the killed writer should have left its staged folder'
    assert [theta for _, theta in plain_duckdb(history)] == [0.9, 0.9, 0.8, 0.8]
    assert len(plain_duckdb(history, 'windows')) == 12
    from prsm_lube_ros.fleet.history import history_writer
    calibration = recording(tmp_path, 'calibration.yaml', b'constants: {}')
    history_writer(history, calibration, None, actuator_id='A')    # the next run removes what the killed one left
    assert not list((history / STAGING).iterdir())
    assert (history / 'calibrations' / f'{content_hash(calibration)[:16]}.yaml').read_bytes() == b'constants: {}'


def test_a_folder_recording_hashes_names_and_bytes(tmp_path):
    folder = tmp_path / 'bag'
    folder.mkdir()
    (folder / 'metadata.yaml').write_text('x')
    (folder / 'bag_0.mcap').write_bytes(b'y')
    first = content_hash(folder)
    (folder / 'bag_0.mcap').write_bytes(b'z')
    assert content_hash(folder) != first and len(first) == 64


@pytest.mark.parametrize('bad', ['', '/', '..'])
def test_an_actuator_id_that_is_no_folder_name_is_refused(bad):
    from prsm_lube_ros.errors import InputError
    with pytest.raises(InputError, match='actuator id'):
        actuator_key(bad)


def test_not_assessed_runs_are_null_theta(tmp_path):
    history = tmp_path / 'history'
    item = assessment(tmp_path / 'a.mcap', math.nan, runs=1)
    item.runs[0] = RunAssessment(item.path, 1, START, START + 3, 20.9, 0.2, 1.5, math.nan, math.nan, 3,
                                 reason='axial load below 5 N')
    recording(tmp_path, 'a.mcap')
    add_assessment(history, item, actuator_id='A', content='ab' * 32, calibration='c')
    runs = read_table(history)
    assert runs.column('theta_oil').to_pylist() == [None] and runs.column('reason').to_pylist() == [
        'axial load below 5 N']


def test_new_content_at_a_reused_path_is_a_new_recording(tmp_path):
    history = tmp_path / 'history'
    latest = recording(tmp_path, 'latest.mcap', b'monday')
    add(history, latest, 0.9)
    latest.write_bytes(b'tuesday')              # the logger overwrites latest.mcap with a new recording
    add(history, latest, 0.8)
    runs = read_table(history, 'runs')
    assert sorted(runs.column('theta_oil').to_pylist()) == [0.8, 0.8, 0.9, 0.9]
    assert read_table(history, 'windows').num_rows == 12
    add(history, latest, 0.7)                   # tuesday's recording re-assessed: replaces tuesday's rows only
    assert sorted(read_table(history, 'runs').column('theta_oil').to_pylist()) == [0.7, 0.7, 0.9, 0.9]


def test_a_recording_moved_to_another_actuator_is_never_in_two_places(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)
    add(history, recording(tmp_path, 'b.mcap', b'b'), 0.8)
    killed_writer(history, bag, actuator='B')
    assert [theta for _, theta in plain_duckdb(history)] == [0.9, 0.9, 0.8, 0.8]
    add(history, bag, 0.1, actuator='B')
    assert [theta for _, theta in plain_duckdb(history)] == [0.1, 0.1, 0.8, 0.8]
    assert sorted(read_table(history).column('actuator').to_pylist()) == ['B', 'B', 'ema_left.prsm', 'ema_left.prsm']


def test_a_file_that_is_not_parquet_or_not_in_the_layout_is_named_and_skipped(tmp_path):
    history = tmp_path / 'history'
    add(history, recording(tmp_path, 'a.mcap'), 0.9)
    broken = add(history, recording(tmp_path, 'b.mcap', b'b'), 0.8)
    broken.write_bytes(b'PAR1 not really')
    (history / 'runs' / 'notes.txt').write_text('hello')
    problems = []
    runs = read_table(history, on_problem=problems.append)
    assert runs.column('theta_oil').to_pylist() == [0.9, 0.9]
    assert len(problems) == 2 and 'notes.txt' in problems[0] and str(broken) in problems[1]
    from prsm_lube_ros.errors import ConfigError
    with pytest.raises(ConfigError, match='notes.txt'):
        read_table(history)


@pytest.mark.parametrize('layout', ['missing', 'empty', 'recordings'])
def test_a_folder_that_is_not_a_history_is_one_line(tmp_path, layout):
    from prsm_lube_ros.errors import ConfigError
    folder = tmp_path / 'h'
    if layout != 'missing':
        folder.mkdir()
    if layout == 'recordings':
        (folder / 'day1.mcap').write_bytes(b'x')
    with pytest.raises(ConfigError, match=str(folder)) as caught:
        read_table(folder)
    assert '\n' not in str(caught.value)


def test_recordings_overlapping_in_time_under_one_id_are_refused_not_merged(tmp_path):
    """Two actuators filed under one id: the second recording overlapping the first is refused in one line."""
    import dataclasses
    from prsm_lube_ros.fleet.history import history_writer
    from prsm_lube_ros.fleet.parallel import BagOutcome
    history = tmp_path / 'history'
    calibration = recording(tmp_path, 'calibration.yaml', b'constants: {}')
    first, second, copy = (recording(tmp_path, name, name.encode()) for name in ('a.mcap', 'b.mcap', 'a.db3'))
    write = history_writer(history, calibration, None, actuator_id='line')
    assert write(BagOutcome(str(first), assessment(first, 0.9), content_hash(first))) == ''
    shifted = assessment(second, 0.8)
    shifted = dataclasses.replace(shifted, runs=[dataclasses.replace(r, start=r.start + 5, end=r.end + 5)
                                                 for r in shifted.runs])
    line = write(BagOutcome(str(second), shifted, content_hash(second)))
    assert str(second) in line and str(first) in line and '--actuator-id' in line and '\n' not in line
    # the same recording stored in another format (same span, other bytes) is no clash, nor is a re-assessment
    assert write(BagOutcome(str(copy), assessment(copy, 0.9), content_hash(copy))) == ''
    again = history_writer(history, calibration, None, actuator_id='line')      # a later run reads the history
    assert again(BagOutcome(str(first), assessment(first, 0.85), content_hash(first))) == ''
    assert again(BagOutcome(str(second), shifted, content_hash(second))) != ''
    assert sorted(set(read_table(history).column('recording_path').to_pylist())) == [str(copy), str(first)]


# -- issue 36: concurrent writers and any file name ----------------------------------------------
def _commit_at_once(history, bag, actuator, barrier_path, writers):
    """One writer: stage, wait until every writer has staged, then commit (the race of issue 36)."""
    import time

    def gather(staged):
        Path(barrier_path, f'{os.getpid()}').touch()
        while len(list(Path(barrier_path).iterdir())) < writers:
            time.sleep(0.001)
    try:
        add_assessment(history, assessment(bag, 0.9), actuator_id=actuator, content=content_hash(bag),
                       calibration='c0ffee', before_commit=gather)
        return ''
    except Exception as exc:      # reported to the test
        return f'{type(exc).__name__}: {exc}'


def test_two_writers_committing_together_never_split_or_double_a_recording(tmp_path):
    """The issue saw one recording under two actuator ids (1 in 30) and 'No such file or directory'."""
    bag = recording(tmp_path, 'a.mcap')
    context = multiprocessing.get_context('fork')
    with ProcessPoolExecutor(4, mp_context=context) as pool:
        for attempt in range(12):
            history, barrier = tmp_path / f'history{attempt}', tmp_path / f'barrier{attempt}'
            barrier.mkdir()
            actuators = ['/left/prsm', '/right/prsm', '/left/prsm', '/right/prsm']
            errors = list(pool.map(_commit_at_once, [history] * 4, [bag] * 4, actuators, [barrier] * 4, [4] * 4))
            assert errors == [''] * 4, errors
            files = list(history.glob('runs/actuator=*/*.parquet'))
            assert len(files) == 1, files
            assert [f.name for f in history.glob('windows/actuator=*/*.parquet')] == [files[0].name]
            assert read_table(history).num_rows == 2


def test_a_recording_name_that_is_not_utf8_goes_into_the_history(tmp_path):
    """Issue 36: a non-UTF-8 byte in a recording name with --history was a traceback."""
    name = os.fsdecode(b'run\xff.mcap')
    bag = recording(tmp_path, name)
    add_assessment(tmp_path / 'history', assessment(bag, 0.9), actuator_id='a', content=content_hash(bag),
                   calibration='c0ffee')
    paths = read_table(tmp_path / 'history').column('recording_path').to_pylist()
    assert paths == [str(tmp_path).encode().decode() + '/run\\xff.mcap'] * 2
    folder = tmp_path / 'bag'
    folder.mkdir()
    (folder / name).write_bytes(b'x')
    assert len(content_hash(folder)) == 64
