# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Recordings in, windows, calibrations and assessments out: the offline pipeline.

This is what ``prsm-lube calibrate | assess`` and the calibration service run.
Recordings are streamed slice by slice through :class:`WindowBuilder`, so
memory stays flat whatever their length.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, cast
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from ..errors import InputError, NotIdentifiable, ProblemSink
from ..recording import reader as recording_reader
from ..validation import finite_or_none
from .assessment import Assessor, condition_json, RunAssessment, WindowAssessment
from .calibration import Calibration, fit_windows
from .calibration_file import baseline_note
from .conditioning import AnalysisBand, band_text
from .domain import CalibrationDomain
from ..physics.defect_orders import DefectOrder
from .defect_screen import ConditionBaseline, run_condition
from .windowing import (DEFAULT_DEFECT_ORDERS, MIN_AXIAL_LOAD, runs_of, usable_windows, Window, WindowBuilder,
                        WindowSettings)

__all__ = ['ASSESSMENT_SLICE_SECONDS', 'HEAP_ARRAY_BYTES', 'KEPT_FREE_BYTES', 'RecordingAssessment',
           'RecordingWindows', 'analysis_settings', 'assess_recording', 'assessment_json', 'calibrate_recordings',
           'condition_baseline', 'keep_freed_memory', 'read_recordings', 'recording_windows', 'require_usable',
           'with_band_and_domain']

#: Seconds of recording per slice streamed through the windows: long enough that per-slice numpy call
#: overhead stops mattering (an hour: 0.63 s CPU with 10 s slices, 0.34 s with 60 s; nothing gained
#: beyond), short enough that memory stays flat (a 60 s slice of 4 kHz float32 samples is about 1 MB).
ASSESSMENT_SLICE_SECONDS = 60.0


@dataclass
class RecordingWindows:
    """The windows of one recording and the problems met while reading it."""

    path: str
    windows: list[Window]
    problems: list[str] = field(default_factory=list)
    #: messages read per batch kind (``VibrationBatch``, ``ScrewStateBatch``, ...), and the fastest screw speed
    messages_read: dict[str, int] = field(default_factory=dict)
    max_speed: float = 0.0
    #: band of the window RMS (upper edge chosen at the first block); None: raw RMS
    band: AnalysisBand | None = None
    #: defect orders that labelled the windows' envelope lines (the settings')
    defect_orders: tuple[DefectOrder, ...] = DEFAULT_DEFECT_ORDERS

    def why_no_window(self, settings: WindowSettings | None = None) -> str:
        """Why the recording gave no window, in a few words (for a recording with messages on its topics)."""
        settings = settings or WindowSettings()
        names = {'VibrationBatch': 'vibration', 'ScrewStateBatch': 'joint_states', 'AxialLoadBatch': 'axial_load'}
        missing = [topic for kind, topic in names.items() if not self.messages_read.get(kind)]
        if missing:
            return 'no message could be read on ' + ', '.join(missing)
        if not self.max_speed >= settings.min_speed:
            return (f'the screw never turned at {settings.min_speed:g} rad/s or faster '
                    f'(fastest {self.max_speed:.3g} rad/s; standstill only?)')
        reasons: dict[str, int] = {}
        for window in self.windows:
            reasons[window.reason] = reasons.get(window.reason, 0) + 1
        reason = (f'no stretch of {settings.window_length:g} s at steady speed and load with vibration '
                  'and load data covering it')
        if reasons:
            common = max(reasons, key=cast(Callable[[str], int], reasons.get))
            reason += f' (none of {len(self.windows)} windows steady; most: {common})'
        return reason + (f'; {self.problems[-1]}' if self.problems else '')


