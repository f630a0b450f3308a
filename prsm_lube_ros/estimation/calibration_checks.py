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
  C_lambda > 0 (oil lowers the excitation, Eq. 19), C_F > 0 (load raises it,
  Eq. 18) -- or C_F <= 0 where the fit itself said so in ``fit.flags`` (the
  line :func:`~.calibration.sign_flags` writes for these very constants);
* magnitudes an accelerometer can resolve, at the calibration's own speeds and
  loads: Eq. 19's exponent ``theta C_lambda omega^0.68 F^-0.073`` within
  :data:`OIL_EXPONENT_RANGE` (a C_lambda scaled by 1e-6 would turn a 1e-6
  change of the vibration into a unit change of theta_Oil) and Eq. 18's
  ``|C_F F|`` at most :data:`MAX_LOAD_EXPONENT`;
* the covariance of (ln C_sys, C_F, C_lambda) finite, symmetric and positive
  definite (its square roots are the standard errors), and no constant's
  one-sigma moving ln A by more than :data:`MAX_LOG_SIGMA` at those speeds
  and loads (a diagonal of 1e300 is no uncertainty a fit gives);
* the fit's figures (residual scatter, RMS error) finite and >= 0 or missing,
  the reference theta_Oil finite and > 0, speed and load levels positive and
  within what the contract's sensors give (:mod:`..recording.plausibility`);
* Eq. 22 with these constants, at the calibration's own speeds and loads and
  reference theta_Oil, predicts amplitudes an accelerometer can give
  (:data:`MIN_PLAUSIBLE_RMS` to ``MAX_ACCELERATION``): a C_sys scaled by
  1e-6 cannot pass for a calibration;
* a model extension (and each entry of its ``effects`` list) names a known
  effect and gives every parameter as a finite number (or null), within its
  physical range (:data:`EXTENSION_BOUNDS`: no negative resonance speed,
  damping, background or viscosity slope).

