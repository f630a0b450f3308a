# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What several ``prsm-lube`` commands share: options, reading recordings with a progress bar, writing JSON.

Imports nothing heavy at module level: each command pays only for what it uses.
"""
from __future__ import annotations

import json
from pathlib import Path
import sys
from typing import TYPE_CHECKING

from ..errors import ConfigError
from ..validation import finite_or_none

if TYPE_CHECKING:
    import argparse
    from collections.abc import Callable, Iterable, Iterator
    from typing import IO

    from tqdm import tqdm

    from ..estimation.pipeline import RecordingWindows
    from ..physics.actuator import Actuator

__all__ = ['EXIT_USER_ERROR', 'HiddenBar', 'add_band_option', 'add_recording_options', 'json_pieces',
           'percent_updater', 'progress_bar', 'read_recordings', 'warn', 'write_json']

#: Exit status of a user error (bad file, bad option, unusable data).
EXIT_USER_ERROR = 2


def add_recording_options(parser: argparse.ArgumentParser) -> None:
    """``--namespace``, ``--window`` and ``--actuator``, for commands that read recordings."""
    parser.add_argument('--namespace', default='/prsm', help='topic namespace of the actuator (default /prsm)')
    parser.add_argument('--window', type=float, default=1.0, metavar='S',
                        help='window length in s for the RMS (default 1.0)')
    parser.add_argument('--actuator', default=None, metavar='YAML',
                        help='actuator geometry (default: the contract\'s default actuator)')


def progress_bar(total: int, description: str, unit: str = '%') -> tqdm | HiddenBar:
    """A tqdm bar on stderr, hidden when stderr is not a terminal; counts ``unit`` (default percent).

    Hidden, it is a :class:`HiddenBar` and tqdm is not imported (a script or a
    pipe pays nothing for a bar nobody sees).
    """
    if not _stderr_is_terminal():
        return HiddenBar()
    from tqdm import tqdm
    if unit != '%':
        return tqdm(total=total, desc=description, unit=unit, disable=None, leave=False)
    return tqdm(total=total, desc=description, unit='%', disable=None, leave=False,
                bar_format='{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}')


class HiddenBar:
    """The bar when stderr is no terminal: counts (``n``, as tqdm) and shows nothing."""

    def __init__(self) -> None:
        self.n: float = 0

    def update(self, n: float = 1) -> None:
        """Count ``n`` more."""
        self.n += n

    def close(self) -> None:
        """Nothing to close."""


def _stderr_is_terminal() -> bool:
    """Whether stderr is a terminal (tqdm's ``disable=None`` test)."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):      # replaced or closed stderr
        return False


def percent_updater(bar: tqdm | HiddenBar) -> Callable[[float], None]:
    """A ``progress(fraction)`` callback that advances ``bar`` in whole percent."""
    last = [0]

    def progress(fraction: float) -> None:
        step = int(100 * fraction)
        if step > last[0]:
            bar.update(step - last[0])
            last[0] = step
    return progress


def warn(line: str) -> None:
    """One warning line on stderr."""
    print(f'warning: {line}', file=sys.stderr)


def add_band_option(parser: argparse.ArgumentParser) -> None:
    """``--band-high``: the analysis band's upper edge for a new calibration (default: from the first recording)."""
    parser.add_argument('--band-high', type=float, metavar='HZ', default=None,
                        help='upper edge of the analysis band, Hz (default 0.8 x the Nyquist frequency of the first '
                        'recording; 1600 lets one calibration serve every rate from 4 kHz up)')


def read_recordings(paths: Iterable[str | Path], args: argparse.Namespace, *,
                    spectra: bool = False) -> tuple[list[RecordingWindows], Actuator]:
    """Windows of each recording (``RecordingWindows``) and the actuator, with a progress bar per file."""
    from ..estimation.pipeline import analysis_settings, read_recordings as read
    from ..physics.actuator import load_actuator
    from ..physics.defect_orders import defect_orders
    from ..validation import require_positive
    actuator = load_actuator(args.actuator)
    band_high = getattr(args, 'band_high', None)
    settings = analysis_settings(require_positive('--window', args.window), spectra=spectra,
                                 band_high=None if band_high is None else require_positive('--band-high', band_high),
                                 defect_orders=defect_orders(actuator))
    paths = list(paths)
    bars: list[tqdm] = []

    def bar_of(index: int) -> Callable[[float], None]:
        for done in bars:
            done.close()
        bars[:] = [progress_bar(100, Path(paths[index]).name)]
        return percent_updater(bars[0])
    try:      # the band rule (the first recording's band is every later one's) is read_recordings'
        recordings = read(paths, lead=actuator.lead, settings=settings, namespace=args.namespace, on_problem=warn,
                          progress=bar_of)
    finally:
        for bar in bars:
            bar.close()
    return recordings, actuator


def write_json(path: str | Path, document: object, indent: int | None = 1) -> None:
    """``document`` as JSON at ``path`` (folders made, written atomically); no NaN or infinity.

    ``indent`` spaces per level for people; ``None``: compact (no spaces, one
    line), streamed out element by element of the top-level lists with the C
    encoder, so a long window list is neither held twice nor encoded in Python.
    JSON has no NaN: a non-finite number that reached the document (the
    builders give ``None`` for them already) is written as ``null``, not a traceback.
    """
    from ..atomic_file import write_atomically

    def write(stream: IO[str]) -> None:
        for piece in json_pieces(document, indent):
            stream.write(piece)
    try:
        write_atomically(Path(path), write, binary=False)    # a full disk leaves the earlier file whole
    except OSError as exc:
        raise ConfigError(f'{path}: cannot write ({exc.strerror or exc})') from None


def json_pieces(document: object, indent: int | None = None) -> Iterator[str]:
    """The JSON text of ``document`` in pieces (non-finite numbers as ``null``); compact when ``indent`` is None.

    Compact: an object's members and a top-level list's items are encoded one
    at a time by ``json.dumps`` (its C encoder); indented: the standard
    encoder's ``iterencode``.
    """
    if indent is not None:
        yield from json.JSONEncoder(indent=indent, allow_nan=False).iterencode(_finite_or_null(document))
        return
    if not isinstance(document, dict):
        yield _compact(document)
        return
    yield '{'
    for number, (key, value) in enumerate(document.items()):
        yield (',' if number else '') + json.dumps(str(key)) + ':'
        if isinstance(value, (list, tuple)):
            yield '['
            for position, item in enumerate(value):
                yield (',' if position else '') + _compact(item)
            yield ']'
        else:
            yield _compact(value)
    yield '}'


def _compact(value: object) -> str:
    """``value`` as compact JSON, non-finite numbers as ``null``."""
    try:
        return json.dumps(value, separators=(',', ':'), allow_nan=False)
    except ValueError:      # "Out of range float values are not JSON compliant"
        return json.dumps(_finite_or_null(value), separators=(',', ':'), allow_nan=False)


def _finite_or_null(value: object) -> object:
    """``value`` with every non-finite float (at any depth of dicts and lists) replaced by None."""
    if isinstance(value, float):
        return finite_or_none(value)
    if isinstance(value, dict):
        return {key: _finite_or_null(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite_or_null(item) for item in value]
    return value
