# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube assess --history --jobs``: a bad recording is one line, the others are assessed and recorded."""
import json
from pathlib import Path
import shutil

from prsm_lube_ros.cli import main
from prsm_lube_ros.fleet.history import read_table


def test_a_bad_recording_among_good_ones_is_one_line_and_the_rest_go_on(small_fleet, tmp_path, capsys):
    bad = tmp_path / 'X' / 'broken.mcap'
    bad.parent.mkdir()
    bad.write_bytes(b'\x89MCAP0\r\n truncated')
    good = small_fleet['bags'][:3]
    history, out = tmp_path / 'history', tmp_path / 'a.json'
    status = main(['assess', good[0], str(bad), *good[1:], '--calibration', str(small_fleet['calibration']),
                   '--history', str(history), '--actuator-id', 'folder', '--jobs', '2', '--json', str(out)])
    captured = capsys.readouterr()
    assert status == 2 and 'Traceback' not in captured.err
    errors = [line for line in captured.err.splitlines() if 'error' in line]
    assert len(errors) == 1 and str(bad) in errors[0]
    assert len({run['bag'] for run in json.loads(out.read_text())['runs']}) == 3
    runs = read_table(history)
    assert len(set(runs.column('recording_path').to_pylist())) == 3
    assert set(runs.column('actuator').to_pylist()) == {'A01'}
    assert set(runs.column('calibration_id').to_pylist()) != {''}


def test_history_actuator_defaults_to_the_real_folder(small_fleet, tmp_path):
    history = tmp_path / 'history'
    assert main(['assess', small_fleet['bags'][0], '--calibration', str(small_fleet['calibration']),
                 '--history', str(history)]) == 0
    runs = read_table(history)
    assert set(runs.column('actuator').to_pylist()) == {'A01'}
    folder = Path(small_fleet['bags'][0]).resolve().parent
    assert set(runs.column('actuator_source').to_pylist()) == {f'folder {folder}'}


def test_the_calibrations_share_of_the_uncertainty_is_recorded(small_fleet):
    from prsm_lube_ros.fleet.forecast import recording_points
    runs = read_table(small_fleet['history']).to_pylist()
    assessed = [run for run in runs if run['theta_oil'] is not None]
    assert assessed and all(0 < run['theta_oil_std_calibration'] < run['theta_oil_std'] for run in assessed)
    assert all(run['theta_oil_std_calibration'] is None for run in runs if run['theta_oil'] is None)
    point = recording_points(read_table(small_fleet['history']))['A01'][0]
    assert 0 < point.calibration_std < point.theta_oil_std and point.independent_std < point.theta_oil_std


def test_each_recording_is_in_the_history_as_soon_as_it_is_assessed(small_fleet, tmp_path, monkeypatch):
    """A run killed after the first recording keeps that recording's rows."""
    from prsm_lube_ros.fleet import parallel
    real, calls = parallel.assess_bag, []

    def killed_on_the_second(path, job):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(path, job)

    monkeypatch.setattr(parallel, 'assess_bag', killed_on_the_second)
    history = tmp_path / 'history'
    try:
        main(['assess', *small_fleet['bags'][:3], '--calibration', str(small_fleet['calibration']),
              '--history', str(history)])
    except BaseException:       # noqa: B036 -- the "kill" may surface as KeyboardInterrupt or SystemExit
        pass
    assert len(calls) == 2
    assert set(read_table(history).column('recording_path').to_pylist()) == {
        str(__import__('pathlib').Path(small_fleet['bags'][0]).resolve())}


def test_recordings_of_several_folders_under_the_default_id_are_refused_in_one_line(small_fleet, tmp_path):
    import subprocess
    import sys

    def run_cli(*args):
        return subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', *map(str, args)], capture_output=True,
                              text=True, timeout=300)

    a01, a02 = small_fleet['bags'][0], small_fleet['bags'][-1]
    history = tmp_path / 'history'
    result = run_cli('assess', a01, a02, '--calibration', small_fleet['calibration'], '--history', history)
    lines = result.stderr.strip().splitlines()
    assert result.returncode == 2 and len(lines) == 1, result.stderr
    assert all(word in lines[0] for word in ('2 folders', 'A01', 'A04', '--actuator-id'))
    assert not (history / 'runs').exists()
    assert run_cli('assess', a01, a02, '--calibration', small_fleet['calibration'], '--history', history,
                   '--actuator-id', 'folder').returncode == 0
    assert sorted(set(read_table(history).column('actuator').to_pylist())) == ['A01', 'A04']


