# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Files read on a request: confined to a root, regular files only, their size bounded before reading.

Every file the package opens because a user, a request or a recording named
it goes through here: a recording and the files inside a bag folder
(``metadata.yaml``, ``.mcap``, ``.db3``), calibration and configuration
files, the history's Parquet files and kept calibrations.

* :func:`confine` resolves a path (symbolic links followed) and refuses it
  when it leads outside an allowed root -- in one line that names the path
  asked for, never what it points to or holds;
* :func:`check_regular` refuses a FIFO, a device, a socket or a folder, and a
  file larger than a bound, from ``stat`` alone (nothing is opened);
* :func:`open_regular` opens without blocking (a FIFO with no writer cannot
  hang the caller), checks the opened file with ``fstat`` (what was checked
  is what is read) and hands back a blocking binary stream;
* :func:`read_bytes` and :func:`read_text` read at most the bound.

Each refusal is one line of the ``error`` class the caller names (a
:class:`~prsm_lube_ros.errors.ConfigError` for a calibration file, a
:class:`~prsm_lube_ros.errors.RecordingError` for a recording).  Imports only
:mod:`.errors`.
"""
from __future__ import annotations

import os
from pathlib import Path
import stat
from typing import BinaryIO

from .errors import InputError

__all__ = ['MAX_METADATA_BYTES', 'MAX_RECORDING_BYTES', 'check_regular', 'confine', 'file_kind', 'open_regular',
           'read_bytes', 'read_text']

#: Largest storage file read (bytes): a recording is streamed, this only refuses what no logger writes.
MAX_RECORDING_BYTES = 1 << 40
#: Largest rosbag2 ``metadata.yaml`` read, bytes (a bag with a thousand topics writes a few hundred kB).
MAX_METADATA_BYTES = 8 << 20

_KINDS = ((stat.S_ISDIR, 'a folder'), (stat.S_ISFIFO, 'a FIFO (named pipe)'), (stat.S_ISCHR, 'a character device'),
          (stat.S_ISBLK, 'a block device'), (stat.S_ISSOCK, 'a socket'))


def file_kind(mode: int) -> str:
    """What a ``st_mode`` is, in words: 'a regular file', 'a FIFO (named pipe)', 'a folder'..."""
    return next((name for test, name in _KINDS if test(mode)), 'a regular file' if stat.S_ISREG(mode) else
                'not a file')


def confine(path: str | Path, root: str | Path | None, what: str,
            error: type[InputError] = InputError) -> Path:
    """``path`` resolved (links followed); ``error`` when it lies outside ``root`` (None: anywhere).

    The line names ``path`` as asked for, not where it leads: a link to a
    secret says no more than that it leads out.
    """
    resolved = Path(path).resolve()
    if root is not None and not resolved.is_relative_to(Path(root).resolve()):
        raise error(f'{path}: {what} leads outside {root} (a symbolic link out of it?); not read')
    return resolved


def _check_mode(path: str | Path, status: os.stat_result, what: str, max_bytes: int | None,
                error: type[InputError]) -> None:
    if not stat.S_ISREG(status.st_mode):
        raise error(f'{path}: {what} is {file_kind(status.st_mode)}, not a regular file; not read')
    if max_bytes is not None and status.st_size > max_bytes:
        raise error(f'{path}: {what} is {status.st_size} bytes, more than {max_bytes} (not a {what}?); not read')


def _os_error(path: str | Path, what: str, exc: OSError, error: type[InputError]) -> InputError:
    """One line for an OSError met opening or checking ``path``."""
    if isinstance(exc, FileNotFoundError):
        return error(f'{path}: {what} not found')
    if isinstance(exc, IsADirectoryError):
        return error(f'{path}: {what} is a folder, not a file')
    return error(f'{path}: cannot read {what} ({exc.strerror or exc})')


def check_regular(path: str | Path, what: str, *, max_bytes: int | None = None, root: str | Path | None = None,
                  error: type[InputError] = InputError) -> os.stat_result:
    """``stat`` of ``path`` (links followed) when it is a regular file within ``max_bytes`` and ``root``.

    Opens nothing: what ``sqlite3`` or another library will open by name is
    checked here first, so it meets no FIFO or device.
    """
    confine(path, root, what, error)
    try:
        status = os.stat(path)
    except OSError as exc:
        raise _os_error(path, what, exc, error) from None
    _check_mode(path, status, what, max_bytes, error)
    return status


def open_regular(path: str | Path, what: str, *, max_bytes: int | None = None, root: str | Path | None = None,
                 error: type[InputError] = InputError) -> BinaryIO:
    """A binary stream of ``path``, once it is known to be a regular file within ``max_bytes`` and ``root``.

    The open does not block (``O_NONBLOCK``: a FIFO without a writer opens at
    once, and is then refused); the checks are made on the opened file.
    """
    confine(path, root, what, error)
    flags = os.O_RDONLY | getattr(os, 'O_NONBLOCK', 0) | getattr(os, 'O_NOCTTY', 0) | getattr(os, 'O_CLOEXEC', 0)
    try:
        handle = os.open(path, flags)
    except OSError as exc:
        raise _os_error(path, what, exc, error) from None
    try:
        _check_mode(path, os.fstat(handle), what, max_bytes, error)
        os.set_blocking(handle, True)
        return os.fdopen(handle, 'rb')
    except BaseException:
        os.close(handle)
        raise


def read_bytes(path: str | Path, what: str, *, max_bytes: int, root: str | Path | None = None,
               error: type[InputError] = InputError) -> bytes:
    """The content of a regular file of at most ``max_bytes`` (also if it grows while read)."""
    try:
        with open_regular(path, what, max_bytes=max_bytes, root=root, error=error) as stream:
            data = stream.read(max_bytes + 1)
    except OSError as exc:
        raise _os_error(path, what, exc, error) from None
    if len(data) > max_bytes:
        raise error(f'{path}: {what} is more than {max_bytes} bytes (not a {what}?); not read')
    return data


def read_text(path: str | Path, what: str, *, max_bytes: int, root: str | Path | None = None,
              error: type[InputError] = InputError) -> str:
    """:func:`read_bytes` as UTF-8 text; a file that is not UTF-8 is one line too."""
    try:
        return read_bytes(path, what, max_bytes=max_bytes, root=root, error=error).decode('utf-8')
    except UnicodeDecodeError:
        raise error(f'{path}: {what} is not text (not UTF-8)') from None
