# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What the calibration service does with a request, without ROS: check, read, fit.

The estimator node runs :func:`calibrate_from_request` on a worker thread and
swaps the result in; everything wrong with a request comes out as one
:class:`~prsm_lube_ros.errors.InputError` line for the response's ``message``.
"""
from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
import re
from collections.abc import Callable, Sequence

from ..errors import InputError, NotIdentifiable
from ..estimation.calibration import Calibration
from ..estimation.windowing import WindowSettings
from ..validation import reference_theta as checked_reference_theta

__all__ = ['CalibrationOutcome', 'calibrate_from_request', 'recording_namespace', 'recordings_folder',
           'reference_theta', 'resolve_bag_paths']

_NAMESPACE = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*[/_]?')


def recordings_folder(folder: str) -> Path:
    """The configured recordings folder, ``~`` expanded and resolved."""
    return Path(os.path.expanduser(folder or '.')).resolve()


def resolve_bag_paths(bag_paths: Sequence[str], folder: str | Path) -> list[Path]:
    """Bag paths of a request, resolved inside ``folder`` (relative paths are taken from it).

    Raises :class:`InputError` for no paths, a path outside the folder (also
    through ``..`` or symbolic links), a recording that does not exist or one
    named twice (also as a relative and an absolute path).
    """
    root = recordings_folder(str(folder))
    if not bag_paths:
        raise InputError('calibrate: bag_paths is empty; name at least one recording in '
                         f'{root} made in the reference lubrication state')
    resolved = []
    for raw in bag_paths:
        if not str(raw).strip():
            raise InputError('calibrate: an entry of bag_paths is empty')
        path = Path(os.path.expanduser(str(raw)))
        path = (path if path.is_absolute() else root / path).resolve()
        if not path.is_relative_to(root):
            raise InputError(f'calibrate: {raw} is outside the recordings folder {root} '
                             '(parameter recordings_dir); only recordings inside it are read')
        if not path.exists():
            raise InputError(f'calibrate: {raw}: recording not found (looked at {path})')
        if path in resolved:         # the same recording twice would weigh its windows double in the fit
            raise InputError(f'calibrate: {raw} is named twice in bag_paths (as {path}); name each recording once')
        resolved.append(path)
    return resolved


def recording_namespace(requested: str, live: str) -> str:
    """The namespace to read in the request's recordings: ``requested`` when given, else ``live``.

    Raises :class:`InputError` for a name ROS could not have recorded (characters
    other than letters, digits, ``_`` and ``/``, or ``//``).
    """
    name = (requested or '').strip()
    if not name:
        return live
    if not _NAMESPACE.fullmatch(name):
        raise InputError(f'calibrate: recording_namespace {requested!r} is not a ROS namespace or topic prefix '
                         "(letters, digits, '_' and '/', e.g. /rig/left)")
    return name if name.startswith('/') else '/' + name


def reference_theta(value: float) -> float:
    """The request's ``reference_theta``: 0 means 1.0; must be positive and finite."""
    return checked_reference_theta(value, 'calibrate: reference_theta (0 means 1.0)')


@dataclass(frozen=True)
class CalibrationOutcome:
    """A fitted calibration and the problems met reading the recordings."""

    calibration: Calibration
    recordings: tuple
    problems: tuple


def calibrate_from_request(bag_paths: Sequence[str], theta: float, *, folder: str | Path, lead: float,
                           settings: WindowSettings, namespace: str, min_axial_load: float,
                           on_problem: Callable[[str], None] | None = None,
                           on_progress: Callable[[str, int, int, int], None] | None = None,
                           check: Callable[[], None] | None = None) -> CalibrationOutcome:
    """Check a request, read its recordings and fit C_sys, C_F, C_lambda (seconds per recording).

    ``on_progress(stage, recordings_read, recording_count, steady_windows)``
    is called before each recording is read (stage ``reading``) and before
    the fit (``fitting``).  ``check()`` is called as each piece of a
    recording is read and before the fit: it raises to stop the calibration
    there (a deadline, a cancel), before anything was changed.  Every file
    read lies inside ``folder`` and is a regular file (a FIFO or a link out is
    refused before it is opened).  Raises :class:`InputError` for anything
    wrong with the request or the data.
    """
    theta = reference_theta(theta)
    paths = resolve_bag_paths(bag_paths, folder)
    root = recordings_folder(str(folder))
    try:
        from ..estimation.pipeline import calibrate_recordings, read_recordings
    except ImportError as exc:    # the bag reader is not installed with this build
        raise InputError(f'calibrate: cannot read recordings on this installation ({exc})') from None
    problems: list[str] = []

    def report(line: str) -> None:
        problems.append(line)
        if on_problem:
            on_problem(line)

    checked = check or (lambda: None)

    def before_each(read: int, steady: int) -> None:
        checked()
        if on_progress:
            on_progress('reading', read, len(paths), steady)
    try:      # the command line's reading and band rule; its files inside the folder too
        recordings = read_recordings(paths, lead=lead, settings=settings, namespace=namespace, on_problem=report,
                                     root=root, before_each=before_each, progress=lambda _: lambda _f: checked())
    except NotIdentifiable as exc:      # the command line's words for the same lack
        raise InputError(f'calibrate: {exc} (topics under {namespace})') from None
    steady = sum(1 for recording in recordings for w in recording.windows if w.steady)
    checked()
    if on_progress:
        on_progress('fitting', len(paths), len(paths), steady)
    calibration = calibrate_recordings(recordings, theta, min_axial_load=min_axial_load)
    return CalibrationOutcome(calibration, tuple(str(p) for p in paths), tuple(problems))
