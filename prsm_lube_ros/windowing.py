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

Memory stays flat: only windows that can still receive data are open; a window
is closed once every input stream has passed its end by ``completion_delay``
(a stream silent for ``stale_timeout`` while others advance stops holding
windows open, so lost topics give NaN windows with a reason, not a stall).
Bad input (non-finite samples, empty blocks, rates <= 0, stamps going back)
is left out and reported once per kind through ``problems``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math

import numpy as np

from .errors import InputError
from .events import AxialLoadBatch, ScrewStateBatch, TemperatureBatch, VibrationBatch

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
    stale_timeout: float = 3.0
    reset_after_backstep: float = 5.0
    spectrum_segment: int = 0

    def __post_init__(self):
        """Reject settings that cannot cut windows."""
        checks = {
            'window_length': self.window_length > 0,
            'min_speed': self.min_speed > 0,
            'max_speed_spread': self.max_speed_spread > 0,
            'min_coverage': 0 < self.min_coverage <= 1,
            'completion_delay': self.completion_delay >= 0,
            'stale_timeout': self.stale_timeout > 0,
            'reset_after_backstep': self.reset_after_backstep > 0,
            'spectrum_segment': self.spectrum_segment >= 0,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not (ok and math.isfinite(value)):
                raise InputError(f'window setting {name}={value!r} is out of range')


@dataclass(frozen=True)
class Window:
    """One closed window of the inputs.

    ``reason`` is empty for a steady window; otherwise it says in words why the
    window is not steady (and so not assessable).
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
    steady: bool
    reason: str = ''
    spectrum: np.ndarray | None = field(default=None, compare=False, repr=False)
    spectrum_resolution: float = math.nan  # Hz per spectrum bin


class _OpenWindow:
    """Running sums of one window still receiving data."""

    __slots__ = ('sumsq', 'count', 'rate', 'speed_n', 'speed_sum', 'speed_min', 'speed_max',
                 'travel_n', 'travel_sum', 'load_n', 'load_sum', 'temp_n', 'temp_sum',
                 'run_min', 'run_max', 'revolutions', 'chunks')

    def __init__(self):
        self.sumsq = 0.0
        self.count = 0
        self.rate = 0.0
        self.speed_n = 0
        self.speed_sum = 0.0
        self.speed_min = math.inf
        self.speed_max = -math.inf
        self.travel_n = 0
        self.travel_sum = 0.0
        self.load_n = 0
        self.load_sum = 0.0
        self.temp_n = 0
        self.temp_sum = 0.0
        self.run_min = None
        self.run_max = None
        self.revolutions = math.nan
        self.chunks = None


def _grouped(keys: np.ndarray):
    """Sort order, unique keys and segment starts for reduceat over ``keys``."""
    order = np.argsort(keys, kind='stable')
    sorted_keys = keys[order]
    starts = np.flatnonzero(np.r_[True, sorted_keys[1:] != sorted_keys[:-1]])
    return order, sorted_keys[starts], starts


class WindowBuilder:
    """Turns input batches into closed :class:`Window` objects, in time order.

    ``lead`` (m per screw revolution) converts screw angle to nut travel.  Feed
    batches with :meth:`add`, collect closed windows with :meth:`pop_closed`
    and, at the end of a recording, :meth:`finish`.  One-line problem reports
    accumulate in :attr:`problems` (drain it with :meth:`take_problems`).
    """

    def __init__(self, settings: WindowSettings | None = None, lead: float = 0.005):
        self.settings = settings or WindowSettings()
        self.lead = float(lead)
        self._open: dict[int, _OpenWindow] = {}
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
        self._block_stamps: set[int] = set()   # vibration block stamps (us) of open windows

    # -- problem reports -------------------------------------------------
    def _report(self, kind: str, line: str, count: int = 1):
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
    def add(self, batch) -> None:
        """Take one input batch of any kind (see :mod:`prsm_lube_ros.events`)."""
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

    def _window(self, index: int) -> _OpenWindow:
        acc = self._open.get(index)
        if acc is None:
            acc = self._open[index] = _OpenWindow()
        return acc

    def _first_sight(self, stamps: np.ndarray, good: np.ndarray) -> np.ndarray:
        """Mask of blocks whose stamp was not seen before in an open window (repeats are left out)."""
        keep = np.ones(stamps.size, bool)
        for i in np.flatnonzero(good).tolist():
            key = int(round(float(stamps[i]) * 1e6))
            if key in self._block_stamps:
                keep[i] = False
            else:
                self._block_stamps.add(key)
        repeats = int((good & ~keep).sum())
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

    def _restart_time(self):
        """Close everything open and forget time progress (after a clock reset)."""
        self._close(math.inf)
        self._progress = {name: -math.inf for name in GATING_STREAMS}
        self._closed_before = -math.inf
        self._moving = False
        self._last_angle = math.nan

    def _advance(self, stream: str, stamp: float):
        if stamp > self._progress.get(stream, -math.inf):
            self._progress[stream] = stamp

    def _add_vibration(self, batch: VibrationBatch):
        rates = np.asarray(batch.sample_rates, float)
        stamps = np.asarray(batch.stamps, float)
        offsets = np.asarray(batch.offsets, np.int64)
        counts = np.diff(offsets)
        good = self._check_time(stamps, 'vibration')
        bad_rate = ~(np.isfinite(rates) & (rates > 0))
        if (bad_rate & good).any():
            n = int((bad_rate & good).sum())
            self._report('vibration-rate', f'vibration: {n} block(s) with sample_rate '
                         f'{rates[bad_rate & good][0]!r} Hz (must be > 0) left out', n)
        empty = counts == 0
        if (empty & good).any():
            n = int((empty & good).sum())
            self._report('vibration-empty', f'vibration: {n} empty block(s) (no samples) left out', n)
        good &= ~bad_rate & ~empty
        if not good.any():
            return
        samples = np.asarray(batch.samples)
        values = samples.astype(np.float64)
        finite = np.isfinite(values)
        all_finite = bool(finite.all())
        if not all_finite:
            n = int((~finite).sum())
            self._report('vibration-nonfinite', f'vibration: {n} NaN or inf sample(s) left out', n)
            values = np.where(finite, values, 0.0)
        length = self.settings.window_length
        good &= self._first_sight(stamps, good)
        if not good.any():
            return
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
        csum = np.concatenate(([0.0], np.cumsum(values * values)))
        seg_sumsq = csum[hi] - csum[lo]
        if all_finite:
            seg_count = hi - lo
        else:
            ccount = np.concatenate(([0], np.cumsum(finite)))
            seg_count = ccount[hi] - ccount[lo]
        order, keys, starts = _grouped(seg_k)
        sumsq = np.add.reduceat(seg_sumsq[order], starts)
        count = np.add.reduceat(seg_count[order], starts)
        rate = np.maximum.reduceat(b_rate[seg_block][order], starts)
        keep_spectra = self.settings.spectrum_segment > 0
        for j, k in enumerate(keys.tolist()):
            acc = self._window(k)
            acc.sumsq += float(sumsq[j])
            acc.count += int(count[j])
            acc.rate = max(acc.rate, float(rate[j]))
        if keep_spectra:
            for s, k in enumerate(seg_k.tolist()):
                acc = self._open[k]
                if acc.chunks is None:
                    acc.chunks = []
                acc.chunks.append(values[lo[s]:hi[s]])
        self._advance('vibration', float(b_end.max()))

    def _add_screw(self, batch: ScrewStateBatch):
        stamps = np.asarray(batch.stamps, float)
        good = self._check_time(stamps, 'screw')
        speeds = np.abs(np.asarray(batch.speeds, float))
        angles = np.asarray(batch.angles, float)
        bad = good & ~np.isfinite(speeds)
        if bad.any():
            self._report('screw-nonfinite', f'joint_states: {int(bad.sum())} screw state(s) without a finite '
                         'velocity left out', int(bad.sum()))
        good &= np.isfinite(speeds)
        if not good.any():
            return
        order = np.argsort(stamps[good], kind='stable')
        stamps, speeds, angles = stamps[good][order], speeds[good][order], angles[good][order]
        # Runs: a new run starts where the speed rises to min_speed after standstill.
        moving = speeds >= self.settings.min_speed
        previous = np.r_[self._moving, moving[:-1]]
        starts = moving & ~previous
        run = self._run_index + np.cumsum(starts)
        # Nut travel from the angle at motion start (CONTRACT.md).
        start_angle = np.where(starts, angles, np.nan)
        start_angle[0] = start_angle[0] if starts[0] else self._run_start_angle
        start_angle = _forward_fill(start_angle)
        travel = np.where(moving, self.lead * (angles - start_angle) / (2 * math.pi), np.nan)
        # Revolutions turned since the builder started.
        steps = np.abs(np.diff(np.r_[self._last_angle, angles]))
        steps[~np.isfinite(steps)] = 0.0
        revolutions = self._revolutions + np.cumsum(steps) / (2 * math.pi)
        self._moving = bool(moving[-1])
        self._run_index = int(run[-1])
        self._run_start_angle = float(start_angle[-1])
        finite_angles = angles[np.isfinite(angles)]
        if finite_angles.size:
            self._last_angle = float(finite_angles[-1])
        self._revolutions = float(revolutions[-1])

        keys = np.floor(stamps / self.settings.window_length).astype(np.int64)
        order, unique, seg = _grouped(keys)
        sp = speeds[order]
        n = np.diff(np.r_[seg, sp.size])
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
        rev_last = revolutions[order][np.r_[seg[1:], sp.size] - 1]
        for j, k in enumerate(unique.tolist()):
            acc = self._window(k)
            acc.speed_n += int(n[j])
            acc.speed_sum += float(ssum[j])
            acc.speed_min = min(acc.speed_min, float(smin[j]))
            acc.speed_max = max(acc.speed_max, float(smax[j]))
            acc.travel_n += int(tn[j])
            acc.travel_sum += float(tsum[j])
            acc.run_min = int(rmin[j]) if acc.run_min is None else min(acc.run_min, int(rmin[j]))
            acc.run_max = int(rmax[j]) if acc.run_max is None else max(acc.run_max, int(rmax[j]))
            acc.revolutions = float(rev_last[j])
        self._advance('screw', float(stamps[-1]))

    def _add_scalar(self, stamps, values, stream: str):
        stamps = np.asarray(stamps, float)
        good = self._check_time(stamps, stream)
        bad = good & ~np.isfinite(values)
        if bad.any():
            topic = 'axial_load' if stream == 'load' else stream
            self._report(f'{stream}-nonfinite', f'{topic}: {int(bad.sum())} non-finite value(s) left out',
                         int(bad.sum()))
        good &= np.isfinite(values)
        if not good.any():
            return
        keys = np.floor(stamps[good] / self.settings.window_length).astype(np.int64)
        order, unique, seg = _grouped(keys)
        vals = values[good][order]
        n = np.diff(np.r_[seg, vals.size])
        sums = np.add.reduceat(vals, seg)
        for j, k in enumerate(unique.tolist()):
            acc = self._window(k)
            if stream == 'load':
                acc.load_n += int(n[j])
                acc.load_sum += float(sums[j])
            else:
                acc.temp_n += int(n[j])
                acc.temp_sum += float(sums[j])
        if stream in self._progress:
            self._advance(stream, float(stamps[good].max()))

    # -- closing ---------------------------------------------------------
    def _close_ready(self):
        """Close windows every live stream has passed by ``completion_delay``."""
        known = [p for p in self._progress.values() if math.isfinite(p)]
        if not known:
            return
        lead = max(known)
        live = [p for p in known if p >= lead - self.settings.stale_timeout]
        horizon = min(live) - self.settings.completion_delay
        self._close(horizon)

    def _close(self, horizon: float):
        length = self.settings.window_length
        ready = sorted(k for k in self._open if (k + 1) * length <= horizon)
        for k in ready:
            self._closed.append(self._finish_window(k, self._open.pop(k)))
        if math.isfinite(horizon):
            self._closed_before = max(self._closed_before, math.floor(horizon / length) * length)
            floor = int(round(self._closed_before * 1e6))
            self._block_stamps = {key for key in self._block_stamps if key >= floor}
        else:
            self._block_stamps.clear()

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

    def _finish_window(self, k: int, acc: _OpenWindow) -> Window:
        s = self.settings
        start, end = k * s.window_length, (k + 1) * s.window_length
        rms = math.sqrt(acc.sumsq / acc.count) if acc.count else math.nan
        coverage = acc.count / (s.window_length * acc.rate) if acc.rate > 0 else 0.0
        speed = acc.speed_sum / acc.speed_n if acc.speed_n else math.nan
        spread = (acc.speed_max - acc.speed_min) / speed if acc.speed_n and speed > 0 else math.nan
        load = acc.load_sum / acc.load_n if acc.load_n else math.nan
        temperature = acc.temp_sum / acc.temp_n if acc.temp_n else math.nan
        position = acc.travel_sum / acc.travel_n if acc.travel_n else math.nan
        if acc.count == 0:
            reason = 'no vibration samples in the window'
        elif coverage < s.min_coverage:
            reason = (f'vibration covers {100 * coverage:.0f}% of the window '
                      f'(< {100 * s.min_coverage:.0f}%): blocks lost')
        elif acc.speed_n == 0:
            reason = 'no screw speed in the window (joint_states entry "screw")'
        elif speed < s.min_speed:
            reason = f'screw at rest or crawling ({speed:.3g} rad/s < min_speed {s.min_speed:.3g} rad/s)'
        elif spread > s.max_speed_spread:
            reason = (f'screw speed not steady (varies {100 * spread:.1f}% > {100 * s.max_speed_spread:.1f}%):'
                      ' acceleration or deceleration')
        elif acc.run_min != acc.run_max:
            reason = 'window spans the end of one run and the start of the next'
        elif acc.load_n == 0:
            reason = 'no axial load in the window'
        else:
            reason = ''
        spectrum, resolution = None, math.nan
        if acc.chunks and s.spectrum_segment > 0 and acc.rate > 0:
            spectrum, resolution = _power_spectrum(np.concatenate(acc.chunks), acc.rate, s.spectrum_segment)
        return Window(start=start, end=end, vibration_rms=rms, sample_count=acc.count,
                      coverage=coverage, screw_speed=speed, speed_spread=spread, axial_load=load,
                      temperature=temperature, nut_position=position, revolutions=acc.revolutions,
                      run_index=acc.run_max if acc.run_max is not None else self._run_index,
                      steady=not reason, reason=reason, spectrum=spectrum,
                      spectrum_resolution=resolution)


def _forward_fill(values: np.ndarray) -> np.ndarray:
    """Replace NaNs by the last finite value before them (leading NaNs stay)."""
    valid = np.isfinite(values)
    index = np.where(valid, np.arange(values.size), 0)
    np.maximum.accumulate(index, out=index)
    filled = values[index]
    filled[~valid & (np.cumsum(valid) == 0)] = np.nan
    return filled


def _power_spectrum(samples: np.ndarray, rate: float, segment: int):
    """Welch power spectral density, (m/s^2)^2/Hz, and its bin width in Hz."""
    from scipy.signal import welch
    nperseg = min(segment, samples.size)
    if nperseg < 8:
        return None, math.nan
    freqs, psd = welch(samples, fs=rate, nperseg=nperseg)
    return psd, float(freqs[1] - freqs[0])
