# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Streaming windows over the inputs: RMS, speed, load and run of each window.

The same :class:`WindowBuilder` serves recordings and live topics, so a replay
assessed live gives the windows ``prsm-lube assess`` gives.  Windows lie on a
fixed grid of absolute time, ``[k L, (k + 1) L)`` for window length ``L``, so
they do not depend on where a recording or a subscription starts.

Runs (traverses at one speed and load) and their steady part are found from the
``screw`` velocity alone (CONTRACT.md): a run starts when the screw speed rises
above ``min_speed`` after standstill; a window is steady when its speed is
above ``min_speed`` and varies by less than ``max_speed_spread`` inside it,
which leaves out acceleration and deceleration.

The RMS is that of the analysis band (``WindowSettings.band``, see
:mod:`.conditioning`): the samples of each open window are kept, and when it
closes the mean square of its FFT bins inside the band is its RMS squared (DC
and gravity, the window mean, out).  Blocks whose sample rate cannot cover
the band are left out and said once (:attr:`WindowBuilder.band_refusal`);
``band=None`` gives the raw RMS (calibrations written before bands).

Memory stays flat: only windows that can still receive data are open; a window
is closed once every input stream has passed its end by ``completion_delay``
(a stream silent for ``stream_timeout`` while others advance stops holding
windows open, so lost topics give NaN windows with a reason, not a stall).
Bad input (non-finite samples, empty blocks, rates <= 0, stamps going back)
is left out and reported once per kind through ``problems``.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from ..errors import InputError
from ..recording.batches import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch
from ..physics.actuator import Actuator
from ..physics.defect_orders import defect_orders as actuator_defect_orders, DefectOrder
from .condition_indicators import BATCH_SAMPLES, condition_indicators_batch, ConditionIndicators
from .conditioning import AnalysisBand, band_mean_squares, DEFAULT_BAND, rate_refusal, spectrum_segment
from ..recording.plausibility import (duration_problem, MAX_ACCELERATION, MAX_AXIAL_LOAD, MAX_SCREW_SPEED,
                                      plausible_durations, plausible_magnitudes, plausible_rates,
                                      plausible_temperatures, rate_problem, TEMPERATURE_RANGE)

if TYPE_CHECKING:
    from collections.abc import Iterable, Sequence

    import numpy.typing as npt

    from ..recording.batches import InputBatch

__all__ = ['AT_REST', 'BLOCKS_LOST', 'DEFAULT_DEFECT_ORDERS',
           'GATING_STREAMS', 'MIN_AXIAL_LOAD', 'NO_LOAD', 'NO_SPEED', 'NO_VIBRATION',
           'SPANS_RUNS', 'SPEED_CHANGING', 'UNSTEADY_KINDS', 'Window', 'WindowBuilder', 'WindowSettings',
           'assessable', 'not_assessable_reason', 'runs_of', 'usable_windows']

#: Defect orders of the contract's default actuator (:mod:`..physics.defect_orders`).
DEFAULT_DEFECT_ORDERS: tuple[DefectOrder, ...] = actuator_defect_orders(Actuator())

#: Streams whose progress closes windows.
GATING_STREAMS = ('vibration', 'screw', 'load')


