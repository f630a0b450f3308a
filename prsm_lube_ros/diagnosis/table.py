# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The steady windows of diagnosis recordings as one table of numpy columns.

Diagnosis works on the windows ``prsm-lube calibrate`` would fit (steady, under
load), with the covariates the contract's topics give: screw speed, axial load,
nut position, revolutions and time since the start of the recording, and, when
recorded, temperature and the Welch spectrum of each window.  Of the windows
at standstill it keeps one figure, their median RMS (``rest_rms``): what the
accelerometer reads with the screw still, the windows at rest counted in
``rest_windows``.

Runs are numbered uniquely over all recordings (``run``); ``recording`` says
which recording a window came from.  ``position`` is the nut's place along the
stroke, m from the end where forward runs start: forward runs (nut travel > 0)
use their travel, backward runs ``stroke + travel`` with ``stroke`` the
largest forward travel seen (the paper's runs all start at one end).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any, cast, Protocol, TYPE_CHECKING
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from ..errors import InputError
from ..estimation.defect_screen import run_condition, strike_line, unexplained_level
from ..estimation.windowing import AT_REST, DEFAULT_DEFECT_ORDERS, MIN_AXIAL_LOAD, runs_of, usable_windows
from ..physics.vibration_model import film_speed_load_term, reduced_log_amplitude

if TYPE_CHECKING:
    from ..estimation.conditioning import AnalysisBand
    from ..estimation.domain import CalibrationDomain
    from ..estimation.pipeline import RecordingWindows
    from ..estimation.windowing import Window
    from ..physics.defect_orders import DefectOrder

__all__ = ['COLUMNS', 'Columns', 'DRIFT_COVARIATES', 'INDICATOR_COLUMNS', 'PLAN_COVARIATES', 'REST_SPEED',
           'REST_WINDOWS_NEEDED', 'SPECTRA_NEEDED', 'TEMPERATURE_GAP', 'WindowTable', 'band_high_of', 'band_of',
           'table_from_windows']

#: Longest time between two windows holding a temperature across which it is interpolated, s.
TEMPERATURE_GAP = 30.0
#: Columns every table has, in SI units (temperature in degC, time in s).
COLUMNS = ('speed', 'load', 'rms', 'position', 'revolutions', 'time', 'temperature', 'run', 'recording')

#: The plan's set-points: columns that take a few levels, one per (speed, load) condition.  A law of them alone is
#: tested by the conditions (as many as its parameters and the constants), never by a located pattern: a law of
#: two or three parameters follows a few level means whatever the physics.
PLAN_COVARIATES = ('speed', 'load')
#: Columns that drift over a session, run after run (compared over runs for confounding and collinearity).
DRIFT_COVARIATES = ('revolutions', 'time', 'temperature')

#: The indicator columns each window gives by itself (:func:`_indicators`); the others are its run's.
_WINDOW_INDICATORS = ('kurtosis', 'crest_factor', 'defect_db', 'defect_order', 'gaussian_rms')
#: Optional columns of condition indicators (NaN where a window has none).
INDICATOR_COLUMNS = _WINDOW_INDICATORS + ('run_defect_db', 'run_unexplained_db')

#: Spectra are kept when at least this share of the windows has one (of one size).
SPECTRA_NEEDED = 0.9
#: Screw speed, rad/s, at or below which a window at rest counts as standstill (a servo holding
#: position), so a window that holds the end of a run's deceleration does not.
REST_SPEED = 0.05
#: Windows at standstill needed for :attr:`WindowTable.rest_rms`.
REST_WINDOWS_NEEDED = 3


class Columns(Protocol):
    """The columns of a :class:`WindowTable` that Eq. 22 and the effects' laws read.

    The table itself has them, and so has a cache of its columns
    (``fitting._CachedColumns``); read-only, units as in :class:`WindowTable`.
    """

    @property
    def speed(self) -> np.ndarray:
        """Screw speed, rad/s."""

    @property
    def load(self) -> np.ndarray:
        """Axial load, N."""

    @property
    def position(self) -> np.ndarray:
        """Nut place along the stroke, m."""

    @property
    def revolutions(self) -> np.ndarray:
        """Revolutions since the start of the recording."""

    @property
    def time(self) -> np.ndarray:
        """Time since the start of the recording, s."""

    @property
    def temperature(self) -> np.ndarray:
        """Temperature, degC (NaN when not recorded)."""

    @property
    def run(self) -> np.ndarray:
        """Run number of each window."""

    @property
    def recording(self) -> np.ndarray:
        """Recording index of each window."""

    @property
    def direction(self) -> np.ndarray | None:
        """+1 on runs out, -1 on runs back."""

    @property
    def theta(self) -> float:
        """Lubrication state theta_Oil the windows were recorded at."""

    @property
    def film_term(self) -> np.ndarray:
        """``omega^0.68 F^-0.073`` (Eq. 19)."""

    @property
    def reduced(self) -> np.ndarray:
        """``ln(A omega^-2 F^(1/3))`` (Eq. 22's left side)."""

    def __len__(self) -> int:
        """Number of windows."""


@dataclass(frozen=True)
class WindowTable:
    """Steady windows, one row each; arrays share one length.

    speed rad/s, load N, rms m/s^2, position m along the stroke, revolutions
    since the start of the recording, time s since the start of the recording,
    temperature degC (NaN when not recorded), run (unique over recordings),
    recording index.  ``direction`` is +1 on windows of runs out (nut travel > 0) and -1 on
    runs back (default: the sign of ``speed``).  ``spectra`` (n x bins, (m/s^2)^2/Hz) and
    ``spectrum_resolution`` (Hz) are set when the windows carried spectra; ``band_high`` (Hz)
    is the upper edge of the band the RMS was taken in (NaN: raw RMS, or not known), so
    spectral content above it is not in ``rms``.  ``rest_rms`` (m/s^2, same band) is the
    median RMS of the windows recorded at standstill (:data:`REST_SPEED`), NaN with fewer than
    :data:`REST_WINDOWS_NEEDED` of them: what the accelerometer reads with the screw still, which
    the contact law of Eq. 22 puts at zero; ``rest_windows`` is how many windows it was taken over
    (counted also when too few).
    """

    speed: np.ndarray
    load: np.ndarray
    rms: np.ndarray
    position: np.ndarray
    revolutions: np.ndarray
    time: np.ndarray
    temperature: np.ndarray
    run: np.ndarray
    recording: np.ndarray
    theta: float = 1.0
    spectra: np.ndarray | None = field(default=None, compare=False, repr=False)
    spectrum_resolution: float = math.nan
    sources: tuple[str, ...] = ()
    direction: np.ndarray | None = field(default=None, compare=False, repr=False)
    band_high: float = math.nan
    rest_rms: float = math.nan
    rest_windows: int = 0
    #: Condition indicators per window (:mod:`prsm_lube_ros.estimation.condition_indicators`), NaN where not
    #: computed: kurtosis of the band signal (3 Gaussian), crest factor, and the strongest envelope line at a
    #: strike order (:func:`~prsm_lube_ros.estimation.defect_screen.strike_line`): dB over the floor and its order.
    kurtosis: np.ndarray | None = field(default=None, compare=False, repr=False)
    crest_factor: np.ndarray | None = field(default=None, compare=False, repr=False)
    defect_db: np.ndarray | None = field(default=None, compare=False, repr=False)
    defect_order: np.ndarray | None = field(default=None, compare=False, repr=False)
    #: The strongest strike-order line of the window's run, its windows' envelope spectra averaged (dB over the
    #: floor, as the defect screen judges a run): one window's line reaches 10 dB by chance now and then.
    run_defect_db: np.ndarray | None = field(default=None, compare=False, repr=False)
    #: The strongest line of that averaged spectrum at an order no component explains (dB over the floor, 0 when
    #: none is reported): lines the machine makes wherever no defect is, against which a strike-order line is judged.
    run_unexplained_db: np.ndarray | None = field(default=None, compare=False, repr=False)
    #: RMS of the band signal's Gaussian part, m/s^2 (its median |x| over the Gaussian's,
    #: :func:`~prsm_lube_ros.estimation.condition_indicators.gaussian_rms`): the RMS without sparse strikes.
    gaussian_rms: np.ndarray | None = field(default=None, compare=False, repr=False)
    #: The actuator's defect orders the envelope lines were labelled with.
    defect_orders: tuple[DefectOrder, ...] = ()
    #: The analysis band the RMS was taken in (None: raw RMS, or not known) and the ranges of the windows kept
    #: (speed, load, temperature, sample rate): what a calibration fitted on this table must carry.
    band: AnalysisBand | None = field(default=None, compare=False, repr=False)
    domain: CalibrationDomain | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        """Coerce the columns to arrays of one length."""
        n = None
        for name in COLUMNS:
            kind = np.int64 if name in ('run', 'recording') else float
            value = np.atleast_1d(np.asarray(getattr(self, name), dtype=kind))
            object.__setattr__(self, name, value)
            if n is None:
                n = value.size
            elif value.size != n:
                raise InputError(f'window table: column {name} has {value.size} rows, expected {n}')
        direction = np.where(self.speed < 0, -1.0, 1.0) if self.direction is None else self.direction
        direction = np.atleast_1d(np.asarray(direction, dtype=float))
        if direction.size != n:
            raise InputError(f'window table: column direction has {direction.size} rows, expected {n}')
        object.__setattr__(self, 'direction', direction)
        for name in INDICATOR_COLUMNS:
            value = getattr(self, name)
            value = np.full(n or 0, math.nan) if value is None else np.atleast_1d(np.asarray(value, dtype=float))
            if value.size != n:
                raise InputError(f'window table: column {name} has {value.size} rows, expected {n}')
            object.__setattr__(self, name, value)

    @property
    def has_indicators(self) -> bool:
        """True when most windows carry condition indicators."""
        assert self.kurtosis is not None  # __post_init__ fills it
        return bool(np.isfinite(self.kurtosis).mean() >= 0.8) if len(self) else False

    def __len__(self) -> int:
        """Number of windows."""
        return int(self.speed.size)

    # -- derived columns -------------------------------------------------
    @property
    def log_rms(self) -> np.ndarray:
        """ln of the window RMS."""
        return np.log(self.rms)

    @property
    def reduced(self) -> np.ndarray:
        """``ln(A omega^-2 F^(1/3))``, the left side of the linear form of Eq. 22."""
        return reduced_log_amplitude(self.rms, self.speed, self.load)

    @property
    def film_term(self) -> np.ndarray:
        """``omega^0.68 F^-0.073`` (Eq. 19)."""
        return film_speed_load_term(self.speed, self.load)

    @property
    def runs(self) -> np.ndarray:
        """Distinct run numbers, sorted."""
        return np.unique(self.run)

    @property
    def has_temperature(self) -> bool:
        """True when most windows carry a temperature."""
        return bool(np.isfinite(self.temperature).mean() >= 0.8) if len(self) else False

    @property
    def temperature_span(self) -> float:
        """Highest minus lowest recorded temperature, K (NaN when no window carries one)."""
        finite = self.temperature[np.isfinite(self.temperature)]
        return float(np.max(finite) - np.min(finite)) if finite.size else math.nan

    def subset(self, mask: npt.ArrayLike) -> WindowTable:
        """Rows where ``mask`` is true (a boolean array or indices)."""
        mask = np.asarray(mask)
        spectra = self.spectra[mask] if self.spectra is not None else None
        values = {name: getattr(self, name)[mask] for name in COLUMNS}
        for name in INDICATOR_COLUMNS:    # a table pickled before a column was added has none: NaN
            column = getattr(self, name, None)
            values[name] = column[mask] if column is not None else np.full(len(self), math.nan)[mask]
        assert self.direction is not None  # __post_init__ fills it
        return replace(self, spectra=spectra, direction=self.direction[mask], **values)

    def gaussian_part(self) -> WindowTable:
        """The windows whose Gaussian part was measured, with it as their RMS: the table without sparse strikes.

        ``rms`` is each window's :attr:`gaussian_rms` (the band signal's median
        |x| over the Gaussian's); the condition indicators and the spectra,
        which hold the strikes, are left out (NaN, None).  The vibration at
        standstill (:attr:`rest_rms`) stays: nothing strikes with the screw still.
        """
        assert self.gaussian_rms is not None  # __post_init__ fills it
        measured = np.isfinite(self.gaussian_rms) & (self.gaussian_rms > 0)
        return replace(self.subset(measured), rms=self.gaussian_rms[measured], spectra=None,
                       spectrum_resolution=math.nan, kurtosis=None, crest_factor=None, defect_db=None,
                       defect_order=None, gaussian_rms=None, run_defect_db=None,
                       run_unexplained_db=None)

    def run_means(self, column: str | np.ndarray) -> np.ndarray:
        """Mean of ``column`` per run, in the order of :attr:`runs` (NaN-aware)."""
        values = np.asarray(getattr(self, column), dtype=float) if isinstance(column, str) else column
        out = np.full(self.runs.size, np.nan)
        for i, r in enumerate(self.runs):
            sel = values[self.run == r]
            if np.isfinite(sel).any():
                out[i] = float(np.nanmean(sel))
        return out


def band_of(recordings: Sequence[RecordingWindows]) -> AnalysisBand | None:
    """The RMS band the recordings were read in (the first with a band; None: raw RMS)."""
    return next((recording.band for recording in recordings if recording.band is not None), None)


def band_high_of(recordings: Sequence[RecordingWindows]) -> float:
    """Upper edge (Hz) of the RMS band the recordings were read in (the first with a band; NaN: raw RMS)."""
    band = band_of(recordings)
    return math.nan if band is None else float(band.high)


def table_from_windows(windows_per_recording: Sequence[Sequence[Window]], *, theta: float = 1.0,
                       min_axial_load: float = MIN_AXIAL_LOAD, sources: Sequence[str] = (),
                       band_high: float = math.nan, band: AnalysisBand | None = None,
                       defect_orders: Sequence[DefectOrder] = DEFAULT_DEFECT_ORDERS) -> WindowTable:
    """Build a :class:`WindowTable` from lists of windows (``estimation.windowing.Window``), one per recording.

    Keeps steady windows with a finite positive RMS, speed and load of at least
    ``min_axial_load``; raises :class:`InputError` when none is left.
    ``band``: the RMS's analysis band, if any (``band_high``: only its upper
    edge, Hz, when the band itself is not at hand); ``defect_orders`` the
    actuator's, which labelled the windows' envelope lines.  The table keeps
    the band and the domain of the windows kept (:attr:`WindowTable.domain`).
    """
    from ..estimation.domain import CalibrationDomain
    if band is not None:
        band_high = band.high
    kept: list[Window] = []
    rows: dict[str, list] = {name: [] for name in COLUMNS + INDICATOR_COLUMNS}
    directions: list[float] = []
    orders: tuple[DefectOrder, ...] = tuple(defect_orders)
    spectra: list[np.ndarray | None] = []
    resolution, run_offset = math.nan, 0
    for rec_index, windows in enumerate(windows_per_recording):
        chosen = usable_windows(windows, min_axial_load)
        if not chosen:
            continue
        kept.extend(chosen)
        t0 = min(w.start for w in windows)
        travel = np.array([w.nut_position for w in chosen], dtype=float)
        run_ids = np.array([w.run_index for w in chosen])
        position = _stroke_position(travel, run_ids)
        _, local_run = np.unique(run_ids, return_inverse=True)
        rows['speed'].extend(w.screw_speed for w in chosen)
        rows['load'].extend(w.axial_load for w in chosen)
        rows['rms'].extend(w.vibration_rms for w in chosen)
        rows['position'].extend(position.tolist())
        rows['revolutions'].extend(w.revolutions for w in chosen)
        rows['time'].extend(0.5 * (w.start + w.end) - t0 for w in chosen)
        rows['temperature'].extend(_temperatures(windows, chosen))
        rows['run'].extend((local_run + run_offset).tolist())
        rows['recording'].extend([rec_index] * len(chosen))
        back = {r for r in np.unique(run_ids) if np.nanmedian(travel[run_ids == r]) < 0}
        directions.extend(-1.0 if r in back else 1.0 for r in run_ids)
        run_offset += int(local_run.max()) + 1
        _add_indicators(rows, chosen, orders)
        spectra.extend(w.spectrum for w in chosen)
        resolution = next((w.spectrum_resolution for w in reversed(chosen) if math.isfinite(w.spectrum_resolution)),
                          resolution)
    if not rows['speed']:
        raise InputError('diagnose: no steady window under load in the recordings; record runs at constant '
                         'speed under axial load')
    rest = _rest_rms_values(windows_per_recording)
    return WindowTable(theta=float(theta), spectra=_spectrum_array(spectra), spectrum_resolution=resolution,
                       sources=tuple(str(s) for s in sources), direction=cast(Any, directions),
                       band_high=float(band_high), rest_windows=int(rest.size),
                       rest_rms=float(np.median(rest)) if rest.size >= REST_WINDOWS_NEEDED else math.nan,
                       defect_orders=orders, band=band, domain=CalibrationDomain.of_windows(kept),
                       **cast(dict[str, Any], rows))   # __post_init__ makes arrays of the lists


def _spectrum_array(spectra: Sequence[np.ndarray | None]) -> np.ndarray | None:
    """The windows' spectra as rows, when enough of them have one of one size (else None).

    Windows without a spectrum (too few samples) are NaN rows, which the spectral tests skip.
    """
    sizes = [s.size for s in spectra if s is not None]
    if sizes and len(set(sizes)) == 1 and len(sizes) >= SPECTRA_NEEDED * len(spectra):
        return np.vstack([s if s is not None else np.full(sizes[0], np.nan) for s in spectra])
    return None


def _add_indicators(rows: dict[str, list], windows: Sequence[Window], orders: Sequence[DefectOrder]) -> None:
    """Append the windows' :data:`INDICATOR_COLUMNS` to ``rows``: each window's own, then its run's lines."""
    own = [_indicators(w, orders) for w in windows]
    for k, name in enumerate(_WINDOW_INDICATORS):
        rows[name].extend(values[k] for values in own)
    lines, unexplained = _run_lines(windows, orders)
    rows['run_defect_db'].extend(lines)
    rows['run_unexplained_db'].extend(unexplained)


def _run_lines(windows: Sequence[Window], orders: Sequence[DefectOrder]) -> tuple[list[float], list[float]]:
    """For each window, its run's strongest strike-order line and strongest unexplained line, dB.

    Both of the run's averaged envelope spectrum (:func:`strike_line`,
    :func:`unexplained_level`: at an order no component explains); 0 where the
    run's spectrum shows none (none reaches the report level), NaN where its
    windows have none.
    """
    levels: dict[int, tuple[float, float]] = {}
    for run, members in runs_of(windows).items():
        condition = run_condition([w.condition for w in members if w.condition is not None], orders)
        line = strike_line(condition.envelope_peaks, orders, condition.order_resolution)
        if condition.envelope is not None:   # no line reported: under the report level, taken as 0 dB
            levels[run] = (line.db if line is not None else 0.0, unexplained_level(condition.envelope_peaks))
    pairs = [levels.get(w.run_index, (math.nan, math.nan)) for w in windows]
    return [p[0] for p in pairs], [p[1] for p in pairs]


def _indicators(window: Window, orders: Sequence[DefectOrder]) -> tuple[float, float, float, float, float]:
    """The window's own indicator columns: kurtosis, crest factor, strike line dB, its order, Gaussian RMS.

    NaN where it has none.
    """
    condition = window.condition
    if condition is None:
        return math.nan, math.nan, math.nan, math.nan, math.nan
    line = strike_line(condition.envelope_peaks, orders, condition.order_resolution)
    return (condition.kurtosis, condition.crest_factor, line.db if line else math.nan,
            line.order if line else math.nan, condition.gaussian_rms)


def _rest_rms_values(windows_per_recording: Sequence[Sequence[Window]]) -> np.ndarray:
    """RMS (m/s^2) of every window at standstill: at rest, screw speed at most :data:`REST_SPEED`, RMS finite."""
    return np.array([w.vibration_rms for windows in windows_per_recording for w in windows
                     if w.reason_kind == AT_REST and w.screw_speed <= REST_SPEED
                     and math.isfinite(w.vibration_rms) and w.vibration_rms > 0], dtype=float)


def _temperatures(windows: Sequence[Window], chosen: Sequence[Window]) -> list[float]:
    """Mean temperature of each chosen window, degC; interpolated in time where no sample fell in it.

    Temperature changes slowly and is often published at 1 Hz, so a 1 s window
    can hold no sample (NaN) although the sensor ran: such a window takes the
    linear interpolation between the nearest windows of the recording (steady
    or not) that hold one, when those lie at most :data:`TEMPERATURE_GAP` s apart.
    """
    own = np.array([w.temperature for w in chosen], dtype=float)
    if np.isfinite(own).all():
        return own.tolist()
    times = np.array([0.5 * (w.start + w.end) for w in windows], dtype=float)
    values = np.array([w.temperature for w in windows], dtype=float)
    known = np.isfinite(values) & np.isfinite(times)
    if known.sum() < 2:
        return own.tolist()
    order = np.argsort(times[known], kind='stable')
    at, value = times[known][order], values[known][order]
    mid = np.array([0.5 * (w.start + w.end) for w in chosen], dtype=float)
    after = np.searchsorted(at, mid)
    inside = (after > 0) & (after < at.size)
    gap = np.where(inside, at[np.minimum(after, at.size - 1)] - at[np.maximum(after - 1, 0)], np.inf)
    fill = ~np.isfinite(own) & inside & (gap <= TEMPERATURE_GAP)
    own[fill] = np.interp(mid[fill], at, value)
    return own.tolist()


def _stroke_position(travel: np.ndarray, run_ids: np.ndarray) -> np.ndarray:
    """Nut place along the stroke from travel since each run's motion start (see module doc)."""
    position = np.where(np.isfinite(travel), travel, 0.0)
    forward = [np.nanmax(travel[run_ids == r]) for r in np.unique(run_ids)
               if np.nanmedian(travel[run_ids == r]) > 0]
    stroke = max(forward) if forward else float(np.nanmax(np.abs(travel))) if np.isfinite(travel).any() else 0.0
    for r in np.unique(run_ids):
        sel = run_ids == r
        if np.nanmedian(travel[sel]) < 0:
            position[sel] = stroke + position[sel]
    return position
