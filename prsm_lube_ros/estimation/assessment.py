# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""theta_Oil and its one-sigma uncertainty for windows and runs (Eq. 23).

Uncertainty is propagated to first order from two sources:

* the scatter of the measured RMS as a *new run* shows it: every run (traverse)
  has its own amplitude factor (sensor coupling, preload, temperature), so a
  run's ln(RMS) scatters by the run-to-run scatter ``tau`` learnt at
  calibration plus its windows' scatter over sqrt(n) (its own windows' with
  three or more, else the calibration's); a single window by
  ``sqrt(tau^2 + sigma_w^2)``.  Both are the standard deviation of a Student t
  with the calibration's run degrees of freedom
  (:meth:`.run_scatter.RunScatter.new_run_variance`), never 0;
* the covariance of (ln C_sys, C_F, C_lambda) from the calibration fit (the
  run-level model, :mod:`.calibration`).

With ``g = C_lambda omega^0.68 F^-0.073`` Eq. 23 has the partial derivatives
``d theta/d ln A = -1/g``, ``d theta/d ln C_sys = 1/g``,
``d theta/d C_F = F/g`` and ``d theta/d C_lambda = -theta/C_lambda``.  The
last is taken at the reference state (``theta = theta_ref``, 1 by default),
so the sigma is that of the reading against the reference: there the three
derivatives are the model's prediction of ln A at the run's speed and load
over ``g``, and the constants contribute the uncertainty of that prediction.
Taken at the reading instead, an ill-determined C_lambda (three conditions on
a line leave it near zero +/- several times itself) would make sigma grow
with the reading's own noise, so that readings scattered far from 1 by noise
carry the largest sigma; how well C_lambda, the scale of theta, is known is
said by the calibration instead (``C_lambda not identified`` flag).

Where Eq. 23 means nothing (screw at rest or crawling, no load, no film term,
no vibration) theta is NaN and ``reason`` says why, in words.

theta_Oil is a supply factor: 0 is no oil film term at all, 1 the reference
(fully lubricated) state.  A value below 0, or far above 1 (beyond
:data:`THETA_PLAUSIBLE_MAX`), is not a lubrication state: the vibration lies
outside what the calibrated model can produce, and :func:`theta_range_flag`
says so with the likely reason (``theta_oil_flag`` in the JSON, a mark in the
table).  The value is still reported.

Windows and runs outside the calibration's domain (the speeds, loads and
temperatures it was fitted on, :mod:`.domain`) carry ``domain_flag``: how far
outside, in words (``extrapolated: speed 40 % below the calibrated 63-188
rad/s``); the value is still reported.

A calibration with a model extension (``Calibration.extension``, written by
``prsm-lube diagnose``) is honoured: each window's RMS is first mapped back to
the amplitude Eq. 22 describes and theta_Oil divided by the extension's film
factor (see :mod:`prsm_lube_ros.estimation.extension`).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import TYPE_CHECKING
from collections.abc import Iterable, Sequence

import numpy as np

from ..physics.vibration_model import film_speed_load_term, lubrication_index
from ..validation import finite_or_none
from .calibration import Calibration
from .condition_indicators import ConditionIndicators
from .defect_screen import DEFAULT_RULES, DefectFinding, DefectRules, NOT_SUSPECTED, run_condition, RunCondition, screen
from .domain import domain_flag
from .windowing import assessable, DEFAULT_DEFECT_ORDERS, MIN_AXIAL_LOAD, not_assessable_reason, runs_of, Window

if TYPE_CHECKING:
    from typing import TypeAlias

    from ..physics.defect_orders import DefectOrder

    #: One run pooled over its windows: ``(rms, amplitude, factor, speed, load, temperature, ln_var, reason)``.
    _PooledRun: TypeAlias = tuple[float, float, float, float, float, float, float, str]

__all__ = ['Assessor', 'RunAssessment', 'THETA_PLAUSIBLE_MAX', 'WindowAssessment', 'condition_json',
           'theta_range_flag']

#: Highest theta_Oil taken as a lubrication state (1 = reference; the paper's stages span 0.72-1).
THETA_PLAUSIBLE_MAX = 1.5


