# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Which effects act on the simulated rig, and their strengths drawn in physical ranges.

The laws themselves live in :mod:`prsm_lube_ros.physics.effects` (one module
per effect, shared with the diagnosis); this module holds the simulator's
side: the :class:`Effects` container of active laws written to
``truth.json`` (recordings carry no label of them) and a ``draw_*`` function
per effect that picks its parameters inside a documented physical range, for
studies of the diagnosis, and among the effect's physical forms (bearing
arrangement, band position and rotation order of a resonance, viscosity law,
depletion form, background lines or floor) at random unless one is asked
for.  All effects are off by default.
"""
from __future__ import annotations

from dataclasses import asdict, fields
import math
from typing import Any, TYPE_CHECKING, TypeVar
from collections.abc import Sequence

import numpy as np

from ..errors import ConfigError
from ..physics.effects import effect_ids, law_type
from ..physics.effects.background_vibration import BackgroundVibration, FORMS as BACKGROUND_FORMS
from ..physics.effects.lubricant_depletion import FORMS as DEPLETION_FORMS, LubricantDepletion
from ..physics.effects.position_dependent_stiffness import PositionDependentStiffness
from ..physics.effects.resonance import Resonance
from ..physics.effects.thermal_viscosity import LAWS as VISCOSITY_LAWS, ThermalViscosity

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = ['BACKGROUND_FRACTION_RANGE', 'DEPLETION_FALL_RANGE', 'DRAWN_ARRANGEMENTS', 'Effects',
           'REFERENCE_VISCOSITY_RANGE', 'RESONANCE_BANDS', 'RESONANCE_BELOW_RATIO_RANGE', 'RESONANCE_DAMPING_RANGE',
           'RESONANCE_INSIDE_RANGE', 'RESONANCE_RATIO_RANGE', 'STIFFNESS_CHANGE_RANGE', 'TEMPERATURE_RISE_RANGE',
           'THERMAL_TIME_CONSTANT_RANGE', 'TONE_FREQUENCY_RANGE', 'VOGEL_DISTANCE_RANGE',
           'draw_background_vibration', 'draw_lubricant_depletion', 'draw_position_dependent_stiffness',
           'draw_resonance', 'draw_thermal_viscosity']

#: Drawn range of the amplitude change over one stroke at the reference load (fraction).
STIFFNESS_CHANGE_RANGE = (0.05, 0.30)
#: Drawn range of the frequency ratio r = n f_S / f_r at the plan's top forward speed (mode above the band).
RESONANCE_RATIO_RANGE = (0.5, 0.9)
#: Drawn range of r at the lowest speed for a mode below the band.
RESONANCE_BELOW_RATIO_RANGE = (1.3, 3.0)
#: Drawn position of a mode inside the band, ln(omega_r / omega_min) / ln(omega_max / omega_min).
RESONANCE_INSIDE_RANGE = (0.25, 0.75)
#: Where the mode lies against the speed band.
RESONANCE_BANDS = ('above', 'inside', 'below')
#: Bearing arrangements drawn (fixed-supported has the axial law of fixed-free).
DRAWN_ARRANGEMENTS = ('fixed-free', 'free-fixed', 'fixed-fixed')
#: Drawn range of Vogel's T0 - T_V, K (mineral oils).
VOGEL_DISTANCE_RANGE = (90.0, 150.0)
#: Drawn range of the kinematic viscosity at ambient for the Walther law, mm^2/s (ISO VG 32-320).
REFERENCE_VISCOSITY_RANGE = (30.0, 300.0)
#: Drawn range of background tone frequencies, Hz.
TONE_FREQUENCY_RANGE = (60.0, 900.0)
#: Drawn range of the damping ratio of the structural mode.
RESONANCE_DAMPING_RANGE = (0.02, 0.20)
#: Drawn range of the steady temperature rise of nut and oil while running, K.
TEMPERATURE_RISE_RANGE = (5.0, 25.0)
#: Drawn range of the thermal time constant of nut and oil, s.
THERMAL_TIME_CONSTANT_RANGE = (120.0, 600.0)
#: Drawn range of the fall of theta_Oil over one session (one bag) by depletion (fraction).
DEPLETION_FALL_RANGE = (0.05, 0.25)
#: Drawn range of the background RMS relative to the thread-contact RMS at the lowest speed.
#: Background RMS as a fraction of the thread-contact amplitude at the lowest speed.  Adding in power, 0.5 raises
#: the low-speed amplitude by 12 % (the least at which "the amplitude stops following the model" at low speed)
#: and 1.5 by 80 % (motor and bearing vibration dominating a slowly turning screw).
BACKGROUND_FRACTION_RANGE = (0.50, 1.50)


class Effects:
    """Which physical effects act on the simulated rig, by ID, each with its law (absent = off).

    ``Effects(resonance=Resonance(...))``; ``effects.resonance`` is the law or
    ``None``.  The IDs and law types come from :mod:`prsm_lube_ros.physics.effects`.
    """

    def __init__(self, **laws: object) -> None:
        """Keep the laws that are not None, each checked against its effect's law type."""
        known = effect_ids()
        self._laws: dict[str, DataclassInstance] = {}
        for name, law in laws.items():
            if name not in known:
                raise ConfigError(f'effects: unknown effect {name!r}; known: {", ".join(known)}')
            if law is None:
                continue
            if not isinstance(law, law_type(name)):
                raise ConfigError(f'effects: {name} must be a {law_type(name).__name__}, got {law!r}')
            self._laws[name] = law

    def __getattr__(self, name: str) -> Any:
        """The law of effect ``name`` or None when it is off (``Any``: its type depends on ``name``)."""
        if name.startswith('_'):
            raise AttributeError(name)
        if name in effect_ids():
            return self._laws.get(name)
        raise AttributeError(f'no effect {name!r}')

    def __eq__(self, other: object) -> bool:
        """Same effects with equal laws."""
        return isinstance(other, Effects) and self._laws == other._laws

    def __repr__(self) -> str:
        """``Effects(name=law, ...)``."""
        return 'Effects(' + ', '.join(f'{k}={v!r}' for k, v in self._laws.items()) + ')'

    @property
    def active(self) -> tuple[str, ...]:
        """IDs of the effects that are on, in the registry's order."""
        return tuple(name for name in effect_ids() if name in self._laws)

    def as_dict(self) -> dict:
        """``{effect_id: parameters or None}`` for ``truth.json``."""
        result: dict[str, Any] = {}
        for name in effect_ids():
            law = self._laws.get(name)
            if law is None:
                result[name] = None
                continue
            result[name] = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(law).items()}
            if hasattr(law, 'stiffness_ratio_at_start'):
                result[name]['stiffness_ratio_at_start'] = law.stiffness_ratio_at_start
        return result

    @classmethod
    def from_dict(cls, mapping: dict | None) -> Effects:
        """Inverse of :meth:`as_dict` (derived entries are ignored)."""
        values = {}
        for name, params in (mapping or {}).items():
            kind = law_type(name)
            if params is None:
                continue
            known = {f.name for f in fields(kind)}
            try:
                values[name] = kind(**{k: (tuple(v) if isinstance(v, list) else v)
                                       for k, v in params.items() if k in known})
            except TypeError as exc:
                raise ConfigError(f'effects: {name} parameters incomplete ({exc})') from None
        return cls(**values)


