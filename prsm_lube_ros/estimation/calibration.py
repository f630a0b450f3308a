# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Least-squares fit of C_sys, C_F and C_lambda on windows at a known theta_Oil.

With theta_Oil known, Eq. 22 is linear in ``p = (ln C_sys, C_F, C_lambda)``::

    ln(A_0 omega_S^-2 F_a^(1/3)) = ln C_sys + C_F F_a - C_lambda theta_Oil omega_S^0.68 F_a^-0.073

so the constants follow from ordinary least squares on the steady windows of
reference recordings, with the usual covariance ``s^2 (X^T X)^-1``.  The three
columns are only independent when the windows span at least two axial loads
and two screw speeds; anything less gets an :class:`InputError` that says what
to record, never a fit.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..physics.vibration_model import acceleration_amplitude, design_matrix, ModelConstants, reduced_log_amplitude
from .windowing import MIN_AXIAL_LOAD, usable_windows

#: Relative tolerance within which two speeds or loads count as one operating level.
LEVEL_TOLERANCE = 0.05
#: Fewest windows for a fit with standard errors (three constants and one degree of freedom).
MIN_WINDOWS = 4


@dataclass(frozen=True)
class Calibration:
    """Fitted constants with their uncertainty and what they were fitted on."""

    constants: ModelConstants
    covariance: np.ndarray          # 3x3 covariance of (ln C_sys, C_F, C_lambda)
    fit_rmse: float                 # relative RMS error of the fitted amplitudes
    residual_std: float             # std of ln(A) residuals (window-to-window scatter), dimensionless
    windows_used: int
    reference_theta: float
    speed_levels: tuple = ()        # rad/s, distinct screw speeds in the data
    load_levels: tuple = ()         # N, distinct axial loads in the data
    sources: tuple = ()             # recordings the fit used
    extension: dict = field(default_factory=dict)  # model extension (effect id and parameters), if any

    @property
    def c_sys_std(self) -> float:
        """One-sigma standard error of C_sys (delta method from ln C_sys)."""
        return self.constants.c_sys * math.sqrt(self.covariance[0, 0])

    @property
    def c_f_std(self) -> float:
        """One-sigma standard error of C_F, 1/N."""
        return math.sqrt(self.covariance[1, 1])

    @property
    def c_lambda_std(self) -> float:
        """One-sigma standard error of C_lambda."""
        return math.sqrt(self.covariance[2, 2])


def operating_levels(values: Sequence[float], tolerance: float = LEVEL_TOLERANCE) -> list[float]:
    """Distinct levels in ``values``: sorted values closer than ``tolerance`` (relative) merge."""
    ordered = np.sort(np.abs(np.asarray(values, dtype=float)))
    levels: list[list[float]] = []
    for value in ordered:
        if levels and value <= levels[-1][0] * (1 + tolerance):
            levels[-1].append(value)
        else:
            levels.append([value])
    return [float(np.mean(group)) for group in levels]


def check_identifiable(speeds, loads) -> tuple[list[float], list[float]]:
    """Raise :class:`InputError` saying what to record unless the data can identify all three constants.

    Returns the speed and load levels found.
    """
    n = len(speeds)
    speed_levels = operating_levels(speeds)
    load_levels = operating_levels(loads)
    if n == 0:
        raise InputError('calibration: no steady window with a screw speed and an axial load in the '
                         'recordings; record runs at constant speed under load (3 speeds x 2 loads as in the paper)')
    missing = []
    if len(load_levels) < 2:
        missing.append(f'a second axial load (all windows at {_levels(load_levels, "N")}); '
                       'C_sys and C_F cannot be told apart at one load')
    if len(speed_levels) < 2:
        missing.append(f'a second screw speed (all windows at {_levels(speed_levels, "rad/s")}); '
                       'C_lambda cannot be told from C_F with one speed')
    if n < MIN_WINDOWS:
        missing.append(f'more windows ({n} steady, need at least {MIN_WINDOWS}): longer runs or shorter windows')
    if missing:
        raise InputError('calibration cannot identify C_sys, C_F and C_lambda: record ' + '; and '.join(missing))
    return speed_levels, load_levels


def _levels(levels, unit):
    return ', '.join(f'{v:.4g} {unit}' for v in levels) or 'none'


def fit_constants(speeds, loads, amplitudes, theta: float = 1.0, *, sources: Sequence[str] = (),
                  ) -> Calibration:
    """Fit Eq. 22 by least squares on windows at lubrication state ``theta``.

    speeds in rad/s, loads in N, amplitudes (window RMS) in m/s^2, theta
    dimensionless (the reference state, 1 = fully lubricated).
    """
    speeds = np.abs(np.asarray(speeds, dtype=float))
    loads = np.abs(np.asarray(loads, dtype=float))
    amplitudes = np.asarray(amplitudes, dtype=float)
    if not (math.isfinite(theta) and theta > 0):
        raise InputError(f'calibration: reference theta {theta!r} must be a positive number')
    usable = (np.isfinite(speeds) & np.isfinite(loads) & np.isfinite(amplitudes)
              & (speeds > 0) & (loads > 0) & (amplitudes > 0))
    speeds, loads, amplitudes = speeds[usable], loads[usable], amplitudes[usable]
    speed_levels, load_levels = check_identifiable(speeds, loads)
    x = design_matrix(speeds, loads, theta)
    y = reduced_log_amplitude(amplitudes, speeds, loads)
    # Scale columns so the conditioning test means something whatever the units.
    scale = np.linalg.norm(x, axis=0)
    xs = x / scale
    singular = np.linalg.svd(xs, compute_uv=False)
    if singular[-1] < 1e-9 * singular[0]:
        raise InputError('calibration cannot identify C_sys, C_F and C_lambda: the speeds and loads recorded '
                         'leave the fit degenerate; record at least 2 loads and 2 speeds (3 x 2 as in the paper)')
    solution, *_ = np.linalg.lstsq(xs, y, rcond=None)
    params = solution / scale
    residual = y - x @ params
    dof = max(len(y) - 3, 1)
    residual_var = float(residual @ residual) / dof
    covariance = residual_var * np.linalg.inv(x.T @ x)
    constants = ModelConstants.from_vector(params)
    fitted = acceleration_amplitude(speeds, loads, theta, constants)
    fit_rmse = float(np.sqrt(np.mean((fitted / amplitudes - 1.0) ** 2)))
    return Calibration(constants=constants, covariance=covariance, fit_rmse=fit_rmse,
                       residual_std=math.sqrt(residual_var), windows_used=int(len(y)),
                       reference_theta=float(theta), speed_levels=tuple(speed_levels),
                       load_levels=tuple(load_levels), sources=tuple(str(s) for s in sources))


def fit_windows(windows, theta: float = 1.0, *, min_axial_load: float = MIN_AXIAL_LOAD, sources=()) -> Calibration:
    """Fit on the steady windows (see :mod:`.windowing`) whose load is at least ``min_axial_load``."""
    chosen = usable_windows(windows, min_axial_load)
    return fit_constants([w.screw_speed for w in chosen], [w.axial_load for w in chosen],
                         [w.vibration_rms for w in chosen], theta, sources=sources)
