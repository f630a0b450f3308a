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
"""
from __future__ import annotations

from contextlib import contextmanager
import socket
import struct
import time
from collections.abc import Iterator
import logging
import warnings

from ..errors import InputError

__all__ = ['CONNECT_TIMEOUT', 'LOCAL_SCHEDULER', 'MAX_HANDSHAKE', 'NotAScheduler', 'dask_client', 'probe_scheduler']

LOCAL_SCHEDULER = 'local'
#: s to connect to a scheduler and read its handshake (the whole probe)
CONNECT_TIMEOUT = 10.0
#: largest handshake message accepted (bytes); a Dask handshake is about 100
MAX_HANDSHAKE = 1 << 16
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

    Every failure to start or connect is one :class:`InputError` line; the
    client (and a local cluster) are closed on leaving.
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
    except InputError:
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
