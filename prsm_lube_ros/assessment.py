"""theta_Oil and its one-sigma uncertainty for windows and runs (Eq. 23).

Uncertainty is propagated to first order from two sources:

* the scatter of the measured RMS: for a window, the window-to-window scatter
  of ln(RMS) seen at calibration (``Calibration.residual_std``); for a run,
  the scatter of its own windows' ln(RMS) divided by sqrt(n);
* the covariance of (ln C_sys, C_F, C_lambda) from the calibration fit.

With ``g = C_lambda omega^0.68 F^-0.073`` Eq. 23 has the partial derivatives
``d theta/d ln A = -1/g``, ``d theta/d ln C_sys = 1/g``,
``d theta/d C_F = F/g`` and ``d theta/d C_lambda = -theta/C_lambda``.

Where Eq. 23 means nothing (screw at rest or crawling, no load, no film term,
no vibration) theta is NaN and ``reason`` says why, in words.

A calibration with a model extension (``Calibration.extension``, written by
``prsm-lube diagnose``) is honoured: each window's RMS is first mapped back to
the amplitude Eq. 22 describes and theta_Oil divided by the extension's film
factor (see :mod:`prsm_lube_ros.diagnosis.extension`).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Iterable, Sequence

import numpy as np

from .calibration import Calibration
from .vibration_model import film_speed_load_term, lubrication_index
from .windowing import Window

#: Default smallest axial load, N, at which Eq. 23 is evaluated (the nut is unloaded below it).
MIN_AXIAL_LOAD = 5.0


@dataclass(frozen=True)
class WindowAssessment:
    """theta_Oil of one window."""

    window: Window
    theta_oil: float
    theta_oil_std: float
    reason: str = ''


@dataclass(frozen=True)
class RunAssessment:
    """theta_Oil of one run (the steady windows of one traverse)."""

    bag: str
    run_index: int
    start: float            # s since the epoch, first steady window
    end: float              # s since the epoch, last steady window
    screw_speed: float      # rad/s
    axial_load: float       # N
    vibration_rms: float    # m/s^2 over the run's steady windows
    theta_oil: float
    theta_oil_std: float
    windows: int
    temperature: float = math.nan
    reason: str = ''

    def as_json(self) -> dict:
        """Mapping for the contract's ``runs`` list (plus extra fields)."""
        return {'bag': self.bag, 'start': self.start, 'end': self.end,
                'screw_speed': self.screw_speed, 'axial_load': self.axial_load,
                'vibration_rms': self.vibration_rms, 'theta_oil': self.theta_oil,
                'theta_oil_std': self.theta_oil_std, 'run_index': self.run_index,
                'windows': self.windows, 'temperature': _json_float(self.temperature),
                'reason': self.reason}


def _json_float(value: float):
    return value if math.isfinite(value) else None


