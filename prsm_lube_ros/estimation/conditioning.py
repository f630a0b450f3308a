# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Signal conditioning before the window RMS: DC and gravity out, the analysis band, spectrum segments.

The RMS of Eq. 22 is the thread-contact vibration; what an accelerometer also
records is not:

* **DC**: gravity on a DC-coupled axis (9.81 m/s^2 on a vertical one, and
  every ``sensor_msgs/Imu`` includes it), offsets of the sensor and its
  amplifier;
* **content outside the band**: what a recording carries above some frequency
  depends on its sample rate, so the same vibration recorded at 4 kHz and at
  51.2 kHz gives different raw RMS.

So the window RMS is that of one band, ``AnalysisBand.low`` to
``AnalysisBand.high`` Hz, whatever the rate: each window's samples are
transformed (``numpy.fft.rfft``, rectangular window) and the mean square is
summed over the bins inside the band (Parseval).  The bins lie at multiples of
1 / window length (1 Hz for 1 s windows) whatever the sample rate, so a
recording at 4 kHz and one at 51.2 kHz give the RMS of the same bins; bin 0,
the window mean (DC, gravity), is always out.  ``low`` is
:data:`HIGHPASS_CORNER`, below the lowest shaft order of interest (order 1 of
the screw at the paper's slowest 100 r/min is 1.67 Hz, bin 1 or 2 of a 1 s
window: kept).  ``high`` is by default :data:`ANTI_ALIAS_MARGIN` of the
Nyquist frequency of the first recording calibrated (the whole band the
acquisition gives, its anti-alias filter left out), or what ``calibrate
--band-high`` sets (:data:`COMMON_BAND_HIGH`, 1600 Hz, lets one calibration
serve every rate from the paper's 4 kHz up).  Nothing is carried from one window to the next,
so gaps and clock resets need no care.

The band is stored in the calibration (``band:``) and assessment uses the
calibration's band; a recording whose sample rate cannot cover it (below
:meth:`AnalysisBand.min_sample_rate`) is refused.  A calibration file without
``band:`` was fitted on the raw RMS (DC included, 0 Hz to half the sample rate
of its recordings), and is assessed that way (:data:`RAW_BAND_TEXT`).