def theta_range_flag(theta: float, std: float = math.nan) -> str:
    """Why a theta_Oil lies outside its physical range, in words ('' inside it or when NaN)."""
    if not math.isfinite(theta):
        return ''
    sigma = f' +/- {std:.2f}' if math.isfinite(std) else ''
    if theta < 0:
        return (f'theta_oil {theta:.2f}{sigma} below 0 is not physical: the vibration is higher than Eq. 22 allows '
                'with no oil film term, so the calibration does not describe this actuator or these conditions '
                '(another vibration source, other speeds or loads than calibrated, a changed sensor)')
    if theta > THETA_PLAUSIBLE_MAX:
        return (f'theta_oil {theta:.2f}{sigma} far above 1 (the reference state) is not physical: the vibration '
                'is lower than the calibrated fully lubricated level, so the calibration does not describe this '
                'actuator or these conditions (other speeds or loads than calibrated, a changed sensor or mounting)')
    return ''


@dataclass(frozen=True)
class WindowAssessment:
    """theta_Oil of one window."""

    window: Window
    theta_oil: float
    theta_oil_std: float
    reason: str = ''
    domain_flag: str = ''   # :func:`.domain.domain_flag` of an assessed window outside the calibration's domain
    #: The surface defect screen of the window's run (:meth:`Assessor.runs_screen_windows`): one window's
    #: envelope is too noisy to judge alone (a quarter of healthy windows would trip it at low speed)
    defect: DefectFinding = NOT_SUSPECTED

    @property
    def flag(self) -> str:
        """:func:`theta_range_flag` of this window ('' when theta_Oil is in its physical range)."""
        return theta_range_flag(self.theta_oil, self.theta_oil_std)


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
    domain_flag: str = ''   # :func:`.domain.domain_flag` of an assessed run outside the calibration's domain
    condition: RunCondition | None = None   # the run's pooled condition indicators
    defect: DefectFinding = NOT_SUSPECTED   # surface defect screen of the run (:mod:`.defect_screen`)

    @property
    def flag(self) -> str:
        """:func:`theta_range_flag` of this run ('' when theta_Oil is in its physical range)."""
        return theta_range_flag(self.theta_oil, self.theta_oil_std)

    def as_json(self) -> dict:
        """Mapping for the contract's ``runs`` list (plus extra fields)."""
        return {'bag': self.bag, 'start': self.start, 'end': self.end,
                'screw_speed': self.screw_speed, 'axial_load': self.axial_load,
                'vibration_rms': self.vibration_rms, 'theta_oil': self.theta_oil,
                'theta_oil_std': self.theta_oil_std, 'theta_oil_flag': self.flag, 'run_index': self.run_index,
                'windows': self.windows, 'temperature': finite_or_none(self.temperature),
                'reason': self.reason, 'domain_flag': self.domain_flag,
                'condition_indicators': condition_json(self.condition), **self.defect.as_dict()}


def condition_json(condition: RunCondition | ConditionIndicators | None) -> dict:
    """The contract's ``condition_indicators`` of a run or window (nulls and no peaks where none were computed)."""
    if condition is None:
        return {'kurtosis': None, 'crest_factor': None, 'envelope_peaks': []}
    return condition.as_dict()


