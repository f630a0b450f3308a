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
* the **demodulation band**, chosen from the data by spectral kurtosis (Antoni
  2006-2007; the fast kurtogram's dyadic tree): the analysis band and its
  halves, quarters, ... down to bands still wide enough to carry the envelope
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

Costs about a band-RMS FFT plus one inverse FFT per band of the tree (each as
long as its band), a few ms for a 1 s window at 25.6 kHz.  Pure numpy.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from ..physics.defect_orders import label_order, ORDER_TOLERANCE

if TYPE_CHECKING:
    from collections.abc import Sequence

    import numpy.typing as npt

    from ..physics.defect_orders import DefectOrder

__all__ = ['ConditionIndicators', 'ENVELOPE_HARMONICS', 'EnvelopePeak', 'FLOOR_LOWEST_ORDER', 'MAX_ORDER',
           'MAX_PEAKS', 'MAX_TREE_LEVEL', 'ORDER_GRID', 'ORDER_STEP', 'REPORT_DB', 'condition_indicators',
           'envelope_floor', 'envelope_peaks', 'kurtosis', 'order_spectrum_db']

#: Highest screw order the envelope spectrum is kept to (3 harmonics of the default screw raceway order 6.25,
#: 3 of a support bearing's BPFI near 7.4).
MAX_ORDER = 24.0
#: Step of the fixed order grid, orders.
ORDER_STEP = 0.025
#: The fixed order grid the envelope spectra are kept on (0 to :data:`MAX_ORDER`).
ORDER_GRID = np.arange(0.0, MAX_ORDER + ORDER_STEP / 2, ORDER_STEP)
#: Harmonics of the highest defect order a demodulation band must be wide enough to carry.
ENVELOPE_HARMONICS = 2.5
#: Deepest level of the dyadic band tree (2^level bands), the fast kurtogram's usual depth for 1 s windows.
MAX_TREE_LEVEL = 5
#: Lowest order of the floor's median (below it the envelope holds the run's slow amplitude changes).
FLOOR_LOWEST_ORDER = 1.0
#: dB over the floor a local maximum needs to be reported as an envelope peak.
REPORT_DB = 6.0
#: Envelope peaks reported per window (the largest).
MAX_PEAKS = 5
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


def condition_indicators(samples: npt.ArrayLike, rate: float, screw_speed: float, band: tuple[float, float],
                         orders: Sequence[DefectOrder], *, angle_times: npt.ArrayLike | None = None,
                         angles: npt.ArrayLike | None = None, spectrum: np.ndarray | None = None
                         ) -> ConditionIndicators:
    """Indicators of one window's ``samples`` (m/s^2 at ``rate`` Hz, screw at ``screw_speed`` rad/s).

    ``band`` (Hz) is the analysis band; ``orders`` the actuator's defect
    orders.  ``angle_times`` (s from the first sample) and ``angles`` (rad)
    give the screw angle through the window for order tracking.  ``spectrum``
    is ``numpy.fft.rfft`` of the mean-free samples when the caller has it.
    """
    x = np.asarray(samples, dtype=float)
    n = x.size
    if n < MIN_SAMPLES or not rate > 0:
        return NO_INDICATORS
    spec = np.fft.rfft(x - x.mean()) if spectrum is None else spectrum
    df = rate / n
    lo_bin = max(1, int(math.ceil(band[0] / df)))
    hi_bin = min(spec.size - 1, int(math.floor(band[1] / df)))
    if hi_bin - lo_bin < 8:
        return NO_INDICATORS
    in_band = np.zeros(spec.size, dtype=complex)
    in_band[lo_bin:hi_bin + 1] = spec[lo_bin:hi_bin + 1]
    signal = np.fft.irfft(in_band, n)
    rms = math.sqrt(float(np.mean(signal * signal)))
    kurt = kurtosis(signal)
    crest = float(np.max(np.abs(signal)) / rms) if rms > 0 else math.nan
    shaft_hz = abs(screw_speed) / (2.0 * math.pi)
    if not (shaft_hz > 0 and math.isfinite(shaft_hz)):
        return ConditionIndicators(kurt, crest, (), math.nan, (math.nan, math.nan), math.nan)
    highest = max((o.order for o in orders), default=MAX_ORDER / 3)
    min_bins = max(int(math.ceil(ENVELOPE_HARMONICS * highest * shaft_hz / df)), 8)
    sk, (first, last) = _demodulation_band(spec, lo_bin, hi_bin, min_bins)
    envelope = np.abs(_complex_envelope(spec, first, last, n))
    duration = n / rate
    grid, resolution = _order_spectrum(envelope, duration, shaft_hz, angle_times, angles)
    peaks = envelope_peaks(grid, resolution, orders)
    return ConditionIndicators(kurt, crest, peaks, sk, (first * df, last * df), resolution, grid.astype(np.float32))


def _demodulation_band(spec: np.ndarray, lo_bin: int, hi_bin: int, min_bins: int) -> tuple[float, tuple[int, int]]:
    """The band of the dyadic tree over bins ``[lo_bin, hi_bin]`` with the largest spectral kurtosis, and that SK.

    The fast kurtogram's dyadic tree (Antoni 2007) on the window's own FFT:
    level k splits the analysis band into 2^k bands of equal width (down to
    :data:`MAX_TREE_LEVEL` or to ``min_bins`` bins); each band's complex
    envelope is its bins shifted to 0 Hz and inverse-transformed (all bands of
    a level in one 2-D inverse FFT), and its spectral kurtosis is
    ``E|z|^4 / E^2|z|^2 - 2`` (0 for Gaussian vibration whatever the width,
    -1 for a steady tone, large where impulses ring).
    """
    best_sk, best = -math.inf, (lo_bin, hi_bin)
    width = hi_bin - lo_bin + 1
    for level in range(MAX_TREE_LEVEL + 1):
        parts = 2 ** level
        bins = width // parts
        if bins < min_bins:
            break
        size = 1 << int(math.ceil(math.log2(max(bins, 8))))   # a complex band of ``bins`` bins needs no more
        shifted = np.zeros((parts, size), dtype=complex)
        shifted[:, :bins] = spec[lo_bin:lo_bin + parts * bins].reshape(parts, bins)
        power = np.abs(np.fft.ifft(shifted, axis=1)) ** 2
        mean = power.mean(axis=1)
        with np.errstate(divide='ignore', invalid='ignore'):
            sk = np.where(mean > 0, (power ** 2).mean(axis=1) / mean ** 2 - 2.0, -np.inf)
        k = int(np.argmax(sk))
        if sk[k] > best_sk + 1e-12:
            best_sk, best = float(sk[k]), (lo_bin + k * bins, lo_bin + (k + 1) * bins - 1)
    return best_sk, best


def _complex_envelope(spec: np.ndarray, first: int, last: int, n: int) -> np.ndarray:
    """The band's analytic signal shifted to 0 Hz and decimated, m/s^2: bins ``first..last`` inverse-transformed.

    ``spec`` is the rfft of ``n`` samples; ``|z|`` is the band's Hilbert envelope.
    """
    count = last - first + 1
    size = 1 << int(math.ceil(math.log2(max(2 * count, 8))))
    shifted = np.zeros(size, dtype=complex)
    shifted[:count] = spec[first:last + 1]
    return np.fft.ifft(shifted) * (2.0 * size / n)


def _order_spectrum(envelope: np.ndarray, duration: float, shaft_hz: float, angle_times: npt.ArrayLike | None,
                    angles: npt.ArrayLike | None) -> tuple[np.ndarray, float]:
    """Envelope power spectrum on :data:`ORDER_GRID` and its resolution in orders.

    With the screw angle through the window the envelope is first resampled
    to uniform angle (order tracking); otherwise orders are Hz / ``shaft_hz``.
    """
    m = envelope.size
    times = np.arange(m) * (duration / m)
    revolutions = duration * shaft_hz
    values = envelope
    if angle_times is not None and angles is not None:
        t, a = np.asarray(angle_times, dtype=float), np.asarray(angles, dtype=float)
        if t.size >= 2 and np.all(np.diff(t) > 0) and t[0] <= times[0] + 0.1 * duration \
                and t[-1] >= times[-1] - 0.1 * duration:
            angle = np.abs(np.interp(times, t, a) - np.interp(0.0, t, a))
            if np.all(np.diff(angle) > 0):
                uniform = np.linspace(angle[0], angle[-1], m)
                values = np.interp(uniform, angle, envelope)
                revolutions = (angle[-1] - angle[0]) / (2.0 * math.pi) * m / max(m - 1, 1)
    power = np.abs(np.fft.rfft(values - values.mean())) ** 2 / m ** 2
    bin_orders = np.arange(power.size) / revolutions
    grid = np.interp(ORDER_GRID, bin_orders, power, right=math.nan)
    return grid, 1.0 / revolutions


def envelope_floor(grid: np.ndarray) -> float:
    """Floor of an order spectrum on :data:`ORDER_GRID`: its median above :data:`FLOOR_LOWEST_ORDER`."""
    part = grid[(ORDER_GRID >= FLOOR_LOWEST_ORDER) & np.isfinite(grid)]
    return float(np.median(part)) if part.size else math.nan


def order_spectrum_db(grid: np.ndarray) -> np.ndarray:
    """An order spectrum in dB over its floor (NaN where it holds nothing)."""
    floor = envelope_floor(grid)
    with np.errstate(divide='ignore', invalid='ignore'):
        return 10.0 * np.log10(np.asarray(grid, dtype=float) / floor)


def envelope_peaks(grid: np.ndarray, resolution: float, orders: Sequence[DefectOrder],
                   min_db: float = REPORT_DB, count: int = MAX_PEAKS) -> tuple[EnvelopePeak, ...]:
    """Lines of an order spectrum at least ``min_db`` over its floor, labelled, in order of their order.

    The largest ``count`` local maxima, and the largest level near each
    defect order's fundamental (within ``max(ORDER_TOLERANCE o, resolution / 2)``)
    when it reaches ``min_db``: a line at a defect order is reported even where
    larger lines elsewhere fill the ``count``.  Maxima closer than the
    resolution to a larger one are the same line.
    """
    db = order_spectrum_db(grid)
    valid = np.isfinite(db) & (ORDER_GRID >= 0.5 * min((o.order for o in orders), default=1.0))
    if not valid.any():
        return ()
    padded = np.where(valid, db, -np.inf)
    local = np.flatnonzero((padded[1:-1] >= padded[:-2]) & (padded[1:-1] > padded[2:]) & (padded[1:-1] >= min_db)) + 1
    separation = max(resolution, 2 * ORDER_STEP)
    chosen: list[int] = []
    for k in sorted(local.tolist(), key=lambda k: -padded[k]):
        if all(abs(ORDER_GRID[k] - ORDER_GRID[j]) > separation for j in chosen):
            chosen.append(k)
        if len(chosen) == count:
            break
    for item in orders:
        near = np.flatnonzero(np.abs(ORDER_GRID - item.order) <= max(ORDER_TOLERANCE * item.order, resolution / 2))
        if near.size:
            k = int(near[np.argmax(padded[near])])
            if padded[k] >= min_db and all(abs(ORDER_GRID[k] - ORDER_GRID[j]) > ORDER_STEP / 2 for j in chosen):
                chosen.append(k)
    return tuple(EnvelopePeak(float(ORDER_GRID[k]), float(padded[k]),
                              label_order(float(ORDER_GRID[k]), orders, resolution / 2))
                 for k in sorted(chosen))
