# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A calibration file is untrusted input: what its values must satisfy before anything uses them.

:func:`check_calibration` is called by the loader
(:func:`~prsm_lube_ros.estimation.calibration_file.calibration_from_dict`)
once the file has been turned into a :class:`~.calibration.Calibration`; each
failure is one :class:`~prsm_lube_ros.errors.ConfigError` line naming the
file.  The rules:

* no infinity anywhere in the document (NaN only where a figure may be missing);
* constants finite, with the signs of the physics: C_sys > 0 (an amplitude),
  C_lambda > 0 (oil lowers the excitation, Eq. 19); C_F finite;
* the covariance of (ln C_sys, C_F, C_lambda) finite, symmetric and positive
  definite (its square roots are the standard errors);
* the fit's figures (residual scatter, RMS error) finite and >= 0 or missing,
  the reference theta_Oil finite and > 0, speed and load levels positive and
  within what the contract's sensors give (:mod:`..recording.plausibility`);
* Eq. 22 with these constants, at the calibration's own speeds and loads and
  reference theta_Oil, predicts amplitudes an accelerometer can give
  (:data:`MIN_PLAUSIBLE_RMS` to ``MAX_ACCELERATION``): a C_sys scaled by
  1e-6 cannot pass for a calibration;
* a model extension names a known effect and gives every parameter as a
  finite number (or null).

