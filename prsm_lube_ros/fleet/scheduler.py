# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Connecting to Dask for ``--scheduler local|ADDRESS``: a scheduler that answers, or one line within the timeout.

A Dask scheduler speaks first: on every new TCP connection it sends its
handshake (one message of msgpack frames: compression, Python version, pickle
protocol).  :func:`probe_scheduler` reads that greeting itself, with a
deadline and a size cap, before :class:`distributed.Client` is let near the
address, so a port that answers with something else (an HTTP server that waits
for a request, a service that sends a huge length prefix) is one
:class:`InputError` line instead of a hang or an "array is too big" traceback.
Addresses other than ``tcp://`` (``tls://``, ``ucx://``) are not probed.

Every wait is bounded by one ``timeout`` (``--scheduler-timeout``): the
probe, the connection, a first worker to join (a scheduler without workers
is one line, not a wait for ever), and, while results are awaited
(:func:`finished_batches`), a spell without any worker (all lost) or without
the scheduler itself: the batches left then fail, each recording one line.
"""
from __future__ import annotations

from contextlib import contextmanager
import math
import socket
import struct
import time
from typing import Any
from collections.abc import Iterator
import logging
import warnings

from ..errors import InputError

__all__ = ['CONNECT_TIMEOUT', 'LOCAL_SCHEDULER', 'MAX_HANDSHAKE', 'NotAScheduler', 'POLL_SECONDS', 'dask_client',
           'finished_batches', 'probe_scheduler', 'scattered']

LOCAL_SCHEDULER = 'local'
#: s to connect to a scheduler and read its handshake (the whole probe)
CONNECT_TIMEOUT = 10.0
#: largest handshake message accepted (bytes); a Dask handshake is about 100
MAX_HANDSHAKE = 1 << 16
#: s between two looks at the cluster while results are awaited
POLL_SECONDS = 0.5
_LENGTH = struct.Struct('Q')


class NotAScheduler(Exception):
    """The address answered, but not as a Dask scheduler (what it did instead)."""


def _read_exactly(sock: socket.socket, size: int, deadline: float) -> bytes:
    """``size`` bytes from ``sock`` before ``deadline`` (monotonic s)."""
    data = bytearray()
    while len(data) < size:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise NotAScheduler('sent no Dask handshake')
        sock.settimeout(remaining)
        try:
            chunk = sock.recv(size - len(data))
        except TimeoutError:
            raise NotAScheduler('sent no Dask handshake') from None
        if not chunk:
            raise NotAScheduler('closed the connection without a Dask handshake')
        data += chunk
    return bytes(data)


def _handshake(sock: socket.socket, deadline: float) -> dict:
    """The greeting a Dask scheduler sends on connect, checked for size and shape."""
    from distributed.protocol.core import loads
    from distributed.protocol.utils import unpack_frames
    (total,) = _LENGTH.unpack(_read_exactly(sock, _LENGTH.size, deadline))
    if not _LENGTH.size <= total <= MAX_HANDSHAKE:
        raise NotAScheduler(f'sent a message of {total} bytes where a Dask handshake has about 100')
    try:
        info = loads(unpack_frames(_read_exactly(sock, total, deadline)), deserialize=False)
    except Exception:  # noqa: BLE001 -- any decoding failure means "not Dask"
        info = None
    if not isinstance(info, dict) or 'pickle-protocol' not in info:
        raise NotAScheduler('sent something that is not a Dask handshake')
    return info


def probe_scheduler(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Check that a ``tcp://`` ``address`` is a Dask scheduler within ``timeout`` s; :class:`InputError` if not."""
    from distributed.comm.addressing import parse_address, parse_host_port
    try:
        scheme, location = parse_address(address)
        if scheme != 'tcp':
            return
        host, port = parse_host_port(location)
    except (ValueError, TypeError) as exc:
        raise InputError(f'--scheduler {address}: not a scheduler address ({exc})') from None
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            _handshake(sock, deadline)
    except NotAScheduler as exc:
        raise InputError(f'--scheduler {address}: not a Dask scheduler: it {exc} within {timeout:g} s') from None
    except OSError as exc:
        raise InputError(f'--scheduler {address}: cannot connect ({exc.strerror or exc})') from None


