# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Condition indicators of one window: impulsiveness and the envelope spectrum in screw orders.

theta_Oil follows the band RMS, and a surface defect raises the RMS as oil
loss does.  What tells them apart (envelope analysis, spectral kurtosis,
ISO 13373-3) is the *form* of the vibration: a spall is struck once per
passing contact, so the signal carries short impulses (kurtosis far above the
3 of Gaussian vibration, a high crest factor) repeating at a defect order
(:mod:`prsm_lube_ros.physics.defect_orders`); oil loss raises the smooth,
Gaussian-like contact vibration and leaves its form alone.

Per window, from its samples (already in the window builder for the band RMS):

* ``kurtosis`` and ``crest_factor`` of the signal in the analysis band
  (:mod:`.conditioning`: DC, gravity and everything above the band out);
  kurtosis is Pearson's ``E[x^4] / E[x^2]^2`` (3 for Gaussian vibration, 1.5
  for a pure tone), crest factor ``max |x| / RMS``;
* ``gaussian_rms``, the RMS of the band signal's Gaussian part: its median
  ``|x|`` over the Gaussian's 0.6745 sigma (:func:`gaussian_rms`); sparse
  strikes leave it, so ``RMS^2 - gaussian_rms^2`` is their power;
* the **demodulation band**, chosen from the data by spectral kurtosis (Antoni
  2006-2007; the fast kurtogram's 1/3-binary tree): the analysis band and its
  halves, thirds, quarters, sixths, ... down to bands still wide enough to carry the envelope
  up to :data:`ENVELOPE_HARMONICS` times the highest defect order; each band's
  complex envelope is taken from the window's FFT (bins of the band shifted
  to 0 Hz, inverse FFT: the decimated analytic signal, a Hilbert envelope), its
  spectral kurtosis ``E|z|^4 / E^2|z|^2 - 2`` (0 for Gaussian noise, -1 for a
  tone, large for impulses), and the band of the largest is kept;
* the **envelope spectrum** of that band, ``|FFT(|z| - mean)|^2``, in screw
  orders.  Where the screw angle is known through the window (``angle_times``
  and ``angles``) the envelope is resampled to uniform screw angle before the
  FFT (order tracking), so the orders stay sharp while the speed varies;
  otherwise orders are Hz over the window's mean shaft frequency.  The
  resolution is one over the revolutions in the window (0.6 orders at
  100 r/min in 1 s windows, 0.033 at 1800 r/min);
* **envelope peaks**: local maxima of the order spectrum at least
  :data:`REPORT_DB` over its floor (the median of the spectrum between order
  :data:`FLOOR_LOWEST_ORDER` and the highest order it holds), the largest
  :data:`MAX_PEAKS`, each labelled with the component whose defect order (or a
  harmonic) it points at (:func:`~prsm_lube_ros.physics.defect_orders.label_order`).

The envelope spectrum is also kept on the fixed order grid :data:`ORDER_GRID`
(float32), so windows of different speeds average into one run spectrum
(:mod:`.defect_screen` does it) and a report can draw a waterfall.

Costs one inverse FFT per band of the tree (each as long as its band) and the
envelope's transforms, a few ms for a 1 s window at 25.6 kHz; the window's own
FFT is the band RMS's, which the window builder hands over (``spectra``), and
every transform runs over the windows of one size at once.  Pure numpy.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, TYPE_CHECKING
import warnings

import numpy as np

from ..physics.defect_orders import label_order, ORDER_TOLERANCE

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy.typing as npt

    from ..physics.defect_orders import DefectOrder

__all__ = ['BATCH_SAMPLES', 'ConditionIndicators', 'ENVELOPE_HARMONICS', 'EnvelopePeak', 'FLOOR_LOWEST_ORDER',
           'GAUSSIAN_MEDIAN_ABS', 'GAUSSIAN_SAMPLES', 'MAX_ORDER', 'MAX_PEAKS', 'MAX_TREE_LEVEL', 'MIN_SAMPLES',
           'NO_INDICATORS', 'ORDER_GRID', 'ORDER_STEP',
           'REPORT_DB', 'RUN_REPORT_DB', 'SK_SIGMAS', 'TREE_PARTS', 'condition_indicators',
           'condition_indicators_batch', 'envelope_floor', 'envelope_peaks', 'gaussian_rms',
           'kurtosis', 'order_spectrum_db']

