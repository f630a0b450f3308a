# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Dynamic amplification of a lightly damped structural mode (Eq. 13 without the step to Eq. 14).

Physics: Eq. 14 takes the quasi-static response ``X_0 = F_0 / K_0``, valid far
below every natural frequency.  The thread-contact excitation runs at orders n
of the screw rotation, ``f = n omega_S / (2 pi)``; as it approaches a lightly
damped mode at f_r the full solution of Eq. 13 applies:

    X = (F_0 / K_0) |H(r)|,  |H(r)| = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2),  r = n f_S / f_r

so ``A = A_22 |H(r)|``.

Any rotation order n can excite the mode (roller passing, nut thread starts,
a screw run-out at n = 1); the mode may lie below the speed band (every speed
past resonance, r > 1: the amplitude rises more slowly than omega^2 and
approaches A_22 / r^2), inside it (a peak at ``omega_S = 2 pi f_r / n``) or
above it (r < 1 throughout: the amplitude rises faster than omega^2).  The RMS
amplitude only sees the screw speed at which the excitation meets the mode,
``omega_r = 2 pi f_r / n``; f_r and n separately need the spectrum
(:data:`BAND_POSITIONS`, :func:`band_position`).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import Extension as EffectExtension
from ...validation import require, require_all_positive
from ..vibration_model import forced_response_amplitude

if TYPE_CHECKING:
    from collections.abc import Mapping

    import numpy.typing as npt


__all__ = ['BAND_POSITIONS', 'Extension', 'Law', 'Resonance', 'band_position', 'magnification', 'natural_frequency']


def magnification(frequency_ratio: npt.ArrayLike, damping_ratio: npt.ArrayLike) -> np.ndarray | float:
    """``|H(r)| = 1 / sqrt((1 - r^2)^2 + (2 zeta r)^2)``: Eq. 13's forced response over Eq. 14's X0 = F0/K.

    frequency_ratio r = excitation / natural frequency, damping_ratio zeta (dimensionless).
    Written with :func:`..vibration_model.forced_response_amplitude` for k = 1, m = 1, c = 2 zeta.
    """
    ratio = np.abs(np.asarray(frequency_ratio, dtype=float))
    return forced_response_amplitude(1.0, 1.0, 1.0, 2.0 * np.asarray(damping_ratio, dtype=float), ratio)


#: Where the mode lies relative to the recorded speed band.
BAND_POSITIONS = ('below the speed band', 'inside the speed band', 'above the speed band')


def band_position(resonant_speed: float, lowest_speed: float, highest_speed: float) -> str:
    """Which of :data:`BAND_POSITIONS` the resonant screw speed omega_r (rad/s) takes against the band."""
    if resonant_speed < lowest_speed:
        return BAND_POSITIONS[0]
    if resonant_speed > highest_speed:
        return BAND_POSITIONS[2]
    return BAND_POSITIONS[1]


def natural_frequency(resonant_speed: float, order: float) -> float:
    """``f_r = n omega_r / (2 pi)``, Hz: the mode that order n meets at screw speed omega_r (rad/s)."""
    return order * resonant_speed / (2.0 * math.pi)


@dataclass(frozen=True)
class Resonance:
    """A rotation-order excitation approaching a lightly damped structural mode.

    The excitation at ``order`` times the screw rotation frequency f_S drives
    the mode at natural_frequency f_r; the thread-contact vibration is
    magnified by ``|H(r)|``, ``r = order f_S / f_r``.
    """

    order: float              # excitation order (per screw revolution)
    natural_frequency: float  # Hz, f_r
    damping_ratio: float      # zeta

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('resonance', **self.__dict__)
        require(self.damping_ratio < 1.0, f'resonance damping_ratio must be below 1, got {self.damping_ratio!r}')

    def frequency_ratio(self, screw_speed: npt.ArrayLike) -> np.ndarray | float:
        """``r = order |omega_S| / (2 pi f_r)`` for screw_speed in rad/s."""
        return self.order * np.abs(np.asarray(screw_speed, dtype=float)) / (2.0 * math.pi * self.natural_frequency)

    def amplitude_factor(self, screw_speed: npt.ArrayLike) -> np.ndarray | float:
        """``|H(r)|`` at screw_speed in rad/s."""
        return magnification(self.frequency_ratio(screw_speed), self.damping_ratio)


Law = Resonance


class Extension(EffectExtension):
    """Eq. 22 times ``|H(omega_S / omega_r)|`` with ``resonant_speed`` omega_r (rad/s) and ``damping_ratio``."""

    id = 'resonance'

    def log_gain(self, params: Mapping[str, float], covariates: Any, ln_a22: np.ndarray | float) -> np.ndarray | float:
        """``ln |H(omega_S / omega_r)|``."""
        ratio = np.abs(np.asarray(covariates.speed, dtype=float)) / params['resonant_speed']
        return np.log(magnification(ratio, params['damping_ratio']))