def analysis_settings(window_length: float = 1.0, *, spectra: bool = False, band_high: float | None = None,
                      defect_orders: Sequence[DefectOrder] | None = None) -> WindowSettings:
    """The window settings ``calibrate``, ``assess`` and ``diagnose`` use (the studies too).

    window_length s; ``spectra`` keeps each window's spectrum at a resolution
    that separates the lowest rotation orders (:data:`.conditioning.LOWEST_ORDER_FREQUENCY`);
    ``band_high`` (Hz) the analysis band's upper edge (default: from the first recording);
    ``defect_orders`` the actuator's (default: the contract's default actuator's).
    """
    from .conditioning import LOWEST_ORDER_FREQUENCY
    settings = WindowSettings(window_length=window_length,
                              spectrum_lowest_frequency=LOWEST_ORDER_FREQUENCY if spectra else 0.0)
    if band_high is not None:
        settings = replace(settings, band=AnalysisBand(high=band_high))
    if defect_orders is not None:
        settings = replace(settings, defect_orders=tuple(defect_orders))
    return settings


def recording_windows(path: str | Path, *, lead: float, settings: WindowSettings | None = None,
                      namespace: str = '/prsm', on_problem: ProblemSink | None = None,
                      progress: Callable[[float], None] | None = None,
                      slice_seconds: float = ASSESSMENT_SLICE_SECONDS,
                      root: str | Path | None = None) -> RecordingWindows:
    """Stream one recording through a :class:`WindowBuilder` and return its windows.

    Problems (bad messages, truncation) are collected and, if given, passed to
    ``on_problem`` as one line each, prefixed with the recording's path.
    ``progress`` receives the fraction of the recording read so far.
    ``slice_seconds`` is how much recording is decoded and windowed at a time.
    Every file read must resolve inside ``root`` (default: a bag folder's
    files inside the folder; the calibrate service gives ``recordings_dir``).
    Raises :class:`InputError` for a recording that cannot be read at all, or
    whose sample rate cannot cover the analysis band (``settings.band``).
    """
    keep_freed_memory()
    problems: list[str] = []

    def report(line: str) -> None:
        line = f'{path}: {line}'
        problems.append(line)
        if on_problem:
            on_problem(line)

    builder = WindowBuilder(settings, lead=lead)
    windows: list[Window] = []
    recording = recording_reader.open_recording(path, namespace=namespace, root=root)
    messages_read: dict[str, int] = {}
    max_speed = 0.0
    for batches in recording.slices(on_problem=report, progress=progress, slice_seconds=slice_seconds):
        for batch in batches:
            kind = type(batch).__name__
            messages_read[kind] = messages_read.get(kind, 0) + len(batch.stamps)
            speeds = getattr(batch, 'speeds', None)
            if speeds is not None and speeds.size and np.isfinite(speeds).any():
                max_speed = max(max_speed, float(np.nanmax(np.abs(speeds))))
            builder.add(batch)
        windows.extend(builder.pop_closed())
        for line in builder.take_problems():
            report(line)
    windows.extend(builder.finish())
    for line in builder.take_problems():
        report(line)
    if builder.band_refusal:
        raise InputError(f'{path}: {builder.band_refusal}')
    return RecordingWindows(str(path), windows, problems, messages_read, max_speed, builder.band,
                            builder.settings.defect_orders)


#: Arrays up to this many bytes come from the C heap, not fresh memory maps (glibc ``M_MMAP_THRESHOLD``).
HEAP_ARRAY_BYTES = 32 << 20
#: Freed heap memory up to this many bytes stays with the process (glibc ``M_TRIM_THRESHOLD``).
KEPT_FREE_BYTES = 64 << 20


