# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Calibration files: YAML with the constants, their uncertainty and the fit's record.

Writes are atomic: the new content goes to a temporary file in the same folder,
is flushed to disk, then replaces the old file in one rename, so a crash in the
middle leaves the old calibration whole.

A file ends where it was meant to: its first line (:data:`SEAL_HEAD`) says the
last line holds the SHA-256 of every line before it, whatever sections the
file holds, so a file cut short or damaged after writing is refused instead of
read as an older format.  Files written before (no first line) load as ever.
"""
from __future__ import annotations

import datetime
import hashlib
import math
from pathlib import Path

import numpy as np
import yaml

from ..atomic_file import write_atomically
from ..config_file import MAX_YAML_BYTES, parse_yaml
from ..errors import ConfigError, InputError
from ..input_file import read_text
from ..physics.vibration_model import ModelConstants
from .calibration import Calibration
from .calibration_checks import check_calibration, check_document
from .conditioning import AnalysisBand, RAW_BAND_TEXT
from .defect_screen import ConditionBaseline
from .domain import CalibrationDomain
from .run_scatter import RunScatter

__all__ = ['FORMAT', 'SEAL_HEAD', 'SEAL_TAIL', 'VERSION', 'band_note', 'baseline_note', 'calibration_from_dict',
           'calibration_to_dict', 'load_calibration', 'save_calibration']

FORMAT = 'prsm_lube_ros/calibration'
VERSION = 1
#: First line of a sealed file, and the start of its last line (followed by 64 hex digits)
SEAL_HEAD = '# prsm_lube_ros calibration: its last line is the SHA-256 of the lines before it\n'
SEAL_TAIL = '# end sha256 '


def calibration_to_dict(calibration: Calibration) -> dict:
    """Plain mapping of a calibration, as written to YAML."""
    c = calibration.constants
    return {
        'format': FORMAT,
        'version': VERSION,
        'created': datetime.datetime.now(datetime.UTC).isoformat(timespec='seconds'),
        'constants': c.by_name(),
        'std': {'c_sys': calibration.c_sys_std, 'c_f': calibration.c_f_std,
                'c_lambda': calibration.c_lambda_std},
        # C_sys is fitted as ln C_sys: one sigma is a factor (C_sys x/ c_sys_factor), the std above its linearisation.
        'c_sys_factor': calibration.c_sys_factor,
        'units': {'c_sys': 'm N^(1/3)', 'c_f': '1/N', 'c_lambda': '(rad/s)^-0.68 N^0.073'},
        'covariance_ln_csys_cf_clambda': [[float(v) for v in row] for row in calibration.covariance],
        'fit': {'rmse_relative': calibration.fit_rmse, 'residual_std_ln': calibration.residual_std,
                'windows_used': calibration.windows_used, 'reference_theta': calibration.reference_theta,
                'speed_levels_rad_s': [float(v) for v in calibration.speed_levels],
                'load_levels_n': [float(v) for v in calibration.load_levels],
                'conditions': calibration.conditions, 'runs': calibration.runs,
                'standard_errors': calibration.standard_errors, 'merged_levels': list(calibration.merged),
                'flags': list(calibration.flags),
                'sources': list(calibration.sources), **_scatter_to_dict(calibration.scatter)},
        'extension': dict(calibration.extension),
        # Band of the window RMS the constants fit (absent: raw RMS, as files before bands; see band_note).
        **({'band': calibration.band.as_dict()} if calibration.band is not None else {}),
        'domain': calibration.domain.as_dict() if calibration.domain is not None else None,
        # Healthy condition indicators of the calibration runs (absent: a file from before; see baseline_note).
        **({'condition_baseline': calibration.condition_baseline.as_dict()}
           if calibration.condition_baseline is not None else {}),
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
            flags=tuple(str(v) for v in fit.get('flags', ()) or ()),
            scatter=_scatter_from_dict(fit),
            band=AnalysisBand.from_dict(data['band']) if data.get('band') else None,
            domain=(CalibrationDomain.from_dict(data['domain']) if data.get('domain')
                    else CalibrationDomain.of_levels(fit.get('speed_levels_rad_s', ()),
                                                     fit.get('load_levels_n', ()))),
            condition_baseline=(ConditionBaseline.from_dict(data['condition_baseline'], origin)
                                if data.get('condition_baseline') is not None else None))
    except InputError as exc:
        raise exc if origin in str(exc) else ConfigError(f'{origin}: {exc}') from None
    except (KeyError, IndexError, TypeError, ValueError, AttributeError, OverflowError) as exc:
        raise ConfigError(f'{origin}: malformed calibration ({exc.__class__.__name__}: {exc})') from None
    check_document(data, origin)
    check_calibration(calibration, origin)
    return calibration


def _scatter_to_dict(scatter: RunScatter | None) -> dict:
    """The run-level variance model's keys under ``fit:`` (none for a calibration without one)."""
    if scatter is None:
        return {}
    return {'run_std_ln': scatter.run_std, 'window_std_ln': scatter.window_std, 'run_dof': scatter.dof,
            'run_scatter_estimated': scatter.estimated, 'run_scatter': scatter.summary}


