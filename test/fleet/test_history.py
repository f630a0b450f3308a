# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The Parquet history: one file per recording, re-assessment replaces rows, a killed writer leaves it readable."""
import datetime
import math
import os
from pathlib import Path
import subprocess
import sys
import textwrap

import pyarrow.parquet as pq
import pytest

from prsm_lube_ros.estimation.assessment import RunAssessment, WindowAssessment
from prsm_lube_ros.estimation.pipeline import RecordingAssessment
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.fleet.history import add_assessment, actuator_key, content_hash, read_table

START = datetime.datetime(2026, 3, 4, 10, 0, tzinfo=datetime.timezone.utc).timestamp()


def assessment(path, theta, runs=2):
    """A recording's assessment with ``runs`` runs of three windows each at ``theta``."""
    windows, run_list = [], []
    for run in range(1, runs + 1):
        for k in range(3):
            t = START + 10 * run + k
            window = Window(t, t + 1, 1.5, 4000, 1.0, 20.9, 0.01, 200.0, 30.0, 0.05, 1.0, run)
            windows.append(WindowAssessment(window, theta, 0.01))
        run_list.append(RunAssessment(str(path), run, START + 10 * run, START + 10 * run + 3, 20.9, 200.0, 1.5,
                                      theta, 0.005, 3, 30.0))
    return RecordingAssessment(str(path), windows, run_list)


def recording(tmp_path, name, content=b'bag bytes'):
    path = tmp_path / name
    path.write_bytes(content)
    return path


def add(history, path, theta, actuator='/ema_left/prsm', **options):
    return add_assessment(history, assessment(path, theta), actuator_id=actuator, content=content_hash(path),
                          calibration='c0ffee', **options)


def test_rows_land_in_actuator_and_date_partitions_and_read_back(tmp_path):
    history = tmp_path / 'history'
    files = add(history, recording(tmp_path, 'a.mcap'), 0.9)
    assert [f.relative_to(history).parts[:3] for f in files] == [
        ('runs', 'actuator=ema_left.prsm', 'date=2026-03-04'), ('windows', 'actuator=ema_left.prsm', 'date=2026-03-04')]
    runs = read_table(history, 'runs')
    assert runs.num_rows == 2 and set(runs.column('actuator').to_pylist()) == {'ema_left.prsm'}
    assert runs.column('theta_oil').to_pylist() == [0.9, 0.9]
    assert read_table(history, 'windows', actuator='/ema_left/prsm').num_rows == 6
    assert read_table(history, 'runs', actuator='other').num_rows == 0
    # each file is plain Parquet, readable without this package's reader
    assert pq.read_table(files[0]).num_rows == 2


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
    assert len(list((history / 'runs').rglob('*.parquet'))) == 2
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


def test_an_exception_between_temporary_write_and_rename_leaves_the_old_rows(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)

    def crash(temporary):
        assert temporary.exists() and temporary.name.startswith('.')
        raise RuntimeError('power cut')

    with pytest.raises(RuntimeError):
        add(history, bag, 0.5, before_replace=crash)
    assert read_table(history, 'runs').column('theta_oil').to_pylist() == [0.9, 0.9]
    assert not [p for p in history.rglob('*') if p.name.endswith('.tmp')]


def test_a_writer_killed_mid_write_leaves_a_readable_dataset(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)
    add(history, recording(tmp_path, 'b.mcap', b'b'), 0.8)
    script = textwrap.dedent(f'''
        import os, signal, sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_history import add
        from pathlib import Path
        def die(temporary):
            os.kill(os.getpid(), signal.SIGKILL)
        add(Path({str(history)!r}), Path({str(bag)!r}), 0.1, before_replace=die)
    ''')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, timeout=120)
    assert done.returncode == -9, done.stderr.decode()
    leftovers = [p for p in history.rglob('*') if p.name.endswith('.tmp')]
    assert leftovers, 'the killed writer should have left its temporary file'
    runs = read_table(history, 'runs')
    assert sorted(runs.column('theta_oil').to_pylist()) == [0.8, 0.8, 0.9, 0.9]
    import pyarrow.dataset as ds
    assert ds.dataset(history / 'windows', format='parquet', partitioning='hive').to_table().num_rows == 12


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


def test_a_writer_killed_between_the_rename_and_the_removal_leaves_no_duplicate(tmp_path):
    history = tmp_path / 'history'
    bag = recording(tmp_path, 'a.mcap')
    add(history, bag, 0.9)
    add(history, recording(tmp_path, 'b.mcap', b'b'), 0.8)
    moved = tmp_path / 'moved'
    moved.mkdir()
    os.replace(bag, moved / 'a.mcap')             # same content at another path: another file name
    script = textwrap.dedent(f'''
        import os, signal, sys
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_history import add
        from pathlib import Path
        def die(target):
            assert target.exists()
            os.kill(os.getpid(), signal.SIGKILL)
        add(Path({str(history)!r}), Path({str(moved / 'a.mcap')!r}), 0.1, after_replace=die)
    ''')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, timeout=120)
    assert done.returncode == -9, done.stderr.decode()
    assert len(list((history / 'runs').rglob('*.parquet'))) == 3, 'the old file of a.mcap should be left'
    runs = read_table(history, 'runs')
    assert sorted(runs.column('theta_oil').to_pylist()) == [0.1, 0.1, 0.8, 0.8]
