# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""SIGINT and SIGTERM end a command with one line and 130/143, never an abort, outputs whole (issue 36, item 5)."""
import os
from pathlib import Path
import shutil
import signal
import subprocess
import time

import pytest

from prsm_lube_ros import cli
from prsm_lube_ros.estimation.calibration_file import load_calibration

from fuzzing import seed_calibration


@pytest.fixture
def patched(monkeypatch):
    """``patched(action)``: the argv of a command whose handler is now ``action(args)``."""
    def use(action):
        from prsm_lube_ros.cli import simulate
        monkeypatch.setattr(simulate, 'run', action)
        return ['simulate', '/nonexistent-never-written']
    return use


@pytest.mark.parametrize('signum, status', [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_while_a_command_runs_is_one_line_and_its_status(patched, capsys, signum, status):
    cleaned = []

    def action(args):
        try:
            os.kill(os.getpid(), signum)
            time.sleep(5)
        finally:
            cleaned.append(True)       # the command's own clean-up ran
        return 0
    before = signal.getsignal(signal.SIGINT)      # SIG_IGN in a shell's background job, else Python's own
    assert cli.main(patched(action)) == status
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f'prsm-lube simulate: interrupted by {signal.Signals(signum).name}; files being written were '
                     'left as they were']
    assert cleaned == [True]
    assert signal.getsignal(signal.SIGINT) is before      # handlers restored


@pytest.mark.parametrize('signal_at', ['after the command', 'after the rename', 'inside the note'])
def test_a_signal_after_an_output_was_put_in_place_names_it_on_the_line(patched, capsys, tmp_path, monkeypatch,
                                                                        signal_at):
    from prsm_lube_ros import atomic_file
    target = tmp_path / 'calib.yaml'
    if signal_at == 'after the rename':      # the signal lands on the very bytecode after the rename
        real_replace = os.replace

        def replace_then_signal(source, destination):
            real_replace(source, destination)
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        monkeypatch.setattr(atomic_file.os, 'replace', replace_then_signal)
    if signal_at == 'inside the note':      # renamed, and the signal lands before the note is taken (Kilted CI)
        class SignalOnce:
            fired = False

            def search(self, part):
                if not SignalOnce.fired:
                    SignalOnce.fired = True
                    os.kill(os.getpid(), signal.SIGTERM)
                    time.sleep(5)
                return None
        monkeypatch.setattr(atomic_file, '_OWNED', SignalOnce())

    def action(args):
        atomic_file.write_text_atomically(target, 'whole\n')
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)
        return 0
    assert cli.main(patched(action)) == 143
    assert target.read_text() == 'whole\n'
    assert capsys.readouterr().err.strip().splitlines() == [
        f'prsm-lube simulate: interrupted by SIGTERM; {target} was written whole before it; files being written were '
        'left as they were']


def test_a_signal_between_a_staged_file_s_rename_and_its_note_still_names_it(patched, capsys, tmp_path, monkeypatch):
    from prsm_lube_ros import atomic_file
    report = tmp_path / 'report'
    real_replace = os.replace

    def replace_then_signal(source, destination):
        real_replace(source, destination)
        if Path(destination).parent == report:      # the move out of the staged folder, not the write into it
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)

    def action(args):
        with atomic_file.staged_folder(report) as staged:
            atomic_file.write_text_atomically(staged / 'index.md', 'index')
            monkeypatch.setattr(atomic_file.os, 'replace', replace_then_signal)
    assert cli.main(patched(action)) == 143
    assert (report / 'index.md').read_text() == 'index'
    assert capsys.readouterr().err.strip().splitlines() == [
        f'prsm-lube simulate: interrupted by SIGTERM; {report / "index.md"} was written whole before it; files being '
        'written were left as they were']


