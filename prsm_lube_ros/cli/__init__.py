# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube``: simulate, calibrate, assess and diagnose recordings from the command line.

Owns: one module per command, each with ``add_command(subparsers)`` (which adds
its parser with ``set_defaults(func=run)``) and ``run(args)`` returning the
exit status.  Building the parser imports no numpy, scipy or ROS: each
command imports what it needs when it runs, so ``prsm-lube --help`` starts
at once and ``assess`` does not pay for the diagnosis engine.

User errors (a missing or broken recording, data that cannot calibrate, a bad
option) end with one line on stderr naming the input and a non-zero status;
there is no traceback for them.  SIGINT and SIGTERM, at any point of a
command, end it with one line and status 130 or 143
(:mod:`prsm_lube_ros.stopping`).  This package may import every other one.
"""
from __future__ import annotations

import argparse
import importlib
import signal
import sys
from typing import TYPE_CHECKING

from ..errors import InputError
from .common import EXIT_USER_ERROR
from ..stopping import stop_at_once, STOP_SIGNALS, StopSignals, Terminated

if TYPE_CHECKING:
    from collections.abc import Sequence

#: Command modules, in the order ``--help`` lists them.
COMMAND_MODULES = ('simulate', 'calibrate', 'assess', 'trend', 'diagnose', 'demo', 'run')

__all__ = ['build_parser', 'COMMAND_MODULES', 'EXIT_USER_ERROR', 'main', 'stop_at_once', 'STOP_SIGNALS',
           'Terminated']


def build_parser() -> argparse.ArgumentParser:
    """The ``prsm-lube`` argument parser."""
    parser = argparse.ArgumentParser(prog='prsm-lube', description=(
        'Lubrication assessment of planetary roller screws (theta_Oil) from nut vibration, '
        'screw speed and axial load.'))
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')
    for name in COMMAND_MODULES:
        importlib.import_module(f'{__name__}.{name}').add_command(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status (128 + the signal's number after SIGINT or SIGTERM: 130, 143)."""
    command = ''
    _names_in_any_encoding()
    with StopSignals() as stop:
        try:
            args = build_parser().parse_args(argv)
            command = stop.command = args.command
            status = _run(args)
        except (Terminated, KeyboardInterrupt) as exc:
            stop.arrived(getattr(exc, 'signum', signal.SIGINT))
        except BaseException:
            if stop.signum is None:
                raise
            # A signal's exception turned into another on its way (an extension module that was initialising
            # reports ImportError): it is still the interruption.
        return stop.status(command, status if stop.signum is None else 0)


def _names_in_any_encoding() -> None:
    """stdout and stderr print any file name the file system allows (its bytes back, not UnicodeEncodeError)."""
    for stream in (sys.stdout, sys.stderr):
        if getattr(stream, 'errors', None) == 'strict' and hasattr(stream, 'reconfigure'):
            stream.reconfigure(errors='surrogateescape' if stream.encoding.lower().replace('-', '') == 'utf8'
                               else 'backslashreplace')


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command; a user error or a refused file operation is one line on stderr."""
    try:
        return args.func(args)
    except InputError as exc:
        print(f'prsm-lube {args.command}: error: {exc}', file=sys.stderr)
        return EXIT_USER_ERROR
    except OSError as exc:      # the file system refused (disk full, ulimit -f, permissions): outputs stay whole
        where = f'{exc.filename}: ' if exc.filename else ''
        print(f'prsm-lube {args.command}: error: {where}cannot write or read ({exc.strerror or exc})', file=sys.stderr)
        return EXIT_USER_ERROR
