# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Oil flung out of the contacts as the screw turns: theta_Oil falls with revolutions.

Physics: the paper notes centrifugal loss of oil (Sec. 2.2); between
lubrications the supply factor falls with the revolutions run.  Two forms
(:data:`FORMS`), N the (effective) revolutions since the last lubrication:

* ``exponential``: each revolution loses a fixed share of the oil left,
  ``theta_eff = theta_Oil exp(-N / N_d)``;
* ``linear``: each revolution loses a fixed amount (a reservoir draining at a
  constant rate), ``theta_eff = theta_Oil max(1 - N / N_d, MIN_SUPPLY)``.

The film term of Eq. 22 carries the factor.  At rest oil creeps back into the
contacts (capillary flow from the thread flanks): the loss recovers with time
constant tau_r, ``N_eff <- N_eff exp(-t_rest / tau_r)`` for each standstill of
t_rest, so a long pause restores part of the supply (``tau_r`` infinite: no
recovery).  Between rests ``N_eff`` grows by the revolutions run.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, TYPE_CHECKING

import numpy as np

from . import choose, Extension as EffectExtension, Simulation as EffectSimulation
from ...validation import require, require_all_positive

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import numpy.typing as npt

    from . import ContactState, SimulationContext

__all__ = ['Extension', 'FALL_RANGE', 'FORMS', 'Law', 'LubricantDepletionLaw', 'MIN_SUPPLY', 'REST_SLACK', 'Simulation',
           'draw', 'effective_revolutions', 'rest_durations', 'theta_factor']

#: Forms of the loss (see module doc).
FORMS = ('exponential', 'linear')
#: Smallest supply factor the linear form falls to (a film of residual oil stays).
MIN_SUPPLY = 0.05
#: A gap between windows longer than their own running time by this factor counts as rest, s per s.
REST_SLACK = 1.5
#: Drawn range of the fall of theta_Oil over one session (one bag) by depletion (fraction).
FALL_RANGE = (0.05, 0.25)


def theta_factor(revolutions: npt.ArrayLike, depletion_per_revolution: npt.ArrayLike,
                 form: str = 'exponential') -> np.ndarray | float:
    """Supply factor for (effective) revolutions N at rate 1/N_d per revolution: ``exp(-N/N_d)`` or linear."""
    loss = np.asarray(depletion_per_revolution, dtype=float) * np.asarray(revolutions, dtype=float)
    if form == 'linear':
        return np.maximum(1.0 - loss, MIN_SUPPLY)
    if form != 'exponential':
        raise ValueError(f'unknown depletion form {form!r}; known: {", ".join(FORMS)}')
    return np.exp(-loss)


def rest_durations(revolutions: np.ndarray, time: npt.ArrayLike, speed: np.ndarray,
                   recording: npt.ArrayLike | None = None) -> np.ndarray:
    """Standstill before each window, s: the time gap not explained by turning at the window's speed.

    Windows are taken in time order within each recording (the first of a
    recording has no rest before it).  revolutions since lubrication, time in
    s, speed in rad/s.
    """
    revolutions = np.nan_to_num(np.asarray(revolutions, dtype=float))
    time = np.asarray(time, dtype=float)
    speed = np.abs(np.asarray(speed, dtype=float))
    recording = np.zeros(time.size) if recording is None else np.asarray(recording)
    rest = np.zeros(time.size)
    order = np.lexsort((time, recording))
    same = recording[order][1:] == recording[order][:-1]
    gap = np.diff(time[order])
    turning = 2.0 * math.pi * np.abs(np.diff(revolutions[order])) / np.maximum(speed[order][1:], 1e-9)
    idle = np.where(same & (gap > REST_SLACK * turning), gap - turning, 0.0)
    rest[order[1:]] = np.where(np.isfinite(idle), np.maximum(idle, 0.0), 0.0)
    return rest


def effective_revolutions(revolutions: np.ndarray, rest: npt.ArrayLike, recovery_rate: float,
                          recording: npt.ArrayLike | None = None, time: npt.ArrayLike | None = None) -> np.ndarray:
    """``N_eff``: revolutions since lubrication with the loss recovering at rest, ``exp(-t_rest / tau_r)``.

    rest in s before each window (:func:`rest_durations`), recovery_rate 1/tau_r in 1/s (0: none).
    """
    revolutions = np.nan_to_num(np.asarray(revolutions, dtype=float))
    if recovery_rate <= 0:
        return revolutions
    recording = np.zeros(revolutions.size) if recording is None else np.asarray(recording)
    time = np.arange(revolutions.size, dtype=float) if time is None else np.asarray(time, dtype=float)
    order = np.lexsort((time, recording))
    keep = np.exp(-recovery_rate * np.asarray(rest, dtype=float)[order])
    out = np.empty(revolutions.size)
    effective, previous, last_recording = 0.0, 0.0, None
    for i, k in enumerate(order):
        if recording[k] != last_recording:
            effective, previous, last_recording = 0.0, 0.0, recording[k]
        effective = effective * keep[i] + max(revolutions[k] - previous, 0.0)
        previous = revolutions[k]
        out[k] = effective
    return out


