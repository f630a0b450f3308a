# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""SIGINT and SIGTERM end a command cleanly: one line on stderr, status 128 + the signal's number, never an abort.

While a command runs (:class:`StopSignals`), the first signal raises
:class:`Terminated` in the main thread, so every ``finally`` and every
temporary of :mod:`prsm_lube_ros.atomic_file` is cleaned up on the way out;
later signals are ignored while that happens.  Python cannot raise into code
that swallows exceptions (a weakref callback or ``__del__`` that the signal
happened to interrupt): such a swallowed :class:`Terminated` is not printed,
and a watchdog ends the process :data:`GRACE` s later with the same line and
status (a temporary it leaves names its writer and is removed by the next).
Before and after a command (the entry scripts' start-up and exit),
:func:`stop_at_once` ends the process at once with the line; the scripts
install it before they import anything else of the package, and end with
:func:`exit_now` (exit handlers run, then ``os._exit``) instead of the
interpreter's finalisation, which puts the default actions back and can
abort on daemon threads.  Only the interpreter's own start-up is left to the
signals' default action.  Imports nothing of the package.
"""
from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from types import TracebackType
from typing import Any

__all__ = ['GRACE', 'STOP_SIGNALS', 'StopSignals', 'Terminated', 'exit_now', 'note_written', 'stop_at_once']

#: Signals that end a command cleanly.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: s the command has, after a signal, to unwind before the watchdog ends the process.
GRACE = 5.0


class Terminated(BaseException):
    """SIGINT or SIGTERM arrived: the command stops where it is; what it was writing stays as it was."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class _Written:
    """How many files the running command has put in place whole, and the last (:func:`note_written`)."""

    active = False      # only inside a command's StopSignals: a node writing for days keeps nothing
    count = 0
    last = ''


def note_written(path: str | os.PathLike[str]) -> None:
    """Record that ``path`` was put in place whole (renamed over its target), for the line a signal prints.

    The same path noted again straight after (a signal between the rename and
    the first note, whose handler notes it too) counts once.  Count and name
    are stored in one statement, where no signal handler runs in between.
    """
    if _Written.active:
        name = os.fspath(path).replace('\n', '\\n')     # the line stays one line
        if name != _Written.last:
            _Written.count, _Written.last = _Written.count + 1, name


def _line(command: str, signum: int) -> str:
    """The one line of an interruption: what was already written whole, and that nothing was left half-written."""
    done = ''
    if _Written.count:
        done = (f'{_Written.last} was written whole before it' if _Written.count == 1 else
                f'{_Written.count} files were written whole before it, the last {_Written.last}') + '; '
    return (f'prsm-lube{" " + command if command else ""}: interrupted by {signal.Signals(signum).name}; {done}files '
            'being written were left as they were')


def stop_at_once() -> None:
    """Outside a command (the entry scripts' start-up and exit): SIGINT and SIGTERM end the process at once.

    Nothing is being written then, so nothing is left to clean up.
    """
    def end(signum: int, frame: object) -> None:
        os.write(2, f'prsm-lube: interrupted by {signal.Signals(signum).name}\n'.encode(errors='surrogateescape'))
        os._exit(128 + signum)
    for signum in STOP_SIGNALS:
        signal.signal(signum, end)


def exit_now(status: int) -> None:
    """End the process with ``status``: output flushed, exit handlers run, no finalisation (see above)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):    # a closed pipe: nothing more can be said there
            pass
    run = getattr(atexit, '_run_exitfuncs', None)
    if run is not None:
        run()
    os._exit(status)


class StopSignals:
    """Context of one command: its stop signals raise :class:`Terminated` (in the main thread only)."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self.command = ''
        self._finished = threading.Event()
        self._previous: dict[int, Any] = {}
        self._hook = sys.unraisablehook
        self._active = threading.current_thread() is threading.main_thread()

    def __enter__(self) -> StopSignals:
        _Written.active, _Written.count, _Written.last = self._active, 0, ''
        if self._active:
            self._previous = {signum: signal.getsignal(signum) for signum in STOP_SIGNALS}
            for signum in STOP_SIGNALS:
                signal.signal(signum, self._stop)
            sys.unraisablehook = self._unraisable
        return self

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self._finished.set()
        _Written.active = False
        if self._active:
            sys.unraisablehook = self._hook
            for signum, handler in self._previous.items():
                signal.signal(signum, handler)

    def arrived(self, signum: int) -> None:
        """Record the signal that ends the command (also when it came as a KeyboardInterrupt)."""
        if self.signum is None:
            self.signum = int(signum)

    def status(self, command: str, status: int) -> int:
        """``status``, or after a signal its one line on stderr and 128 + its number."""
        self._finished.set()
        if self.signum is None:
            return status
        print(_line(command, self.signum), file=sys.stderr)
        sys.stderr.flush()
        return 128 + self.signum

    def _stop(self, signum: int, frame: object) -> None:
        if self.signum is None:
            self.arrived(signum)
            for other in STOP_SIGNALS:
                signal.signal(other, signal.SIG_IGN)
            threading.Thread(target=self._watch, name='stop watchdog', daemon=True).start()
        raise Terminated(signum)

    def _watch(self) -> None:
        if not self._finished.wait(GRACE) and self.signum is not None:
            os.write(2, (_line(self.command, self.signum) + '\n').encode(errors='surrogateescape'))
            os._exit(128 + self.signum)

    def _unraisable(self, unraisable: Any) -> None:
        if not isinstance(unraisable.exc_value, (Terminated, KeyboardInterrupt)):
            self._hook(unraisable)