_T = TypeVar('_T')


def _choose(rng: np.random.Generator, options: Sequence[_T], chosen: _T | None = None) -> _T:
    """``chosen`` when given (checked against ``options``), else one of ``options`` at random."""
    if chosen is None:
        return options[int(rng.integers(len(options)))]
    if chosen not in options:
        raise ConfigError(f'effects: {chosen!r} is not one of {", ".join(map(str, options))}')
    return chosen


def draw_position_dependent_stiffness(rng: np.random.Generator, *, youngs_modulus: float,
                                      root_diameter: float, stroke: float, fixed_end_offset: float,
                                      reference_load: float, arrangement: str | None = None
                                      ) -> PositionDependentStiffness:
    """Random shaft-compliance effect: 5-30 % amplitude change over the stroke at reference_load.

    ``arrangement`` (default: drawn) is one of :data:`DRAWN_ARRANGEMENTS`:
    the fixed bearing fixed_end_offset (m) beyond the end of the stroke
    (``fixed-free``: the amplitude falls along the stroke), as far before its
    start (``free-fixed``: it rises), or both (``fixed-fixed``: an arch,
    highest mid-travel).  With the shaft compliance q(x) = 1/k_s(x) the
    amplitude factor is ``1 + k_c q(x)``; its relative change over the stroke
    ``c = k_c (q_max - q_min) / (1 + k_c q_max)`` is drawn uniformly from
    :data:`STIFFNESS_CHANGE_RANGE` and k_c solved from it.
    """
    arrangement = _choose(rng, DRAWN_ARRANGEMENTS, arrangement)
    change = rng.uniform(*STIFFNESS_CHANGE_RANGE)
    shape = PositionDependentStiffness(contact_stiffness=1.0, reference_load=reference_load,
                                       youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                       free_length_at_start=stroke + fixed_end_offset, arrangement=arrangement,
                                       near_length_at_start=fixed_end_offset)
    compliance = 1.0 / shape.shaft_stiffness(np.linspace(0.0, stroke, 201))
    spread, largest = float(np.ptp(compliance)), float(np.max(compliance))
    if change >= spread / largest:
        raise ConfigError(f'position_dependent_stiffness: a {change:.0%} change is impossible with '
                          f'fixed_end_offset {fixed_end_offset} m ({arrangement})')
    contact = change / (spread - change * largest)
    return PositionDependentStiffness(contact_stiffness=float(contact), reference_load=reference_load,
                                      youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                      free_length_at_start=stroke + fixed_end_offset, arrangement=arrangement,
                                      near_length_at_start=fixed_end_offset)


