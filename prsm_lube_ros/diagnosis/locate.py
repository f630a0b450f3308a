# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Where recording and model disagree: residual tests against covariates and the spectrum.

Residuals are the baseline's ``ln A_model - ln A`` per window.  For each
covariate a test says how much of the residual variance it carries and how
strongly, with windows of one run treated as correlated:

* ``position`` — nut position inside runs (residual and position centred per
  run, so only the within-run trend counts);
* ``revolutions``, ``time`` and ``temperature`` — linear trend over all
  windows (temperature only when it spans ``DiagnosisRules.min_temperature_span`` K,
  the floor the thermal candidate needs too: less is the sensor's noise);
* ``speed`` and ``load`` — residual means per operating level (what the
  model's speed and load laws leave over);
* ``direction`` — out and back at the same speed and load (return runs:
  ``direction`` -1): run-level residuals of returns minus outs, paired by
  condition, t test (:func:`_direction_test`).

Trends use a cluster-robust (by run) standard error and a t test with
``runs - 1`` degrees of freedom; level means use an F test with the effective
sample size of :func:`~.fitting.effective_sample_size`.

A straight line misses arches, steps and curvature, so every continuous
covariate (position within runs, revolutions, time, temperature) is also
tested for *any* shape: residual means in ``DiagnosisRules.bins`` quantile bins, their
equality tested by a Wald test with a run-clustered (sandwich) covariance and
the small-sample Hotelling correction ``F = W (G - q) / (q (G - 1))`` on
``(q, G - q)`` degrees of freedom, G runs and q = bins - 1, so the runs, not
the windows, are the units of evidence.  A covariate that moves mostly between
runs (revolutions, time and temperature usually do) puts few runs in a bin,
which makes that covariance far too small; it is tested on run means instead,
binned by run (up to ``DiagnosisRules.bins`` bins of at least three runs), with a one-way
ANOVA F on ``(bins - 1, runs - bins)`` degrees of freedom.  The bin profile is reported as the
amplitude relative to its mean per bin, with its shape in words (an arch, a
trough, a steady rise or fall, or a step) and, for nut position, in how many
runs the same shape is seen.

The spectral test looks for lines at fixed frequencies: narrow peaks standing
out of their neighbourhood at the same frequency at two screw speeds at least
(so not rotation orders, which move with speed) whose power stays put wherever
it can be measured (the line at least as strong as the floor under it) and wherever a line of that power would
stand out (so not two orders that meet on one bin at two speeds, nor a mode ringing at two), while the total power
changes with speed (so not a resonance of the thread-contact excitation, which scales with it).  That is the
signature of vibration from elsewhere.  Any two speeds, not the two lowest: a
mode the orders pass raises the floor around the line at the speeds where it
rings, yet the line's power is still measured there.

The same spectra are order-tracked for a structural mode: a band standing out
at the same frequency in Hz at two speeds or more while the rotation orders
move past it (so a frequency where no order stays), at three speeds or more (two speeds can put two
different orders on one bin), whose power and share of
the paper's model's mean square both change with the operating point.  A mode that the
thread-contact excitation drives rings at its natural frequency with a power
that follows the excitation's approach to it (Eq. 13's |H(r)|), unlike a fixed
line from elsewhere (constant power) or the contact's own response (constant
share).  Below the frequency where neighbouring speeds move an order by two
bins, fixed and moving content cannot be told apart and nothing is reported.
When the orders themselves carry the excitation (lines, no broadband to ring),
the mode shows in their powers instead: the same order grows and falls as its
frequency in Hz approaches and leaves f_r, and every order follows the one
transfer |H(f / f_r)|^2 in Hz (:func:`order_tracked_mode`).

The spectral shape is compared between the lowest and the highest speed
(:func:`spectral_shape`): each window's spectrum summarised as medians over
third-octave bands (medians step over narrow order lines), averaged per speed
and normalised to unit sum.  Anything that multiplies the whole response (the
paper's law, a lubrication change, a mode the orders have passed) leaves that
shape alone; power added from elsewhere with its own spectrum (a background
floor) changes it, the more the lower the speed.  The distance between the two
shapes (total variation, 0..1) is compared with the distance between halves of
the runs at one speed.
"""
from __future__ import annotations

from collections.abc import Sequence
import copy
from dataclasses import dataclass, field
import math
from typing import Any
import weakref

import numpy as np
from scipy import stats
from scipy.ndimage import median_filter, uniform_filter1d

from ..estimation.calibration import condition_labels, operating_levels
from .fitting import effective_sample_size, run_deviations
from .rules import DEFAULT_RULES, DEFAULT_SPECTRAL_RULES, DiagnosisRules
from ..validation import finite_or_none
from .table import WindowTable

__all__ = ['COVARIATE_UNITS', 'CovariateTest', 'FIXED_LINE_BINS', 'Location', 'SHAPE_NOISE_FACTOR', 'SIGNIFICANCE',
           'SpectralLines', 'SpectralShape', 'covariate_tests', 'direction_pairs', 'fixed_line_power',
           'impulse_tracking', 'locate', 'partial_trend',
           'order_tracked_mode', 'residual_holding', 'spectral_lines', 'spectral_shape', 'strongest_test',
           'time_segment']

#: The spectral measurements' thresholds (:class:`.rules.SpectralRules`: each with where its value comes from).
_SPECTRAL = DEFAULT_SPECTRAL_RULES
#: Kept for the effect plug-ins that read it (:attr:`.rules.SpectralRules.shape_noise_factor`).
SHAPE_NOISE_FACTOR = _SPECTRAL.shape_noise_factor
#: The covariate tests' defaults (:class:`.rules.DiagnosisRules`; :func:`locate` takes the diagnosis' policy).
SIGNIFICANCE = DEFAULT_RULES.significance
#: Bins either side of a line fixed in Hz within which a band or an order's peak is the line's, not its own.
FIXED_LINE_BINS = 3

COVARIATE_UNITS = {'position': 'm', 'revolutions': 'rev', 'time': 's', 'temperature': 'degC',
                   'speed': 'rad/s', 'load': 'N', 'direction': 'sign of the screw speed'}


@dataclass
class CovariateTest:
    """How much of the residual one covariate carries."""

    covariate: str
    kind: str                 # 'within-run trend', 'trend' or 'level means'
    r_squared: float          # share of residual variance explained
    statistic: float          # t or F
    p_value: float
    slope: float = math.nan   # relative amplitude change per unit covariate (trends)
    shape: str = ''           # the binned profile in words (binned means)
    bin_centres: list = field(default_factory=list)      # covariate median per bin
    bin_amplitudes: list = field(default_factory=list)   # amplitude / mean amplitude - 1 per bin

    def as_json(self) -> dict:
        """Plain mapping."""
        out: dict[str, Any] = {'covariate': self.covariate, 'test': self.kind,
                               'r_squared': finite_or_none(self.r_squared),
                               'statistic': finite_or_none(self.statistic), 'p_value': finite_or_none(self.p_value),
                               'slope_per_unit': finite_or_none(self.slope),
                               'unit': COVARIATE_UNITS.get(self.covariate, '')}
        if self.kind in ('binned means', 'segment of runs', 'paired by direction'):
            out.update({'shape': self.shape, 'bin_centres': [finite_or_none(v) for v in self.bin_centres],
                        'bin_amplitudes': [finite_or_none(v) for v in self.bin_amplitudes]})
        return out


@dataclass
class SpectralLines:
    """Fixed-frequency lines whose power does not follow the operating point."""

    frequencies: list = field(default_factory=list)     # Hz
    powers: list = field(default_factory=list)          # (m/s^2)^2 per line (median over speed levels)
    total_power: float = 0.0                            # (m/s^2)^2, sum of the lines
    share_at_lowest_speed: float = 0.0                  # of the mean square RMS at the lowest speed
    testable: bool = False
    note: str = ''
    mode_frequencies: list = field(default_factory=list)   # Hz, fixed bands whose power follows the speed
    mode_shares: list = field(default_factory=list)        # per band: its power / the model's mean square per speed
    mode_speeds: list = field(default_factory=list)        # rad/s, the speed levels of mode_shares
    mode_note: str = ''
    order_mode: dict = field(default_factory=dict)        # order-tracked line gains following a mode (see below)
    ring_frequencies: list = field(default_factory=list)   # Hz, bands fixed in Hz standing out at every speed
    ring_shares: list = field(default_factory=list)        # per ring band: power / the model's mean square per speed

    def _shares_by_speed(self, shares: Sequence[float], digits: str) -> str:
        """Shares (of the model's mean square) per speed level in words, slowest first."""
        return ', '.join(f'{100 * shares[i]:{digits}} % at {self.mode_speeds[i]:.1f} rad/s'
                         for i in np.argsort(self.mode_speeds))

    def band_note(self, band: int) -> str:
        """The mode band ``band`` (index into :attr:`mode_frequencies`) in words, its share at each speed."""
        by_speed = self._shares_by_speed(self.mode_shares[band], '.0f')
        # Against the model's mean square, not the recorded power: a mode's band may exceed it (187 %).
        return (f'a band fixed at {self.mode_frequencies[band]:.1f} Hz while the orders move, its power over the '
                f'floor against the mean square the paper\'s model gives at each speed ({by_speed})')

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'testable': self.testable, 'frequencies_hz': [float(f) for f in self.frequencies],
                'order_tracked_mode': {k: (finite_or_none(v) if isinstance(v, float) else v)
                                       for k, v in self.order_mode.items()},
                'line_powers': [float(p) for p in self.powers], 'total_power': float(self.total_power),
                'share_at_lowest_speed': float(self.share_at_lowest_speed), 'note': self.note,
                'mode_frequencies_hz': [float(f) for f in self.mode_frequencies],
                'mode_shares': [[float(v) for v in shares] for shares in self.mode_shares],
                'mode_speed_levels': [float(v) for v in self.mode_speeds], 'mode_note': self.mode_note,
                'ring_frequencies_hz': [float(f) for f in self.ring_frequencies],
                'ring_shares': [[float(v) for v in shares] for shares in self.ring_shares]}

    def ring_note(self, band: int) -> str:
        """The ring band ``band`` (index into :attr:`ring_frequencies`) in words, its share at each speed."""
        by_speed = self._shares_by_speed(self.ring_shares[band], '.2g')
        return (f'a band fixed at {self.ring_frequencies[band]:.1f} Hz at every recorded speed while the orders move, '
                f'its power over the floor against the mean square the paper\'s model gives ({by_speed})')


@dataclass
class SpectralShape:
    """How the spectrum's shape differs between the lowest and the highest speed (module doc)."""

    testable: bool = False
    distance: float = math.nan      # total variation between the two normalised band spectra, 0..1
    noise: float = math.nan         # the same between halves of the runs at one speed (the larger of the two)
    structure: float = math.nan     # total variation of the highest speed's shape from a white spectrum
    added_ratio: float = math.nan   # band power at the highest over the lowest speed where the lowest's share is up
    bands: int = 0
    note: str = ''

    @property
    def changes(self) -> bool:
        """The shape differs beyond ``SpectralRules.shape_noise_factor`` times the noise and ``shape_min_distance``."""
        return self.testable and self.distance > max(_SPECTRAL.shape_noise_factor * self.noise,
                                                     _SPECTRAL.shape_min_distance)

    @property
    def floor_added(self) -> bool:
        """The shape changes as power of constant size would change it.

        Where the lowest speed's share is up, the band power does not fall as the
        speed rises (a mode past which the orders move makes it fall).
        """
        return self.changes and self.added_ratio >= 1.0 / _SPECTRAL.line_constancy

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'testable': self.testable, 'distance': finite_or_none(self.distance),
                'noise': finite_or_none(self.noise),
                'structure': finite_or_none(self.structure), 'added_power_ratio': finite_or_none(self.added_ratio),
                'bands': self.bands, 'changes': self.changes, 'floor_added': self.floor_added, 'note': self.note}


