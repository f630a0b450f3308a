# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Assess many recordings: serially, in local processes, or on a Dask distributed cluster, with equal results.

The unit of work is one recording (:func:`assess_bag`): read it into windows,
assess every window and run with the calibration, and hash its content for
the history.  It is a pure function of the recording's bytes and its
arguments, so where it runs does not change a single number: serial, ``jobs``
processes (:class:`concurrent.futures.ProcessPoolExecutor`) and a Dask
cluster (``scheduler`` an address such as ``tcp://host:8786``, or ``'local'``
for a :class:`distributed.LocalCluster` of ``jobs`` worker processes) give
bit-identical outcomes, returned in the order of the paths.

A recording that cannot be assessed (unreadable, no usable window, a worker
lost) is an outcome with ``error``, one line naming it; the others go on.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING
from collections.abc import Callable, Sequence

from ..errors import InputError
from ..estimation.calibration import Calibration
from ..estimation.pipeline import assess_recording, recording_windows, RecordingAssessment, require_usable
from ..estimation.windowing import WindowSettings
from .scheduler import CONNECT_TIMEOUT

if TYPE_CHECKING:
    from concurrent.futures import Future

    from _typeshed import DataclassInstance
    import distributed

__all__ = ['BagJob', 'BagOutcome', 'TASKS_PER_WORKER', 'assess_bag', 'assess_bags', 'assess_batch', 'batches',
           'outcomes_fingerprint']


@dataclass(frozen=True)
class BagOutcome:
    """What assessing one recording gave: the assessment and content hash, or the error in one line."""

    path: str
    assessment: RecordingAssessment | None = None
    content: str = ''
    error: str = ''


@dataclass(frozen=True)
class BagJob:
    """Everything a worker needs to assess recordings (picklable)."""

    calibration: Calibration
    lead: float                                  # m per screw revolution
    settings: WindowSettings = WindowSettings()
    namespace: str = '/prsm'
    hash_content: bool = False                   # compute the SHA-256 for the history


def assess_bag(path: str, job: BagJob) -> BagOutcome:
    """Assess one recording; never raises for a bad recording (the outcome carries the error line)."""
    try:
        recording = require_usable(recording_windows(path, lead=job.lead, settings=job.settings,
                                                     namespace=job.namespace), job.settings)
        content = ''
        if job.hash_content:
            from .history import content_hash
            content = content_hash(path)
        return BagOutcome(str(path), assess_recording(recording, job.calibration), content)
    except InputError as exc:
        return BagOutcome(str(path), error=str(exc))
    except Exception as exc:  # noqa: BLE001 -- one bad recording must not stop a fleet; named in one line
        return BagOutcome(str(path), error=f'{path}: {exc.__class__.__name__}: {exc}')


def assess_bags(paths: Sequence[str] | Sequence[Path], job: BagJob, *, jobs: int = 1, scheduler: str | None = None,
                on_done: Callable[[BagOutcome], object] | None = None,
                timeout: float = CONNECT_TIMEOUT) -> list[BagOutcome]:
    """:func:`assess_bag` for every path; outcomes in the order of ``paths``.

    ``jobs`` > 1 runs that many local processes; ``scheduler`` (an address or
    ``'local'``) runs on Dask instead (``jobs`` workers for ``'local'``).
    ``on_done(outcome)`` is called in the calling process as each one finishes.
    ``timeout`` (s) bounds each wait on Dask: to connect, for a first worker,
    and without any worker while recordings are left (those then fail, one
    line each).
    """
    paths = [str(p) for p in paths]
    if not isinstance(jobs, int) or jobs < 1:
        raise InputError(f'--jobs must be a whole number >= 1, got {jobs!r}')
    if scheduler:
        outcomes = _on_dask(paths, job, scheduler, jobs, on_done, timeout)
    elif jobs > 1 and len(paths) > 1:
        outcomes = _in_processes(paths, job, jobs, on_done)
    else:
        outcomes = {}
        for path in paths:
            outcomes[path] = assess_bag(path, job)
            if on_done is not None:
                on_done(outcomes[path])
    return [outcomes[path] for path in paths]


def _in_processes(paths: list[str], job: BagJob, jobs: int,
                  on_done: Callable[[BagOutcome], object] | None) -> dict[str, BagOutcome]:
    from concurrent.futures import as_completed, ProcessPoolExecutor    # here: one recording needs no pool
    outcomes = {}
    with ProcessPoolExecutor(max_workers=min(jobs, len(paths))) as pool:
        futures = {pool.submit(assess_bag, path, job): path for path in dict.fromkeys(paths)}
        for future in as_completed(futures):
            outcomes[futures[future]] = _outcome(futures[future], future)
            if on_done is not None:
                on_done(outcomes[futures[future]])
    return outcomes