Imports numpy, the physics and the plausibility bounds only.
"""
from __future__ import annotations

import math
from typing import NoReturn, TYPE_CHECKING
from collections.abc import Callable, Iterator

import numpy as np
import numpy.typing as npt

from ..errors import ConfigError
from ..physics.vibration_model import acceleration_amplitude
from ..recording.plausibility import MAX_ACCELERATION, MAX_AXIAL_LOAD, MAX_SCREW_SPEED

if TYPE_CHECKING:
    from .calibration import Calibration

__all__ = ['MIN_PLAUSIBLE_RMS', 'OPTIONAL_FIGURES', 'check_calibration', 'check_document']

#: Smallest window RMS (m/s^2) the constants may predict at their own reference conditions: 10 micro-g,
#: the noise floor of an IEPE accelerometer (the paper's 100 mV/g sensor).
MIN_PLAUSIBLE_RMS = 1e-4
#: Fit figures that may be missing (NaN) in a file; every other number must be finite.
OPTIONAL_FIGURES = ('fit_rmse', 'residual_std')


def _numbers(data: object, path: str = '') -> Iterator[tuple[str, float]]:
    """``(where, value)`` of every float in a parsed YAML document, each shared (aliased) node visited once."""
    stack: list[tuple[str, object]] = [(path, data)]
    seen: set[int] = set()
    while stack:
        where, node = stack.pop()
        if isinstance(node, (dict, list, tuple)):
            if id(node) in seen:
                continue
            seen.add(id(node))
        if isinstance(node, dict):
            stack.extend((f'{where}.{key}' if where else str(key), value) for key, value in node.items())
        elif isinstance(node, (list, tuple)):
            stack.extend((f'{where}[{index}]', value) for index, value in enumerate(node))
        elif isinstance(node, float):
            yield where, node


def check_document(data: dict, origin: str) -> None:
    """No infinity anywhere in the parsed file (``origin`` names it in the error)."""
    for where, value in _numbers(data):
        if math.isinf(value):
            raise ConfigError(f'{origin}: {where} is {value} (a calibration holds finite numbers)')


def check_calibration(calibration: Calibration, origin: str) -> None:
    """Raise one :class:`ConfigError` line naming ``origin`` when ``calibration`` breaks a rule above."""
    def refuse(what: str) -> NoReturn:
        raise ConfigError(f'{origin}: {what}')

    c = calibration.constants
    values = c.by_name()
    for name, value in values.items():
        if not math.isfinite(value):
            refuse(f'constants {name} is {value} (must be finite)')
    if not c.c_sys > 0:
        refuse(f'constants c_sys = {c.c_sys:g} must be > 0 (an amplitude scale)')
    if not c.c_lambda > 0:
        refuse(f'constants c_lambda = {c.c_lambda:g} must be > 0 (oil lowers the excitation, Eq. 19)')
    _check_covariance(np.asarray(calibration.covariance, float), refuse)
    for name in OPTIONAL_FIGURES:
        value = getattr(calibration, name)
        if not (math.isnan(value) or (math.isfinite(value) and value >= 0)):
            refuse(f'fit {name} = {value} must be a number >= 0')
    if not (math.isfinite(calibration.reference_theta) and calibration.reference_theta > 0):
        refuse(f'fit reference_theta = {calibration.reference_theta} must be a positive number')
    if calibration.windows_used < 0 or calibration.conditions < 0 or calibration.runs < 0:
        refuse('fit windows_used, conditions and runs must be >= 0')
    speeds = _levels(calibration.speed_levels, 'speed_levels_rad_s', MAX_SCREW_SPEED, refuse)
    loads = _levels(calibration.load_levels, 'load_levels_n', MAX_AXIAL_LOAD, refuse)
    if speeds.size and loads.size:
        speed, load = np.meshgrid(speeds, loads)
        with np.errstate(all='ignore'):
            predicted = np.asarray(acceleration_amplitude(speed, load, calibration.reference_theta, c))
        if not (np.all(np.isfinite(predicted)) and predicted.min() >= MIN_PLAUSIBLE_RMS
                and predicted.max() <= MAX_ACCELERATION):
            low, high = float(np.nanmin(predicted)), float(np.nanmax(predicted))
            refuse(f'the constants predict window RMS {low:.3g} to {high:.3g} m/s^2 at the calibration\'s own '
                   f'speeds and loads, outside what an accelerometer gives ({MIN_PLAUSIBLE_RMS:g} to '
                   f'{MAX_ACCELERATION:g} m/s^2): damaged or edited constants')
    _check_extension(calibration.extension, refuse)


def _check_covariance(covariance: np.ndarray, refuse: Callable[[str], NoReturn]) -> None:
    """Finite, symmetric, positive definite 3x3 (judged on the correlation matrix, so any units pass)."""
    if covariance.shape != (3, 3) or not np.all(np.isfinite(covariance)):
        refuse('covariance_ln_csys_cf_clambda must be a 3x3 matrix of finite numbers')
    if not np.allclose(covariance, covariance.T, rtol=1e-9, atol=0.0):
        refuse('covariance_ln_csys_cf_clambda is not symmetric')
    variance = np.diag(covariance)
    if not np.all(variance > 0):
        refuse('covariance_ln_csys_cf_clambda has a variance <= 0 on its diagonal (must be positive definite)')
    scale = np.sqrt(variance)
    correlation = covariance / np.outer(scale, scale)
    if not np.linalg.eigvalsh(correlation).min() > 1e-12:
        refuse('covariance_ln_csys_cf_clambda is not positive definite (correlations beyond +-1)')


def _levels(levels: npt.ArrayLike, name: str, limit: float, refuse: Callable[[str], NoReturn]) -> np.ndarray:
    """A level list as an array; each level finite, > 0 and at most ``limit``."""
    try:
        array = np.asarray(levels, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        refuse(f'fit {name} must be a list of numbers')
    if not np.all((array > 0) & (array <= limit)):
        refuse(f'fit {name} must hold numbers > 0 and <= {limit:g}')
    return array


def _check_extension(extension: dict, refuse: Callable[[str], NoReturn]) -> None:
    """An extension names a known effect and gives finite numbers (or null) as parameters."""
    if not extension:
        return
    from ..physics.effects import effect_ids
    effect = extension.get('effect') if isinstance(extension, dict) else None
    params = extension.get('params') if isinstance(extension, dict) else None
    if str(effect) not in effect_ids():
        refuse(f'extension effect {effect!r} is not one of {", ".join(effect_ids())}')
    if not isinstance(params, dict):
        refuse('extension params must be a mapping of parameter names to numbers')
    for key, value in params.items():
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            refuse(f'extension parameter {key} = {value!r} must be a finite number')