def draw_resonance(rng: np.random.Generator, *, order: float, top_speed: float, bottom_speed: float | None = None,
                   orders: Sequence[float] | None = None, band: str | None = None) -> Resonance:
    """Random resonance excited by rotation ``order`` (or one of ``orders`` at random), zeta in its range.

    ``band`` (default: drawn when bottom_speed is given, else ``above``): the
    mode above the speed band (r at top_speed in :data:`RESONANCE_RATIO_RANGE`),
    inside it (resonant speed log-uniform in the middle of the band) or below it
    (r at bottom_speed in :data:`RESONANCE_BELOW_RATIO_RANGE`); speeds in rad/s.
    """
    order = float(_choose(rng, tuple(orders))) if orders else float(order)
    bands = RESONANCE_BANDS if bottom_speed is not None else RESONANCE_BANDS[:1]
    band = _choose(rng, bands, band)
    damping = rng.uniform(*RESONANCE_DAMPING_RANGE)
    top = abs(top_speed)
    if band == 'above':
        resonant = top / rng.uniform(*RESONANCE_RATIO_RANGE)
    elif band == 'inside':
        assert bottom_speed is not None  # the band is below or inside only with a bottom speed
        low = abs(bottom_speed)
        resonant = low * (top / low) ** rng.uniform(*RESONANCE_INSIDE_RANGE)
    else:
        assert bottom_speed is not None  # the band is below or inside only with a bottom speed
        resonant = abs(bottom_speed) / rng.uniform(*RESONANCE_BELOW_RATIO_RANGE)
    natural = order * resonant / (2.0 * math.pi)
    return Resonance(order=order, natural_frequency=float(natural), damping_ratio=float(damping))


def draw_thermal_viscosity(rng: np.random.Generator, *, viscosity_temperature_coefficient: float,
                           law: str | None = None) -> ThermalViscosity:
    """Random warming: dT and tau uniform in their ranges; beta (1/K) is the oil's slope at ambient.

    ``law`` (default: drawn) is one of the viscosity laws; Vogel's distance
    T0 - T_V and Walther's nu_ref are drawn in :data:`VOGEL_DISTANCE_RANGE` and
    :data:`REFERENCE_VISCOSITY_RANGE`.
    """
    law = _choose(rng, VISCOSITY_LAWS, law)
    return ThermalViscosity(temperature_rise=float(rng.uniform(*TEMPERATURE_RISE_RANGE)),
                            time_constant=float(rng.uniform(*THERMAL_TIME_CONSTANT_RANGE)),
                            viscosity_temperature_coefficient=float(viscosity_temperature_coefficient),
                            viscosity_law=law, vogel_distance=float(rng.uniform(*VOGEL_DISTANCE_RANGE)),
                            reference_viscosity=float(rng.uniform(*REFERENCE_VISCOSITY_RANGE)))


def draw_lubricant_depletion(rng: np.random.Generator, *, session_revolutions: float,
                             form: str | None = None) -> LubricantDepletion:
    """Random depletion: theta falls by 5-25 % over session_revolutions (one bag), exponentially or linearly.

    ``form`` (default: drawn) is ``exponential`` or ``linear``.  The rig
    simulator has no recovery at rest (the window-table simulator has).
    """
    form = _choose(rng, DEPLETION_FORMS, form)
    fall = rng.uniform(*DEPLETION_FALL_RANGE)
    revolutions = session_revolutions / -math.log1p(-fall) if form == 'exponential' else session_revolutions / fall
    return LubricantDepletion(depletion_revolutions=float(revolutions), form=form)


def draw_background_vibration(rng: np.random.Generator, *, reference_amplitude: float,
                              form: str | None = None, highest_frequency: float = math.inf) -> BackgroundVibration:
    """Random background: B = 50-150 % of reference_amplitude (m/s^2, thread contacts at the lowest speed).

    ``form`` (default: drawn) is one of the background forms: two fixed
    tones (drive and frame, frequencies drawn in :data:`TONE_FREQUENCY_RANGE`
    below ``highest_frequency``, Hz: the upper edge of the band the
    recording's window RMS holds), a broadband floor, or both (tones 40 % of
    the power).  A tone above that edge is not in the recording the model is
    fitted to, and concealing it would test nothing: at 1 kHz the band ends at
    400 Hz, and two tones at 430 and 513 Hz (two 273 of the fresh random
    study) were concealed where no method could see them.
    """
    form = _choose(rng, BACKGROUND_FORMS, form)
    fraction = rng.uniform(*BACKGROUND_FRACTION_RANGE)
    low, high = TONE_FREQUENCY_RANGE
    tones = tuple(float(f) for f in np.sort(rng.uniform(low, max(min(high, highest_frequency), low), size=2)))
    if form == BACKGROUND_FORMS[1]:
        return BackgroundVibration(rms=float(fraction * reference_amplitude), tone_frequencies=(), tone_shares=(),
                                   broadband_share=1.0)
    shares = (0.5, 0.5) if form == BACKGROUND_FORMS[0] else (0.2, 0.2)
    return BackgroundVibration(rms=float(fraction * reference_amplitude), tone_frequencies=tones,
                               tone_shares=shares, broadband_share=1.0 - sum(shares))
