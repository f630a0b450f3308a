# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube assess --scheduler`` as users run it: the installed command, ``python -m``, a real Dask cluster.

Dask starts its workers by spawn, which imports the command's main module
again; these tests run the command in a fresh process the way a shell does,
so a missing ``__main__`` guard or an unresolved path shows here.
"""
from pathlib import Path
import socket
import subprocess
import sys
import threading
import time

import pytest

from prsm_lube_ros.fleet.scheduler import CONNECT_TIMEOUT

ROOT = Path(__file__).resolve().parents[2]
INSTALLED = [sys.executable, str(ROOT / 'scripts' / 'prsm-lube')]
MODULE = [sys.executable, '-m', 'prsm_lube_ros.cli']

pytest.importorskip('distributed')


def assess(entry, fleet, bags, *options, cwd=None, timeout=300):
    """One ``assess`` process; the completed process."""
    return subprocess.run(entry + ['assess', *bags, '--calibration', str(fleet['calibration']), *options],
                          capture_output=True, text=True, timeout=timeout, cwd=cwd)


def table(result) -> list[str]:
    """The runs table lines of ``assess``'s stdout (recording name, run, speed, load, RMS, theta)."""
    return [line for line in result.stdout.splitlines() if line.endswith(tuple('0123456789'))]


@pytest.fixture(scope='module')
def serial(small_fleet):
    result = assess(INSTALLED, small_fleet, small_fleet['bags'][:4])
    assert result.returncode == 0, result.stderr
    return table(result)


@pytest.mark.parametrize('entry', [INSTALLED, MODULE], ids=['scripts/prsm-lube', 'python -m'])
def test_a_local_cluster_from_the_command_line_equals_serial(small_fleet, serial, entry):
    result = assess(entry, small_fleet, small_fleet['bags'][:4], '--scheduler', 'local', '--jobs', '2')
    assert result.returncode == 0, result.stderr[-3000:]
    assert 'Traceback' not in result.stderr and table(result) == serial


@pytest.fixture(scope='module')
def dask_cluster():
    """A real ``dask scheduler`` and ``dask worker`` (2 processes) on localhost, as an operator starts them."""
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        port = sock.getsockname()[1]
    address = f'tcp://127.0.0.1:{port}'
    scheduler = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_scheduler', '--host', '127.0.0.1',
                                  '--port', str(port), '--dashboard-address', ':0'],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_worker', address, '--nworkers', '2',
                               '--nthreads', '1', '--no-dashboard'], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, cwd='/')
    try:
        from distributed import Client
        with Client(address, timeout='60s') as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for process in (worker, scheduler):
            process.terminate()
            process.wait(timeout=60)


def test_an_external_scheduler_gets_relative_paths_resolved_and_equals_serial(small_fleet, serial, dask_cluster,
                                                                              tmp_path):
    fleet = small_fleet['root']
    relative = [str(Path(bag).relative_to(fleet)) for bag in small_fleet['bags'][:4]]
    history = tmp_path / 'history'
    result = assess(INSTALLED, small_fleet, relative, '--scheduler', dask_cluster, '--history', str(history),
                    '--actuator-id', 'A01', cwd=fleet)
    assert result.returncode == 0, result.stderr[-3000:]
    assert table(result) == serial
    from prsm_lube_ros.fleet.history import read_table
    assert sorted(set(read_table(history).column('recording_path').to_pylist())) == sorted(relative)
    # each file written by the installed command says what it holds when read alone
    import pyarrow.parquet as pq
    alone = pq.read_table(next(history.glob('runs/actuator=A01/*.parquet')))
    assert alone.schema.metadata[b'prsm_lube_ros.actuator'] == b'A01'
    assert str(alone.schema.field('date').type) == 'date32[day]' and alone.schema.field('screw_speed').metadata
    identifier = alone.column('calibration_id')[0].as_py()
    assert (history / 'calibrations' / f'{identifier}.yaml').read_bytes() == small_fleet['calibration'].read_bytes()


class Impostor:
    """A TCP port that is no Dask scheduler: silent (like an HTTP server waiting for a request) or garbage."""

    def __init__(self, greeting: bytes):
        self.greeting, self.server = greeting, socket.socket()
        self.server.bind(('127.0.0.1', 0))
        self.server.listen()
        self.address = f'tcp://127.0.0.1:{self.server.getsockname()[1]}'
        self.held = []
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self):
        while True:
            try:
                connection, _ = self.server.accept()
            except OSError:
                return
            self.held.append(connection)
            if self.greeting:
                connection.sendall(self.greeting)


@pytest.mark.parametrize('greeting', [b'', b'\xff' * 8 + b'garbage', b'HTTP/1.0 200 OK\r\n\r\nhello'],
                         ids=['silent', 'huge length', 'http'])