Imports numpy, the physics and the plausibility bounds only.
"""
from __future__ import annotations

import math
from typing import NoReturn, TYPE_CHECKING
from collections.abc import Callable, Iterator

import numpy as np
import numpy.typing as npt

from ..errors import ConfigError
from ..physics.vibration_model import acceleration_amplitude, film_speed_load_term
from ..recording.plausibility import MAX_ACCELERATION, MAX_AXIAL_LOAD, MAX_SCREW_SPEED, TEMPERATURE_RANGE

if TYPE_CHECKING:
    from .calibration import Calibration

__all__ = ['EXTENSION_BOUNDS', 'MAX_LOAD_EXPONENT', 'MAX_LOG_SIGMA', 'MIN_PLAUSIBLE_RMS', 'OIL_EXPONENT_RANGE',
           'OPTIONAL_FIGURES', 'check_calibration', 'check_document']

#: Smallest window RMS (m/s^2) the constants may predict at their own reference conditions: 10 micro-g,
#: the noise floor of an IEPE accelerometer (the paper's 100 mV/g sensor).
MIN_PLAUSIBLE_RMS = 1e-4
#: Fit figures that may be missing (NaN) in a file; every other number must be finite.
OPTIONAL_FIGURES = ('fit_rmse', 'residual_std')
#: Range of Eq. 19's exponent theta C_lambda omega^0.68 F^-0.073 at the calibration's speeds and loads: below,
#: theta_Oil would move by 1 for a 0.1 % change of the vibration; above, the oil factor is below e^-50.
#: (The rig's constants give about 1, the FEMTO bearings' 2 to 7.)
OIL_EXPONENT_RANGE = (1e-3, 50.0)
#: Largest |C_F F_a| (Eq. 18's exponent) at the calibration's loads.
MAX_LOAD_EXPONENT = 50.0
#: Largest one-sigma of ln A a constant's uncertainty may give at the calibration's speeds and loads (the
#: FEMTO calibrations, whose C_sys is barely identified, give 7.7: a factor of 2000).
MAX_LOG_SIGMA = 20.0
#: Physical range of each extension parameter the effects write: (lowest, highest, lowest itself allowed).
EXTENSION_BOUNDS: dict[str, tuple[float, float, bool]] = {
    'resonant_speed': (0.0, 100 * MAX_SCREW_SPEED, False), 'damping_ratio': (0.0, 1.0, False),
    'top_speed': (0.0, MAX_SCREW_SPEED, False), 'bottom_speed': (0.0, MAX_SCREW_SPEED, False),
    'background_rms': (0.0, MAX_ACCELERATION, True), 'rms_scale': (0.0, MAX_ACCELERATION, True),
    'line_rms': (0.0, MAX_ACCELERATION, True),
    'depletion_per_revolution': (0.0, 1.0, True), 'recovery_rate': (0.0, 1e3, True), 'linear': (0.0, 1.0, True),
    'revolution_scale': (0.0, 1e12, False), 'rest_scale': (0.0, 1e9, False),
    'stroke': (0.0, 100.0, False), 'reference_load': (0.0, MAX_AXIAL_LOAD, False),
    'ratio_at_start': (0.0, 1e3, True), 'ratio_at_end': (0.0, 1e3, True), 'contact_over_ea': (0.0, 1e6, True),
    'bearing_before': (0.0, 100.0, True), 'bearing_after': (0.0, 100.0, True),
    'reference_temperature': (TEMPERATURE_RANGE[0], TEMPERATURE_RANGE[1], True),
    'viscosity_temperature_coefficient': (0.0, 1.0, True), 'vogel_distance': (0.0, 1e3, False),
    'reference_viscosity': (0.0, 1e6, False),
}


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
    if not c.c_f > 0:
        from .calibration import sign_flags
        if not (c.c_f < 0 and set(sign_flags(c)) <= set(calibration.flags)):
            refuse(f'constants c_f = {c.c_f:g} must be > 0 (the load raises the excitation, Eq. 18); a fit that gave '
                   'it says so in fit.flags, and this file does not')
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
        _check_magnitudes(calibration, speeds, loads, refuse)
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


def _check_magnitudes(calibration: Calibration, speeds: np.ndarray, loads: np.ndarray,
                      refuse: Callable[[str], NoReturn]) -> None:
    """Eq. 18's and 19's exponents, and the constants' one-sigma in ln A, at the calibration's speeds and loads."""
    c = calibration.constants
    term = np.asarray(film_speed_load_term(speeds[:, None], loads[None, :]), float)
    oil = calibration.reference_theta * c.c_lambda * term
    low, high = OIL_EXPONENT_RANGE
    if not (oil.min() >= low and oil.max() <= high):
        refuse(f'constants c_lambda = {c.c_lambda:g} gives Eq. 19\'s exponent theta C_lambda omega^0.68 F^-0.073 '
               f'{oil.min():.3g} to {oil.max():.3g} at the calibration\'s speeds and loads, outside {low:g} to '
               f'{high:g} (an accelerometer cannot resolve theta_oil with it): damaged or edited constants')
    if abs(c.c_f) * loads.max() > MAX_LOAD_EXPONENT:
        refuse(f'constants c_f = {c.c_f:g} gives |C_F F| = {abs(c.c_f) * loads.max():.3g} at the calibration\'s '
               f'largest load, more than {MAX_LOAD_EXPONENT:g} (Eq. 18): damaged or edited constants')
    variance = np.diag(np.asarray(calibration.covariance, float))
    effects = np.sqrt(variance) * np.array([1.0, loads.max(), calibration.reference_theta * term.max()])
    for name, effect in zip(('ln c_sys', 'c_f', 'c_lambda'), effects):
        if not effect <= MAX_LOG_SIGMA:
            refuse(f'covariance_ln_csys_cf_clambda: the one-sigma of {name} moves ln A by {effect:.3g} at the '
                   f'calibration\'s speeds and loads, more than {MAX_LOG_SIGMA:g} (no fit gives that): damaged '
                   'or edited covariance')


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
    """An extension, and each entry of its ``effects``, names a known effect with parameters in range."""
    if not extension:
        return
    if not isinstance(extension, dict):
        refuse('extension must be a mapping with effect and params')
    entries = extension.get('effects')
    if entries is not None and not isinstance(entries, list):
        refuse('extension effects must be a list of mappings with effect and params')
    for index, entry in enumerate([extension] + list(entries or [])):
        where = 'extension' if index == 0 else f'extension effects[{index - 1}]'
        _check_effect(entry, where, refuse)


def _check_effect(entry: object, where: str, refuse: Callable[[str], NoReturn]) -> None:
    """One effect entry: a known effect id, params a mapping of finite numbers (or null) in their ranges."""
    from ..physics.effects import effect_ids
    effect = entry.get('effect') if isinstance(entry, dict) else None
    params = entry.get('params') if isinstance(entry, dict) else None
    if str(effect) not in effect_ids():
        refuse(f'{where} effect {str(effect)[:60]!r} is not one of {", ".join(effect_ids())}')
    if not isinstance(params, dict):
        refuse(f'{where} params must be a mapping of parameter names to numbers')
    for key, value in params.items():
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            refuse(f'{where} parameter {str(key)[:60]} = {str(value)[:60]!r} must be a finite number')
        low, high, closed = EXTENSION_BOUNDS.get(str(key), (-math.inf, math.inf, True))
        if not ((value >= low if closed else value > low) and value <= high):
            refuse(f'{where} parameter {key} = {value:g} is outside its physical range '
                   f'{"[" if closed else "("}{low:g}, {high:g}]')