def test_a_recording_name_that_is_not_utf8_is_assessed_into_the_history(small_fleet, tmp_path):
    """Issue 36: a non-UTF-8 byte in a recording name with --history was a traceback (and so was printing it)."""
    import os
    import shutil
    import subprocess
    import sys
    name = os.fsdecode(str(tmp_path).encode() + b'/run\xff.mcap')
    shutil.copy(small_fleet['bags'][0], name)
    history = tmp_path / 'history'
    result = subprocess.run([sys.executable, '-m', 'prsm_lube_ros.cli', 'assess', name, '--calibration',
                             str(small_fleet['calibration']), '--history', str(history), '--json',
                             str(tmp_path / 'out.json')], capture_output=True, timeout=300,
                            env={**os.environ, 'PYTHONIOENCODING': 'utf-8:strict'})
    assert result.returncode == 0 and b'Traceback' not in result.stderr, result.stderr[-500:]
    assert b'run\xff.mcap' in result.stdout
    assert set(read_table(history).column('recording_path').to_pylist()) == {f'{tmp_path}/run\\xff.mcap'}


# -- issue 37: an actuator id that cannot merge two actuators ------------------------------------
def two_fleets(small_fleet, root):
    """Fleets s1 and s2 with the same folder names: s1/A01 holds A01's first days, s2/A01 A02's."""
    bags = {name: [b for b in small_fleet['bags'] if Path(b).parent.name == name] for name in ('A01', 'A02')}
    copies = {}
    for fleet, source in (('s1', 'A01'), ('s2', 'A02')):
        folder = root / fleet / 'A01'
        folder.mkdir(parents=True)
        copies[fleet] = [str(Path(shutil.copy(bag, folder))) for bag in bags[source][:2]]
    return copies


def assess_into(small_fleet, history, bags, *options):
    return main(['assess', *bags, '--calibration', str(small_fleet['calibration']), '--history', str(history),
                 *options])


def test_two_fleets_with_the_same_folder_names_are_never_one_actuator(small_fleet, tmp_path, capsys):
    fleets = two_fleets(small_fleet, tmp_path)
    history = tmp_path / 'history'
    # in one call: refused before anything is assessed, one line naming a recording of each folder
    assert assess_into(small_fleet, history, [*fleets['s1'], *fleets['s2']], '--actuator-id', 'folder') == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and fleets['s1'][0] in lines[0] and fleets['s2'][0] in lines[0]
    assert not (history / 'runs').exists()
    # in two calls: the second folder's recordings are refused, each in one line naming the first folder's
    assert assess_into(small_fleet, history, fleets['s1'], '--actuator-id', 'folder') == 0
    capsys.readouterr()
    assert assess_into(small_fleet, history, fleets['s2']) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if 'error' in line]
    assert len(lines) == 2 and all(str(tmp_path / 's1' / 'A01') in line for line in lines)
    assert fleets['s2'][0] in lines[0] and 'Traceback' not in ''.join(lines)
    assert sorted(set(read_table(history).column('recording_path').to_pylist())) == fleets['s1']
    # named apart by a map, both fleets go in as two actuators
    table = tmp_path / 'actuators.csv'
    table.write_text('s1/A01,s1-A01\ns2/A01,s2-A01\n')
    other = tmp_path / 'history2'
    assert assess_into(small_fleet, other, [*fleets['s1'], *fleets['s2']], '--actuator-map', str(table)) == 0
    runs = read_table(other)
    assert sorted(set(runs.column('actuator').to_pylist())) == ['s1-A01', 's2-A01']


def test_a_symlinked_folder_is_its_real_folders_actuator(small_fleet, tmp_path):
    real = tmp_path / 'fleet' / 'A05'
    real.mkdir(parents=True)
    bags = [str(Path(shutil.copy(bag, real))) for bag in small_fleet['bags'][:2]]
    (tmp_path / 'PUMP7').symlink_to(real)
    history = tmp_path / 'history'
    assert assess_into(small_fleet, history, [str(tmp_path / 'PUMP7' / Path(bags[0]).name)]) == 0
    assert assess_into(small_fleet, history, [bags[1]]) == 0
    runs = read_table(history)
    assert set(runs.column('actuator').to_pylist()) == {'A05'}
    assert set(runs.column('actuator_source').to_pylist()) == {f'folder {real.resolve()}'}


def test_two_calls_with_the_default_id_are_kept_apart(small_fleet, tmp_path):
    """Both calls used to be actuator 'prsm' (the namespace): two actuators merged into one."""
    history = tmp_path / 'history'
    first = [b for b in small_fleet['bags'] if Path(b).parent.name == 'A01'][:2]
    second = [b for b in small_fleet['bags'] if Path(b).parent.name == 'A02'][:2]
    assert assess_into(small_fleet, history, first) == 0
    assert assess_into(small_fleet, history, second) == 0
    runs = read_table(history).to_pylist()
    by_actuator = {}
    for row in runs:
        by_actuator.setdefault(row['actuator'], set()).add(row['recording_path'])
    assert by_actuator == {'A01': set(first), 'A02': set(second)}
