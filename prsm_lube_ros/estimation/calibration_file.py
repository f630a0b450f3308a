# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Calibration files: YAML with the constants, their uncertainty and the fit's record.

Writes are atomic: the new content goes to a temporary file in the same folder,
is flushed to disk, then replaces the old file in one rename, so a crash in the
middle leaves the old calibration whole.
"""
from __future__ import annotations

import datetime
import math
from pathlib import Path

import numpy as np
import yaml

from ..atomic_file import write_atomically
from ..config_file import read_yaml
from ..errors import ConfigError, InputError
from ..physics.vibration_model import ModelConstants
from .calibration import Calibration

FORMAT = 'prsm_lube_ros/calibration'
VERSION = 1


def calibration_to_dict(calibration: Calibration) -> dict:
    """Plain mapping of a calibration, as written to YAML."""
    c = calibration.constants
    return {
        'format': FORMAT,
        'version': VERSION,
        'created': datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds'),
        'constants': {'c_sys': c.c_sys, 'c_f': c.c_f, 'c_lambda': c.c_lambda},
        'std': {'c_sys': calibration.c_sys_std, 'c_f': calibration.c_f_std,
                'c_lambda': calibration.c_lambda_std},
        'units': {'c_sys': 'm N^(1/3)', 'c_f': '1/N', 'c_lambda': '(rad/s)^-0.68 N^0.073'},
        'covariance_ln_csys_cf_clambda': [[float(v) for v in row] for row in calibration.covariance],
        'fit': {'rmse_relative': calibration.fit_rmse, 'residual_std_ln': calibration.residual_std,
                'windows_used': calibration.windows_used, 'reference_theta': calibration.reference_theta,
                'speed_levels_rad_s': [float(v) for v in calibration.speed_levels],
                'load_levels_n': [float(v) for v in calibration.load_levels],
                'conditions': calibration.conditions, 'runs': calibration.runs,
                'standard_errors': calibration.standard_errors, 'merged_levels': list(calibration.merged),
                'flags': list(calibration.flags),
                'sources': list(calibration.sources)},
        'extension': dict(calibration.extension),
    }


def calibration_from_dict(data: dict, origin: str = 'calibration') -> Calibration:
    """Inverse of :func:`calibration_to_dict`; raises :class:`InputError` naming ``origin``."""
    try:
        if data.get('format') != FORMAT:
            raise ConfigError(f'{origin}: not a prsm_lube_ros calibration (format: {data.get("format")!r})')
        const = data['constants']
        constants = ModelConstants(float(const['c_sys']), float(const['c_f']), float(const['c_lambda']))
        covariance = np.array(data['covariance_ln_csys_cf_clambda'], dtype=float).reshape(3, 3)
        fit = data.get('fit', {})
        calibration = Calibration(
            constants=constants, covariance=covariance,
            fit_rmse=float(fit.get('rmse_relative', math.nan)),
            residual_std=float(fit.get('residual_std_ln', math.nan)),
            windows_used=int(fit.get('windows_used', 0)),
            reference_theta=float(fit.get('reference_theta', 1.0)),
            speed_levels=tuple(fit.get('speed_levels_rad_s', ())),
            load_levels=tuple(fit.get('load_levels_n', ())),
            sources=tuple(fit.get('sources', ())),
            extension=dict(data.get('extension') or {}),
            conditions=int(fit.get('conditions', 0)), runs=int(fit.get('runs', 0)),
            standard_errors=str(fit.get('standard_errors', '')),
            merged=tuple(str(v) for v in fit.get('merged_levels', ()) or ()),
            flags=tuple(str(v) for v in fit.get('flags', ()) or ()))
    except InputError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ConfigError(f'{origin}: malformed calibration ({exc.__class__.__name__}: {exc})') from None
    if not (constants.c_sys > 0 and math.isfinite(constants.c_f) and math.isfinite(constants.c_lambda)):
        raise ConfigError(f'{origin}: constants must be finite with C_sys > 0, got {constants}')
    if constants.c_lambda == 0:
        raise ConfigError(f'{origin}: C_lambda is 0, theta_Oil (Eq. 23) cannot be computed')
    return calibration


def save_calibration(calibration: Calibration, path: str | Path) -> Path:
    """Write atomically (temporary file, fsync, rename); returns the path written.

    Temporaries a killed earlier write left beside ``path`` are removed
    (:func:`~prsm_lube_ros.atomic_file.remove_stale`).
    """
    path = Path(path)
    text = yaml.safe_dump(calibration_to_dict(calibration), sort_keys=False)
    try:
        write_atomically(path, lambda stream: stream.write(text), binary=False)
    except OSError as exc:
        raise ConfigError(f'{path}: cannot write calibration ({exc.strerror or exc})') from None
    return path


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file; one-line :class:`ConfigError` naming the file for anything wrong."""
    path = Path(path)
    data = read_yaml(path, 'calibration file')
    if not isinstance(data, dict):
        raise ConfigError(f'{path}: not a prsm_lube_ros calibration (expected a mapping)')
    return calibration_from_dict(data, str(path))