class Assessor:
    """Evaluates Eq. 23 with a calibration, for windows and for runs."""

    def __init__(self, calibration: Calibration, min_axial_load: float = MIN_AXIAL_LOAD,
                 defect_orders: Sequence[DefectOrder] = DEFAULT_DEFECT_ORDERS,
                 defect_rules: DefectRules = DEFAULT_RULES):
        self.calibration = calibration
        self.min_axial_load = float(min_axial_load)
        self.defect_orders = tuple(defect_orders)
        self.defect_rules = defect_rules

    def screen(self, conditions: Sequence[ConditionIndicators | None]) -> tuple[RunCondition | None, DefectFinding]:
        """Pooled indicators of windows (a run, or a window alone) and the surface defect screen on them."""
        present = [c for c in conditions if c is not None]
        if not present:
            return None, NOT_SUSPECTED
        pooled = run_condition(present, self.defect_orders)
        return pooled, screen(pooled, self.defect_orders, self.calibration.condition_baseline, self.defect_rules)

    def theta(self, rms: float, speed: float, load: float, ln_rms_var: float) -> tuple[float, float]:
        """theta_Oil (Eq. 23) and its one-sigma uncertainty for one amplitude, speed and load.

        ``ln_rms_var`` is the variance of ln(rms) from measurement scatter.
        """
        theta, std = self.thetas(np.array([rms], float), np.array([speed], float), np.array([load], float),
                                 np.array([ln_rms_var], float))
        return float(theta[0]), float(std[0])

    def thetas(self, rms: np.ndarray, speed: np.ndarray, load: np.ndarray,
               ln_rms_var: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`theta` element by element for arrays of amplitudes, speeds, loads and ln(rms) variances.

        Each element gets the same numbers whatever the length of the arrays, so
        one window, all windows of a recording and runs are evaluated alike.
        NaN (theta and std) where Eq. 23 has no finite value.
        """
        constants = self.calibration.constants
        theta = np.asarray(lubrication_index(rms, speed, load, constants), float).reshape(-1)
        std = np.full(theta.shape, math.nan)
        ok = np.isfinite(theta)
        theta[~ok] = math.nan
        if ok.any():
            g = constants.c_lambda * film_speed_load_term(speed[ok], load[ok])
            reference = np.full(g.shape, self.calibration.reference_theta)
            gradient = np.stack((1.0 / g, np.abs(load[ok]) / g, -reference / constants.c_lambda), axis=-1)
            parameters = (gradient[:, None, :] @ self.calibration.covariance @ gradient[:, :, None])[:, 0, 0]
            variance = ln_rms_var[ok] / g ** 2 + parameters
            std[ok] = np.sqrt(np.maximum(variance, 0.0))
        return theta, std

    def _through_extension(self, windows: Sequence[Window]) -> tuple[np.ndarray, np.ndarray]:
        """Window RMS mapped to Eq. 22's amplitude and the film factor of the calibration's extension."""
        rms = np.array([w.vibration_rms for w in windows], dtype=float)
        if not self.calibration.extension:
            return rms, np.ones_like(rms)
        from .extension import eq22_inputs
        return eq22_inputs(self.calibration.extension, windows, rms)

    def assess_window(self, window: Window) -> WindowAssessment:
        """theta_Oil of one window, NaN with the reason where it is not assessable."""
        return self.assess_windows([window])[0]

    def assess_windows(self, windows: Iterable[Window]) -> list[WindowAssessment]:
        """:meth:`assess_window` for each window, evaluated for all of them at once."""
        windows = list(windows)
        theta = np.full(len(windows), math.nan)
        std = np.full(len(windows), math.nan)
        reasons = [w.reason for w in windows]
        steady = [i for i, w in enumerate(windows) if w.steady]
        if steady:
            speed = np.array([windows[i].screw_speed for i in steady], float)
            load = np.array([windows[i].axial_load for i in steady], float)
            rms = np.array([windows[i].vibration_rms for i in steady], float)
            ok = assessable(speed, load, rms, self.min_axial_load)
            for j in np.flatnonzero(~ok).tolist():
                reasons[steady[j]] = not_assessable_reason(float(speed[j]), float(load[j]), float(rms[j]),
                                                           self.min_axial_load)
            rows = [steady[j] for j in np.flatnonzero(ok).tolist()]
            if rows:
                amplitude, factor = self._through_extension([windows[i] for i in rows])
                window_variance = self.calibration.run_scatter.new_run_variance(1)
                values, errors = self.thetas(amplitude, speed[ok], load[ok], np.full(len(rows), window_variance))
                with np.errstate(divide='ignore', invalid='ignore'):
                    values, errors = values / factor, errors / np.abs(factor)
                finite = np.isfinite(values)
                theta[rows] = np.where(finite, values, math.nan)
                std[rows] = np.where(finite, errors, math.nan)
                for j in np.flatnonzero(~finite).tolist():
                    reasons[rows[j]] = 'Eq. 23 has no finite value for this window'
        domain = self.calibration.domain
        return [WindowAssessment(w, t, s, r, domain_flag(domain, w.screw_speed, w.axial_load, w.temperature)
                                 if domain is not None and t == t else '')
                for w, t, s, r in zip(windows, theta.tolist(), std.tolist(), reasons)]

    @staticmethod
    def runs_screen_windows(assessed: Sequence[WindowAssessment],
                            runs: Sequence[RunAssessment]) -> list[WindowAssessment]:
        """Each steady window with its run's defect finding (the screen judges pooled windows, not one)."""
        findings = {run.run_index: run.defect for run in runs}
        return [replace(item, defect=findings.get(item.window.run_index, NOT_SUSPECTED)) if item.window.steady
                else item for item in assessed]

    def assess_runs(self, assessed: Sequence[WindowAssessment], bag: str = '') -> list[RunAssessment]:
        """One :class:`RunAssessment` per run that has steady windows, in run order."""
        return self._assess_runs(list(runs_of(item.window for item in assessed).values()), bag)

    def assess_run(self, windows: Sequence[Window], bag: str = '') -> RunAssessment:
        """theta_Oil of a run from its steady windows' pooled RMS, mean speed and load."""
        return self._assess_runs([list(windows)], bag)[0]

    def _assess_runs(self, runs: Sequence[Sequence[Window]], bag: str) -> list[RunAssessment]:
        """:meth:`assess_run` for each run: pooled per run, Eq. 23 for all runs at once."""
        if not runs:
            return []
        pooled = self._pooled(runs)
        rms, amplitude, factor, speed, load, temperature, ln_var, reasons = (list(c) for c in zip(*pooled))
        theta, std = self.thetas(np.array(amplitude), np.array(speed), np.array(load), np.array(ln_var))
        with np.errstate(divide='ignore', invalid='ignore'):
            theta, std = theta / np.array(factor), std / np.abs(factor)
        results = []
        for i, windows in enumerate(runs):
            reason = reasons[i]
            theta_i, std_i = (math.nan, math.nan) if reason else (float(theta[i]), float(std[i]))
            if not reason and not math.isfinite(theta_i):
                reason = 'Eq. 23 has no finite value for this run'
            condition, defect = self.screen([w.condition for w in windows])
            results.append(RunAssessment(bag=bag, run_index=windows[0].run_index, start=windows[0].start,
                                         end=windows[-1].end, screw_speed=speed[i], axial_load=load[i],
                                         vibration_rms=rms[i], theta_oil=theta_i, theta_oil_std=std_i,
                                         windows=len(windows), temperature=temperature[i], reason=reason,
                                         domain_flag='' if reason else domain_flag(
                                             self.calibration.domain, speed[i], load[i], temperature[i]),
                                         condition=condition, defect=defect))
        return results

    def _pooled(self, runs: Sequence[Sequence[Window]]) -> list[_PooledRun]:
        """Per run ``(rms, amplitude, factor, speed, load, temperature, ln_var, reason)`` from its windows.

        The RMS, Eq. 22's amplitude and the extension's film factor, speed and
        load pooled over the run's windows (weighted by their sample counts),
        its mean known temperature, the variance of its ln(RMS) as a new run
        (:meth:`.run_scatter.RunScatter.new_run_variance`) and why Eq. 23
        cannot be evaluated for it ('' when it can).
        """
        everything = [w for windows in runs for w in windows]
        amplitudes, factors = self._through_extension(everything)
        # The same numpy reductions as np.average, np.nanmean and np.var per run, on slices of one array each.
        counts_all = np.array([w.sample_count for w in everything], dtype=float)
        rms_all = np.array([w.vibration_rms for w in everything], dtype=float)
        speed_all = np.array([w.screw_speed for w in everything], dtype=float)
        load_all = np.array([w.axial_load for w in everything], dtype=float)
        temps_all = np.array([w.temperature for w in everything], dtype=float)
        with np.errstate(divide='ignore', invalid='ignore'):
            log_rms_all = np.log(rms_all)
            weighted = [counts_all * rms_all ** 2, counts_all * amplitudes ** 2, counts_all * factors,
                        counts_all * speed_all, counts_all * load_all]
        temp_known = ~np.isnan(temps_all)
        temps_zeroed = np.where(temp_known, temps_all, 0.0)
        temp_finite = np.isfinite(temps_all)
        scatter = self.calibration.run_scatter
        pooled = []
        first = 0
        for windows in runs:
            n = len(windows)
            last = first + n
            total = np.sum(counts_all[first:last])
            sq_sum, amp_sum, factor_sum, speed_sum, load_sum = (float(np.sum(w[first:last])) for w in weighted)
            rms = float(np.sqrt(sq_sum / total))
            amplitude = float(np.sqrt(amp_sum / total))
            factor, speed, load = float(factor_sum / total), float(speed_sum / total), float(load_sum / total)
            if temp_finite[first:last].any():
                temperature = float(np.sum(temps_zeroed[first:last]) / np.count_nonzero(temp_known[first:last]))
            else:
                temperature = math.nan
            own_variance = None
            if n >= 3:
                logs = log_rms_all[first:last]
                deviation = logs - np.sum(logs) / n
                own_variance = float(np.sum(deviation * deviation) / (n - 1))
            ln_var = scatter.new_run_variance(n, own_variance)
            pooled.append((rms, amplitude, factor, speed, load, temperature, ln_var,
                           not_assessable_reason(speed, load, rms, self.min_axial_load)))
            first = last
        return pooled