@dataclass(frozen=True)
class WindowSettings:
    """How windows are cut and judged; all times in s, speeds in rad/s."""

    window_length: float = 1.0
    min_speed: float = 1.0
    max_speed_spread: float = 0.03
    min_coverage: float = 0.8
    completion_delay: float = 0.5
    stream_timeout: float = 3.0
    reset_after_backstep: float = 5.0
    spectrum_segment: int = 0
    #: Band of the window RMS (see :mod:`.conditioning`); None: raw RMS (calibrations without a band).
    band: AnalysisBand | None = DEFAULT_BAND
    #: Hz; > 0: spectra resolve this frequency (lowest order at the lowest speed), segment from
    #: :func:`.conditioning.spectrum_segment` (overrides ``spectrum_segment``'s length).
    spectrum_lowest_frequency: float = 0.0
    #: Compute each window's :class:`~.condition_indicators.ConditionIndicators` (needs the band's samples).
    condition_indicators: bool = True
    #: Compute them only on windows whose grid index is a multiple of this (1: every window); a live estimator
    #: serving many actuators trades the screen's reaction time for CPU with it.
    condition_every: int = 1
    #: Defect orders that label the envelope lines (the actuator's, :func:`~..physics.defect_orders.defect_orders`).
    defect_orders: tuple[DefectOrder, ...] = DEFAULT_DEFECT_ORDERS

    def __post_init__(self) -> None:
        """Reject settings that cannot cut windows."""
        if self.band is not None and not isinstance(self.band, AnalysisBand):
            raise InputError(f'window setting band={self.band!r} is not an analysis band')
        checks = {
            'window_length': self.window_length > 0,
            'min_speed': self.min_speed > 0,
            'max_speed_spread': self.max_speed_spread > 0,
            'min_coverage': 0 < self.min_coverage <= 1,
            'completion_delay': self.completion_delay >= 0,
            'stream_timeout': self.stream_timeout > 0,
            'reset_after_backstep': self.reset_after_backstep > 0,
            'spectrum_segment': self.spectrum_segment >= 0,
            'spectrum_lowest_frequency': self.spectrum_lowest_frequency >= 0,
            'condition_every': isinstance(self.condition_every, int) and self.condition_every >= 1,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not (ok and math.isfinite(value)):
                raise InputError(f'window setting {name}={value!r} is out of range')


#: Why a window is not steady, as codes (``Window.reason_kind``); the words are in ``Window.reason``.
NO_VIBRATION, BLOCKS_LOST, NO_SPEED, AT_REST, SPEED_CHANGING, SPANS_RUNS, NO_LOAD = (
    'no_vibration', 'blocks_lost', 'no_speed', 'at_rest', 'speed_changing', 'spans_runs', 'no_load')
UNSTEADY_KINDS = (NO_VIBRATION, BLOCKS_LOST, NO_SPEED, AT_REST, SPEED_CHANGING, SPANS_RUNS, NO_LOAD)

#: Smallest axial load, N, at which Eq. 23 is evaluated and a window is fitted.
MIN_AXIAL_LOAD = 5.0


def assessable(speed: npt.ArrayLike, load: npt.ArrayLike, rms: npt.ArrayLike,
               min_axial_load: float = MIN_AXIAL_LOAD) -> np.ndarray:
    """Where Eq. 23 can be evaluated: finite RMS > 0, speed > 0 and load >= ``min_axial_load`` (arrays, vectorised).

    The one definition of "assessable", used by assessment, calibration and the diagnosis's window table.
    """
    speed, load, rms = (np.asarray(v, dtype=float) for v in (speed, load, rms))
    with np.errstate(invalid='ignore'):
        return (np.isfinite(rms) & (rms > 0) & np.isfinite(load) & (load >= min_axial_load)
                & np.isfinite(speed) & (speed > 0))


def not_assessable_reason(speed: float, load: float, rms: float, min_axial_load: float = MIN_AXIAL_LOAD) -> str:
    """Why :func:`assessable` is false for one window, in words ('' when it is true)."""
    if not (math.isfinite(rms) and rms > 0):
        return 'no vibration: the RMS is zero or missing'
    if not (math.isfinite(load) and load >= min_axial_load):
        return f'axial load {load:.3g} N is below {min_axial_load:.3g} N: Eq. 23 needs the nut under load'
    if not (math.isfinite(speed) and speed > 0):
        return 'screw at rest: Eq. 23 needs a screw speed'
    return ''


def usable_windows(windows: Iterable[Window], min_axial_load: float = MIN_AXIAL_LOAD) -> list[Window]:
    """The steady and assessable windows, in order: what calibration and diagnosis fit."""
    windows = [w for w in windows if w.steady]
    if not windows:
        return []
    keep = assessable([w.screw_speed for w in windows], [w.axial_load for w in windows],
                      [w.vibration_rms for w in windows], min_axial_load)
    return [w for w, ok in zip(windows, keep.tolist()) if ok]


def runs_of(windows: Iterable[Window]) -> dict[int, list[Window]]:
    """Steady windows grouped by run index, in run order."""
    by_run: dict[int, list[Window]] = {}
    for window in windows:
        if window.steady:
            by_run.setdefault(window.run_index, []).append(window)
    return dict(sorted(by_run.items()))


@dataclass(frozen=True)
class Window:
    """One closed window of the inputs.

    ``reason_kind`` is empty for a steady window; otherwise one of the
    :data:`UNSTEADY_KINDS` codes, for code to branch on, and ``reason`` says the
    same in words (with the numbers) for people.  :attr:`steady` derives from it.
    """

    start: float                # s since the epoch
    end: float                  # s since the epoch
    vibration_rms: float        # m/s^2 over the samples present (NaN if none)
    sample_count: int           # finite vibration samples in the window
    coverage: float             # sample_count / (window_length * sample_rate)
    screw_speed: float          # rad/s, mean magnitude (NaN if no screw state)
    speed_spread: float         # (max - min) / mean of the speed magnitude
    axial_load: float           # N, mean magnitude (NaN if no load)
    temperature: float          # degC, mean (NaN if not recorded)
    nut_position: float         # m, mean nut travel since the run's motion start (NaN if unknown)
    revolutions: float          # screw revolutions turned since the builder started, at the window end
    run_index: int              # run counter (0 before the first motion)
    reason_kind: str = ''       # '' when steady, else one of UNSTEADY_KINDS
    reason: str = ''
    spectrum: np.ndarray | None = field(default=None, compare=False, repr=False)
    spectrum_resolution: float = math.nan  # Hz per spectrum bin
    sample_rate: float = math.nan          # Hz, vibration sample rate in the window (highest if several)
    #: Kurtosis, crest factor and envelope spectrum of the window (None where not computed or no samples).
    condition: ConditionIndicators | None = field(default=None, compare=False, repr=False)

    @property
    def steady(self) -> bool:
        """True when the window is steady, i.e. has no unsteady reason."""
        return not self.reason_kind


# Columns of the open-window table (one row per open window, counts held exactly as float64).
(_SUMSQ, _COUNT, _RATE, _SPEED_N, _SPEED_SUM, _SPEED_MIN, _SPEED_MAX, _TRAVEL_N, _TRAVEL_SUM,
 _LOAD_N, _LOAD_SUM, _TEMP_N, _TEMP_SUM, _RUN_MIN, _RUN_MAX, _REVOLUTIONS) = range(16)
_EMPTY_ROW = np.array([0.0, 0.0, 0.0, 0.0, 0.0, math.inf, -math.inf, 0.0, 0.0,
                       0.0, 0.0, 0.0, 0.0, math.inf, -math.inf, math.nan])


class _OpenWindows:
    """Running sums of the windows still receiving data: one table row per window, rows sorted by key.

    Windows are keyed by their grid index ``k`` (window ``[k L, (k + 1) L)``).
    Keys need not be contiguous (a gap in a recording opens no windows), and
    only open windows are held, so memory stays flat.
    """

    __slots__ = ('keys', 'table')

    def __init__(self) -> None:
        self.keys = np.zeros(0, np.int64)
        self.table = np.zeros((0, _EMPTY_ROW.size))

    def __len__(self) -> int:
        return int(self.keys.size)

    def rows(self, keys: np.ndarray) -> np.ndarray:
        """Row of each of ``keys`` (sorted, unique), opening the windows not open yet."""
        have = self.keys
        pos = np.searchsorted(have, keys)
        inside = pos < have.size
        known = np.zeros(keys.size, bool)
        known[inside] = have[pos[inside]] == keys[inside]
        if not known.all():
            new = keys[~known]
            at = np.searchsorted(have, new)
            self.keys = np.insert(have, at, new)
            self.table = np.insert(self.table, at, _EMPTY_ROW, axis=0)
            pos = np.searchsorted(self.keys, keys)
        return pos

    def pop_first(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """Remove the ``count`` earliest windows; return their keys and table rows."""
        keys, table = self.keys[:count], self.table[:count]
        self.keys, self.table = self.keys[count:].copy(), self.table[count:].copy()
        return keys, table


def _grouped(keys: np.ndarray) -> tuple[slice | np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sort order, unique keys, segment starts and segment sizes for reduceat over ``keys``.

    The order is ``slice(None)`` when ``keys`` is sorted already (the usual case).
    """
    if keys.size == 1:
        return slice(None), keys, np.zeros(1, np.int64), np.ones(1, np.int64)
    if (keys[1:] >= keys[:-1]).all():
        order: slice | np.ndarray
        order, sorted_keys = slice(None), keys
    else:
        order = np.argsort(keys, kind='stable')
        sorted_keys = keys[order]
    starts = np.flatnonzero(np.concatenate(([True], sorted_keys[1:] != sorted_keys[:-1])))
    return order, sorted_keys[starts], starts, np.diff(np.append(starts, keys.size))


@dataclass
class _BlockPieces:
    """Vibration blocks cut at window edges: per block, and per piece of a block that lies in one window."""

    stamps: np.ndarray      # per block: stamp of its first sample, s
    rates: np.ndarray       # per block: sample rate, Hz
    offsets: np.ndarray     # per block: index of its first sample in the batch's samples
    ends: np.ndarray        # per block: stamp of its last sample, s
    keys: np.ndarray        # per piece: key of its window
    blocks: np.ndarray      # per piece: its block (index into the per-block arrays)
    lo: np.ndarray          # per piece: its first sample, index into the batch's samples
    hi: np.ndarray          # per piece: the end of its samples (exclusive)

    @classmethod
    def cut(cls, stamps: np.ndarray, rates: np.ndarray, counts: np.ndarray, offsets: np.ndarray, good: np.ndarray,
            length: float) -> _BlockPieces:
        """The ``good`` blocks of a batch (stamps, rates, sample counts, offsets) cut at windows of ``length`` s."""
        idx = np.flatnonzero(good)
        b_stamp, b_rate, b_count = stamps[idx], rates[idx], counts[idx]
        b_off = offsets[idx]
        b_end = b_stamp + (b_count - 1) / b_rate
        k_first = np.floor(b_stamp / length).astype(np.int64)
        k_last = np.floor(b_end / length).astype(np.int64)
        spans = k_last - k_first + 1
        seg_block = np.repeat(np.arange(idx.size), spans)
        seg_k = k_first[seg_block] + (np.arange(seg_block.size)
                                      - np.repeat(np.cumsum(spans) - spans, spans))
        lo = np.ceil((seg_k * length - b_stamp[seg_block]) * b_rate[seg_block] - 1e-9)
        hi = np.ceil(((seg_k + 1) * length - b_stamp[seg_block]) * b_rate[seg_block] - 1e-9)
        lo = np.clip(lo, 0, b_count[seg_block]).astype(np.int64) + b_off[seg_block]
        hi = np.clip(hi, 0, b_count[seg_block]).astype(np.int64) + b_off[seg_block]
        return cls(b_stamp, b_rate, b_off, b_end, seg_k, seg_block, lo, hi)


class WindowBuilder:
    """Turns input batches into closed :class:`Window` objects, in time order.

    ``lead`` (m per screw revolution) converts screw angle to nut travel.  Feed
    batches with :meth:`add`, collect closed windows with :meth:`pop_closed`
    and, at the end of a recording, :meth:`finish`.  One-line problem reports
    accumulate in :attr:`problems` (drain it with :meth:`take_problems`).
    """

    def __init__(self, settings: WindowSettings | None = None, lead: float = 0.005, *,
                 defer_conditions: bool = False) -> None:
        self.settings = settings or WindowSettings()
        self.lead = float(lead)
        #: Closed windows come out with their band RMS but no condition indicators yet; those are computed by
        #: :meth:`complete_conditions` (a live node publishes theta_Oil first, then screens the surface).
        self.defer_conditions = bool(defer_conditions)
        #: (closed windows, indicator arguments) of the indicators deferred since the last complete_conditions
        self._deferred: list[tuple[list[Window], tuple]] = []
        self._open = _OpenWindows()
        #: (time s, samples) per open window key, for the band and spectra
        self._chunks: dict[int, list[tuple[float, np.ndarray]]] = {}
        #: (stamps s, unsigned screw angle rad) per open window key, for order tracking of the envelope
        self._angle_chunks: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
        self._progress = {name: -math.inf for name in GATING_STREAMS}
        self._closed_before = -math.inf   # every window ending at or before this is closed
        self._moving = False
        self._run_index = 0
        self._run_start_angle = math.nan
        self._last_angle = math.nan
        self._revolutions = 0.0
        self._problem_counts: dict[str, int] = {}
        self.problems: list[str] = []
        self._closed: list[Window] = []
        self._block_stamps = np.zeros(0, np.int64)   # vibration block stamps (us) of open windows
        self._square_buffer = np.empty(0)
        self.band = self.settings.band     # the band of the RMS; its upper edge is chosen at the first block
        self.band_refusal = ''             # why blocks were refused for the band (a sample rate too low), if any

    # -- problem reports -------------------------------------------------
    def _report(self, kind: str, line: str, count: int = 1) -> None:
        """Record a problem; the first of each kind is reported in words, later ones counted."""
        seen = self._problem_counts.get(kind, 0)
        self._problem_counts[kind] = seen + count
        if seen == 0:
            self.problems.append(line)

    def take_problems(self) -> list[str]:
        """Problem lines reported since the last call."""
        lines, self.problems = self.problems, []
        return lines

    def problem_summary(self) -> dict[str, int]:
        """How often each kind of problem occurred so far."""
        return dict(self._problem_counts)

    # -- input -----------------------------------------------------------
    def add(self, batch: InputBatch) -> None:
        """Take one input batch of any kind (see :mod:`prsm_lube_ros.recording.batches`)."""
        if len(batch) == 0:
            return
        if isinstance(batch, VibrationBatch):
            self._add_vibration(batch)
        elif isinstance(batch, ScrewStateBatch):
            self._add_screw(batch)
        elif isinstance(batch, AxialLoadBatch):
            self._add_scalar(batch.stamps, np.abs(np.asarray(batch.forces, float)), 'load')
        elif isinstance(batch, TemperatureBatch):
            self._add_scalar(batch.stamps, np.asarray(batch.temperatures, float), 'temperature')
        else:
            raise TypeError(f'not an input batch: {type(batch).__name__}')

    def _first_sight(self, stamps: np.ndarray, good: np.ndarray) -> np.ndarray:
        """Mask of blocks whose stamp was not seen before in an open window (repeats are left out)."""
        keep = np.ones(stamps.size, bool)
        index = np.flatnonzero(good)
        if index.size == 0:
            return keep
        keys = np.round(stamps[index] * 1e6).astype(np.int64)
        seen = self._block_stamps   # kept sorted
        if (keys[1:] > keys[:-1]).all() and (seen.size == 0 or keys[0] > seen[-1]):
            fresh = np.ones(index.size, bool)   # the usual case: later than every stamp seen, in order
            self._block_stamps = np.concatenate((seen, keys))
        else:
            fresh = np.zeros(index.size, bool)
            fresh[np.unique(keys, return_index=True)[1]] = True   # first of equal stamps in this batch
            if seen.size:
                fresh &= ~np.isin(keys, seen)
            self._block_stamps = np.sort(np.concatenate((seen, keys[fresh])))
        keep[index[~fresh]] = False
        repeats = int(index.size - np.count_nonzero(fresh))
        if repeats:
            self._report('vibration-repeat', f'vibration: {repeats} block(s) repeating an earlier block\'s stamp '
                         '(stamps going backwards or repeated) left out', repeats)
        return keep

    def _check_time(self, stamps: np.ndarray, stream: str) -> np.ndarray:
        """Mask of stamps still usable; handles non-finite stamps, back-steps and time resets."""
        finite = np.isfinite(stamps)
        if not finite.all():
            self._report(f'{stream}-stamp', f'{stream}: {int((~finite).sum())} message(s) with a non-finite '
                         'stamp left out', int((~finite).sum()))
        if not finite.any():
            return finite
        latest = self._progress.get(stream, -math.inf)
        first = float(stamps[finite].min())
        if math.isfinite(latest) and first < latest - self.settings.reset_after_backstep:
            self._report('time-reset', f'{stream}: stamps went back {latest - first:.3f} s '
                         '(clock reset or replay restarted); closing open windows and starting over')
            self._restart_time()
        usable = finite & (stamps >= self._closed_before)
        late = int((finite & ~usable).sum())
        if late:
            self._report(f'{stream}-late', f'{stream}: {late} message(s) stamped before already closed windows '
                         '(stamps going backwards or arriving late) left out', late)
        return usable

    def _restart_time(self) -> None:
        """Close everything open and forget time progress (after a clock reset)."""
        self._close(math.inf)
        self._progress = {name: -math.inf for name in GATING_STREAMS}
        self._closed_before = -math.inf
        self._moving = False
        self._last_angle = math.nan

    def _advance(self, stream: str, stamp: float) -> None:
        if stamp > self._progress.get(stream, -math.inf):
            self._progress[stream] = stamp

    def _add_vibration(self, batch: VibrationBatch) -> None:
        """Add the usable blocks of a vibration batch to the open windows (sums, and samples where kept)."""
        rates = np.asarray(batch.sample_rates, float)
        stamps = np.asarray(batch.stamps, float)
        offsets = np.asarray(batch.offsets, np.int64)
        counts = np.diff(offsets)
        good = self._usable_blocks(stamps, rates, counts)
        if not good.any():
            return
        samples = np.asarray(batch.samples).reshape(-1)
        finite = plausible_magnitudes(samples, MAX_ACCELERATION)   # finite, and what an accelerometer gives
        all_finite = bool(finite.all())
        keep_samples = self._keeps_samples()
        if all_finite:
            values = samples.astype(np.float64) if keep_samples else samples
        else:
            self._report_bad_values(samples, finite, 'vibration', 'vibration', 'sample(s)',
                                    f'beyond {MAX_ACCELERATION:g} m/s^2')
            with np.errstate(invalid='ignore'):       # a signalling NaN warns when cast
                values = np.where(finite, samples.astype(np.float64), 0.0)
        length = self.settings.window_length
        good &= self._first_sight(stamps, good)
        if not good.any():
            return
        pieces = _BlockPieces.cut(stamps, rates, counts, offsets, good, length)
        self._add_pieces(pieces, values, None if all_finite else finite, keep_samples)

    def _usable_blocks(self, stamps: np.ndarray, rates: np.ndarray, counts: np.ndarray) -> np.ndarray:
        """Mask of the blocks of a batch that can go into windows; the others are reported.

        Their stamps must be usable (:meth:`_check_time`), their header
        plausible, they must hold samples and their rate must cover the band.
        """
        good = self._check_time(stamps, 'vibration')
        good &= self._plausible_blocks(rates, counts, good)
        empty = counts == 0
        if (empty & good).any():
            n = int((empty & good).sum())
            self._report('vibration-empty', f'vibration: {n} empty block(s) (no samples) left out', n)
        good &= ~empty
        if self.band is not None and good.any():
            good &= self._band_covered(rates, good)
        return good

    def _add_pieces(self, pieces: _BlockPieces, values: np.ndarray, finite: np.ndarray | None,
                    keep_samples: bool) -> None:
        """Add block pieces to their windows' sums: squares of ``values`` and counts of finite samples.

        ``values``: the batch's samples in float64 (non-finite ones 0) or, when
        all are finite and none is kept, as they came; ``finite``: which are
        finite (None: all).  With ``keep_samples`` each piece's samples are kept
        for its window, with the time of its first sample.
        """
        lo, hi, seg_k, seg_block, b_rate = pieces.lo, pieces.hi, pieces.keys, pieces.blocks, pieces.rates
        seg_sumsq = _segment_sums(self._squares(values), lo, hi)
        if finite is None:
            seg_count = hi - lo
        else:
            seg_count = _segment_sums(finite.astype(np.int64), lo, hi)
        if seg_k.size == 1:
            keys, sumsq, count, rate = seg_k, seg_sumsq, seg_count, b_rate
        else:
            order, keys, starts, _ = _grouped(seg_k)
            sumsq = np.add.reduceat(seg_sumsq[order], starts)
            count = np.add.reduceat(seg_count[order], starts)
            rate = np.maximum.reduceat(b_rate[seg_block][order], starts)
        rows = self._open.rows(keys)
        table = self._open.table
        table[rows, _SUMSQ] += sumsq
        table[rows, _COUNT] += count
        table[rows, _RATE] = np.maximum(table[rows, _RATE], rate)
        if keep_samples:   # views of ``values`` (the batch's own float64 copy), with the time of their first sample
            # A view holds the batch's samples until its last window closes: one batch more than copies would.
            b_stamp, b_off = pieces.stamps, pieces.offsets
            seg_time = b_stamp[seg_block] + (lo - b_off[seg_block]) / b_rate[seg_block]
            for k, first, last, time in zip(seg_k.tolist(), lo.tolist(), hi.tolist(), seg_time.tolist()):
                self._chunks.setdefault(k, []).append((time, values[first:last]))
        self._advance('vibration', float(pieces.ends.max()))

    def _keeps_samples(self) -> bool:
        """Whether open windows keep their samples (for the band's RMS or for spectra)."""
        s = self.settings
        return self.band is not None or s.spectrum_segment > 0 or s.spectrum_lowest_frequency > 0

    def _band_covered(self, rates: np.ndarray, good: np.ndarray) -> np.ndarray:
        """Mask of blocks whose sample rate covers the band (choosing its upper edge at the first block)."""
        assert self.band is not None  # called only for a band
        if not self.band.chosen:
            self.band = self.band.resolved(float(rates[np.flatnonzero(good)[0]]))
        covered = rates >= self.band.min_sample_rate * (1 - 1e-9)
        refused = good & ~covered
        if refused.any():
            line = f'vibration: {rate_refusal(self.band, float(rates[refused][0]))}'
            self.band_refusal = self.band_refusal or line
            self._report('vibration-band', line + f'; {int(refused.sum())} block(s) left out', int(refused.sum()))
        return covered

    def _plausible_blocks(self, rates: np.ndarray, counts: np.ndarray, good: np.ndarray) -> np.ndarray:
        """Mask of blocks whose header can size windows: rate and duration within :mod:`..recording.plausibility`.

        Checked before anything is sized from them, so a corrupt ``sample_rate``
        (1e-6 Hz: one block spanning years of windows) is one named problem.
        """
        rate_ok = plausible_rates(rates)
        bad = good & ~rate_ok
        if bad.any():
            n = int(bad.sum())
            self._report('vibration-rate', f'vibration: {n} block(s) with {rate_problem(rates[bad][0])} left out', n)
        long = good & rate_ok & ~plausible_durations(counts, rates)
        if long.any():
            n, first = int(long.sum()), int(np.flatnonzero(long)[0])
            self._report('vibration-length', f'vibration: {n} block(s) of '
                         f'{duration_problem(counts[first], rates[first])} left out', n)
        return rate_ok & ~long

    def _report_bad_values(self, values: np.ndarray, ok: np.ndarray, stream: str, topic: str, what: str,
                           bound: str) -> None:
        """Report the entries of ``values`` failing ``ok``: non-finite ones, and finite ones beyond ``bound``."""
        finite = np.isfinite(values)
        nonfinite = int(values.size - np.count_nonzero(finite))
        if nonfinite:
            self._report(f'{stream}-nonfinite', f'{topic}: {nonfinite} NaN or inf {what} left out', nonfinite)
        implausible = int(np.count_nonzero(finite & ~ok))
        if implausible:
            self._report(f'{stream}-implausible', f'{topic}: {implausible} {what} {bound} (no sensor of the '
                         'contract gives that: corrupt data?) left out', implausible)

    def _squares(self, values: np.ndarray) -> np.ndarray:
        """``values ** 2`` in float64, written into a buffer kept between batches (no new pages per batch)."""
        if self._square_buffer.size < values.size:
            self._square_buffer = np.empty(max(values.size, 2 * self._square_buffer.size))
        squares = self._square_buffer[:values.size]
        np.square(values, out=squares, dtype=np.float64)
        return squares

    def _add_screw(self, batch: ScrewStateBatch) -> None:
        """Add the usable screw states of a batch to the open windows: speed, run, nut travel, revolutions."""
        usable = self._usable_screw_states(batch)
        if usable is None:
            return
        stamps, speeds, angles = usable
        run, travel, revolutions = self._follow_runs(speeds, angles)
        self._add_screw_rows(stamps, speeds, run, travel, revolutions)
        self._advance('screw', float(stamps[-1]))

    def _usable_screw_states(self, batch: ScrewStateBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Stamps, speed magnitudes and angles of the usable screw states, in stamp order (None: none usable).

        States with an unusable stamp (:meth:`_check_time`) or a non-finite or
        implausible speed are left out and reported.
        """
        stamps = np.asarray(batch.stamps, float)
        good = self._check_time(stamps, 'screw')
        speeds = np.abs(np.asarray(batch.speeds, float))
        angles = np.asarray(batch.angles, float)
        bad = good & ~np.isfinite(speeds)
        if bad.any():
            self._report('screw-nonfinite', f'joint_states: {int(bad.sum())} screw state(s) without a finite '
                         'velocity left out', int(bad.sum()))
        wild = good & ~plausible_magnitudes(speeds, MAX_SCREW_SPEED)
        if wild.any():
            self._report_bad_values(speeds[wild], np.zeros(int(wild.sum()), bool), 'screw', 'joint_states',
                                    'screw speed(s)', f'beyond {MAX_SCREW_SPEED:g} rad/s')
        good &= ~wild
        if not good.any():
            return None
        if not good.all():
            stamps, speeds, angles = stamps[good], speeds[good], angles[good]
        if stamps.size > 1 and not (stamps[1:] >= stamps[:-1]).all():
            order = np.argsort(stamps, kind='stable')
            stamps, speeds, angles = stamps[order], speeds[order], angles[order]
        return stamps, speeds, angles

    def _follow_runs(self, speeds: np.ndarray, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Run index, nut travel and revolutions at each screw state (in stamp order), carrying them on.

        The builder's run state (moving, run index, angle at motion start, last
        angle, revolutions) goes from the batch before to the batch after.
        """
        # Runs: a new run starts where the speed rises to min_speed after standstill.
        moving = speeds >= self.settings.min_speed
        previous = np.concatenate(([self._moving], moving[:-1]))
        starts = moving & ~previous
        run = self._run_index + np.cumsum(starts)
        # Nut travel from the angle at motion start (CONTRACT.md).
        start_angle = np.where(starts, angles, np.nan)
        start_angle[0] = start_angle[0] if starts[0] else self._run_start_angle
        start_angle = _forward_fill(start_angle)
        travel = np.where(moving, self.lead * (angles - start_angle) / (2 * math.pi), np.nan)
        # Revolutions turned since the builder started.
        steps = np.abs(np.diff(angles, prepend=self._last_angle))
        steps[~np.isfinite(steps)] = 0.0
        revolutions = self._revolutions + np.cumsum(steps) / (2 * math.pi)
        self._moving = bool(moving[-1])
        self._run_index = int(run[-1])
        self._run_start_angle = float(start_angle[-1])
        finite_angles = angles[np.isfinite(angles)]
        if finite_angles.size:
            self._last_angle = float(finite_angles[-1])
        self._revolutions = float(revolutions[-1])
        return run, travel, revolutions

    def _add_screw_rows(self, stamps: np.ndarray, speeds: np.ndarray, run: np.ndarray, travel: np.ndarray,
                        revolutions: np.ndarray) -> None:
        """Add screw states to their windows' rows: speed count, sum, min, max; travel; runs; last revolutions."""
        keys = np.floor(stamps / self.settings.window_length).astype(np.int64)
        order, unique, seg, n = _grouped(keys)
        sp = speeds[order]
        ssum = np.add.reduceat(sp, seg)
        smin = np.minimum.reduceat(sp, seg)
        smax = np.maximum.reduceat(sp, seg)
        run_sorted = run[order]
        rmin = np.minimum.reduceat(run_sorted, seg)
        rmax = np.maximum.reduceat(run_sorted, seg)
        tr = travel[order]
        tr_ok = np.isfinite(tr)
        tsum = np.add.reduceat(np.where(tr_ok, tr, 0.0), seg)
        tn = np.add.reduceat(tr_ok.astype(np.int64), seg)
        rev_last = revolutions[order][seg + n - 1]
        if self.settings.condition_indicators and self.band is not None:
            # The turned angle (monotonic in either direction) through each window, for order tracking.
            turned = 2 * math.pi * revolutions[order]
            stamps_sorted = stamps[order]
            for k, first, count in zip(unique.tolist(), seg.tolist(), n.tolist()):
                self._angle_chunks.setdefault(k, []).append((stamps_sorted[first:first + count],
                                                             turned[first:first + count]))
        rows = self._open.rows(unique)
        table = self._open.table
        table[rows, _SPEED_N] += n
        table[rows, _SPEED_SUM] += ssum
        table[rows, _SPEED_MIN] = np.minimum(table[rows, _SPEED_MIN], smin)
        table[rows, _SPEED_MAX] = np.maximum(table[rows, _SPEED_MAX], smax)
        table[rows, _TRAVEL_N] += tn
        table[rows, _TRAVEL_SUM] += tsum
        table[rows, _RUN_MIN] = np.minimum(table[rows, _RUN_MIN], rmin)
        table[rows, _RUN_MAX] = np.maximum(table[rows, _RUN_MAX], rmax)
        table[rows, _REVOLUTIONS] = rev_last

    def _add_scalar(self, stamps: npt.ArrayLike, values: np.ndarray, stream: str) -> None:
        stamps = np.asarray(stamps, float)
        good = self._check_time(stamps, stream)
        bad = good & ~np.isfinite(values)
        topic = 'axial_load' if stream == 'load' else stream
        if bad.any():
            self._report(f'{stream}-nonfinite', f'{topic}: {int(bad.sum())} non-finite value(s) left out',
                         int(bad.sum()))
        good &= np.isfinite(values)
        plausible = (plausible_magnitudes(values, MAX_AXIAL_LOAD) if stream == 'load'
                     else plausible_temperatures(values))
        wild = good & ~plausible
        if wild.any():
            bound = (f'beyond {MAX_AXIAL_LOAD:g} N' if stream == 'load'
                     else f'outside {TEMPERATURE_RANGE[0]:g} to {TEMPERATURE_RANGE[1]:g} degC')
            self._report_bad_values(values[wild], np.zeros(int(wild.sum()), bool), stream, topic, 'value(s)',
                                    bound)
        good &= ~wild
        if not good.any():
            return
        keys = np.floor(stamps[good] / self.settings.window_length).astype(np.int64)
        order, unique, seg, n = _grouped(keys)
        vals = values[good][order]
        sums = np.add.reduceat(vals, seg)
        count_column, sum_column = (_LOAD_N, _LOAD_SUM) if stream == 'load' else (_TEMP_N, _TEMP_SUM)
        rows = self._open.rows(unique)
        table = self._open.table
        table[rows, count_column] += n
        table[rows, sum_column] += sums
        if stream in self._progress:
            self._advance(stream, float(stamps[good].max()))

    # -- closing ---------------------------------------------------------
    def _close_ready(self) -> None:
        """Close windows every live stream has passed by ``completion_delay``."""
        known = [p for p in self._progress.values() if math.isfinite(p)]
        if not known:
            return
        lead = max(known)
        live = [p for p in known if p >= lead - self.settings.stream_timeout]
        horizon = min(live) - self.settings.completion_delay
        self._close(horizon)

    def _close(self, horizon: float) -> None:
        length = self.settings.window_length
        keys = self._open.keys
        ready = int(np.count_nonzero((keys + 1) * length <= horizon)) if keys.size else 0
        if ready:   # keys are sorted, so the ready windows are the first ones
            self._closed.extend(self._finish_windows(*self._open.pop_first(ready)))
        if math.isfinite(horizon):
            self._closed_before = max(self._closed_before, math.floor(horizon / length) * length)
            floor = int(round(self._closed_before * 1e6))
            self._block_stamps = self._block_stamps[self._block_stamps >= floor]
        else:
            self._block_stamps = self._block_stamps[:0]

    def earliest_open_end(self) -> float:
        """End in s of the earliest open window (-inf when none is open): the next one a close can bring."""
        keys = self._open.keys
        return float((keys[0] + 1) * self.settings.window_length) if keys.size else -math.inf

    def pop_closed(self) -> list[Window]:
        """Close what every live stream has passed and return the closed windows, in time order.

        Call it after adding all batches of one time slice (a live node: after
        each message), so a stream is not judged stale within a slice.
        """
        self._close_ready()
        closed, self._closed = self._closed, []
        return closed

    def finish(self) -> list[Window]:
        """Close every open window (end of a recording) and return what was not yet popped."""
        self._close(math.inf)
        closed, self._closed = self._closed, []
        return closed

    def _finish_windows(self, keys: np.ndarray, table: np.ndarray) -> list[Window]:
        """Closed windows from the keys and table rows of windows leaving the open set, in key order."""
        s = self.settings
        length = s.window_length
        count, rate, speed_n = table[:, _COUNT], table[:, _RATE], table[:, _SPEED_N]
        with np.errstate(divide='ignore', invalid='ignore'):
            rms = np.where(count > 0, np.sqrt(table[:, _SUMSQ] / count), math.nan)
            coverage = np.where(rate > 0, count / (length * rate), 0.0)
            speed = np.where(speed_n > 0, table[:, _SPEED_SUM] / speed_n, math.nan)
            spread = np.where((speed_n > 0) & (speed > 0),
                              (table[:, _SPEED_MAX] - table[:, _SPEED_MIN]) / speed, math.nan)
            load = _mean(table[:, _LOAD_SUM], table[:, _LOAD_N])
            temperature = _mean(table[:, _TEMP_SUM], table[:, _TEMP_N])
            position = _mean(table[:, _TRAVEL_SUM], table[:, _TRAVEL_N])
        # Steady unless one of _unsteady_reason's tests fires; only the others get a reason in words.
        maybe_steady = ((count > 0) & ~(coverage < s.min_coverage) & (speed_n > 0) & ~(speed < s.min_speed)
                        & ~(spread > s.max_speed_spread) & (table[:, _RUN_MIN] == table[:, _RUN_MAX])
                        & (table[:, _LOAD_N] > 0))
        run_index = np.where(speed_n > 0, table[:, _RUN_MAX], self._run_index).astype(np.int64)
        spectra: list[tuple[np.ndarray | None, float]] = [(None, math.nan)] * keys.size
        conditions: list[ConditionIndicators | None] = [None] * keys.size
        spectral = s.spectrum_segment > 0 or s.spectrum_lowest_frequency > 0
        indicators = s.condition_indicators and self.band is not None
        #: windows of the band, transformed together by (sample count, rate): (row, samples, speed, track); the
        #: track is None for a window that gets no condition indicators
        jobs: dict[tuple[int, float], list[tuple[int, np.ndarray, float, tuple[Any, Any] | None]]] = {}
        row: Any   # an index in the first loop, a row of ``table`` in the second
        if self._keeps_samples():
            for row, (k, rate_k) in enumerate(zip(keys.tolist(), rate.tolist())):
                chunks = self._chunks.pop(k, None)
                if not (chunks and rate_k > 0):
                    continue
                chunks.sort(key=lambda chunk: chunk[0])   # blocks may arrive out of order
                samples = np.concatenate([c for _, c in chunks]) if len(chunks) > 1 else chunks[0][1]
                first_time = chunks[0][0]
                if self.band is not None and count[row] > 0:   # non-finite samples are zeros in ``samples``
                    wanted = indicators and maybe_steady[row] and k % s.condition_every == 0
                    jobs.setdefault((samples.size, rate_k), []).append(
                        (row, samples, float(speed[row]), self._window_angles(k, first_time) if wanted else None))
                if spectral:
                    segment = (spectrum_segment(rate_k, s.spectrum_lowest_frequency, int(round(length * rate_k)))
                               if s.spectrum_lowest_frequency > 0 else s.spectrum_segment)
                    spectra[row] = _power_spectrum(samples, rate_k, segment)
        deferring = self._band_and_conditions(jobs, rms, count, conditions)
        for k in keys.tolist():
            self._angle_chunks.pop(k, None)
        columns = zip((keys * length).tolist(), ((keys + 1) * length).tolist(), rms.tolist(),
                      count.astype(np.int64).tolist(), coverage.tolist(), speed.tolist(), spread.tolist(),
                      load.tolist(), temperature.tolist(), position.tolist(), table[:, _REVOLUTIONS].tolist(),
                      run_index.tolist(), maybe_steady.tolist(), table, spectra, rate.tolist(), conditions)
        windows = []
        for (start, end, rms_k, count_k, coverage_k, speed_k, spread_k, load_k, temperature_k, position_k,
             revolutions_k, run_k, steady_k, row, (spectrum, resolution), rate_k, condition) in columns:
            kind, reason = ('', '') if steady_k else _unsteady_reason(s, row, coverage_k, speed_k, spread_k)
            # Positional, in field order (start ... sample_rate): a third cheaper than keywords.
            windows.append(Window(start, end, rms_k, count_k, coverage_k, speed_k, spread_k, load_k, temperature_k,
                                  position_k, revolutions_k, run_k, kind, reason, spectrum, resolution,
                                  rate_k if rate_k > 0 else math.nan, condition))
        self._deferred.extend(([windows[row] for row in rows], arguments) for rows, arguments in deferring)
        return windows

    def conditions_deferred(self, window: Window) -> bool:
        """Whether ``window`` (closed, not yet through :meth:`complete_conditions`) gets its indicators there."""
        return any(window is waiting for windows, _ in self._deferred for waiting in windows)

    def complete_conditions(self, windows: Sequence[Window] | None = None) -> list[tuple[Window, Window]]:
        """``(closed window, the same with its condition)`` for each window whose indicators were deferred.

        Every window closed since the last call that waits for its indicators
        (``defer_conditions``), or those of ``windows`` (closed windows, by
        identity: the others, closed later, keep waiting), grouped as they are
        transformed (by sample count and rate, not always in closing order:
        match them by the first item).  The numbers are those without
        deferring: the windows of one batch are transformed together, as
        :meth:`_band_and_conditions` would have.
        """
        wanted = None if windows is None else {id(window) for window in windows}
        deferred, self._deferred = self._deferred, []
        completed: list[tuple[Window, Window]] = []
        for waiting, arguments in deferred:
            if wanted is not None and not any(id(window) in wanted for window in waiting):
                self._deferred.append((waiting, arguments))
                continue
            found = _indicators_of(arguments)
            completed.extend((window, replace(window, condition=found_k)) for window, found_k in zip(waiting, found))
        return completed

    def _band_and_conditions(self, jobs: dict[tuple[int, float], list[tuple[int, np.ndarray, float, Any]]],
                             rms: np.ndarray, count: np.ndarray,
                             conditions: list[ConditionIndicators | None]) -> list[tuple[list[int], tuple]]:
        """Band RMS of the windows in ``jobs`` into ``rms``, and their indicators (where asked) into ``conditions``.

        The windows of one sample count and rate are transformed together, a
        cache-sized batch (:data:`~.condition_indicators.BATCH_SAMPLES`) at a
        time, in one ``rfft``: the band's mean square is summed over its bins
        (:func:`~.conditioning.band_mean_squares`, Parseval) and the same
        spectra go to :func:`~.condition_indicators.condition_indicators_batch`,
        so no window is transformed twice.  Rows of ``rms`` and ``count``
        (finite samples: non-finite ones are zeros in the samples) are the
        windows' rows in the closing table.  With ``defer_conditions`` the
        indicators are not computed: returns ``(rows, arguments)`` of each batch
        for :meth:`complete_conditions` (else nothing).
        """
        deferring: list[tuple[list[int], tuple]] = []
        if not jobs or self.band is None:
            return deferring
        band = self.band
        for (n, rate), group in jobs.items():
            if n < 2:
                rms[[job[0] for job in group]] = math.nan
                continue
            step = max(1, BATCH_SAMPLES // n)
            for start in range(0, len(group), step):
                part = group[start:start + step]
                x = np.vstack([job[1] for job in part])
                spectra = np.fft.rfft(x, axis=1)
                rows = np.array([job[0] for job in part])
                rms[rows] = np.sqrt(band_mean_squares(spectra, n, rate, band) * n / count[rows])
                wanted = [i for i, job in enumerate(part) if job[3] is not None]
                if not wanted:
                    continue
                every = len(wanted) == len(part)     # the arrays as they are, no copy of their rows
                arguments = (x if every else x[wanted], rate, [part[i][2] for i in wanted], (band.low, band.high),
                             self.settings.defect_orders, [part[i][3] for i in wanted],
                             spectra if every else spectra[wanted])
                if self.defer_conditions:
                    deferring.append(([part[i][0] for i in wanted], arguments))
                    continue
                found = _indicators_of(arguments)
                for i, condition in zip(wanted, found):
                    conditions[part[i][0]] = condition
        return deferring

    def _window_angles(self, key: int, first_time: float) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Stamps (s from ``first_time``, the window's first sample) and turned screw angle (rad) in window ``key``."""
        chunks = self._angle_chunks.get(key)
        if not chunks:
            return None, None
        stamps = np.concatenate([c[0] for c in chunks]) if len(chunks) > 1 else chunks[0][0]
        angles = np.concatenate([c[1] for c in chunks]) if len(chunks) > 1 else chunks[0][1]
        order = np.argsort(stamps, kind='stable')
        return stamps[order] - first_time, angles[order]


def _indicators_of(arguments: tuple) -> list[ConditionIndicators]:
    """:func:`condition_indicators_batch` of one batch's arguments, as ``_band_and_conditions`` keeps them.

    ``(samples, rate, speeds, band, defect orders, tracks, spectra)``.
    """
    samples, rate, speeds, band, orders, tracks, spectra = arguments
    return condition_indicators_batch(samples, rate, speeds, band, orders, tracks, spectra=spectra)


def _mean(sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """``sums / counts`` where counts > 0, NaN elsewhere."""
    return np.where(counts > 0, sums / counts, math.nan)


def _unsteady_reason(s: WindowSettings, row: np.ndarray, coverage: float, speed: float,
                     spread: float) -> tuple[str, str]:
    """Why a closed window (its open-table row and derived values) is not steady: (kind, words); ('', '') if it is."""
    if row[_COUNT] == 0:
        return NO_VIBRATION, 'no vibration samples in the window'
    if coverage < s.min_coverage:
        return BLOCKS_LOST, (f'vibration covers {100 * coverage:.0f}% of the window '
                             f'(< {100 * s.min_coverage:.0f}%): blocks lost')
    if row[_SPEED_N] == 0:
        return NO_SPEED, 'no screw speed in the window (joint_states entry "screw")'
    if speed < s.min_speed:
        return AT_REST, f'screw at rest or crawling ({speed:.3g} rad/s < min_speed {s.min_speed:.3g} rad/s)'
    if spread > s.max_speed_spread:
        return SPEED_CHANGING, (f'screw speed not steady (varies {100 * spread:.1f}% > '
                                f'{100 * s.max_speed_spread:.1f}%): acceleration or deceleration')
    if row[_RUN_MIN] != row[_RUN_MAX]:
        return SPANS_RUNS, 'window spans the end of one run and the start of the next'
    if row[_LOAD_N] == 0:
        return NO_LOAD, 'no axial load in the window'
    return '', ''


def _segment_sums(values: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """``values[lo[i]:hi[i]].sum()`` for each i, in one pass when the segments do not overlap."""
    sums = np.zeros(lo.size, values.dtype)
    full = hi > lo
    first, last = lo[full], hi[full]
    if first.size == 0:
        return sums
    if first.size > 1 and not (first[1:] >= last[:-1]).all():   # overlapping blocks: malformed offsets
        sums[full] = [values[a:b].sum() for a, b in zip(first.tolist(), last.tolist())]
        return sums
    bounds = np.unique(np.concatenate((first, last)))
    bounds = bounds[bounds < values.size]
    sums[full] = np.add.reduceat(values, bounds)[np.searchsorted(bounds, first)]
    return sums


def _forward_fill(values: np.ndarray) -> np.ndarray:
    """Replace NaNs by the last finite value before them (leading NaNs stay)."""
    valid = np.isfinite(values)
    if values.size == 1 or valid.all():
        return values
    index = np.where(valid, np.arange(values.size), 0)
    np.maximum.accumulate(index, out=index)
    filled = values[index]
    filled[~valid & (np.cumsum(valid) == 0)] = np.nan
    return filled


def _power_spectrum(samples: np.ndarray, rate: float, segment: int) -> tuple[np.ndarray | None, float]:
    """Welch power spectral density, (m/s^2)^2/Hz, and its bin width in Hz.

    A window shorter than ``segment`` (lost blocks) is zero-padded to it, so
    every window of a recording has the same bins.
    """
    from scipy.signal import welch
    nperseg = min(segment, samples.size)
    if nperseg < 8:
        return None, math.nan
    freqs, psd = welch(samples, fs=rate, nperseg=nperseg, nfft=max(segment, nperseg))
    return psd, float(freqs[1] - freqs[0])