@dataclass(frozen=True)
class LubricantDepletionLaw:
    """Oil flung out of the contacts: ``theta_eff = theta_Oil exp(-N_rev / N_d)`` or linear in N_rev.

    N_rev is the screw revolutions (either direction) run since the last
    lubrication, i.e. since the start of the bag.  ``form`` is one of
    :data:`FORMS`; ``recovery_time`` tau_r (s) of the loss at rest, None
    for none (the rig simulator runs without recovery; the window-table
    simulator applies it).
    """

    depletion_revolutions: float   # N_d, revolutions
    form: str = 'exponential'
    recovery_time: float | None = None   # s, tau_r (None: no recovery)

    def __post_init__(self) -> None:
        """Reject non-physical parameters."""
        require_all_positive('lubricant_depletion', depletion_revolutions=self.depletion_revolutions)
        if self.recovery_time is not None:
            require_all_positive('lubricant_depletion', recovery_time=self.recovery_time)
        require(self.form in FORMS, f'lubricant_depletion form must be one of {", ".join(FORMS)}, '
                                    f'got {self.form!r}')

    def theta_factor(self, revolutions: npt.ArrayLike) -> np.ndarray | float:
        """Supply factor for (effective) revolutions N_rev since the last lubrication."""
        return theta_factor(revolutions, 1.0 / self.depletion_revolutions, self.form)


Law = LubricantDepletionLaw


class Extension(EffectExtension):
    """theta_Oil in Eq. 22 times the supply factor at ``depletion_per_revolution``.

    Optional parameters: ``linear`` (1 for the linear form) and ``recovery_rate`` 1/tau_r (1/s).
    """

    id = 'lubricant_depletion'

    def film_factor(self, params: Mapping[str, float], covariates: Any) -> np.ndarray | float:
        """``exp(-N_eff / N_d)`` or ``1 - N_eff / N_d``."""
        revolutions = np.nan_to_num(np.asarray(covariates.revolutions, dtype=float))
        rate = params.get('recovery_rate', 0.0)
        if rate > 0:
            recording = getattr(covariates, 'recording', None)
            rest = rest_durations(revolutions, covariates.time, covariates.speed, recording)
            revolutions = effective_revolutions(revolutions, rest, rate, recording, covariates.time)
        form = 'linear' if params.get('linear', 0.0) else 'exponential'
        return theta_factor(revolutions, params['depletion_per_revolution'], form)

    def assessment_film_factor(self, params: Mapping[str, float], covariates: Any) -> np.ndarray:
        """1: depletion is a real fall of theta_Oil, which assessment must report."""
        return np.ones_like(np.asarray(covariates.speed, dtype=float))


def draw(rng: np.random.Generator, *, session_revolutions: float, form: str | None = None) -> LubricantDepletionLaw:
    """Random depletion: theta falls by 5-25 % over session_revolutions (one bag), exponentially or linearly.

    ``form`` (default: drawn) is ``exponential`` or ``linear``.  The rig
    simulator has no recovery at rest (the window-table simulator has).
    """
    form = choose(rng, FORMS, form)
    fall = rng.uniform(*FALL_RANGE)
    revolutions = session_revolutions / -math.log1p(-fall) if form == 'exponential' else session_revolutions / fall
    return LubricantDepletionLaw(depletion_revolutions=float(revolutions), form=form)


class Simulation(EffectSimulation):
    """theta_Oil times the supply factor at the revolutions since the last lubrication."""

    id = 'lubricant_depletion'
    #: The supply factor multiplies theta_Oil before the other film factors (as the rig simulator always did).
    film_rank = -1

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> LubricantDepletionLaw:
        """:func:`draw` over one session's revolutions."""
        return draw(rng, session_revolutions=context.session_revolutions)

    def film_factor(self, law: LubricantDepletionLaw, state: ContactState) -> np.ndarray | float:
        """The supply factor at the revolutions since the last lubrication."""
        return law.theta_factor(state.revolutions)

    def form_words(self, params: Mapping[str, Any], speeds: Sequence[float]) -> list[str]:
        """``recovery at rest`` when the drawn law recovers."""
        return ['recovery at rest'] if params.get('recovery_time') else []