def keep_freed_memory() -> None:
    """Let the C allocator reuse the memory of the arrays each slice frees instead of returning it (glibc only).

    Streaming a recording makes and frees the same few-MB arrays every slice
    (samples, spectra, the kurtogram's bands).  By default glibc serves each
    from a fresh memory map, or returns the heap's top to the system, so every
    slice pays the page faults of its arrays again: a fifth of the CPU of
    ``assess`` on an hour (system time 0.5 s of 2.9 s).  Kept, the process
    holds at most :data:`KEPT_FREE_BYTES` more than it uses; memory stays flat.
    Nothing happens where the C library has no ``mallopt`` (musl, macOS).
    """
    import ctypes
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return
    m_trim_threshold, m_mmap_threshold = -1, -3     # glibc malloc.h
    mallopt(m_mmap_threshold, HEAP_ARRAY_BYTES)
    mallopt(m_trim_threshold, KEPT_FREE_BYTES)


def read_recordings(paths: Sequence[str | Path], *, lead: float, settings: WindowSettings | None = None,
                    namespace: str = '/prsm', on_problem: ProblemSink | None = None, root: str | Path | None = None,
                    before_each: Callable[[int, int], None] | None = None,
                    progress: Callable[[int], Callable[[float], None] | None] | None = None) \
        -> list[RecordingWindows]:
    """The windows of each recording, as ``calibrate``, ``diagnose`` and the calibrate service read them.

    The band rule: the first recording's band (its upper edge chosen for its
    sample rate, unless ``settings`` fixes it) is every later one's, so one
    calibration holds one band; a later recording too slow for it gives no
    usable window and is refused in one line that says how to choose a band
    every recording covers (:func:`.conditioning.rate_refusal`).  Every
    recording must have a steady window (:func:`require_usable`).
    ``before_each(index, steady_windows_so_far)`` is called before each
    recording is read, ``progress(index)`` gives its progress callback;
    ``root`` confines every file read (:func:`recording_windows`).
    """
    recordings: list[RecordingWindows] = []
    steady = 0
    for index, path in enumerate(paths):
        if before_each is not None:
            before_each(index, steady)
        recording = recording_windows(path, lead=lead, settings=settings, namespace=namespace,
                                      on_problem=on_problem, progress=progress(index) if progress else None,
                                      root=root)
        recordings.append(require_usable(recording, settings))
        steady += sum(1 for w in recording.windows if w.steady)
        settings = replace(settings or WindowSettings(), band=recording.band)   # the others in the first's band
    return recordings


def require_usable(recording: RecordingWindows, settings: WindowSettings | None = None) -> RecordingWindows:
    """``recording`` if it has a steady window, else :class:`NotIdentifiable` saying why in one line."""
    if not any(window.steady for window in recording.windows):
        raise NotIdentifiable(f'{recording.path}: no usable window: {recording.why_no_window(settings)}')
    return recording


def calibrate_recordings(recordings: Sequence[RecordingWindows], theta: float = 1.0,
                         min_axial_load: float = MIN_AXIAL_LOAD) -> Calibration:
    """Fit C_sys, C_F, C_lambda on the steady windows of recordings at lubrication state ``theta``.

    The calibration keeps the band of the recordings' RMS and the domain of the
    windows used.  Recordings whose RMS is in different bands (sample rates too
    low for one common band) are refused in one line.
    """
    bands = {rec.band for rec in recordings if rec.windows}
    if len(bands) > 1:
        raise InputError('calibration: the recordings give the RMS in different bands ('
                         + '; '.join(f'{rec.path}: {band_text(rec.band)}' for rec in recordings)
                         + '); give the slowest recording first, so that the others are filtered to its band')
    windows = [w for rec in recordings for w in rec.windows]
    labels = [index for index, rec in enumerate(recordings) for _ in rec.windows]
    calibration = fit_windows(windows, theta, min_axial_load=min_axial_load,
                              sources=[rec.path for rec in recordings], recordings=labels)
    calibration = replace(calibration, condition_baseline=condition_baseline(recordings, min_axial_load))
    return with_band_and_domain(calibration, bands.pop() if bands else None,
                                usable_windows(windows, min_axial_load))