#: Highest screw order the envelope spectrum is kept to (3 harmonics of the default screw raceway order 6.25,
#: 3 of a support bearing's BPFI near 7.4).
MAX_ORDER = 24.0
#: Step of the fixed order grid, orders.
ORDER_STEP = 0.025
#: The fixed order grid the envelope spectra are kept on (0 to :data:`MAX_ORDER`).
ORDER_GRID = np.arange(0.0, MAX_ORDER + ORDER_STEP / 2, ORDER_STEP)
_GRID_ORDERS: list[float] = ORDER_GRID.tolist()    # the same as Python numbers, for the peaks
#: Harmonics of the highest defect order a demodulation band must be wide enough to carry.
ENVELOPE_HARMONICS = 2.5
#: Deepest level of the band tree (2^level bands), the fast kurtogram's usual depth for 1 s windows.
MAX_TREE_LEVEL = 5
#: Bands the analysis band is split into, level by level: the 1/3-binary tree of the fast kurtogram (the thirds
#: put a band's centre where the halves put an edge).
TREE_PARTS = tuple(sorted({2 ** k for k in range(MAX_TREE_LEVEL + 1)}
                          | {3 * 2 ** (k - 1) for k in range(1, MAX_TREE_LEVEL)}))
#: Lowest order of the floor's median (below it the envelope holds the run's slow amplitude changes).
FLOOR_LOWEST_ORDER = 1.0
#: dB over the floor a local maximum of one window's envelope spectrum needs to be reported (its bins scatter
#: as exponentials: 10 dB over the median is 6.9 times the mean, reached by chance in 0.1 % of the bins).
REPORT_DB = 10.0
#: The same for a spectrum averaged over a run's windows (10 or more: 6 dB is beyond chance).
RUN_REPORT_DB = 6.0
#: Envelope peaks reported per window (the largest).
MAX_PEAKS = 5
#: Standard deviations of Gaussian SK a band's SK is discounted by before bands are compared.
SK_SIGMAS = 3.0
#: Samples of the windows :func:`condition_indicators_batch` transforms together (arrays that stay in cache).
BATCH_SAMPLES = 1 << 18
#: Median of |x| over sigma for Gaussian x (the normal distribution's 75 % point).
GAUSSIAN_MEDIAN_ABS = 0.6744897501960817
#: Most samples of a window the Gaussian part's median is taken over (evenly spaced).
GAUSSIAN_SAMPLES = 1024
#: Fewest samples an indicator is computed on.
MIN_SAMPLES = 64


@dataclass(frozen=True)
class EnvelopePeak:
    """A line of the envelope spectrum: its order (multiples of the screw speed), dB over the floor, component."""

    order: float
    db: float
    component: str      # '' when it points at no defect order

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (CONTRACT.md: order, db, component)."""
        return {'order': round(self.order, 4), 'db': round(self.db, 2), 'component': self.component}


@dataclass(frozen=True)
class ConditionIndicators:
    """Impulsiveness and envelope of one window (see module doc); NaN where a value cannot be had."""

    kurtosis: float                        # Pearson, 3 for Gaussian vibration
    crest_factor: float                    # max |x| / RMS in the analysis band
    envelope_peaks: tuple[EnvelopePeak, ...]
    spectral_kurtosis: float               # of the chosen demodulation band (0 Gaussian)
    demodulation_band: tuple[float, float]  # Hz
    order_resolution: float                # orders per envelope-spectrum bin
    #: Gaussian part of the band signal's RMS, m/s^2: its median absolute value over the Gaussian's (see
    #: :func:`gaussian_rms`); sparse strikes leave it, the contacts' smooth vibration makes it.
    gaussian_rms: float = field(default=math.nan, compare=False)
    #: Envelope power on :data:`ORDER_GRID` (float32, (m/s^2)^2 per bin); None when the window has none.
    envelope: np.ndarray | None = field(default=None, compare=False, repr=False)

    def defect_peak(self) -> EnvelopePeak | None:
        """The largest peak that points at a defect order, or None."""
        labelled = [p for p in self.envelope_peaks if p.component]
        return max(labelled, key=lambda p: p.db) if labelled else None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready mapping with the contract's fields (kurtosis, crest_factor, envelope_peaks) and the band."""
        return {'kurtosis': _finite_or_none(self.kurtosis, 4), 'crest_factor': _finite_or_none(self.crest_factor, 4),
                'envelope_peaks': [p.as_dict() for p in self.envelope_peaks],
                'spectral_kurtosis': _finite_or_none(self.spectral_kurtosis, 4),
                'demodulation_band': [round(self.demodulation_band[0], 1), round(self.demodulation_band[1], 1)],
                'order_resolution': _finite_or_none(self.order_resolution, 4)}