@contextmanager
def dask_client(scheduler: str, workers: int, timeout: float = CONNECT_TIMEOUT) -> Iterator:
    """A :class:`distributed.Client` on ``scheduler`` (an address, or ``'local'``: ``workers`` processes).

    Every failure to start or connect, and a scheduler without a worker
    after ``timeout`` s, is one :class:`InputError` line; the client (and a
    local cluster) are closed on leaving.
    """
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError('--scheduler needs dask.distributed: pip install "distributed>=2024.1"') from None
    cluster = None
    try:
        if scheduler == LOCAL_SCHEDULER:
            with warnings.catch_warnings():     # its HTTP port taken by another cluster: it picks another, say nothing
                warnings.filterwarnings('ignore', message='Port .* is already in use', category=UserWarning)
                # silence_logs: a worker's heartbeat racing the cluster's close logs a traceback on stderr, which
                # is no user's error (task errors reach the client as exceptions, and are one line there)
                cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.CRITICAL)
            client = Client(cluster, timeout=f'{timeout}s')
        else:
            probe_scheduler(scheduler, timeout)
            client = Client(scheduler, timeout=f'{timeout}s')
        _wait_for_a_worker(client, scheduler, timeout)
    except InputError:
        if cluster is not None:
            cluster.close()
        raise
    except Exception as exc:  # noqa: BLE001 -- a cluster that does not start is one line, whatever Dask raised
        if cluster is not None:
            cluster.close()
        raise InputError(f'--scheduler {scheduler}: cannot connect ({exc.__class__.__name__}: {exc})'
                         .replace('\n', ' ')) from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _wait_for_a_worker(client: Any, scheduler: str, timeout: float) -> None:
    """Return once the scheduler has a worker; :class:`InputError` after ``timeout`` s without one."""
    deadline = time.monotonic() + timeout
    while not _workers(client):
        if time.monotonic() > deadline:
            client.close()
            raise InputError(f'--scheduler {scheduler}: no worker joined the scheduler within {timeout:g} s '
                             '(start one: dask worker ADDRESS)')
        time.sleep(min(POLL_SECONDS, timeout / 10))


def scattered(client: Any, value: Any, scheduler: str, timeout: float) -> Any:
    """``value`` sent to every worker once (a future for the tasks); :class:`InputError` after ``timeout`` s."""
    try:
        return client.scatter(value, broadcast=True, timeout=timeout)
    except Exception as exc:  # noqa: BLE001 -- workers gone between connect and scatter: one line
        raise InputError(f'--scheduler {scheduler}: cannot send the calibration to the workers within {timeout:g} s '
                         f'({exc.__class__.__name__})') from None


def _workers(client: Any) -> int:
    """How many workers the scheduler has (0 when it cannot be asked)."""
    try:
        return len(client.scheduler_info().get('workers', {}))
    except Exception:  # noqa: BLE001 -- a scheduler that does not answer has no worker for us
        return 0


def finished_batches(client: Any, futures: list, scheduler: str, timeout: float) -> Iterator[tuple[Any, str]]:
    """(future, '') as each finishes; (future, why) for those left once the cluster had no worker for ``timeout`` s.

    A worker lost while others remain is Dask's to handle (the task is
    retried, then fails with ``KilledWorker``: its recordings' lines).
    """
    from distributed import wait
    pending = set(futures)
    alone_since: float | None = None
    why = ''
    while pending:
        try:
            done = wait(list(pending), timeout=POLL_SECONDS, return_when='FIRST_COMPLETED').done
        except TimeoutError:
            done = set()
        except Exception as exc:  # noqa: BLE001 -- the work dropped (scheduler gone, tasks cancelled): one line each
            done = {future for future in pending if future.done() and future.status == 'finished'}
            alone_since = -math.inf
            why = (f'--scheduler {scheduler}: the cluster dropped the work ({exc.__class__.__name__}'
                   f'{"" if _workers(client) else "; no worker left"})')
        for future in done:
            pending.discard(future)
            yield future, ''
        if not pending:
            return
        if alone_since != -math.inf:
            if _workers(client):
                alone_since = None
                continue
            alone_since = alone_since if alone_since is not None else time.monotonic()
            if time.monotonic() - alone_since < timeout:
                continue
            why = f'--scheduler {scheduler}: no worker left for {timeout:g} s'
        for future in sorted(pending, key=futures.index):
            yield future, why
        return
