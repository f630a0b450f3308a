# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Exception types for problems with what a user gave us, one line each.

An :class:`InputError` carries a single line that names the input (a file, a
topic, a parameter) and what is wrong with it.  Command-line tools print that
line and exit non-zero; nodes log it and keep running.  Anything else that
escapes is a bug in this package, not a user error.  Callers that must tell
kinds apart branch on the subclass, never on the wording:

* :class:`RecordingError` -- a recording cannot be opened or read;
* :class:`ConfigError` -- a configuration file, parameter or option is invalid;
* :class:`NotIdentifiable` -- the data are readable but cannot determine what
  was asked (too few operating conditions for the constants, no usable window).

This module imports nothing of the package.
"""
from collections.abc import Callable

__all__ = ['ConfigError', 'InputError', 'NotIdentifiable', 'ProblemSink', 'RecordingError', 'exception_text']

#: Where a reader or pipeline sends each one-line problem it meets in otherwise usable input.
ProblemSink = Callable[[str], None]


class InputError(ValueError):
    """Bad input, described in one line that names the input."""

    def __init__(self, message: str):
        super().__init__(' '.join(str(message).split()))


class RecordingError(InputError):
    """A recording (file or bag folder) that cannot be opened or read."""


class ConfigError(InputError):
    """A configuration file, parameter value or command-line option that is invalid."""


class NotIdentifiable(InputError):
    """Readable data that cannot determine what was asked of them (constants, windows, a verdict)."""


def exception_text(err: BaseException) -> str:
    """``<ExceptionType>: <message on one line>`` (just the type when the message is empty)."""
    text = ' '.join(str(err).split())
    return f'{type(err).__name__}: {text}' if text else type(err).__name__