def test_a_report_s_files_are_named_where_they_are_put_not_where_they_were_staged(patched, capsys, tmp_path):
    from prsm_lube_ros import atomic_file
    report = tmp_path / 'report'

    def action(args):
        with atomic_file.staged_folder(report) as staged:
            for name in ('index.md', 'runs.png'):
                atomic_file.write_text_atomically(staged / name, name)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)
    assert cli.main(patched(action)) == 143
    assert capsys.readouterr().err.strip().splitlines() == [
        f'prsm-lube simulate: interrupted by SIGTERM; 2 files were written whole before it, the last '
        f'{report / "runs.png"}; files being written were left as they were']


def test_what_an_earlier_command_or_no_command_wrote_is_not_named(patched, capsys, tmp_path):
    from prsm_lube_ros import atomic_file

    def writes(args):
        atomic_file.write_text_atomically(tmp_path / 'done.txt', 'x')
        return 0

    def interrupted(args):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(5)
    assert cli.main(patched(writes)) == 0
    for i in range(3):          # outside any command (a node writing its history for days): nothing is kept
        atomic_file.write_text_atomically(tmp_path / f'{i}.txt', 'x')
    assert cli.main(patched(interrupted)) == 130
    assert capsys.readouterr().err.strip().splitlines() == [
        'prsm-lube simulate: interrupted by SIGINT; files being written were left as they were']


def test_a_signal_turned_into_another_exception_is_still_the_interruption(patched, capsys):
    """A signal during an extension module's initialisation comes out as ImportError (pybind11)."""
    def action(args):
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except BaseException:
            raise ImportError('initialization failed') from None
    assert cli.main(patched(action)) == 143
    assert 'Traceback' not in capsys.readouterr().err


def test_a_swallowed_signal_still_ends_with_its_line(patched, capsys):
    """Python drops an exception raised in a __del__ or weakref callback; the command then ends with the line."""
    def action(args):
        class Swallower:
            def __del__(self):
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(1000):       # the handler runs in here; its exception is dropped
                    pass
        Swallower()
        return 0
    assert cli.main(patched(action)) == 143
    err = capsys.readouterr().err
    assert 'Exception ignored' not in err and err.count('\n') == 1


@pytest.fixture(scope='module')
def reference_bag(tmp_path_factory):
    from fuzzing import seed_simulated
    folder = tmp_path_factory.mktemp('signals')
    return next(path for path, kind in seed_simulated(folder) if kind == 'contract')


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_the_installed_command_ends_cleanly_at_any_point_and_leaves_the_calibration_whole(reference_bag, tmp_path,
                                                                                          signum):
    command = shutil.which('prsm-lube')
    assert command, 'the installed prsm-lube command is not on PATH'
    out = seed_calibration(tmp_path / 'calib.yaml')
    seen = set()
    argv = [command, 'calibrate', str(reference_bag), '--out', str(out)]
    # Signals spread over the command's own run (measured here: 0.45 s on a quiet machine, seconds under load),
    # past the interpreter's start-up, where the command's handlers are not installed yet.
    started = time.monotonic()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, timeout=120)
    full = time.monotonic() - started
    before = out.read_bytes()                           # what that run wrote: an interrupted one must leave it
    first = load_calibration(out)
    for delay in (max(0.2, share * full) for share in (0.45, 0.55, 0.65, 0.75, 0.85, 1.2)):
        previous = out.read_bytes()     # what this run finds (an earlier interrupted run may have committed anew)
        process = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        time.sleep(delay)
        process.send_signal(signum)
        err = process.communicate(timeout=60)[1]
        seen.add(process.returncode)
        assert process.returncode in (0, 128 + signum), (delay, process.returncode, err)
        if process.returncode:
            assert len(err.strip().splitlines()) == 1 and 'interrupted by' in err, err
            if out.read_bytes() != before:      # the signal came after a new file was committed (seen in CI):
                assert load_calibration(out).constants == first.constants      # the same fit, written whole
            if out.read_bytes() != previous:    # this run committed it: its line says so
                assert f'{out} was written whole before it' in err, err
        load_calibration(out)                           # whole: the old one or the new one
        assert [p.name for p in tmp_path.iterdir()] == ['calib.yaml']
    assert 128 + signum in seen
    assert Path(out).is_file()