def test_a_port_that_is_no_dask_scheduler_is_one_line_within_the_timeout(small_fleet, greeting):
    impostor = Impostor(greeting)
    start = time.monotonic()
    result = assess(INSTALLED, small_fleet, small_fleet['bags'][:1], '--scheduler', impostor.address, timeout=120)
    elapsed = time.monotonic() - start
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-3000:]
    assert impostor.address in lines[0] and 'not a Dask scheduler' in lines[0]
    assert elapsed < CONNECT_TIMEOUT + 30      # the probe's deadline plus the process's start-up


# -- issue 37: no workers, lost workers, bad addresses: one line within the timeout; --json as serial ------------
def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


def start_scheduler():
    """A ``dask scheduler`` on localhost without any worker: (process, address), once it answers."""
    port = free_port()
    address = f'tcp://127.0.0.1:{port}'
    process = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_scheduler', '--host', '127.0.0.1',
                                '--port', str(port), '--dashboard-address', ':0'],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    from distributed import Client
    with Client(address, timeout='60s'):
        pass
    return process, address


def stop(*processes):
    for process in processes:
        process.terminate()
        process.wait(timeout=60)


def error_lines(result) -> list[str]:
    return [line for line in result.stderr.splitlines() if line.strip()]


def test_a_scheduler_without_workers_is_one_line_within_the_timeout(small_fleet):
    scheduler, address = start_scheduler()
    try:
        result = assess(INSTALLED, small_fleet, small_fleet['bags'][:2], '--scheduler', address,
                        '--scheduler-timeout', '3', timeout=120)
    finally:
        stop(scheduler)
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-3000:]
    assert address in lines[0] and 'no worker' in lines[0] and '3 s' in lines[0]


KILLER = '''
import os
import prsm_lube_ros.fleet.parallel as parallel


def _die(paths, job):
    os._exit(3)                       # the worker process is lost in the middle of a task


parallel.assess_batch = _die
'''


def test_workers_lost_for_good_fail_each_recording_in_one_line(small_fleet, tmp_path):
    """The only worker dies on its first task and is not restarted: every recording left is one line."""
    killer = tmp_path / 'killer.py'
    killer.write_text(KILLER)
    scheduler, address = start_scheduler()
    worker = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_worker', address, '--no-nanny',
                               '--nthreads', '1', '--no-dashboard', '--preload', str(killer)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd='/')
    try:
        from distributed import Client
        with Client(address, timeout='60s') as client:
            client.wait_for_workers(1, timeout=120)
        bags = small_fleet['bags'][:3]
        result = assess(INSTALLED, small_fleet, bags, '--scheduler', address, '--scheduler-timeout', '3',
                        timeout=180)
    finally:
        stop(worker, scheduler)
    lines = error_lines(result)
    assert result.returncode == 2 and 'Traceback' not in result.stderr, result.stderr[-3000:]
    assert len(lines) == len(bags) and all(bag in line for bag, line in zip(bags, lines)), lines
    assert all('not assessed' in line and address in line and 'no worker left' in line for line in lines), lines


@pytest.mark.parametrize('address', ['tcp://127.0.0.1:{closed}', 'nonsense://somewhere',
                                     'tcp://no-such-host.invalid:8786', 'tcp://127.0.0.1:99999'])
def test_a_bad_scheduler_address_is_one_line(small_fleet, address):
    address = address.format(closed=free_port())
    result = assess(INSTALLED, small_fleet, small_fleet['bags'][:1], '--scheduler', address,
                    '--scheduler-timeout', '3', timeout=120)
    lines = error_lines(result)
    assert result.returncode == 2 and len(lines) == 1, result.stderr[-3000:]
    assert address in lines[0] and 'Traceback' not in result.stderr


def test_the_json_is_the_same_serially_and_on_a_local_cluster(small_fleet, tmp_path):
    """Issue 37: each run's ``bag`` was absolute under --scheduler but as given serially."""
    import json
    fleet = small_fleet['root']
    relative = [str(Path(bag).relative_to(fleet)) for bag in small_fleet['bags'][:3]]
    documents = []
    for name, options in (('serial', ()), ('dask', ('--scheduler', 'local', '--jobs', '2'))):
        out = tmp_path / f'{name}.json'
        result = assess(INSTALLED, small_fleet, relative, '--json', str(out), *options, cwd=fleet)
        assert result.returncode == 0, result.stderr[-3000:]
        documents.append(json.loads(out.read_text()))
    serial, distributed = documents
    assert {run['bag'] for run in serial['runs']} == set(relative)
    assert distributed == serial