Streams that publish samples rather than windows (the IMU source of the
sensor bridge) take gravity out with :class:`HighPassFilter`: a Butterworth
high-pass at :data:`HIGHPASS_CORNER` (order :data:`HIGHPASS_ORDER`) whose state
carries from one block to the next when the next block starts one sample
period after the previous one ends, and starts afresh (at the steady state of
the block's mean, so the gravity step gives no transient) after a gap, a rate
change or a reset.

:func:`spectrum_segment` chooses the Welch segment length for the spectra of
diagnose and its report from the sample rate and the lowest rotation order of
interest at the lowest speed.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math

import numpy as np

from ..errors import InputError

__all__ = ['ANTI_ALIAS_MARGIN', 'AnalysisBand', 'COMMON_BAND_HIGH', 'CONTINUITY_BLOCK_SHARE', 'CONTINUITY_PERIODS',
           'DEFAULT_BAND', 'HIGHPASS_CORNER', 'HIGHPASS_ORDER', 'HighPassFilter', 'LOWEST_ORDER_FREQUENCY',
           'RAW_BAND_TEXT', 'band_mean_square', 'band_mean_squares', 'band_text', 'rate_refusal', 'spectrum_segment']

#: Lower band edge and high-pass corner, Hz: 0.3 x shaft order 1 at the paper's slowest 100 r/min.
HIGHPASS_CORNER = 0.5
#: Butterworth order of the streaming high-pass (the IMU source's gravity removal).
HIGHPASS_ORDER = 2
#: Upper band edge that every rate from the paper's 4 kHz up covers, Hz (0.8 x its Nyquist frequency): the
#: band to ask for (``calibrate --band-high 1600``) when one calibration must serve recordings at several rates.
COMMON_BAND_HIGH = 1600.0
#: The upper edge is at most this fraction of the Nyquist frequency (room for the acquisition's anti-alias filter).
ANTI_ALIAS_MARGIN = 0.8
#: Lowest rotation order of interest at the lowest speed, Hz: shaft order 1 at the paper's slowest 100 r/min.
LOWEST_ORDER_FREQUENCY = 100.0 / 60.0
#: How the RMS of a calibration without ``band:`` (written before bands existed) was computed.
RAW_BAND_TEXT = 'raw RMS: DC included, 0 Hz to half the sample rate of the recording (calibration without band)'
#: A block continues the previous one when its stamp is within this many sample periods of the expected one ...
CONTINUITY_PERIODS = 2.0
#: ... or within this fraction of the previous block's duration (stamp jitter of block publishers).
CONTINUITY_BLOCK_SHARE = 0.25


@dataclass(frozen=True)
class AnalysisBand:
    """The band the window RMS is computed in, Hz (see module doc).

    ``high`` NaN means "not chosen yet": :meth:`resolved` takes
    ``margin x rate / 2`` for the first sample rate met (the whole band the
    acquisition gives: real accelerometers carry most of their vibration well
    above the paper's 1.6 kHz, e.g. bearings at 25.6 kHz).
    """

    low: float = HIGHPASS_CORNER
    high: float = math.nan
    margin: float = ANTI_ALIAS_MARGIN

    def __post_init__(self) -> None:
        """Reject bands that hold nothing."""
        if not (math.isfinite(self.low) and self.low > 0):
            raise InputError(f'analysis band: lower edge {self.low!r} Hz must be a number > 0')
        if not (math.isnan(self.high) or (math.isfinite(self.high) and self.high > self.low)):
            raise InputError(f'analysis band: upper edge {self.high!r} Hz must lie above the lower {self.low:g} Hz')
        if not 0 < self.margin <= 1:
            raise InputError(f'analysis band: anti-alias margin {self.margin!r} must lie in (0, 1]')

    @property
    def chosen(self) -> bool:
        """Whether the upper edge is fixed (not waiting for the first sample rate)."""
        return not math.isnan(self.high)

    def resolved(self, rate: float) -> AnalysisBand:
        """This band with its upper edge chosen for sample rate ``rate`` (Hz) if it is not chosen yet."""
        if self.chosen:
            return self
        return replace(self, high=self.margin * rate / 2.0)

    @property
    def min_sample_rate(self) -> float:
        """Lowest sample rate, Hz, that covers the band with the anti-alias margin (0 while not chosen)."""
        return 2.0 * self.high / self.margin if self.chosen else 0.0

    @property
    def text(self) -> str:
        """The band in words: ``0.5-1600 Hz (per window ...; sample rate at least 4000 Hz)``."""
        high = f'{self.high:g}' if self.chosen else 'auto'
        return (f'{self.low:g}-{high} Hz (per window: FFT bins in the band, the window mean out; '
                f'sample rate at least {self.min_sample_rate:g} Hz)')

    def as_dict(self) -> dict:
        """Mapping for the calibration file's ``band:``."""
        return {'low_hz': float(self.low), 'high_hz': float(self.high), 'anti_alias_margin': float(self.margin),
                'min_sample_rate_hz': float(self.min_sample_rate),
                'method': 'rfft of each window, mean square of the bins from low_hz to high_hz (Parseval)'}

    @classmethod
    def from_dict(cls, data: dict) -> AnalysisBand:
        """Inverse of :meth:`as_dict`."""
        return cls(low=float(data['low_hz']), high=float(data['high_hz']),
                   margin=float(data.get('anti_alias_margin', ANTI_ALIAS_MARGIN)))


#: The band of new calibrations: DC out, upper edge chosen from the first sample rate.
DEFAULT_BAND = AnalysisBand()


def band_text(band: AnalysisBand | None) -> str:
    """The band in words; :data:`RAW_BAND_TEXT` for None (raw RMS)."""
    return band.text if band is not None else RAW_BAND_TEXT


def rate_refusal(band: AnalysisBand, rate: float) -> str:
    """One line: a recording at ``rate`` Hz cannot give the RMS in ``band``, and how to choose a band it covers."""
    return (f'sample rate {rate:g} Hz cannot cover the analysis band {band.low:g}-{band.high:g} Hz '
            f'(needs at least {band.min_sample_rate:g} Hz: upper edge at most {band.margin:g} x the Nyquist '
            f'frequency); record faster, or calibrate in a band every recording covers (prsm-lube calibrate '
            f'--band-high HZ, at most {band.margin * rate / 2:g} Hz for this rate; {COMMON_BAND_HIGH:g} Hz serves '
            f'every rate from {2 * COMMON_BAND_HIGH / band.margin:g} Hz up)')


def band_mean_square(samples: np.ndarray, rate: float, band: AnalysisBand) -> float:
    """Mean square, (m/s^2)^2, of ``samples`` (one window at ``rate`` Hz) in ``band`` (Parseval over rfft bins).

    ``sum x^2 / N = (|X_0|^2 + 2 sum_{0<k<N/2} |X_k|^2 + |X_{N/2}|^2) / N^2``; only the
    bins with ``low <= k rate / N <= high`` are summed (bin 0, the mean, never).
    """
    n = samples.size
    if n < 2:
        return math.nan
    return float(band_mean_squares(np.fft.rfft(samples).reshape(1, -1), n, rate, band)[0])


def band_mean_squares(spectra: np.ndarray, n: int, rate: float, band: AnalysisBand) -> np.ndarray:
    """:func:`band_mean_square` of windows of ``n`` samples at ``rate`` Hz from their rfft, one window a row.

    The window builder transforms the windows of a size together once and
    hands the same spectra to the condition indicators.
    """
    frequencies = np.arange(spectra.shape[1]) * (rate / n)
    weights = np.where((frequencies >= band.low) & (frequencies <= band.high), 2.0, 0.0)
    weights[0] = 0.0
    if n % 2 == 0:
        weights[-1] /= 2.0
    power = spectra.real ** 2 + spectra.imag ** 2
    return (power @ weights) / (n * n)


class HighPassFilter:
    """Streaming Butterworth high-pass over consecutive blocks (see module doc): state carried, reset on gaps."""

    def __init__(self, corner: float = HIGHPASS_CORNER, order: int = HIGHPASS_ORDER):
        """``corner`` in Hz; imports :mod:`scipy.signal` here, not in the first block's callback of a node."""
        import scipy.signal  # noqa: F401
        if not (math.isfinite(corner) and corner > 0 and order >= 1):
            raise InputError(f'high-pass: corner {corner!r} Hz must be > 0 and order {order!r} >= 1')
        self.corner, self.order = float(corner), int(order)
        self._design: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self._state: np.ndarray | None = None
        self._next_stamp = math.nan        # s, where a block continuing the last one starts
        self._rate = math.nan
        self._tolerance = 0.0

    def reset(self) -> None:
        """Start afresh at the next block (clock reset, source restarted)."""
        self._state = None
        self._next_stamp = math.nan

    def _sections(self, rate: float) -> tuple[np.ndarray, np.ndarray]:
        design = self._design.get(rate)
        if design is None:
            from scipy.signal import butter, sosfilt_zi
            sos = butter(self.order, self.corner, 'highpass', fs=rate, output='sos')
            design = self._design[rate] = (sos, sosfilt_zi(sos))
        return design

    def apply(self, samples: np.ndarray, stamps: np.ndarray, rates: np.ndarray,
              starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
        """Filtered copy (float64) of ``samples``; blocks ``[starts[i], starts[i] + counts[i])`` in time order.

        ``stamps`` (s) and ``rates`` (Hz) are those of each block; samples outside the blocks are copied as
        they are.  Consecutive blocks are filtered as one signal when they join (see module doc).
        """
        out = np.array(samples, dtype=np.float64)
        if starts.size == 0:
            return out
        from scipy.signal import sosfilt
        ends = stamps + counts / rates
        expected = np.concatenate(([self._next_stamp], ends[:-1]))
        previous_rate = np.concatenate(([self._rate], rates[:-1]))
        tolerance = np.maximum(CONTINUITY_PERIODS / rates,
                               CONTINUITY_BLOCK_SHARE * np.concatenate(([self._tolerance], counts[:-1] / rates[:-1])))
        joined = (np.abs(stamps - expected) <= tolerance) & (rates == previous_rate)
        # One sosfilt call per stretch of blocks adjacent in ``samples``; the state restarts where blocks do not join.
        adjacent = np.ones(starts.size, bool)
        adjacent[1:] = starts[1:] == starts[:-1] + counts[:-1]
        breaks = np.flatnonzero(~(joined & adjacent)).tolist()
        segments = breaks if breaks and breaks[0] == 0 else [0] + breaks
        state = self._state
        for first, stop in zip(segments, segments[1:] + [starts.size]):
            sos, zi = self._sections(float(rates[first]))
            lo, hi = int(starts[first]), int(starts[stop - 1] + counts[stop - 1])
            if state is None or not joined[first]:
                state = zi * float(np.mean(out[lo:int(starts[first] + counts[first])]))
            out[lo:hi], state = sosfilt(sos, out[lo:hi], zi=state)
        self._state = state
        self._next_stamp = float(ends[-1])
        self._rate = float(rates[-1])
        self._tolerance = float(counts[-1] / rates[-1])
        return out


def spectrum_segment(sample_rate: float, lowest_frequency: float, max_samples: int | None = None,
                     bins_per_interval: float = 4.0) -> int:
    """Welch segment length (samples, a power of 2) that resolves ``lowest_frequency``.

    ``lowest_frequency`` (Hz) is the lowest rotation order of interest at the
    lowest speed (also the spacing of neighbouring orders there): the bin width
    ``sample_rate / nperseg`` is at most ``lowest_frequency / bins_per_interval``,
    so two neighbouring orders fall ``bins_per_interval`` bins apart: 4 puts the
    first null of Welch's Hann window (2 bins from a line) midway between them.
    At most ``max_samples`` (the samples of one window) and at least 64.
    """
    if not (sample_rate > 0 and lowest_frequency > 0):
        raise InputError(f'spectrum: sample rate {sample_rate!r} Hz and lowest frequency '
                         f'{lowest_frequency!r} Hz must be > 0')
    needed = sample_rate * bins_per_interval / lowest_frequency
    segment = 1 << max(6, math.ceil(math.log2(needed)))
    if max_samples is not None:
        segment = min(segment, 1 << max(3, int(math.floor(math.log2(max(max_samples, 8))))))
    return int(segment)
