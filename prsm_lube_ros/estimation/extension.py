# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A calibration's model extension applied in assessment: back to Eq. 22's amplitude and theta_Oil.

``Calibration.extension`` holds ``{'effect': ID, 'params': {...}}`` as
``prsm-lube diagnose --calibration-out`` writes it, and with two named effects
also ``effects``, a list of such entries (files with one effect still load).  For assessment each effect
maps a measured window RMS back to the amplitude Eq. 22 describes
(:meth:`~prsm_lube_ros.physics.effects.Extension.eq22_amplitude`) and gives the factor theta_Oil
of Eq. 23 must be divided by (:meth:`~prsm_lube_ros.physics.effects.Extension.assessment_film_factor`),
from the window's covariates (nut position, revolutions, temperature).
"""
from __future__ import annotations

from types import SimpleNamespace
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from ..errors import ConfigError
from ..physics.effects import extension as effect_extension


__all__ = ['eq22_inputs', 'window_covariates']


def window_covariates(windows: Sequence, stroke: float | None = None) -> SimpleNamespace:
    """Covariate arrays of :class:`~prsm_lube_ros.estimation.windowing.Window` objects, named as in the window table.

    Nut travel of backward runs (negative) becomes a place along the stroke,
    ``stroke + travel``, as :mod:`prsm_lube_ros.diagnosis.table` does.
    """
    travel = np.array([w.nut_position for w in windows], dtype=float)
    position = travel.copy()
    if stroke is not None:
        position = np.where(travel < 0, stroke + travel, travel)
    return SimpleNamespace(speed=np.array([w.screw_speed for w in windows], dtype=float),
                           load=np.array([w.axial_load for w in windows], dtype=float),
                           position=position,
                           revolutions=np.array([w.revolutions for w in windows], dtype=float),
                           temperature=np.array([w.temperature for w in windows], dtype=float),
                           time=np.array([w.start for w in windows], dtype=float))


def _parts(extension: dict) -> list[tuple]:
    """``(Extension, params)`` of every effect of ``extension``, in the order the model applies them."""
    items = extension.get('effects') or [extension]
    if not isinstance(items, list):
        raise ConfigError('calibration extension is malformed (effects must be a list)')
    parts = []
    try:
        for item in items:
            effect = effect_extension(str(item['effect']))
            params = {k: float(v) if v is not None else np.nan for k, v in dict(item['params']).items()
                      if not isinstance(v, str)}
            parts.append((effect, params))
    except (KeyError, TypeError, ValueError, ConfigError) as exc:
        raise ConfigError(f'calibration extension is malformed ({exc.__class__.__name__}: {exc})') from None
    return parts


def eq22_inputs(extension: dict, windows: Sequence, rms: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(amplitude for Eq. 23, film factor)`` per window under ``extension``; identity when it is empty.

    ``extension`` holds one effect (``effect``, ``params``) or, as two named
    effects are written, a list ``effects`` in the order the joint model
    applies their gains: they are undone backwards, and their film factors multiply.
    """
    rms = np.asarray(rms, dtype=float)
    if not extension:
        return rms, np.ones_like(rms)
    amplitude, factor = rms, np.ones_like(rms)
    for effect, params in reversed(_parts(extension)):
        covariates = window_covariates(windows, params.get('stroke'))
        amplitude = np.asarray(effect.eq22_amplitude(params, covariates, amplitude), dtype=float)
        factor = factor * np.broadcast_to(np.asarray(effect.assessment_film_factor(params, covariates),
                                                     dtype=float), rms.shape)
    return amplitude, np.array(factor)
