# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The domain a calibration was fitted in, and how far a window or run lies outside it.

Eq. 22's constants are fitted on the speeds, loads and temperatures of the
reference recordings; theta_Oil from conditions outside them is an
extrapolation of the fitted form (the paper's constants hold for its 100-200
r/min and 100-200 N).  :class:`CalibrationDomain` holds the ranges (speed
rad/s, load N, temperature degC, sample rate Hz), written to the calibration
file's ``domain:``; :func:`domain_flag` says in words how far a window or run
is outside (``speed 40 % below the calibrated 63-188 rad/s``), or '' inside.

Speeds and loads inside the range widened by :data:`SPEED_LOAD_MARGIN`
(relative: the tolerance within which two levels count as one) and
temperatures within :data:`TEMPERATURE_MARGIN` K count as inside.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING
from collections.abc import Iterable

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from .windowing import Window

__all__ = ['CalibrationDomain', 'SPEED_LOAD_MARGIN', 'TEMPERATURE_MARGIN', 'domain_flag']

#: Relative margin on speed and load ranges (as ``calibration.LEVEL_TOLERANCE``: levels closer are one).
SPEED_LOAD_MARGIN = 0.05
#: Margin on the temperature range, K.
TEMPERATURE_MARGIN = 2.0


def _span(values: npt.ArrayLike) -> tuple[float, float] | None:
    """(min, max) of the finite values, None when there are none."""
    array = np.asarray(values, dtype=float)
    finite = array[np.isfinite(array)]
    return (float(finite.min()), float(finite.max())) if finite.size else None


@dataclass(frozen=True)
class CalibrationDomain:
    """Ranges the calibration was fitted in; None where unknown (temperature not recorded, old files)."""

    speed: tuple[float, float] | None = None          # rad/s
    load: tuple[float, float] | None = None           # N
    temperature: tuple[float, float] | None = None    # degC
    sample_rate: tuple[float, float] | None = None    # Hz

    @classmethod
    def of_windows(cls, windows: Iterable[Window]) -> CalibrationDomain:
        """The ranges of the windows a fit used (speed and load magnitudes)."""
        windows = list(windows)
        return cls(speed=_span([abs(w.screw_speed) for w in windows]),
                   load=_span([abs(w.axial_load) for w in windows]),
                   temperature=_span([w.temperature for w in windows]),
                   sample_rate=_span([getattr(w, 'sample_rate', math.nan) for w in windows]))

    @classmethod
    def of_levels(cls, speed_levels: npt.ArrayLike, load_levels: npt.ArrayLike) -> CalibrationDomain | None:
        """The domain an old calibration file implies: its speed and load levels (None without them)."""
        speed, load = _span(speed_levels), _span(load_levels)
        return cls(speed=speed, load=load) if speed and load else None

    def as_dict(self) -> dict:
        """Mapping for the calibration file's ``domain:`` (null where unknown)."""
        def pair(span: tuple[float, float] | None) -> list[float] | None:
            return [float(span[0]), float(span[1])] if span else None
        return {'speed_rad_s': pair(self.speed), 'load_n': pair(self.load),
                'temperature_degc': pair(self.temperature), 'sample_rate_hz': pair(self.sample_rate)}

    @classmethod
    def from_dict(cls, data: dict) -> CalibrationDomain:
        """Inverse of :meth:`as_dict`; ValueError naming the entry for one that is not ``[low, high]``.

        Each range is null or two finite numbers, the first not above the second.
        """
        if not isinstance(data, dict):
            raise ValueError('domain must be a mapping of ranges')

        def pair(key: str) -> tuple[float, float] | None:
            value = data.get(key)
            if value is None:
                return None
            if not isinstance(value, (list, tuple)) or len(value) != 2 or \
                    any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
                raise ValueError(f'domain {key} must be [low, high] (two numbers) or null')
            low, high = float(value[0]), float(value[1])
            if not (math.isfinite(low) and math.isfinite(high) and low <= high):
                raise ValueError(f'domain {key} must be two finite numbers, low <= high')
            return low, high
        return cls(speed=pair('speed_rad_s'), load=pair('load_n'), temperature=pair('temperature_degc'),
                   sample_rate=pair('sample_rate_hz'))

    @property
    def text(self) -> str:
        """The ranges in words: ``speed 10.5-20.9 rad/s, load 100-200 N, temperature 30-31 degC``."""
        parts = []
        for name, span, unit in (('speed', self.speed, 'rad/s'), ('load', self.load, 'N'),
                                 ('temperature', self.temperature, 'degC'),
                                 ('sample rate', self.sample_rate, 'Hz')):
            if span:
                digits = 6 if name == 'sample rate' else 4
                parts.append(f'{name} {span[0]:.{digits}g}-{span[1]:.{digits}g} {unit}')
        return ', '.join(parts) or 'unknown'


def _relative_outside(name: str, value: float, span: tuple[float, float], unit: str) -> str:
    low, high = span
    if value < low * (1 - SPEED_LOAD_MARGIN):
        return f'{name} {100 * (1 - value / low):.0f} % below the calibrated {low:.4g}-{high:.4g} {unit}'
    if value > high * (1 + SPEED_LOAD_MARGIN):
        return f'{name} {100 * (value / high - 1):.0f} % above the calibrated {low:.4g}-{high:.4g} {unit}'
    return ''


def domain_flag(domain: CalibrationDomain | None, speed: float, load: float,
                temperature: float = math.nan) -> str:
    """How far (speed rad/s, load N, temperature degC) lies outside ``domain``, in words; '' inside or unknown."""
    if domain is None:
        return ''
    parts = []
    if domain.speed and math.isfinite(speed):
        parts.append(_relative_outside('speed', abs(speed), domain.speed, 'rad/s'))
    if domain.load and math.isfinite(load):
        parts.append(_relative_outside('load', abs(load), domain.load, 'N'))
    if domain.temperature and math.isfinite(temperature):
        low, high = domain.temperature
        if temperature < low - TEMPERATURE_MARGIN:
            parts.append(f'temperature {low - temperature:.1f} K below the calibrated {low:.4g}-{high:.4g} degC')
        elif temperature > high + TEMPERATURE_MARGIN:
            parts.append(f'temperature {temperature - high:.1f} K above the calibrated {low:.4g}-{high:.4g} degC')
    parts = [p for p in parts if p]
    return ('extrapolated: ' + '; '.join(parts)) if parts else ''