def _outcome(path: str, future: Future[BagOutcome]) -> BagOutcome:
    """The future's outcome, or an error line when its worker was lost."""
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 -- a lost worker is one failed recording, not a failed fleet
        return BagOutcome(path, error=f'{path}: worker failed ({exc.__class__.__name__}: {exc})')


#: Dask tasks per worker: recordings go in batches so that the per-task cost (scheduling, one round trip per
#: result) is paid a few times per worker instead of once per recording
TASKS_PER_WORKER = 4


def assess_batch(paths: Sequence[str], job: BagJob) -> list[BagOutcome]:
    """:func:`assess_bag` of each path, in order (one Dask task)."""
    return [assess_bag(path, job) for path in paths]


def batches(paths: Sequence[str], workers: int) -> list[list[str]]:
    """``paths`` in consecutive batches, :data:`TASKS_PER_WORKER` per worker (at least one path each)."""
    size = max(1, -(-len(paths) // max(1, workers * TASKS_PER_WORKER)))
    return [list(paths[start:start + size]) for start in range(0, len(paths), size)]


def _on_dask(paths: list[str], job: BagJob, scheduler: str, jobs: int,
             on_done: Callable[[BagOutcome], object] | None, timeout: float) -> dict[str, BagOutcome]:
    """Each recording on Dask, sent as its absolute path (remote workers do not share our working folder).

    The outcomes carry the paths as given, so they equal the serial ones.
    """
    from .scheduler import dask_client, finished_batches, scattered
    given = {str(Path(path).resolve()): path for path in dict.fromkeys(paths)}
    outcomes = {}
    with dask_client(scheduler, jobs, timeout) as client:
        workers = len(client.scheduler_info().get('workers', {})) or jobs
        work = batches(list(given), workers)
        futures = client.map(assess_batch, work, job=scattered(client, job, scheduler, timeout), pure=False)
        by_key = dict(zip((f.key for f in futures), work))
        for future, lost in finished_batches(client, futures, scheduler, timeout):
            for sent, outcome in zip(by_key[future.key], _batch_outcomes(by_key[future.key], future, lost)):
                path = given[sent]
                outcomes[path] = _as_given(outcome, path)
                if on_done is not None:
                    on_done(outcomes[path])
    return outcomes


def _batch_outcomes(paths: Sequence[str], future: distributed.Future, lost: str = '') -> list[BagOutcome]:
    """The batch's outcomes, or an error line for each of its recordings when its worker was lost (``lost``: why)."""
    if lost:
        return [BagOutcome(path, error=f'{path}: not assessed: {lost}') for path in paths]
    try:
        return future.result()
    except Exception as exc:  # noqa: BLE001 -- a lost worker fails its recordings, not the fleet
        return [BagOutcome(path, error=f'{path}: worker failed ({exc.__class__.__name__}: {exc})') for path in paths]


def _as_given(outcome: BagOutcome, path: str) -> BagOutcome:
    """``outcome`` named by the path as the user gave it (the worker saw the absolute one).

    The recording, each run's ``bag``, and its problem and error lines, so
    that every output equals the serial one.
    """
    sent = outcome.path
    assessment = outcome.assessment
    if assessment is not None:
        assessment = replace(assessment, path=path, runs=[replace(run, bag=path) if run.bag == sent else run
                                                          for run in assessment.runs],
                             problems=[line.replace(sent, path) for line in assessment.problems])
    return replace(outcome, path=path, assessment=assessment, error=outcome.error.replace(sent, path))


def _compared(item: DataclassInstance) -> tuple:
    """Every compared field of a dataclass instance, in declaration order (a window's spectrum is left out)."""
    return tuple(getattr(item, f.name) for f in fields(item) if f.compare)


def outcomes_fingerprint(outcomes: Sequence[BagOutcome]) -> str:
    """Every number of every outcome as text, for an exact comparison of two ways of assessing.

    Per outcome: path, content hash, error, problems, each run's every field
    (theta, one-sigma, RMS, speed, load, temperature, times, ...) and each
    window's every field (its inputs: speed, load, nut position, coverage,
    ... and its theta and one-sigma).  ``repr``: NaN equals NaN and every
    float is compared to the last bit.
    """
    result: list[tuple] = []
    for outcome in outcomes:
        assessment = outcome.assessment
        if assessment is None:
            result.append((outcome.path, outcome.content, outcome.error))
            continue
        result.append((outcome.path, outcome.content, outcome.error, tuple(assessment.problems),
                       [_compared(run) for run in assessment.runs],
                       [(_compared(item.window), item.theta_oil, item.theta_oil_std, item.reason)
                        for item in assessment.windows]))
    return repr(result)
