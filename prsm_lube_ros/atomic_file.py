# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Temporary files and folders that name their writer, so the next run can remove what a killed one left.

A write that must survive ``kill -9`` goes to a hidden temporary beside its
target, named ``.<target name>.<writer pid>.<random>.tmp``, is flushed to
disk and renamed over the target in one ``os.replace``.  A writer killed
before the rename leaves its temporary; :func:`remove_stale` (called by the
next writer of the same target) removes the temporaries whose writer process
no longer runs, and leaves those of a writer still at work.  Temporaries of
the earlier format (no pid) are removed once older than :data:`LEGACY_AGE`.

Every file the package writes goes this way: :func:`write_atomically` (and
:func:`write_text_atomically`, :func:`save_figure`) for one file,
:func:`staged_folder` for a set of files another module writes by name (a
report: each file is moved into place whole), :func:`exchange` for a folder
replaced by another in one step.  A target that is not a regular file (a
terminal, a FIFO, ``/dev/stdout``) is written directly: a stream cannot be
replaced.  Writers that must not interleave across processes (the history's
commits) hold a :func:`file_lock`, which the kernel releases when its holder
dies.
"""
from __future__ import annotations

from contextlib import contextmanager
import errno
import fcntl
import ctypes
import os
from pathlib import Path
import re
import shutil
import tempfile
import time
from typing import Any, TYPE_CHECKING
from collections.abc import Callable, Iterator

from .stopping import note_written

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ['LEGACY_AGE', 'LOCK_TIMEOUT', 'exchange', 'file_lock', 'is_stale', 'process_alive', 'remove_stale',
           'save_figure', 'staged_folder', 'temporary_prefix', 'write_atomically', 'write_text_atomically']

#: s after which a temporary without a writer pid is taken as stale
LEGACY_AGE = 600.0
#: s a writer waits for another one's :func:`file_lock` before giving up with an OSError
LOCK_TIMEOUT = 120.0
_OWNED = re.compile(r'\.(\d+)\.[^.]+\.tmp$')


def process_alive(pid: int) -> bool:
    """True when a process with ``pid`` runs (or exists under another user)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def temporary_prefix(name: str) -> str:
    """Prefix of this process's temporaries for a target called ``name``."""
    return f'.{name}.{os.getpid()}.'


def is_stale(path: Path, now: float | None = None) -> bool:
    """True for a temporary whose writer is gone (or, without a pid, older than :data:`LEGACY_AGE`)."""
    owned = _OWNED.search(path.name)
    if owned is not None:
        return not process_alive(int(owned.group(1)))
    try:
        return (now or time.time()) - path.lstat().st_mtime > LEGACY_AGE
    except OSError:
        return False


def remove_stale(folder: Path, name: str = '') -> list[Path]:
    """Remove the stale temporaries (files or folders) for ``name`` (every target when empty) in ``folder``."""
    removed = []
    for path in Path(folder).glob(f'.{name}*.tmp' if name else '.*.tmp'):
        if is_stale(path):
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
            else:
                path.unlink(missing_ok=True)
            removed.append(path)
    return removed


def write_atomically(path: Path, write: Callable[[Any], object], *, binary: bool = True,
                     before_replace: Callable[[Path], None] | None = None) -> None:
    """``write(stream)`` into a temporary beside ``path``, fsync, rename over ``path``; stale temporaries removed.

    ``before_replace(temporary)``, if given, runs between the write and the
    rename (tests inject a crash there).  A link is written through (its
    target replaced); a target that exists and is not a regular file (a
    terminal, FIFO, ``/dev/stdout``) is written directly.  OSError propagates.
    """
    path = Path(path)
    if path.exists() and not path.is_file() and not path.is_dir():     # links followed: /dev/stdout, a FIFO
        _write_stream(path, write, binary)
        return
    if path.is_symlink():
        path = path.resolve()
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(path.parent, path.name)
    handle, temporary = tempfile.mkstemp(prefix=temporary_prefix(path.name), suffix='.tmp', dir=path.parent)
    try:
        with os.fdopen(handle, 'wb' if binary else 'w') as stream:
            write(stream)
            stream.flush()
            os.fsync(stream.fileno())
        if before_replace is not None:
            before_replace(Path(temporary))
        _replace_and_note(Path(temporary), path, _note_in_place)
    except BaseException:
        if os.path.lexists(temporary):
            Path(temporary).unlink()
        raise