def condition_baseline(recordings: Sequence[RecordingWindows],
                       min_axial_load: float = MIN_AXIAL_LOAD) -> ConditionBaseline | None:
    """The healthy condition baseline of calibration recordings: their runs' pooled indicators."""
    runs = [run_condition([w.condition for w in windows if w.condition is not None], rec.defect_orders)
            for rec in recordings for windows in runs_of(usable_windows(rec.windows, min_axial_load)).values()]
    orders = recordings[0].defect_orders if recordings else DEFAULT_DEFECT_ORDERS
    return ConditionBaseline.from_runs(runs, orders)


def with_band_and_domain(calibration: Calibration, band: AnalysisBand | None, windows: Iterable[Window]) -> Calibration:
    """``calibration`` with the band its RMS was computed in and the domain of the ``windows`` it was fitted on."""
    return replace(calibration, band=band, domain=CalibrationDomain.of_windows(windows))


@dataclass
class RecordingAssessment:
    """Assessed windows and runs of one recording."""

    path: str
    windows: list[WindowAssessment]
    runs: list[RunAssessment]
    problems: list[str] = field(default_factory=list)


def assess_recording(recording: RecordingWindows, calibration: Calibration,
                     min_axial_load: float = MIN_AXIAL_LOAD) -> RecordingAssessment:
    """theta_Oil of every window and every run of one recording."""
    assessor = Assessor(calibration, min_axial_load=min_axial_load, defect_orders=recording.defect_orders)
    windows = assessor.assess_windows(recording.windows)
    runs = assessor.assess_runs(windows, recording.path)
    return RecordingAssessment(recording.path, assessor.runs_screen_windows(windows, runs), runs,
                               list(recording.problems))


def assessment_json(assessments: Iterable[RecordingAssessment], calibration: Calibration) -> dict:
    """The contract's ``assess`` output: ``runs`` with a finite theta; runs not assessed apart.

    ``windows`` lists every window, steady or not, with ``theta_oil`` null and
    the reason in words where it was not assessable.
    """
    runs: list[dict]
    unassessed: list[dict]
    run: Any   # a RunAssessment, then an unassessed run's mapping
    runs, unassessed, windows, problems = [], [], [], []
    for rec in assessments:
        problems.extend(rec.problems)
        for run in rec.runs:
            (runs if not run.reason else unassessed).append(run.as_json())
        for item in rec.windows:
            w = item.window
            windows.append({'bag': rec.path, 'start': w.start, 'end': w.end, 'run_index': w.run_index,
                            'steady': w.steady,
                            'screw_speed': finite_or_none(w.screw_speed),
                            'axial_load': finite_or_none(w.axial_load),
                            'vibration_rms': finite_or_none(w.vibration_rms),
                            'nut_position': finite_or_none(w.nut_position),
                            'theta_oil': finite_or_none(item.theta_oil),
                            'theta_oil_std': finite_or_none(item.theta_oil_std), 'theta_oil_flag': item.flag,
                            'reason': item.reason, 'domain_flag': item.domain_flag,
                            'sample_rate': finite_or_none(w.sample_rate),
                            'condition_indicators': condition_json(w.condition), **item.defect.as_dict()})
    for run in unassessed:
        run['theta_oil'] = None
        run['theta_oil_std'] = None
    c = calibration.constants
    return {'runs': runs, 'unassessed_runs': unassessed, 'windows': windows,
            'calibration': {**c.by_name(), 'fit_rmse': calibration.fit_rmse, 'windows_used': calibration.windows_used,
                            'flags': list(calibration.flags), 'band': band_text(calibration.band),
                            'domain': calibration.domain.text if calibration.domain is not None else None},
            'runs_flagged': sum(bool(run['theta_oil_flag']) for run in runs),
            'runs_defect_suspected': sum(bool(run['defect_suspected']) for run in runs),
            'condition_baseline': baseline_note(calibration) or 'from the calibration runs',
            'runs_extrapolated': sum(bool(run['domain_flag']) for run in runs),
            'problems': problems}