def _scatter_from_dict(fit: dict) -> RunScatter | None:
    """Inverse of :func:`_scatter_to_dict`; None for a file written before run-level scatter was kept."""
    if 'run_std_ln' not in fit:
        return None
    scatter = RunScatter(run_std=float(fit['run_std_ln']), window_std=float(fit.get('window_std_ln', 0.0)),
                         runs=int(fit.get('runs', 0)), dof=int(fit.get('run_dof', 0)),
                         estimated=bool(fit.get('run_scatter_estimated', True)))
    for name, value in (('run_std_ln', scatter.run_std), ('window_std_ln', scatter.window_std)):
        if not (math.isfinite(value) and 0 <= value < 1):
            raise ValueError(f'fit: {name} must be a number in [0, 1), got {value!r}')
    return scatter


def baseline_note(calibration: Calibration) -> str:
    """'' for a calibration with a healthy condition baseline; else what a defect screen without one can judge."""
    if calibration.condition_baseline is not None:
        return ''
    return ('the calibration holds no healthy condition baseline (written before it was kept): surface defects '
            'are screened against the absolute limits only; calibrate again to keep one')


def band_note(calibration: Calibration) -> str:
    """The band a calibration's RMS is in, in words (a file without ``band:`` implies the raw RMS)."""
    return f'band {calibration.band.text}' if calibration.band is not None else RAW_BAND_TEXT


def save_calibration(calibration: Calibration, path: str | Path) -> Path:
    """Write atomically (temporary file, fsync, rename); returns the path written.

    Temporaries a killed earlier write left beside ``path`` are removed
    (:func:`~prsm_lube_ros.atomic_file.remove_stale`).
    """
    path = Path(path)
    text = SEAL_HEAD + yaml.safe_dump(calibration_to_dict(calibration), sort_keys=False)
    text += f'{SEAL_TAIL}{hashlib.sha256(text.encode()).hexdigest()}\n'
    try:
        write_atomically(path, lambda stream: stream.write(text), binary=False)
    except OSError as exc:
        raise ConfigError(f'{path}: cannot write calibration ({exc.strerror or exc})') from None
    return path


def load_calibration(path: str | Path) -> Calibration:
    """Read a calibration file; one-line :class:`ConfigError` naming the file for anything wrong."""
    path = Path(path)
    text = read_text(path, 'calibration file', max_bytes=MAX_YAML_BYTES, error=ConfigError)
    _check_seal(text, path)
    data = parse_yaml(text, path, 'calibration file')
    if not isinstance(data, dict):
        raise ConfigError(f'{path}: not a prsm_lube_ros calibration (expected a mapping)')
    return calibration_from_dict(data, str(path))


def _check_seal(text: str, path: Path) -> None:
    """A sealed file (first line :data:`SEAL_HEAD`) must end in its checksum line; older files pass as they are."""
    if not text.startswith(SEAL_HEAD):
        return
    cut = text.rfind('\n', 0, len(text) - 1) + 1
    body, last = text[:cut], text[cut:]
    if not (last.startswith(SEAL_TAIL) and last.endswith('\n') and len(last) == len(SEAL_TAIL) + 65):
        raise ConfigError(f'{path}: calibration file ends early (its last line is not the "{SEAL_TAIL.strip()}" line '
                          'its first line promises): cut short while written or copied; write it again')
    if hashlib.sha256(body.encode()).hexdigest() != last[len(SEAL_TAIL):-1]:
        raise ConfigError(f'{path}: calibration file changed after it was written (the SHA-256 of its lines differs '
                          'from its end line): damaged; if edited on purpose, delete its first line to load it '
                          'unchecked')