@dataclass
class Location:
    """All covariate tests, the spectrum's lines and the covariate that carries the mismatch."""

    tests: list
    spectrum: SpectralLines
    located: str              # covariate name, 'spectrum' or 'none'
    summary: str
    shape: SpectralShape = field(default_factory=SpectralShape)

    def test(self, covariate: str) -> CovariateTest | None:
        """The test of one covariate, if run."""
        return next((t for t in self.tests if t.covariate == covariate), None)

    def as_json(self) -> dict:
        """Plain mapping."""
        return {'located': self.located, 'summary': self.summary,
                'tests': [t.as_json() for t in self.tests], 'spectrum': self.spectrum.as_json(),
                'spectral_shape': self.shape.as_json()}


def _cluster_trend(residual: np.ndarray, covariate: np.ndarray, groups: np.ndarray, name: str,
                   kind: str) -> CovariateTest | None:
    """OLS slope of residual on covariate, cluster-robust SE by run, t test with G-1 dof."""
    ok = np.isfinite(residual) & np.isfinite(covariate)
    y, x, g = residual[ok], covariate[ok], groups[ok]
    labels = np.unique(g)
    if y.size < 4 or labels.size < 3 or np.ptp(x) <= 0:
        return None
    xc = x - x.mean()
    yc = y - y.mean()
    sxx = float(xc @ xc)
    slope = float(xc @ yc) / sxx
    e = yc - slope * xc
    meat = sum(float(np.sum(xc[g == label] * e[g == label])) ** 2 for label in labels)
    n, k = y.size, labels.size
    correction = k / (k - 1) * (n - 1) / (n - 2)
    se = math.sqrt(correction * meat) / sxx if meat > 0 else math.inf
    t = slope / se if se > 0 else 0.0
    p = float(2 * stats.t.sf(abs(t), df=k - 1))
    r2 = 1 - float(e @ e) / float(yc @ yc) if yc @ yc > 0 else 0.0
    # Residual is ln A_model - ln A: the amplitude changes by -slope per unit.
    return CovariateTest(name, kind, r2, t, p, -slope)


_WHERE = {'position': 'mid-travel', 'revolutions': 'at intermediate revolutions', 'time': 'mid-recording',
          'temperature': 'at intermediate temperatures'}


def _shape_words(name: str, amplitude: np.ndarray) -> str:
    """An amplitude profile over ordered bins (relative, mean 0) in words."""
    ends = max(amplitude[0], amplitude[-1]), min(amplitude[0], amplitude[-1])
    inner = amplitude[1:-1]
    where = _WHERE.get(name, f'at intermediate {name}')
    steps = np.diff(amplitude)
    spread = float(np.max(amplitude) - np.min(amplitude))
    if inner.size and inner.max() > ends[0] and inner.max() - ends[0] > 0.5 * spread:
        return f'an arch: amplitude {100 * (inner.max() - ends[0]):.1f} % higher {where} than at both ends'
    if inner.size and inner.min() < ends[1] and ends[1] - inner.min() > 0.5 * spread:
        return f'a trough: amplitude {100 * (ends[1] - inner.min()):.1f} % lower {where} than at both ends'
    if np.max(np.abs(steps)) > 0.6 * spread:
        k = int(np.argmax(np.abs(steps)))
        return (f'a step: amplitude {"rises" if steps[k] > 0 else "falls"} by {100 * abs(steps[k]):.1f} % '
                f'between bins {k + 1} and {k + 2} of {amplitude.size} in {name}')
    if np.all(steps >= 0) or np.all(steps <= 0):
        return (f'a steady {"rise" if steps.sum() > 0 else "fall"}: amplitude changes by '
                f'{100 * (amplitude[-1] - amplitude[0]):+.1f} % from the lowest to the highest {name}')
    return (f'amplitude varies by {100 * spread:.1f} % over {name}, highest in bin '
            f'{int(np.argmax(amplitude)) + 1} of {amplitude.size}')