class Assessor:
    """Evaluates Eq. 23 with a calibration, for windows and for runs."""

    def __init__(self, calibration: Calibration, min_axial_load: float = MIN_AXIAL_LOAD):
        self.calibration = calibration
        self.min_axial_load = float(min_axial_load)

    def _not_assessable(self, window_or_values) -> str:
        speed, load, rms = window_or_values
        if not (math.isfinite(rms) and rms > 0):
            return 'no vibration: the RMS is zero or missing'
        if not (math.isfinite(load) and load >= self.min_axial_load):
            return (f'axial load {load:.3g} N is below {self.min_axial_load:.3g} N: Eq. 23 needs the nut '
                    'under load')
        if not (math.isfinite(speed) and speed > 0):
            return 'screw at rest: Eq. 23 needs a screw speed'
        return ''

    def theta(self, rms: float, speed: float, load: float, ln_rms_var: float) -> tuple[float, float]:
        """theta_Oil (Eq. 23) and its one-sigma uncertainty for one amplitude, speed and load.

        ``ln_rms_var`` is the variance of ln(rms) from measurement scatter.
        """
        constants = self.calibration.constants
        theta = lubrication_index(rms, speed, load, constants)
        if not math.isfinite(theta):
            return math.nan, math.nan
        g = constants.c_lambda * float(film_speed_load_term(speed, load))
        gradient = np.array([1.0 / g, abs(load) / g, -theta / constants.c_lambda])
        variance = ln_rms_var / g ** 2 + float(gradient @ self.calibration.covariance @ gradient)
        return theta, math.sqrt(max(variance, 0.0))

    def _through_extension(self, windows: Sequence[Window]) -> tuple[np.ndarray, np.ndarray]:
        """Window RMS mapped to Eq. 22's amplitude and the film factor of the calibration's extension."""
        rms = np.array([w.vibration_rms for w in windows], dtype=float)
        if not self.calibration.extension:
            return rms, np.ones_like(rms)
        from .diagnosis.extension import eq22_inputs
        return eq22_inputs(self.calibration.extension, windows, rms)

    def assess_window(self, window: Window) -> WindowAssessment:
        """theta_Oil of one window, NaN with the reason where it is not assessable."""
        if not window.steady:
            return WindowAssessment(window, math.nan, math.nan, window.reason)
        reason = self._not_assessable((window.screw_speed, window.axial_load, window.vibration_rms))
        if reason:
            return WindowAssessment(window, math.nan, math.nan, reason)
        amplitude, factor = self._through_extension([window])
        theta, std = self.theta(float(amplitude[0]), window.screw_speed, window.axial_load,
                                self.calibration.residual_std ** 2)
        theta, std = theta / float(factor[0]), std / abs(float(factor[0]))
        if not math.isfinite(theta):
            return WindowAssessment(window, math.nan, math.nan, 'Eq. 23 has no finite value for this window')
        return WindowAssessment(window, theta, std)

    def assess_windows(self, windows: Iterable[Window]) -> list[WindowAssessment]:
        """:meth:`assess_window` for each window."""
        return [self.assess_window(w) for w in windows]

    def assess_runs(self, assessed: Sequence[WindowAssessment], bag: str = '') -> list[RunAssessment]:
        """One :class:`RunAssessment` per run that has steady windows, in run order."""
        by_run: dict[int, list[Window]] = {}
        for item in assessed:
            if item.window.steady:
                by_run.setdefault(item.window.run_index, []).append(item.window)
        return [self.assess_run(windows, bag) for _, windows in sorted(by_run.items())]

    def assess_run(self, windows: Sequence[Window], bag: str = '') -> RunAssessment:
        """theta_Oil of a run from its steady windows' pooled RMS, mean speed and load."""
        counts = np.array([w.sample_count for w in windows], dtype=float)
        rms_values = np.array([w.vibration_rms for w in windows])
        rms = float(np.sqrt(np.sum(counts * rms_values ** 2) / np.sum(counts)))
        amplitudes, factors = self._through_extension(windows)
        amplitude = float(np.sqrt(np.sum(counts * amplitudes ** 2) / np.sum(counts)))
        factor = float(np.average(factors, weights=counts))
        speed = float(np.average([w.screw_speed for w in windows], weights=counts))
        load = float(np.average([w.axial_load for w in windows], weights=counts))
        temps = np.array([w.temperature for w in windows])
        temperature = float(np.nanmean(temps)) if np.isfinite(temps).any() else math.nan
        n = len(windows)
        if n >= 3:
            ln_var = float(np.var(np.log(rms_values), ddof=1)) / n
        else:
            ln_var = self.calibration.residual_std ** 2 / n
        reason = self._not_assessable((speed, load, rms))
        theta, std = (math.nan, math.nan) if reason else self.theta(amplitude, speed, load, ln_var)
        theta, std = theta / factor, std / abs(factor)
        if not reason and not math.isfinite(theta):
            reason = 'Eq. 23 has no finite value for this run'
        return RunAssessment(bag=bag, run_index=windows[0].run_index, start=windows[0].start,
                             end=windows[-1].end, screw_speed=speed, axial_load=load, vibration_rms=rms,
                             theta_oil=theta, theta_oil_std=std, windows=n, temperature=temperature,
                             reason=reason)