def _finite_or_none(value: float, digits: int) -> float | None:
    return round(float(value), digits) if math.isfinite(value) else None


NO_INDICATORS = ConditionIndicators(math.nan, math.nan, (), math.nan, (math.nan, math.nan), math.nan)


def kurtosis(values: npt.ArrayLike) -> float:
    """Pearson's kurtosis ``E[x^4] / E[x^2]^2`` of a zero-mean signal (NaN when it is all zero)."""
    x = np.asarray(values, dtype=float)
    power = float(np.mean(x * x))
    return float(np.mean(x ** 4) / power ** 2) if power > 0 else math.nan


def gaussian_rms(signal: np.ndarray) -> np.ndarray:
    """RMS of the Gaussian part of each row of a zero-mean ``signal`` (m/s^2): median |x| / 0.6745.

    Gaussian vibration (the contacts' rolling, whatever the film) has median
    ``|x|`` of 0.6745 sigma; sparse strikes ringing a mode move the median
    only by the share of samples they hold, so the estimate keeps the smooth
    part and leaves the strikes' power ``RMS^2 - gaussian_rms^2`` (high by
    about that share where the strikes ring long).  The median is taken over
    at most :data:`GAUSSIAN_SAMPLES` evenly spaced samples of a row (its
    scatter about 3.5 % a window; the whole row's median costs a tenth of the
    window's indicators, this a hundredth).
    """
    step = max(1, signal.shape[1] // GAUSSIAN_SAMPLES)
    magnitudes = np.abs(signal[:, ::step])
    middle = magnitudes.shape[1] // 2
    magnitudes.partition(middle, axis=1)
    return magnitudes[:, middle] / GAUSSIAN_MEDIAN_ABS


def condition_indicators(samples: npt.ArrayLike, rate: float, screw_speed: float, band: tuple[float, float],
                         orders: Sequence[DefectOrder], *, angle_times: npt.ArrayLike | None = None,
                         angles: npt.ArrayLike | None = None) -> ConditionIndicators:
    """Indicators of one window's ``samples`` (m/s^2 at ``rate`` Hz, screw at ``screw_speed`` rad/s).

    ``band`` (Hz) is the analysis band; ``orders`` the actuator's defect
    orders.  ``angle_times`` (s from the first sample) and ``angles`` (rad)
    give the screw angle through the window for order tracking.  The same
    numbers as :func:`condition_indicators_batch` gives this window among others.
    """
    x = np.asarray(samples, dtype=float)
    return condition_indicators_batch(x.reshape(1, -1), rate, [screw_speed], band, orders,
                                      [(angle_times, angles)])[0]


def condition_indicators_batch(samples: np.ndarray, rate: float, screw_speeds: Sequence[float],
                               band: tuple[float, float], orders: Sequence[DefectOrder],
                               tracks: Sequence[tuple[npt.ArrayLike | None, npt.ArrayLike | None]] | None = None,
                               *, spectra: np.ndarray | None = None) -> list[ConditionIndicators]:
    """Indicators of windows of one length and rate at once: ``samples`` is (windows x samples), m/s^2.

    ``screw_speeds`` rad/s per window; ``tracks`` per window the
    ``(angle_times, angles)`` of order tracking (None: none).  The FFTs run
    over the whole array (the cost is the numpy calls, not the windows).
    ``spectra``: the rows' ``numpy.fft.rfft`` when the caller has it already
    (the window builder's band RMS), used instead of transforming again
    (it is not changed); ``samples`` then only gives the windows' length.
    """
    x = np.asarray(samples) if spectra is not None else np.asarray(samples, dtype=float)
    count, n = x.shape
    if n < MIN_SAMPLES or not rate > 0:
        return [NO_INDICATORS] * count
    tracks = tracks if tracks is not None else [(None, None)] * count
    chunk = max(1, BATCH_SAMPLES // n)
    if count > chunk:    # arrays that stay in cache: a few hundred thousand samples at a time
        return [item for start in range(0, count, chunk)
                for item in condition_indicators_batch(
                    x[start:start + chunk], rate, screw_speeds[start:start + chunk], band, orders,
                    tracks[start:start + chunk], spectra=None if spectra is None else spectra[start:start + chunk])]
    # The window mean (DC, gravity) is bin 0, which no band below uses (they start at bin 1 or above).
    spec = np.fft.rfft(x, axis=1) if spectra is None else spectra
    df = rate / n
    lo_bin = max(1, int(math.ceil(band[0] / df)))
    hi_bin = min(spec.shape[1] - 1, int(math.floor(band[1] / df)))
    if hi_bin - lo_bin < 8:
        return [NO_INDICATORS] * count
    kurt, crest, gaussian = _impulsiveness(spec, lo_bin, hi_bin, n)
    shaft_hz = np.abs(np.asarray(screw_speeds, dtype=float)) / (2.0 * math.pi)
    moving = np.isfinite(shaft_hz) & (shaft_hz > 0)
    highest = max((o.order for o in orders), default=MAX_ORDER / 3)
    min_bins = np.maximum(np.ceil(ENVELOPE_HARMONICS * highest * np.where(moving, shaft_hz, 0.0) / df), 8)
    sk, first, last = _demodulation_bands(spec, lo_bin, hi_bin, min_bins.astype(int))
    enveloped = [k for k in range(count) if moving[k] and math.isfinite(sk[k])]
    envelopes = _envelopes(spec, first, last, n, enveloped)
    order_spectra = _order_spectra([envelopes[k] for k in enveloped], n / rate,
                                   [float(shaft_hz[k]) for k in enveloped], [tracks[k] for k in enveloped])
    grids = {k: grid.astype(np.float32) for k, (grid, _) in zip(enveloped, order_spectra)}
    resolutions = {k: resolution for k, (_, resolution) in zip(enveloped, order_spectra)}
    peaks: dict[int, tuple[EnvelopePeak, ...]] = {}
    if enveloped:    # the peaks of the float32 grids kept, all windows at once
        peaks = dict(zip(enveloped, _peaks(np.vstack([grids[k] for k in enveloped]).astype(float),
                                           [resolutions[k] for k in enveloped], orders)))
    out = []
    for k in range(count):
        if k not in grids:
            out.append(ConditionIndicators(float(kurt[k]), float(crest[k]), (), math.nan, (math.nan, math.nan),
                                           math.nan, float(gaussian[k])))
            continue
        out.append(ConditionIndicators(float(kurt[k]), float(crest[k]), peaks[k], float(sk[k]),
                                       (first[k] * df, last[k] * df), resolutions[k], float(gaussian[k]), grids[k]))
    return out


def _impulsiveness(spec: np.ndarray, lo_bin: int, hi_bin: int, n: int
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kurtosis, crest factor and Gaussian RMS of each window's signal in bins ``lo_bin..hi_bin`` of its rfft ``spec``.

    ``n`` samples a window; the Gaussian RMS is :func:`gaussian_rms`'s.
    """
    # Every bin given (zeros outside the band): numpy's irfft pads a shorter input on a slower path.
    in_band = np.zeros_like(spec)
    in_band[:, lo_bin:hi_bin + 1] = spec[:, lo_bin:hi_bin + 1]
    signal = _irfft(in_band, n)
    peak = np.maximum(signal.max(axis=1), -signal.min(axis=1))     # max |x| without an |x| array
    gaussian = gaussian_rms(signal)
    squares = np.square(signal, out=signal)
    power = squares.mean(axis=1)
    with np.errstate(divide='ignore', invalid='ignore'):
        kurt = np.where(power > 0, np.square(squares, out=squares).mean(axis=1) / power ** 2, math.nan)
        crest = np.where(power > 0, peak / np.sqrt(power), math.nan)
    return kurt, crest, gaussian


def _demodulation_bands(spec: np.ndarray, lo_bin: int, hi_bin: int,
                        min_bins: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per window (row of ``spec``), the band of the dyadic tree with the largest spectral kurtosis.

    The fast kurtogram's 1/3-binary tree (Antoni 2007) on the window's own FFT:
    the analysis band ``[lo_bin, hi_bin]`` split into 1, 2, 3, 4, 6, 8, ...
    bands of equal width (:data:`TREE_PARTS`, or down to ``min_bins`` bins of
    that window); each band's complex envelope is its bins shifted to 0 Hz and
    inverse-transformed (every band of every window of a level in one
    inverse FFT), and its spectral kurtosis is ``E|z|^4 / E^2|z|^2 - 2`` (0 for
    Gaussian vibration whatever the width, -1 for a steady tone, large where
    impulses ring).  A band is scored by its SK less :data:`SK_SIGMAS` times
    the scatter the SK of Gaussian vibration has on its ``M`` complex samples,
    ``2 / sqrt(M)``: a narrow band is chosen for impulses that ring in it, not
    for the chance scatter of its few samples (on pure noise the widest band
    wins, and its envelope spectrum is flat).  Returns that score, first and
    last bin of each window's band.
    """
    count = spec.shape[0]
    best_sk = np.full(count, -np.inf)
    first = np.full(count, lo_bin)
    last = np.full(count, hi_bin)
    width = hi_bin - lo_bin + 1
    levels = [(parts, width // parts, 1 << int(math.ceil(math.log2(max(width // parts, 8)))))
              for parts in TREE_PARTS]    # a complex band of ``bins`` bins needs no more than ``size`` samples
    # One buffer for every level's padded bands and one for their |z|^2: the pages are touched once a call,
    # not once a level (a fresh array of a few MB costs its page faults again each time).
    buffer = np.empty(count * max(parts * size for parts, _, size in levels), dtype=complex)
    squares = np.empty(buffer.size)
    for parts, bins, size in levels:
        allowed = bins >= min_bins
        if not allowed.any():
            break
        rows = None if allowed.all() else np.flatnonzero(allowed)    # None: every window; else those served
        served = count if rows is None else rows.size
        envelope = buffer[:served * parts * size].reshape(served, parts, size)
        envelope[..., :bins] = (spec[:, lo_bin:lo_bin + parts * bins] if rows is None
                                else spec[rows, lo_bin:lo_bin + parts * bins]).reshape(served, parts, bins)
        envelope[..., bins:] = 0.0      # each band's bins zero-padded to ``size``
        _ifft_in_place(envelope)
        mean, fourth = _power_moments(envelope, squares[:envelope.size].reshape(envelope.shape))
        with np.errstate(divide='ignore', invalid='ignore'):
            sk_rows = np.where(mean > 0, fourth / mean ** 2 - 2.0, -np.inf)
        sk_rows -= SK_SIGMAS * 2.0 / math.sqrt(bins)      # a lower bound: Gaussian SK scatters by 2 / sqrt(samples)
        if rows is None:
            sk = sk_rows
        else:
            sk = np.full((count, parts), -np.inf)
            sk[rows] = sk_rows
        part = np.argmax(sk, axis=1)
        value = sk[np.arange(count), part]
        better = allowed & (value > best_sk + 1e-12)
        best_sk = np.where(better, value, best_sk)
        first = np.where(better, lo_bin + part * bins, first)
        last = np.where(better, lo_bin + (part + 1) * bins - 1, last)
    best_sk[~np.isfinite(best_sk)] = math.nan
    return best_sk, first, last


def _power_moments(envelope: np.ndarray, power: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``E|z|^2`` and ``E|z|^4`` over the last axis of the complex ``envelope`` (destroys ``envelope``).

    ``|z|^2`` is ``re^2 + im^2`` squared in place over the array's interleaved
    floats (one contiguous pass instead of strided real and imaginary views),
    written into ``power`` (a float array of the envelope's shape) when given.
    """
    interleaved = envelope.view(np.float64)     # re, im, re, im, ... along the last axis
    np.square(interleaved, out=interleaved)
    power = np.add(interleaved[..., 0::2], interleaved[..., 1::2], out=power)
    mean = power.mean(axis=-1)
    return mean, np.square(power, out=power).mean(axis=-1)


def _ifft_in_place(values: np.ndarray) -> np.ndarray:
    """The inverse FFT of complex ``values`` along the last axis, written over them where numpy can (2.0 on)."""
    if _FFT_TAKES_OUT:
        return np.fft.ifft(values, axis=-1, out=values)
    values[...] = np.fft.ifft(values, axis=-1)
    return values


def _irfft(values: np.ndarray, n: int) -> np.ndarray:
    """``numpy.fft.irfft(values, n)`` along the last axis (numpy >= 2: into a fresh buffer, no temporary)."""
    if _FFT_TAKES_OUT:
        return np.fft.irfft(values, n, axis=-1, out=np.empty(values.shape[:-1] + (n,)))
    return np.fft.irfft(values, n, axis=-1)


#: numpy 2's FFTs write into a given ``out`` (numpy 1, e.g. Ubuntu 24.04's, do not).
_FFT_TAKES_OUT = int(np.__version__.split('.')[0]) >= 2


def _envelopes(spec: np.ndarray, first: np.ndarray, last: np.ndarray, n: int,
               rows: Sequence[int]) -> dict[int, np.ndarray]:
    """Hilbert envelope ``|z|`` (m/s^2) of band ``first[k]..last[k]`` of each window ``k`` in ``rows``.

    ``spec`` holds the rfft of ``n`` samples a row; ``z`` is the band's analytic
    signal shifted to 0 Hz and decimated: its bins inverse-transformed (the
    windows whose bands are equally wide in one inverse FFT).
    """
    by_width: dict[int, list[int]] = {}
    for k in rows:
        by_width.setdefault(int(last[k] - first[k] + 1), []).append(k)
    envelopes: dict[int, np.ndarray] = {}
    for width, members in by_width.items():
        size = 1 << int(math.ceil(math.log2(max(2 * width, 8))))
        index = np.array(members)
        shifted = np.zeros((index.size, size), dtype=complex)
        shifted[:, :width] = spec[index[:, None], first[index][:, None] + np.arange(width)]
        shifted = _ifft_in_place(shifted)
        shifted *= 2.0 * size / n
        found = np.abs(shifted)
        envelopes.update(zip(members, found))
    return envelopes


def _order_spectra(envelopes: Sequence[np.ndarray], duration: float, shaft_hz: Sequence[float],
                   tracks: Sequence[tuple[npt.ArrayLike | None, npt.ArrayLike | None]]
                   ) -> list[tuple[np.ndarray, float]]:
    """Envelope power spectrum on :data:`ORDER_GRID` and its resolution in orders, per envelope.

    With the screw angle through the window the envelope is first resampled
    to uniform angle (order tracking, :func:`_angle_resampled`); otherwise
    orders are Hz / ``shaft_hz``.  Envelopes of one length are transformed together.
    """
    ramps: dict[int, np.ndarray] = {}     # 0, 1, ... m - 1 per envelope length m
    resampled = [_angle_resampled(envelope, duration, hz, *track,
                                  ramp=ramps.setdefault(envelope.size, np.arange(envelope.size, dtype=float)))
                 for envelope, hz, track in zip(envelopes, shaft_hz, tracks)]
    by_size: dict[int, list[int]] = {}
    for k, (values, _) in enumerate(resampled):
        by_size.setdefault(values.size, []).append(k)
    out: list[tuple[np.ndarray, float]] = [(np.zeros(0), math.nan)] * len(resampled)
    for m, members in by_size.items():
        values = np.vstack([resampled[k][0] for k in members])
        values -= values.mean(axis=1, keepdims=True)
        power = np.abs(np.fft.rfft(values, axis=1)) ** 2 / m ** 2
        bins = ramps[m][:power.shape[1]]     # every resampled envelope keeps its length, so its ramp is there
        for k, row in zip(members, power):
            revolutions = resampled[k][1]
            out[k] = (np.interp(ORDER_GRID, bins / revolutions, row, right=math.nan), 1.0 / revolutions)
    return out


def _angle_resampled(envelope: np.ndarray, duration: float, shaft_hz: float, angle_times: npt.ArrayLike | None,
                     angles: npt.ArrayLike | None, *, ramp: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """The envelope at uniform screw angle where the angle through the window is known, and the revolutions.

    Otherwise the envelope as it is and ``duration * shaft_hz`` revolutions.
    ``ramp``: ``0, 1, ... m - 1`` (float) for an envelope of ``m`` samples, when the caller keeps one.
    """
    m = envelope.size
    revolutions = duration * shaft_hz
    values = envelope
    if angle_times is not None and angles is not None:
        ramp = np.arange(m, dtype=float) if ramp is None else ramp
        t, a = np.asarray(angle_times, dtype=float), np.asarray(angles, dtype=float)
        last_time = (m - 1) * (duration / m)
        if t.size >= 2 and (t[1:] > t[:-1]).all() and t[0] <= 0.1 * duration \
                and t[-1] >= last_time - 0.1 * duration:
            times = ramp * (duration / m)
            angle = np.interp(times, t, a)
            angle -= np.interp(0.0, t, a)
            np.abs(angle, out=angle)
            if (angle[1:] > angle[:-1]).all():
                # np.linspace(angle[0], angle[-1], m), the same arithmetic on the kept ramp
                uniform = ramp * ((angle[-1] - angle[0]) / (m - 1))
                uniform += angle[0]
                uniform[-1] = angle[-1]
                values = np.interp(uniform, angle, envelope)
                revolutions = (angle[-1] - angle[0]) / (2.0 * math.pi) * m / max(m - 1, 1)
    return values, revolutions


def envelope_floor(grid: np.ndarray) -> float:
    """Floor of an order spectrum on :data:`ORDER_GRID`: its median above :data:`FLOOR_LOWEST_ORDER`."""
    return float(_floors(np.asarray(grid, dtype=float).reshape(1, -1))[0])


def _floors(grids: np.ndarray) -> np.ndarray:
    """:func:`envelope_floor` of each row."""
    part = grids[:, ORDER_GRID >= FLOOR_LOWEST_ORDER]
    # An order spectrum is NaN only above the highest order it holds: the median of each row's finite head,
    # rows of one head length at once (np.nanmedian goes row by row); other rows the general way.
    finite = np.isfinite(part)
    heads = finite.sum(axis=1)
    plain = finite[np.arange(part.shape[0]), np.maximum(heads - 1, 0)] & (heads > 0)
    plain &= ~finite[np.arange(part.shape[0]), np.minimum(heads, part.shape[1] - 1)] | (heads == part.shape[1])
    floors = np.full(part.shape[0], math.nan)
    for head in np.unique(heads[plain]).tolist():
        rows = np.flatnonzero(plain & (heads == head))
        head_rows = part[rows, :head]
        if np.isfinite(head_rows).all():
            floors[rows] = np.median(head_rows, axis=1)
        else:
            plain[rows] = False
    other = np.flatnonzero(~plain)
    if other.size:
        with np.errstate(invalid='ignore'), warnings.catch_warnings():
            warnings.simplefilter('ignore', RuntimeWarning)     # an all-NaN row: no floor
            floors[other] = np.nanmedian(part[other], axis=1)
    return floors


def order_spectrum_db(grid: np.ndarray) -> np.ndarray:
    """An order spectrum in dB over its floor (NaN where it holds nothing)."""
    grids = np.asarray(grid, dtype=float)
    return _db(grids.reshape(1, -1)).reshape(grids.shape)


def _db(grids: np.ndarray) -> np.ndarray:
    """:func:`order_spectrum_db` of each row."""
    with np.errstate(divide='ignore', invalid='ignore'):
        return 10.0 * np.log10(grids / _floors(grids)[:, None])


def envelope_peaks(grid: np.ndarray, resolution: float, orders: Sequence[DefectOrder],
                   min_db: float = REPORT_DB, count: int = MAX_PEAKS) -> tuple[EnvelopePeak, ...]:
    """Lines of an order spectrum at least ``min_db`` over its floor, labelled, in order of their order.

    The largest ``count`` local maxima, and the largest level near each
    defect order's fundamental (within ``max(ORDER_TOLERANCE o, resolution / 2)``)
    when it reaches ``min_db``: a line at a defect order is reported even where
    larger lines elsewhere fill the ``count``.  Maxima closer than the
    resolution to a larger one are the same line.
    """
    return _peaks(np.asarray(grid, dtype=float).reshape(1, -1), [resolution], orders, min_db, count)[0]


def _peaks(grids: np.ndarray, resolutions: Sequence[float], orders: Sequence[DefectOrder],
           min_db: float = REPORT_DB, count: int = MAX_PEAKS) -> list[tuple[EnvelopePeak, ...]]:
    """:func:`envelope_peaks` of each row (dB, maxima and defect-order levels for all rows at once)."""
    db = _db(grids)
    lowest = 0.5 * min((o.order for o in orders), default=1.0)
    padded = np.where(np.isfinite(db) & (ORDER_GRID >= lowest), db, -np.inf)
    local = np.zeros(padded.shape, dtype=bool)
    local[:, 1:-1] = (padded[:, 1:-1] >= padded[:, :-2]) & (padded[:, 1:-1] > padded[:, 2:]) & (
        padded[:, 1:-1] >= min_db)
    # The local maxima of all rows, each row's from the largest level down (ties in grid order).
    rows, columns = np.nonzero(local)
    by_level = np.lexsort((columns, -padded[rows, columns], rows))
    rows, columns = rows[by_level], columns[by_level]
    row_starts = np.searchsorted(rows, np.arange(len(resolutions) + 1)).tolist()
    columns_list = columns.tolist()
    # The largest level within reach of each defect order's fundamental, all rows at once.
    span_first, span_stop = _order_windows(orders, np.asarray(resolutions, dtype=float))
    span_top = _span_argmax(padded, span_first, span_stop)
    span_open = (span_stop > span_first).tolist()
    span_top_list = span_top.tolist()
    span_level = (padded[np.arange(padded.shape[0])[:, None], span_top] >= min_db).tolist()
    labels: dict[tuple[int, float], str] = {}
    out: list[tuple[EnvelopePeak, ...]] = []
    for row, resolution in enumerate(resolutions):
        candidates = columns_list[row_starts[row]:row_starts[row + 1]][:4 * count]
        separation = max(resolution, 2 * ORDER_STEP) / ORDER_STEP
        chosen: list[int] = []
        for k in candidates:
            if all(abs(k - j) > separation for j in chosen):
                chosen.append(k)
                if len(chosen) == count:
                    break
        for k, is_open, reached in zip(span_top_list[row], span_open[row], span_level[row]):
            if is_open and reached and k not in chosen:
                chosen.append(k)
        if not chosen:
            out.append(())
            continue
        chosen.sort()
        key_resolution = round(resolution, 6)
        peaks = []
        for k, level in zip(chosen, padded[row, chosen].tolist()):
            key = (k, key_resolution)
            if key not in labels:
                labels[key] = label_order(_GRID_ORDERS[k], orders, resolution / 2)
            peaks.append(EnvelopePeak(_GRID_ORDERS[k], level, labels[key]))
        out.append(tuple(peaks))
    return out


def _span_argmax(levels: np.ndarray, first: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Per row and span, the index of the largest of ``levels[row, first:stop]``.

    The first of equals; ``first`` where the span is empty.
    """
    length = max(int((stop - first).max(initial=0)), 1)
    index = first[..., None] + np.arange(length)
    values = levels[np.arange(levels.shape[0])[:, None, None], np.minimum(index, levels.shape[1] - 1)]
    values[index >= stop[..., None]] = -np.inf
    return first + np.argmax(values, axis=2)


def _order_windows(orders: Sequence[DefectOrder], resolutions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grid index ranges ``[first, stop)`` near each defect order's fundamental, per resolution.

    Within ``max(ORDER_TOLERANCE o, resolution / 2)`` of order ``o``; arrays (resolutions x orders).
    """
    order = np.array([item.order for item in orders], dtype=float).reshape(1, -1)
    reach = np.maximum(ORDER_TOLERANCE * order, resolutions.reshape(-1, 1) / 2)
    first = np.maximum(np.ceil((order - reach) / ORDER_STEP - 1e-9).astype(np.int64), 0)
    stop = np.minimum(np.floor((order + reach) / ORDER_STEP + 1e-9).astype(np.int64) + 1, ORDER_GRID.size)
    return first, stop