def _binned_run_means(residual: np.ndarray, covariate: np.ndarray, groups: np.ndarray,
                      name: str, bins: int) -> CovariateTest | None:
    """Any-shape test of a covariate that moves between runs: one-way ANOVA of run means over run bins."""
    ok = np.isfinite(residual) & np.isfinite(covariate)
    y, x, g = residual[ok], covariate[ok], groups[ok]
    labels, g_index = np.unique(g, return_inverse=True)
    counts = np.bincount(g_index).astype(float)
    ry = np.bincount(g_index, weights=y) / counts
    rx = np.bincount(g_index, weights=x) / counts
    n_runs = labels.size
    b = max(2, min(bins, n_runs // 3))
    if n_runs < 6 or np.unique(rx).size < b:
        return None
    index = np.minimum((np.argsort(np.argsort(rx, kind='stable')) * b) // n_runs, b - 1)
    sizes = np.bincount(index, minlength=b).astype(float)
    means = np.bincount(index, weights=ry, minlength=b) / sizes
    within = float(np.sum((ry - means[index]) ** 2))
    between = float(np.sum(sizes * (means - ry.mean()) ** 2))
    if within <= 0:
        return None
    f = (between / (b - 1)) / (within / (n_runs - b))
    p = float(stats.f.sf(f, b - 1, n_runs - b))
    amplitude = -(means - ry.mean())
    centres = [float(np.median(rx[index == i])) for i in range(b)]
    return CovariateTest(name, 'binned means', between / (between + within), f, p,
                         shape=_shape_words(name, amplitude) + f' (run means in {b} bins of runs)',
                         bin_centres=centres, bin_amplitudes=[float(v) for v in amplitude])


def _binned_means(residual: np.ndarray, covariate: np.ndarray, groups: np.ndarray, name: str,
                  within_run: bool, bins: int) -> CovariateTest | None:
    """Any-shape test: equal residual means over quantile bins, run-clustered Wald test (see module doc)."""
    ok = np.isfinite(residual) & np.isfinite(covariate)
    y, x, g = residual[ok], covariate[ok], groups[ok]
    if y.size < 2 * bins:
        return None
    if not within_run:
        spread = np.array([np.ptp(x[g == label]) for label in np.unique(g)])
        if np.median(spread) < 0.25 * np.ptp(x):
            # The covariate moves mostly between runs: the runs are the units (few runs per bin would
            # make the clustered covariance far too small).
            return _binned_run_means(residual, covariate, groups, name, bins)
    labels, g_index = np.unique(g, return_inverse=True)
    if y.size < 2 * bins or np.unique(x).size < 3:
        return None
    edges = np.unique(np.quantile(x, np.linspace(0, 1, bins + 1)[1:-1]))
    index = np.searchsorted(edges, x, side='right')
    used = np.unique(index)
    index = np.searchsorted(used, index)
    b = used.size
    q, n_groups = b - 1, labels.size
    if b < 3 or n_groups <= q + 1:
        return None
    counts = np.bincount(index, minlength=b).astype(float)
    means = np.bincount(index, weights=y, minlength=b) / counts
    e = y - means[index]
    scores = np.zeros((n_groups, b))
    np.add.at(scores, (g_index, index), e)
    scores /= counts[None, :]
    cov = scores.T @ scores * n_groups / (n_groups - 1)
    contrast = np.hstack([-np.ones((q, 1)), np.eye(q)])
    d = contrast @ means
    wald = float(d @ np.linalg.pinv(contrast @ cov @ contrast.T) @ d)
    f = wald * (n_groups - q) / (q * (n_groups - 1))
    p = float(stats.f.sf(f, q, n_groups - q))
    yc = y - y.mean()
    total = float(yc @ yc)
    r2 = 1 - float(e @ e) / total if total > 0 else 0.0
    amplitude = -(means - np.sum(counts * means) / counts.sum())   # residual is ln A_model - ln A
    shape = _shape_words(name, amplitude)
    if within_run:
        same = 0
        for k in range(n_groups):
            sel = g_index == k
            mine: np.ndarray = np.bincount(index[sel], weights=-y[sel], minlength=b)
            n_k = np.bincount(index[sel], minlength=b)
            have = n_k > 0
            if have.sum() >= 3:
                mine = mine[have] / n_k[have]
                ref = amplitude[have]
                if np.ptp(mine) > 0 and np.corrcoef(mine, ref)[0, 1] > 0:
                    same += 1
        shape += f', the same in {same} of {n_groups} runs'
    centres = [float(np.median(x[index == i])) for i in range(b)]
    return CovariateTest(name, 'binned means', r2, f, p, shape=shape, bin_centres=centres,
                         bin_amplitudes=[float(v) for v in amplitude])


#: Fewest runs inside a segment and outside it.


def _segment_statistics(cumulative: np.ndarray, starts: np.ndarray, stops: np.ndarray, total: int) -> np.ndarray:
    """Between-group sum of squares of every (segment, rest) split; ``cumulative`` is the cumsum of centred y."""
    inside = stops - starts
    sums = cumulative[..., stops] - cumulative[..., starts]
    return sums ** 2 * total / (inside * (total - inside))


def time_segment(table: WindowTable, residual: np.ndarray,
                 min_runs: int = DEFAULT_RULES.min_segment_runs) -> dict[str, Any] | None:
    """The stretch of runs in recording order whose residual level differs most from the rest (see below).

    The stretch and the rest hold ``min_runs`` runs or more each.

    Returns None when there are too few runs, else a mapping: ``runs`` (run
    numbers in recording order), ``levels`` (their centred residual means),
    ``inside`` (bool per ordered run), ``first``/``stop`` (slice of the
    stretch), ``times`` (run mean time, s), ``f``, ``p`` (Bonferroni) and
    ``share`` (of the run-level variance).
    """
    levels = table.run_means(residual)
    times = table.run_means('time')
    recordings = table.run_means(table.recording.astype(float))
    ok = np.isfinite(levels) & np.isfinite(times)
    n_runs = int(ok.sum())
    if n_runs < 2 * min_runs + 2:
        return None
    order = np.lexsort((times[ok], recordings[ok]))
    y = levels[ok][order]
    y = y - y.mean()
    total_ss = float(y @ y)
    if total_ss <= 0:
        return None
    starts, stops = np.triu_indices(n_runs + 1, k=min_runs)
    keep = (stops - starts) <= n_runs - min_runs
    starts, stops = starts[keep], stops[keep]
    between = _segment_statistics(np.r_[0.0, np.cumsum(y)], starts, stops, n_runs)
    best = int(np.argmax(between))
    within = max(total_ss - float(between[best]), 1e-300)
    f = float(between[best]) / (within / (n_runs - 2))
    first, stop = int(starts[best]), int(stops[best])
    inside = np.zeros(n_runs, dtype=bool)
    inside[first:stop] = True
    return {'runs': table.runs[ok][order], 'levels': y, 'inside': inside, 'first': first, 'stop': stop,
            'times': times[ok][order], 'f': f, 'p': min(1.0, float(stats.f.sf(f, 1, n_runs - 2)) * starts.size),
            'share': float(between[best] / total_ss)}


def _segment_run_means(table: WindowTable, residual: np.ndarray, min_runs: int) -> CovariateTest | None:
    """A step or a segment in time: run levels in recording order, one stretch of runs against the rest.

    Runs are ordered by recording (as given) and time inside it.  For every
    stretch of consecutive runs (at least ``min_runs`` inside and
    outside) the two-group F of the stretch against the rest is computed on
    ``(1, runs - 2)`` degrees of freedom; the largest F is kept and its p-value
    multiplied by the number of stretches tried (Bonferroni), so that looking
    everywhere does not make chance stretches significant.  A stretch touching
    either end is a step.
    """
    segment = time_segment(table, residual, min_runs)
    if segment is None:
        return None
    y, inside, first, stop, run_times = (segment[k] for k in ('levels', 'inside', 'first', 'stop', 'times'))
    n_runs, f, p, share = y.size, segment['f'], segment['p'], segment['share']
    change = -(float(y[inside].mean()) - float(y[~inside].mean()))     # residual is ln A_model - ln A
    if first == 0 or stop == n_runs:
        at = stop if first == 0 else first
        direction = 'rises' if (change > 0) == (first > 0) else 'falls'
        shape = (f'a step in time: amplitude {direction} by {100 * abs(change):.1f} % after run {at} of {n_runs} '
                 f'(in recording order, at {run_times[at]:.0f} s into its recording)')
    else:
        shape = (f'a stretch in time: amplitude {100 * abs(change):.1f} % {"higher" if change > 0 else "lower"} '
                 f'in runs {first + 1}-{stop} of {n_runs} (in recording order) than before and after')
    amplitude = np.where(inside, change, 0.0)
    return CovariateTest('time', 'segment of runs', share, f, p,
                         shape=shape, bin_centres=[float(v) for v in run_times],
                         bin_amplitudes=[float(v) for v in amplitude - amplitude.mean()])


def direction_pairs(table: WindowTable) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs by direction of travel, paired by condition: (run's condition key, run is a return, run used).

    A return run has ``direction`` -1 (the nut comes back under load).  Runs
    count only at (speed, load) conditions run both ways, so the comparison is
    at the same speed and load.
    """
    speed, load = table.run_means('speed'), table.run_means('load')
    back = table.run_means('direction') < 0
    speeds, loads = np.array(operating_levels(np.abs(speed))), np.array(operating_levels(load))
    key = (np.argmin(np.abs(np.abs(speed)[:, None] - speeds[None, :]), axis=1) * loads.size
           + np.argmin(np.abs(load[:, None] - loads[None, :]), axis=1))
    both = np.array([back[key == k].any() and (~back[key == k]).any() for k in key])
    return key, back, both


def _direction_test(table: WindowTable, residual: np.ndarray) -> CovariateTest | None:
    """Out and back at the same speed and load: the run-level residual of returns minus outs, paired by condition.

    One difference per condition run both ways (mean over its return runs minus
    mean over its out runs); a one-sample t test of the differences on
    ``conditions - 1`` degrees of freedom, so run scatter is the noise.
    """
    levels = table.run_means(residual)
    key, back, both = direction_pairs(table)
    differences = np.array([levels[(key == k) & back].mean() - levels[(key == k) & ~back].mean()
                            for k in np.unique(key[both])])
    differences = differences[np.isfinite(differences)]
    if differences.size < 3:
        return None
    spread = float(np.std(differences, ddof=1))
    t = float(differences.mean()) / (spread / math.sqrt(differences.size)) if spread > 0 else math.inf
    p = float(2 * stats.t.sf(abs(t), df=differences.size - 1))
    log_ratio = -float(differences.mean())          # residual is ln A_model - ln A
    window_back = np.isin(table.run, table.runs[back & both])
    used = np.isin(table.run, table.runs[both])
    y = residual[used] - residual[used].mean()
    fitted = np.where(window_back[used], y[window_back[used]].mean(), y[~window_back[used]].mean())
    r2 = float(fitted @ fitted) / float(y @ y) if y @ y > 0 else 0.0
    shape = (f'a direction factor: amplitude {math.exp(log_ratio):.3f} times as high on the return traverses '
             f'(nut coming back) as out, at the same speed and load ({differences.size} conditions run both '
             'ways)')
    return CovariateTest('direction', 'paired by direction', r2, t, p, slope=math.expm1(log_ratio), shape=shape,
                         bin_centres=[1.0, -1.0], bin_amplitudes=[-0.5 * log_ratio, 0.5 * log_ratio])


def _level_means(residual: np.ndarray, values: np.ndarray, groups: np.ndarray, name: str) -> CovariateTest | None:
    """F test of residual means per operating level, with the effective sample size."""
    levels = operating_levels(values)
    if len(levels) < 2:
        return None
    edges = np.array(levels)
    index = np.argmin(np.abs(np.abs(values)[:, None] - edges[None, :]), axis=1)
    n_eff = effective_sample_size(residual, groups)
    means = np.array([residual[index == i].mean() for i in range(len(levels))])
    fitted = means[index]
    ss_total = float(np.sum((residual - residual.mean()) ** 2))
    ss_between = float(np.sum((fitted - residual.mean()) ** 2))
    if ss_total <= 0:
        return None
    r2 = ss_between / ss_total
    dof1 = len(levels) - 1
    dof2 = max(n_eff - len(levels), 1.0)
    f = (r2 / dof1) / max((1 - r2) / dof2, 1e-300)
    return CovariateTest(name, 'level means', r2, f, float(stats.f.sf(f, dof1, dof2)))


def _drifting_covariates(table: WindowTable, min_temperature_span: float) -> tuple[str, ...]:
    """Revolutions and time, and temperature when it spans ``min_temperature_span`` K or more.

    A smaller span is the sensor's noise and drift, not a condition the
    actuator ran at: binned by it, the windows fall into bins by chance and
    the run scatter can pass for a pattern.
    """
    spans = table.temperature_span >= min_temperature_span      # False when none is recorded (NaN)
    return ('revolutions', 'time', 'temperature') if spans else ('revolutions', 'time')


def covariate_tests(table: WindowTable, residual: np.ndarray,
                    rules: DiagnosisRules = DEFAULT_RULES) -> list[CovariateTest]:
    """Every test the table supports: trends and level means, then binned means, strongest evidence first.

    ``rules``: the bins, the temperature span and the runs a stretch in time needs.
    """
    residual = np.asarray(residual, dtype=float)
    tests: list[Any] = []   # CovariateTest or None, then the tests found
    centred_r = residual - table.run_means(residual)[np.searchsorted(table.runs, table.run)]
    centred_x = table.position - table.run_means('position')[np.searchsorted(table.runs, table.run)]
    tests.append(_cluster_trend(centred_r, centred_x, table.run, 'position', 'within-run trend'))
    drifting = _drifting_covariates(table, rules.min_temperature_span)
    for name in drifting:
        tests.append(_cluster_trend(residual, getattr(table, name), table.run, name, 'trend'))
    for name in ('speed', 'load'):
        tests.append(_level_means(residual, getattr(table, name), table.run, name))
    tests = [t for t in tests if t is not None]
    tests.sort(key=lambda t: (t.p_value, -t.r_squared))
    flexible: list[Any] = [_binned_means(centred_r, table.position, table.run, 'position', True, rules.bins)]
    for name in drifting:
        flexible.append(_binned_means(residual, getattr(table, name), table.run, name, False, rules.bins))
    flexible.append(_segment_run_means(table, residual, rules.min_segment_runs))
    flexible.append(_direction_test(table, residual))
    flexible = [t for t in flexible if t is not None]
    flexible.sort(key=lambda t: (t.p_value, -t.r_squared))
    return tests + flexible


def spectral_lines(table: WindowTable, residual: np.ndarray | None = None) -> SpectralLines:
    """Fixed-frequency lines with constant power and mode bands (module doc); untestable without spectra or one speed.

    ``residual`` (the baseline's ``ln A_model - ln A`` per window) gives the
    paper's model's mean square per speed, against which a mode band's power is
    compared; without it the recorded mean square is used.
    """
    spectra, fixed = _fixed_line_spectra(table)
    result = copy.deepcopy(fixed)            # the cached fixed lines stay as they are
    if isinstance(spectra, str):
        return result
    edges, index, medians, floors, excess, widened, lowest = spectra
    df = table.spectrum_resolution
    modelled = table.rms if residual is None else table.rms * np.exp(residual)
    model_square = np.array([np.mean(modelled[index == i] ** 2) for i in range(len(edges))])
    _mode_bands(result, medians, np.arange(medians.shape[1]) * df, model_square, edges, df)
    _ring_bands(result, medians, np.arange(medians.shape[1]) * df, model_square, edges, df)
    result.order_mode = order_tracked_mode(medians, floors, excess, [float(v) for v in edges], df,
                                           result.frequencies)
    return result


def _speed_spectra(table: WindowTable) -> str | tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                      np.ndarray, float]:
    """Median spectra per speed level and what the line tests need, or why there are none (a str).

    Returns ``(levels, level of each window, medians, floors, excess, widened,
    lowest)``, ``lowest`` the frequency below which a rotation order moves by
    less than 2 bins between neighbouring speeds (Hz).
    """
    if table.spectra is None or not math.isfinite(table.spectrum_resolution):
        return 'no spectra (vibration samples not kept)'
    levels = operating_levels(table.speed)
    if len(levels) < 2:
        return 'one screw speed only: fixed lines cannot be told from rotation orders'
    df = table.spectrum_resolution
    edges = np.array(levels)
    ordered = np.sort(edges)
    lowest = max(3 * df, 2 * df / (float(np.min(ordered[1:] / ordered[:-1])) - 1))
    index = np.argmin(np.abs(np.abs(table.speed)[:, None] - edges[None, :]), axis=1)
    valid = ~np.isnan(table.spectra).any(axis=1)
    if any(not np.any(valid & (index == i)) for i in range(len(levels))):
        return 'a screw speed without a window spectrum'
    medians = np.array([np.median(table.spectra[valid & (index == i)], axis=0) for i in range(len(levels))])
    floors, excess, widened = _excess(medians, _SPECTRAL.floor_half_width)
    return edges, index, medians, floors, excess, widened, lowest


#: Tables whose per-speed spectra and fixed lines are known: id -> (weak reference, (spectra, fixed lines)).
_LINE_SPECTRA: dict[int, tuple[Any, tuple[Any, SpectralLines]]] = {}


def _fixed_line_spectra(table: WindowTable) -> tuple[Any, SpectralLines]:
    """:func:`_speed_spectra` of ``table`` and its fixed lines, computed once per table.

    They depend on the table alone, while :func:`locate` runs once per model
    residual and the background's fits ask for the lines' power
    (:func:`fixed_line_power`); the medians over every window's spectrum are
    the costly part.  Kept while the table lives.
    """
    cached = _LINE_SPECTRA.get(id(table))
    if cached is not None and cached[0]() is table:
        return cached[1]
    spectra = _speed_spectra(table)
    if isinstance(spectra, str):
        fixed = SpectralLines(note=spectra)
    else:
        edges, index, medians, floors, excess, widened, lowest = spectra
        df = table.spectrum_resolution
        mean_square = np.array([np.mean(table.rms[index == i] ** 2) for i in range(len(edges))])
        fixed = SpectralLines(testable=True)
        _fixed_lines(fixed, medians, floors, excess, widened, np.arange(medians.shape[1]) * df, lowest,
                     mean_square, int(np.argmin(edges)), df, table.band_high)
    for key in [key for key, (ref, _) in _LINE_SPECTRA.items() if ref() is None]:
        del _LINE_SPECTRA[key]
    _LINE_SPECTRA[id(table)] = (weakref.ref(table), (spectra, fixed))
    return spectra, fixed


def impulse_tracking(table: WindowTable, frequency: float) -> float:
    """How strongly the power of the band at ``frequency`` (Hz) follows the windows' strikes: a pooled z.

    Per window, the band's power over the level of its neighbours (the median
    bin within 30 % of ``frequency``, times the band's bins), the strikes' power
    ``rms^2 - gaussian_rms^2`` (what sparse impulses add to the Gaussian part)
    and the Gaussian part's power ``gaussian_rms^2`` (the contacts' smooth
    vibration, which an order-excited mode's response scales with); windows
    where either of the first two is not positive are left out.  Within each
    operating condition (speed and load levels) the logarithms less their run
    means (set-up scatter between runs is no strike), the first two less their
    regression on the third (a window louder as a whole is no strike either),
    and the correlation of what is left; the conditions pooled as Fisher z with
    weights ``n - runs - 3`` (n windows, 8 or more):
    ``z = sum(w atanh r) / sqrt(sum w)``, about standard normal where the
    band's power does not follow the strikes.  A mode an order excites
    responds as the speed and the contacts' vibration set it; a band the
    strikes ring follows each window's strikes.  NaN without spectra or the
    Gaussian part, below 10 bins (no neighbours), or where no condition tells.
    """
    if table.spectra is None or table.gaussian_rms is None or not math.isfinite(table.spectrum_resolution):
        return math.nan
    df = table.spectrum_resolution
    bins = np.arange(table.spectra.shape[1]) * df
    band = np.abs(bins - frequency) <= max(0.05 * frequency, 3 * df)
    neighbours = (np.abs(bins - frequency) <= 0.3 * frequency) & ~band
    if not band.any() or not neighbours.any():
        return math.nan
    gaussian = np.asarray(table.gaussian_rms, dtype=float) ** 2
    with np.errstate(invalid='ignore'):
        excess = (table.spectra[:, band].sum(axis=1)
                  - np.median(table.spectra[:, neighbours], axis=1) * band.sum()) * df
        strikes = table.rms ** 2 - gaussian
        usable = (excess > 0) & (strikes > 0) & (gaussian > 0) & np.isfinite(excess + strikes + gaussian)
    labels = condition_labels(table.speed, table.load)
    weighted, weights = 0.0, 0.0
    for condition in np.unique(labels[usable]):
        chosen = usable & (labels == condition)
        runs = table.run[chosen]
        weight = int(chosen.sum()) - np.unique(runs).size - 3
        if chosen.sum() < 8 or weight <= 0:
            continue
        band_log, strike_log, gaussian_log = (run_deviations(np.log(values[chosen]), runs)
                                              for values in (excess, strikes, gaussian))
        scale = float(gaussian_log @ gaussian_log)
        if scale > 0:
            band_log = band_log - (gaussian_log @ band_log) / scale * gaussian_log
            strike_log = strike_log - (gaussian_log @ strike_log) / scale * gaussian_log
        spread = math.sqrt(float(band_log @ band_log) * float(strike_log @ strike_log))
        if spread <= 0:
            continue
        r = float(band_log @ strike_log) / spread
        weighted += weight * math.atanh(min(max(r, -0.999999), 0.999999))
        weights += weight
    return weighted / math.sqrt(weights) if weights > 0 else math.nan


def fixed_line_power(table: WindowTable) -> float:
    """Power in fixed-frequency lines of constant power, (m/s^2)^2 (0 without such lines); cached per table.

    What :func:`spectral_lines` reports as ``total_power``: vibration from
    elsewhere that the spectrum measures directly, whatever the amplitude fit.
    """
    return _fixed_line_spectra(table)[1].total_power


def _on_fixed_line(frequency: float, fixed: Sequence[float], df: float) -> bool:
    """Whether ``frequency`` (Hz) lies within :data:`FIXED_LINE_BINS` bins of one of the lines ``fixed`` in Hz."""
    return any(abs(frequency - f) <= FIXED_LINE_BINS * df for f in fixed)


def _order_lines(medians: np.ndarray, floors: np.ndarray, excess: np.ndarray, speeds: Sequence[float],
                 df: float, fixed: Sequence[float] = ()) -> Sequence[tuple[float, dict[int, float]]]:
    """Rotation-order lines: peaks standing at the same order (f / f_S) at three speeds or more.

    Returns ``[(order, {level: power})]``, power (m/s^2)^2 of the line over its floor at each speed level.
    A peak within ``FIXED_LINE_BINS`` bins of a line fixed in Hz (``fixed``, Hz: a background's tones) is left
    out: there the order's power and the fixed line's add in the same bins, and the order's line would seem
    to gain power where it meets that frequency, as it does where it meets a mode (study two 1874: lines at
    74.5 and 145 Hz read as "one mode at 75.8 Hz, zeta 0.02" the orders pass through).
    """
    peaks = []                                   # (order, level, power)
    for level, speed in enumerate(speeds):
        rotation = speed / (2.0 * math.pi)
        row = excess[level]
        local = (row[1:-1] >= _SPECTRAL.line_prominence) & (row[1:-1] >= row[:-2]) & (row[1:-1] > row[2:])
        for peak in np.flatnonzero(local) + 1:
            if peak < 3 or _on_fixed_line(peak * df, fixed, df):
                continue
            lo, hi = peak - 2, min(peak + 3, medians.shape[1])
            power = float(np.sum(np.maximum(medians[level, lo:hi] - floors[level, lo:hi], 0.0)) * df)
            peaks.append((peak * df / rotation, level, power))
    peaks.sort()
    lines, used = [], set()
    for i, (order, _, _) in enumerate(peaks):
        if i in used:
            continue
        # The same order within 1.5 bins at each speed (the coarsest tolerance among the speeds).
        tolerance = 1.5 * df * 2.0 * math.pi / min(speeds)
        group = {}
        for j in range(i, len(peaks)):
            if peaks[j][0] - order > tolerance:
                break
            if j not in used and peaks[j][1] not in group:
                group[peaks[j][1]] = peaks[j][2]
                used.add(j)
        if len(group) >= _SPECTRAL.mode_min_speeds:
            lines.append((order, group))
    return lines


def order_tracked_mode(medians: np.ndarray, floors: np.ndarray, excess: np.ndarray, speeds: Sequence[float],
                       df: float, fixed: Sequence[float] = ()) -> dict[str, Any]:
    """A mode the rotation orders pass through, from the powers of order lines (module doc).

    Each line seen at the same order at three speeds or more gives its power
    per speed; ``ln P = a_order + b_speed + ln |H(f / f_r)|^2`` with f the line's
    frequency in Hz is fitted against ``ln P = a_order + b_speed``: the speed
    terms take anything common to all orders at one speed (the contact law, a
    background in the total, lubrication), so only a gain that depends on the
    frequency in Hz, the same for every order, counts.  f_r and zeta on a grid
    (f_r within a factor 2 of the lines, zeta 0.02-0.3); evidence when the F
    test gives p < ``DiagnosisRules.significance`` and the residual sum of squares falls by
    half, also without the point the order and speed terms leave furthest out (a
    tone from elsewhere on one order's frequency at one speed).  Returns {} when
    untestable, else the fit and its test.
    """
    lines = _order_lines(medians, floors, excess, speeds, df, fixed)
    points = [(o, level, p) for o, group in lines for level, p in group.items() if p > 0]
    n_orders, n_levels = len(lines), len({level for _, level, _ in points})
    n_params = n_orders + n_levels - 1
    if n_orders < 2 or len(points) - n_params - 2 < 2:
        return {}
    order_of = {o: k for k, (o, _) in enumerate(lines)}
    levels = sorted({level for _, level, _ in points})
    design = np.zeros((len(points), n_params))
    for row, (o, level, _) in enumerate(points):
        design[row, order_of[o]] = 1.0
        if levels.index(level) > 0:
            design[row, n_orders + levels.index(level) - 1] = 1.0
    log_power = np.log([p for _, _, p in points])
    frequency = np.array([o * speeds[level] / (2.0 * math.pi) for o, level, _ in points])
    statistic, p_value, natural, zeta, null_residual = _mode_through_orders(design, log_power, frequency)
    keep = np.arange(len(points)) != int(np.argmax(np.abs(null_residual)))
    robust = (_mode_through_orders(design[keep], log_power[keep], frequency[keep])[1]
              if len(points) - 1 - n_params - 2 >= 2 else 1.0)
    found = p_value < SIGNIFICANCE and robust < SIGNIFICANCE
    return {'found': found, 'natural_frequency_hz': natural, 'damping_ratio': zeta, 'orders': n_orders,
            'order_values': [round(float(o), 3) for o, _ in lines],
            'points': len(points), 'f_statistic': float(statistic), 'p_value': p_value,
            'note': (f'the powers of {n_orders} rotation orders at {n_levels} speeds follow one mode at '
                     f'{natural:.1f} Hz (zeta {zeta:.2f}) in Hz, whatever the order: F = {statistic:.3g}, '
                     f'p = {p_value:.2g}') if found else ''}


def _mode_through_orders(design: np.ndarray, log_power: np.ndarray,
                         frequency: np.ndarray) -> tuple[float, float, float, float, np.ndarray]:
    """(F, p, f_r, zeta, null residual) of ``ln P = design + ln |H(f / f_r)|^2`` against ``ln P = design``.

    f_r on a log grid from half the lowest to twice the highest line frequency,
    zeta on a grid of 0.02-0.3; the F test on (2, points - parameters - 2) degrees
    of freedom, significant only when the residual sum of squares also halves.
    """
    from ..physics.effects.resonance import magnification

    def fit(target: np.ndarray) -> tuple[float, np.ndarray]:
        coef, *_ = np.linalg.lstsq(design, target, rcond=None)
        residual = target - design @ coef
        return float(np.sum(residual ** 2)), residual

    null, null_residual = fit(log_power)
    best = (null, math.nan, math.nan)
    for natural in np.geomspace(frequency.min() / 2.0, frequency.max() * 2.0, 120):
        for zeta in (0.02, 0.03, 0.05, 0.08, 0.12, 0.18, 0.3):
            fitted = fit(log_power - 2.0 * np.log(magnification(frequency / natural, zeta)))[0]
            if fitted < best[0]:
                best = (fitted, float(natural), zeta)
    dof = design.shape[0] - design.shape[1] - 2
    statistic = ((null - best[0]) / 2.0) / max(best[0] / dof, 1e-300)
    p_value = float(stats.f.sf(statistic, 2, dof)) if best[0] > 0 else 0.0
    if best[0] > 0.5 * null:
        p_value = max(p_value, 1.0)
    return statistic, p_value, best[1], best[2], null_residual


def _excess(medians: np.ndarray, half_width: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(floors, excess, widened) of spectra per speed level (rows).

    Floors are running medians over ``2 half_width + 1`` bins, excess the
    spectra over them, widened the excess widened by a bin each side (a line
    may sit one bin off between speeds).
    """
    return _excess_over(medians, median_filter(medians, size=(1, 2 * half_width + 1), mode='nearest'))


def _excess_over(medians: np.ndarray, floors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(floors, excess, widened) of spectra per speed level over given ``floors`` (see :func:`_excess`)."""
    excess = medians / np.maximum(floors, 1e-300)
    return floors, excess, np.maximum(excess, np.maximum(np.roll(excess, 1, axis=1), np.roll(excess, -1, axis=1)))


def _line_groups(candidate: np.ndarray) -> list[np.ndarray]:
    """Runs of candidate bins (gaps of up to two bins joined)."""
    bins = np.flatnonzero(candidate)
    return np.split(bins, np.flatnonzero(np.diff(bins) > 2) + 1) if bins.size else []


def _fixed_lines(result: SpectralLines, medians: np.ndarray, floors: np.ndarray, excess: np.ndarray,
                 widened: np.ndarray, freqs: np.ndarray, lowest: float, mean_square: np.ndarray, slowest: int,
                 df: float, highest: float = math.nan) -> None:
    """Lines prominent at two speeds or more whose power stays put while the total power moves.

    The power is compared over every speed where the line is measurable
    (``SpectralRules.line_measurable``) or where a line of its (median) power would
    carry ``_SPECTRAL.line_prominence - 1`` times the floor's power in its bins.  Only
    lines below ``highest`` (Hz, the RMS band's upper edge; NaN: no edge)
    count: content above it is not in the window RMS the model is fitted to;
    nor does one whose peak lies below ``lowest`` (Hz), where rotation orders
    of neighbouring speeds share bins.  ``slowest``: the row of the lowest speed.
    """
    candidate = (np.count_nonzero(widened >= _SPECTRAL.line_prominence, axis=0) >= 2) & (freqs >= lowest)
    candidate &= excess.max(axis=0) >= _SPECTRAL.line_prominence
    if math.isfinite(highest):
        candidate &= freqs < highest
    for group in _line_groups(candidate):
        lo, hi = max(group[0] - 1, 0), min(group[-1] + 2, medians.shape[1])
        measured = widened[:, lo:hi].max(axis=1) >= _SPECTRAL.line_measurable
        power = np.sum(np.maximum(medians[:, lo:hi] - floors[:, lo:hi], 0.0), axis=1) * df
        if np.count_nonzero(measured) < 2:
            continue
        # Also compared where a line of its power would stand out but may not: two rotation orders on one bin at
        # two speeds, or a mode ringing at two speeds, are absent (power 0) where a fixed line would show.
        floor_power = np.sum(floors[:, lo:hi], axis=1) * df
        should_show = float(np.median(power[measured])) >= (_SPECTRAL.line_prominence - 1.0) * floor_power
        compared = measured | should_show
        power = power[compared]
        if power.min() <= 0:
            continue
        constant = power.max() / power.min() <= _SPECTRAL.line_constancy
        spread = mean_square[compared].max() / mean_square[compared].min()
        # Where the line stands must be above ``lowest`` too, not only the bins that flagged it: the bins around
        # them reach one below, where orders of neighbouring speeds share bins (docs/diagnosis-rules.md, spectral
        # evidence).
        peak = lo + int(np.argmax(medians[measured, lo:hi].mean(axis=0)))
        if constant and spread >= _SPECTRAL.power_spread and freqs[peak] >= lowest:
            result.frequencies.append(float(freqs[peak]))
            result.powers.append(float(np.median(power)))
    result.total_power = float(sum(result.powers))
    result.share_at_lowest_speed = result.total_power / float(mean_square[slowest])
    if result.frequencies:
        result.note = (f'{len(result.frequencies)} line(s) at fixed frequencies '
                       f'({", ".join(f"{f:.0f}" for f in result.frequencies)} Hz) with constant power, '
                       f'{100 * result.share_at_lowest_speed:.2f} % of the power at the lowest speed')
    else:
        result.note = 'no fixed-frequency line with constant power'


def _mode_bands(result: SpectralLines, medians: np.ndarray, freqs: np.ndarray, mean_square: np.ndarray,
                edges: np.ndarray, df: float) -> None:
    """Bands fixed in Hz at three speeds or more whose power and share of ``mean_square`` follow the speed.

    ``mean_square`` per speed level is the paper's model's: the contact's own
    response (a fixed mode it excites broadband) keeps its share of it even when a
    background floor changes its share of the recorded power.  A band counts
    only where a rotation order at its peak would have moved by
    ``SpectralRules.mode_order_shift_bins`` bins between the slowest and the fastest speed
    it is seen at (``f (omega_max / omega_min - 1) >= 3 df``, more than the 2 bins
    its peak may wander), so closely spaced speeds do not hide a mode the whole
    band sweeps past, and an order that barely moves is not taken for one.
    Nor is a peak that climbs a bin with each faster speed across the band's
    window, or whose bins a rotation order fits better than one fixed bin
    (both :func:`_follows_an_order`): at low frequencies and coarse resolution
    an order crossing the window looks fixed within 2 bins.

    Bands are sought twice: over the running median of
    ``SpectralRules.mode_floor_half_width`` bins a side (narrow bands, lines beside them),
    and over the spectrum an octave either side (:func:`_octave_excess`),
    where a well-damped mode's band, wider than that running median, stands
    out by ``SpectralRules.mode_broad_prominence``, when an order up to ``SpectralRules.mode_max_order``
    can reach it (a frequency ratio of ``SpectralRules.mode_ring_ratio`` at the top speed):
    the contact's own mode, far above, is broad too and needs no order to ring;
    and only when the band's upper skirt, to ``SpectralRules.mode_upper_skirt`` times
    its frequency, lies inside the spectrum: near the top the octave above is
    cut off, and a spectrum rising to its edge (the skirt of a mode above the
    top, an anti-alias filter's shape) stands out of the octave below alone
    (the study case: ``docs/diagnosis-rules.md``, spectral evidence).
    Such a band's place at each speed is where its power over the floor is
    centred (its flat top puts the largest bin anywhere), and that is the
    frequency reported.
    """
    reach = _SPECTRAL.mode_max_order * float(np.max(edges)) / (2.0 * math.pi) / _SPECTRAL.mode_ring_ratio
    narrow = _excess(medians, _SPECTRAL.mode_floor_half_width)[::2]
    for floors, widened, prominence, broad in ((*narrow, _SPECTRAL.line_prominence, False),
                                               (*_octave_excess(medians)[::2], _SPECTRAL.mode_broad_prominence, True)):
        within = np.ones(freqs.size, dtype=bool) if not broad else freqs <= reach
        _mode_bands_over(result, medians, freqs, mean_square, edges, df, floors,
                         (widened >= prominence) & within[None, :], broad)
    result.mode_speeds = [float(v) for v in edges]
    if result.mode_frequencies:
        result.mode_note = result.band_note(int(np.argmax([max(v) for v in result.mode_shares])))
    else:
        result.mode_note = 'no band fixed in frequency whose power follows the speed'


def _octave_excess(medians: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(floors, excess, widened) as :func:`_excess`, each bin's floor the median of the spectrum an octave either side.

    A well-damped mode's band is ``2 zeta f_r`` wide (0.4 f_r at zeta 0.2):
    wider than the running median of ``SpectralRules.mode_floor_half_width`` bins at
    fine resolution, which then takes the band for the floor.  Floors are
    medians over ``[f / 2, 2 f]``, computed at 24 centres an octave and
    interpolated in log frequency.
    """
    bins = medians.shape[1]
    centres = np.unique(np.clip(np.round(2.0 ** np.arange(0.0, math.log2(bins) + 1 / 24, 1 / 24)), 1, bins - 1)
                        .astype(int))
    at_centres = np.array([[np.median(row[max(c // 2, 1):min(2 * c + 1, bins)]) for c in centres] for row in medians])
    index = np.arange(bins, dtype=float)
    floors = np.array([np.exp(np.interp(np.log(np.maximum(index, 1.0)), np.log(centres), np.log(np.maximum(r, 1e-300))))
                       for r in at_centres])
    return _excess_over(medians, floors)


def _mode_bands_over(result: SpectralLines, medians: np.ndarray, freqs: np.ndarray, mean_square: np.ndarray,
                     edges: np.ndarray, df: float, floors: np.ndarray, prominent: np.ndarray, broad: bool) -> None:
    """:func:`_mode_bands` against one floor (``prominent``: the bins standing out of it per speed).

    Bands found are added to ``result``, none twice.  A ``broad`` band (the
    octave floor) whose share is largest at the slowest speed it is seen at is
    not taken: the orders, growing faster than the contacts' broadband, take
    share from any band that broadband fills (the contact's own mode, in the
    paper's model), while the orders approaching a mode give it share.
    """
    # Two speeds can put two different orders on one bin; three seldom do.
    candidate = (prominent.sum(axis=0) >= _SPECTRAL.mode_min_speeds) & (freqs >= 3 * df)
    for group in _line_groups(candidate):
        if _on_fixed_line(freqs[group[0]], result.frequencies, df):
            continue
        lo, hi = max(group[0] - 1, 0), min(group[-1] + 2, medians.shape[1])
        power = np.sum(np.maximum(medians[:, lo:hi] - floors[:, lo:hi], 0.0), axis=1) * df
        share = power / mean_square
        seen = prominent[:, lo:hi].any(axis=1)
        # A speed whose largest bin is the window's edge has its power from outside: a neighbouring line's skirt.
        top = _band_tops(medians, lo, hi)
        seen &= (top > lo) & (top < hi - 1)
        if seen.sum() < _SPECTRAL.mode_min_speeds or power[seen].min() <= 0:
            continue
        # A broad band's flat top puts its largest bin anywhere on it (a mode at zeta 0.2: the smoothed top of
        # one band wandered by 16 Hz between speeds); the band sits where its power over the floor is centred.
        peaks = _centroids(medians[:, lo:hi] - floors[:, lo:hi], lo)[seen] if broad else top[seen]
        if not _fixed_in_hz(peaks, edges[seen], lo, hi):
            continue
        centre = float(freqs[int(np.median(peaks))])
        if broad and centre * _SPECTRAL.mode_upper_skirt > freqs[-1]:
            continue            # its upper skirt is cut off by the spectrum's top (see _mode_bands)
        span = float(np.max(edges[seen]) / np.min(edges[seen]))
        if centre * (span - 1.0) < _SPECTRAL.mode_order_shift_bins * df:
            continue
        varies = power[seen].max() / power[seen].min() > _SPECTRAL.line_constancy
        share_varies = share[seen].max() / share[seen].min() >= _SPECTRAL.mode_share_spread
        if broad and np.argmax(np.where(seen, share, -np.inf)) == np.argmin(np.where(seen, edges, np.inf)):
            continue
        if varies and share_varies and share.max() >= _SPECTRAL.mode_min_share:
            if any(freqs[lo] <= f <= freqs[hi - 1] for f in result.mode_frequencies):
                continue
            result.mode_frequencies.append(_band_frequency(medians, freqs, peaks, lo, hi, df, broad))
            result.mode_shares.append([float(v) for v in share])


def _ring_bands(result: SpectralLines, medians: np.ndarray, freqs: np.ndarray, mean_square: np.ndarray,
                edges: np.ndarray, df: float) -> None:
    """Bands fixed in Hz standing out at every speed level (three or more) while the orders move past them.

    A lightly damped mode is driven by every frequency component of the
    contact force (Eq. 13), its broadband part included, so it rings at f_r
    at every speed, in a band ``2 zeta f_r`` wide whose power follows the
    contact excitation, even where the order that sweeps towards it has passed
    (a mode below the band the orders sweep: the order's response is
    attenuated, and :func:`_mode_bands`, which asks for a share that changes
    with the speed, sees nothing).  Sought over the running median of
    ``SpectralRules.mode_floor_half_width`` bins a side and over the octave
    floor (:func:`_octave_excess`) as :func:`_mode_bands` does, with the same
    tests that the band is fixed in Hz (its peak within 2 bins or an eighth of
    the band, not an order crossing it, :func:`_follows_an_order`; an order at
    its frequency would have moved ``SpectralRules.mode_order_shift_bins``
    bins), none at a fixed line of constant power nor at a mode band already
    found.  Whether a band is a mode's ring is the candidate's question (the
    order its frequency implies at the fitted resonant speed): a fixed band
    from elsewhere stands out at every speed too.
    """
    levels = medians.shape[0]
    if levels < _SPECTRAL.mode_min_speeds:
        return
    narrow = _excess(medians, _SPECTRAL.mode_floor_half_width)[::2]
    for floors, widened, broad in ((*narrow, False), (*_octave_excess(medians)[::2], True)):
        prominent = widened >= (_SPECTRAL.mode_broad_prominence if broad else _SPECTRAL.line_prominence)
        for group in _line_groups(prominent.all(axis=0) & (freqs >= 3 * df)):
            lo, hi = max(group[0] - 1, 0), min(group[-1] + 2, medians.shape[1])
            if any(freqs[lo] - FIXED_LINE_BINS * df <= f <= freqs[hi - 1] + FIXED_LINE_BINS * df
                   for f in result.frequencies + result.mode_frequencies + result.ring_frequencies):
                continue
            top = _band_tops(medians, lo, hi)
            if not np.all((top > lo) & (top < hi - 1)):
                continue
            peaks = _centroids(medians[:, lo:hi] - floors[:, lo:hi], lo) if broad else top
            if not _fixed_in_hz(peaks, edges, lo, hi):
                continue
            centre = float(freqs[int(np.median(peaks))])
            if centre * (float(np.max(edges) / np.min(edges)) - 1.0) < _SPECTRAL.mode_order_shift_bins * df:
                continue
            power = np.sum(np.maximum(medians[:, lo:hi] - floors[:, lo:hi], 0.0), axis=1) * df
            if power.min() <= 0:
                continue
            result.ring_frequencies.append(_band_frequency(medians, freqs, peaks, lo, hi, df, broad))
            result.ring_shares.append([float(v) for v in power / mean_square])


def _band_tops(medians: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Per speed, the bin where band ``lo:hi`` peaks, on the spectrum smoothed over a sixth of the band.

    The peak of a wide band (a well-damped mode's flat top) is taken where the noise of single bins does not
    move it.  A speed whose top is the window's edge has its power from outside: a neighbouring line's skirt.
    """
    return lo + np.argmax(uniform_filter1d(medians[:, lo:hi], max((hi - lo) // 6, 1), axis=1), axis=1)


def _fixed_in_hz(peaks: np.ndarray, edges: np.ndarray, lo: int, hi: int) -> bool:
    """Whether a band's peaks per speed (bins, at speeds ``edges``) stay at one frequency, not an order's.

    Not one frequency (lines of different orders side by side) when the peak wanders by more than 2 bins, or
    by an eighth of a wide band; nor when it follows a rotation order (:func:`_follows_an_order`).
    """
    return not (np.ptp(peaks) > max(2, (hi - lo) // 8) or _follows_an_order(peaks, edges))


def _band_frequency(medians: np.ndarray, freqs: np.ndarray, peaks: np.ndarray, lo: int, hi: int, df: float,
                    broad: bool) -> float:
    """The frequency reported for band ``lo:hi``, Hz: a broad band's median centre, else its largest bin."""
    if broad:
        return float(np.median(peaks)) * df
    return float(freqs[lo + int(np.argmax(medians[:, lo:hi].max(axis=0)))])


def _centroids(excess_power: np.ndarray, first: int) -> np.ndarray:
    """Per row, the bin (fractional, counted from ``first``) where the power over the floor is centred."""
    weight = np.maximum(excess_power, 0.0)
    total = weight.sum(axis=1)
    position = weight @ np.arange(first, first + weight.shape[1], dtype=float)
    return np.divide(position, total, out=np.full(total.shape, float(first)), where=total > 0)


def _follows_an_order(peaks: np.ndarray, speeds: np.ndarray) -> bool:
    """The peak bins move with the speed as one rotation order would: an order crossing the band's window.

    A peak that climbs a bin with each faster speed (2 bins in all) is one.
    Otherwise a rotation order puts its peak at bin ``k omega`` and a mode keeps
    it at one bin; both are fitted to the peak bins by least squares (``k``
    through the origin, the mode's bin as the mean), and the peak is an order
    when the order fits with the smaller squared error.
    """
    if np.ptp(peaks) == 2 and np.all(np.diff(peaks[np.argsort(speeds)]) > 0):
        return True
    peaks, speeds = peaks.astype(float), speeds.astype(float)
    fixed_error = float(np.sum((peaks - peaks.mean()) ** 2))
    order = float(peaks @ speeds / (speeds @ speeds))
    return float(np.sum((peaks - order * speeds) ** 2)) < fixed_error


def _band_edges(resolution: float, bins: int) -> list:
    """(first, stop) bin ranges of third-octave bands holding ``SpectralRules.shape_min_bins`` bins or more."""
    width = 2 ** (1 / 6) - 2 ** (-1 / 6)            # a third-octave band's width over its centre
    centre, edges = _SPECTRAL.shape_min_bins / width * resolution, []
    while centre * 2 ** (1 / 6) < bins * resolution:
        lo, hi = int(math.ceil(centre * 2 ** (-1 / 6) / resolution)), int(centre * 2 ** (1 / 6) / resolution)
        if hi - lo >= _SPECTRAL.shape_min_bins:
            edges.append((lo, hi))
        centre *= 2 ** (1 / 3)
    return edges


def _shape(band_power: np.ndarray) -> np.ndarray:
    """Mean band power over windows (rows), normalised to unit sum."""
    mean = band_power.mean(axis=0)
    return mean / mean.sum()


def spectral_shape(table: WindowTable, exclude: Sequence[float] = ()) -> SpectralShape:
    """The third-octave spectral shape at the lowest against the highest speed (module doc).

    Bands within an octave of a frequency of ``exclude`` (Hz: a mode's band,
    which changes the shape by itself, skirts included) are left out.
    """
    if table.spectra is None or not math.isfinite(table.spectrum_resolution):
        return SpectralShape(note='no spectra (vibration samples not kept)')
    levels = operating_levels(table.speed)
    df = table.spectrum_resolution
    edges = [(lo, hi) for lo, hi in _band_edges(df, table.spectra.shape[1])
             if not any(lo * df <= 2 * f and hi * df >= f / 2 for f in exclude)]
    if len(levels) < 2 or len(edges) < 3:
        return SpectralShape(note='one screw speed, or too few spectrum bins for third-octave bands')
    index = np.argmin(np.abs(np.abs(table.speed)[:, None] - np.array(levels)[None, :]), axis=1)
    valid = ~np.isnan(table.spectra).any(axis=1)
    bands = np.column_stack([np.median(table.spectra[:, lo:hi], axis=1) * (hi - lo) for lo, hi in edges])
    shapes, powers, noise = [], [], 0.0
    for level in (int(np.argmin(levels)), int(np.argmax(levels))):
        rows = np.flatnonzero(valid & (index == level))
        runs = np.unique(table.run[rows])
        halves = (np.isin(table.run[rows], runs[::2]) if runs.size >= 2 else np.arange(rows.size) % 2 == 0)
        if rows.size < 4 or halves.all() or not halves.any():
            return SpectralShape(note='too few windows at the lowest or highest speed')
        shapes.append(_shape(bands[rows]))
        powers.append(bands[rows].mean(axis=0))
        noise = max(noise, 0.5 * float(np.abs(_shape(bands[rows[halves]]) - _shape(bands[rows[~halves]])).sum()))
    distance = 0.5 * float(np.abs(shapes[0] - shapes[1]).sum())
    white = np.array([hi - lo for lo, hi in edges], dtype=float)
    structure = 0.5 * float(np.abs(shapes[1] - white / white.sum()).sum())
    up = np.argsort(shapes[1] - shapes[0])[:_SPECTRAL.shape_added_bands]     # where the lowest speed's share is up most
    added = float(np.median(powers[1][up] / np.maximum(powers[0][up], 1e-300)))
    result = SpectralShape(testable=True, distance=distance, noise=noise, structure=structure, added_ratio=added,
                           bands=len(edges))
    verb = 'changes' if result.changes else 'keeps'
    result.note = (f'the spectral shape {verb} between the lowest and highest speed: total variation '
                   f'{distance:.3f} over {len(edges)} third-octave bands, {noise:.3f} between halves of one '
                   "speed's runs")
    if result.changes:
        result.note += (f'; where the lowest speed\'s share is up, the band power at the highest speed is '
                        f'{added:.2f} times that at the lowest')
    return result


def strongest_test(tests: Sequence[CovariateTest], rules: DiagnosisRules = DEFAULT_RULES) -> CovariateTest | None:
    """Of the tests significant at ``rules.significance``, the one carrying most of the residual variance."""
    significant = [t for t in tests if t.p_value < rules.significance]
    return max(significant, key=lambda t: t.r_squared) if significant else None


def residual_holding(table: WindowTable, residual: np.ndarray, covariate: str) -> np.ndarray:
    """``residual`` less what ``covariate`` (a column of ``table``) explains of it by least squares.

    What it explains is a parabola in it: a speed or load set in three levels
    takes out their means, a drift (temperature approaching its steady
    value, revolutions) its trend and bend.  Windows without a value of
    ``covariate`` (a temperature not recorded there) or of ``residual`` are NaN:
    nothing is held there.  Where ``table`` has no such column (the spectrum)
    or it holds one value only, ``residual`` comes back as it is.
    """
    residual = np.asarray(residual, dtype=float)
    values = getattr(table, covariate, None)
    if not isinstance(values, np.ndarray) or values.shape != residual.shape:
        return residual
    ok = np.isfinite(values) & np.isfinite(residual)
    if ok.sum() < 4 or np.ptp(values[ok]) <= 0:
        return residual
    x = (values[ok] - values[ok].mean()) / np.ptp(values[ok])
    design = np.column_stack([np.ones_like(x), x, x * x])
    coefficients, *_ = np.linalg.lstsq(design, residual[ok], rcond=None)
    held = np.full_like(residual, np.nan)
    held[ok] = residual[ok] - design @ coefficients
    return held


def partial_trend(table: WindowTable, residual: np.ndarray, covariate: str, held: str) -> CovariateTest | None:
    """The run-clustered trend of ``residual`` in ``covariate`` with ``held`` taken out of both (None: no test).

    Frisch-Waugh: on the windows that have all three, what ``held`` explains
    (:func:`residual_holding`) is taken out of the residual and of the
    covariate, and the trend of what is left of one in what is left of the
    other is tested as :func:`covariate_tests` tests a trend.  Two drifts that
    move together over a recording (the rig warming up as the revolutions add
    up) each carry a pattern that one of them makes; this tells whether
    ``covariate`` carries it beyond ``held``.  It tests a slope only: a
    pattern of another shape (an arch) that ``held`` leaves is not seen.
    """
    values = getattr(table, covariate, None)
    other = getattr(table, held, None)
    if not isinstance(values, np.ndarray) or not isinstance(other, np.ndarray):
        return None
    residual = np.asarray(residual, dtype=float)
    common = np.isfinite(residual) & np.isfinite(values) & np.isfinite(other)
    if common.sum() < 4:
        return None
    # NaN outside the common windows: both are held on the same windows, and the trend skips the rest.
    return _cluster_trend(residual_holding(table, np.where(common, residual, np.nan), held),
                          residual_holding(table, np.where(common, values, np.nan), held), table.run, covariate,
                          f'trend with {held} held')


def locate(table: WindowTable, residual: np.ndarray, rules: DiagnosisRules = DEFAULT_RULES) -> Location:
    """Test the baseline residual against every covariate and the spectrum (``rules``: the covariate tests')."""
    tests = covariate_tests(table, residual, rules)
    spectrum = spectral_lines(table, residual)
    top = strongest_test(tests, rules)
    if top is not None:
        located = top.covariate
        summary = (f'the mismatch follows {top.covariate} ({top.kind}): it carries '
                   f'{100 * top.r_squared:.0f} % of the residual variance, p = {top.p_value:.2g}')
        if top.shape:
            summary += f'; {top.shape}'
    else:
        located = 'none'
        summary = 'no covariate carries a significant part of the residual'
    for found, note in ((spectrum.frequencies, spectrum.note), (spectrum.mode_frequencies, spectrum.mode_note),
                        (spectrum.order_mode.get('found'), spectrum.order_mode.get('note'))):
        if found:
            assert note is not None  # a finding comes with its note
            summary += '; spectrum: ' + note
            if located == 'none':
                located = 'spectrum'
    return Location(tests, spectrum, located, summary, spectral_shape(table, exclude=spectrum.mode_frequencies))