def _replace_and_note(source: Path, target: Path, note: Callable[[Path], None]) -> None:
    """``os.replace(source, target)``, then ``note(target)``; a signal between the two notes it all the same.

    Once renamed the file is in place whole, so the line a signal prints names
    it whichever bytecode the signal lands on (:func:`.stopping.note_written`
    counts a path noted twice in a row once).
    """
    try:
        os.replace(source, target)
        note(target)
    except BaseException:
        if not os.path.lexists(source):
            note(target)
        raise


def _note_in_place(path: Path) -> None:
    """Tell :mod:`.stopping` that ``path`` is in place whole, unless it lies in a staged folder (not yet in place)."""
    if not any(_OWNED.search(part) for part in path.parent.parts):
        note_written(path)


@contextmanager
def file_lock(path: Path, timeout: float = LOCK_TIMEOUT) -> Iterator[None]:
    """Hold an exclusive ``flock`` on ``path`` (created if missing, never through a link) across processes.

    Waits up to ``timeout`` s for another holder, then raises ``OSError``
    (``ETIMEDOUT``); the kernel drops the lock of a killed holder.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    handle = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW, 0o644)
    try:
        deadline = time.monotonic() + timeout
        while True:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise OSError(errno.ETIMEDOUT, f'another writer held {path.name} for {timeout:g} s',
                                  str(path)) from None
                time.sleep(0.01)
        yield
    finally:
        os.close(handle)


def _write_stream(path: Path, write: Callable[[Any], object], binary: bool) -> None:
    """Write into a stream (a terminal, a FIFO): a FIFO nobody reads is an OSError (ENXIO), not a wait forever."""
    handle = os.open(path, os.O_WRONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    os.set_blocking(handle, True)
    with os.fdopen(handle, 'wb' if binary else 'w') as stream:
        write(stream)


def write_text_atomically(path: Path, text: str) -> None:
    """:func:`write_atomically` of ``text`` (UTF-8)."""
    write_atomically(Path(path), lambda stream: stream.write(text.encode()))


def save_figure(figure: Figure, path: Path) -> None:
    """``figure.savefig`` into a temporary and renamed over ``path`` (format from the suffix, default PNG)."""
    path = Path(path)
    kind = path.suffix[1:].lower() or 'png'
    write_atomically(path, lambda stream: figure.savefig(stream, format=kind))


@contextmanager
def staged_folder(target: Path) -> Iterator[Path]:
    """A new hidden folder beside ``target`` to write into; on success each file moves into ``target`` whole.

    Files of ``target`` not written are left alone; one of the same name is
    replaced in one rename, so a reader sees it old or new.  On an exception
    nothing is moved and the staged folder is removed (a killed writer's is
    removed by the next, as every temporary here).
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    remove_stale(target.parent, target.name)
    staged = Path(tempfile.mkdtemp(prefix=temporary_prefix(target.name), suffix='.tmp', dir=target.parent))
    try:
        yield staged
        for file in sorted(p for p in staged.rglob('*') if p.is_file()):
            place = target / file.relative_to(staged)
            place.parent.mkdir(parents=True, exist_ok=True)
            _replace_and_note(file, place, note_written)
    finally:
        shutil.rmtree(staged, ignore_errors=True)


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def exchange(first: Path, second: Path) -> None:
    """Swap two folders atomically (Linux ``renameat2``); else move ``second`` aside to ``first``'s place first."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        renameat2 = None
    if renameat2 is not None:
        if renameat2(_AT_FDCWD, os.fsencode(first), _AT_FDCWD, os.fsencode(second), _RENAME_EXCHANGE) == 0:
            return
        error = ctypes.get_errno()
        if error not in (22, 38, 95):                     # EINVAL, ENOSYS, EOPNOTSUPP: no exchange here
            raise OSError(error, os.strerror(error), str(second))
    aside = first.with_name(first.name + '.old.tmp')
    os.rename(second, aside)
    os.rename(first, second)
    os.rename(aside, first)
