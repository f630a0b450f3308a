# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Which effects act on the simulated rig, and their strengths drawn in physical ranges.

The laws themselves live in :mod:`prsm_lube_ros.physics.effects` (one module
per effect, shared with the diagnosis); this module holds the simulator's
side: the :class:`Effects` container of active laws written to
``truth.json`` (recordings carry no label of them) and a ``draw_*`` function
per effect that picks its parameters inside a documented physical range, for
studies of the diagnosis.  All effects are off by default.
"""
from __future__ import annotations

from dataclasses import asdict, fields
import math

import numpy as np

from ..errors import ConfigError
from ..physics.effects import effect_ids, law_type
from ..physics.effects.background_vibration import BackgroundVibration
from ..physics.effects.lubricant_depletion import LubricantDepletion
from ..physics.effects.position_dependent_stiffness import PositionDependentStiffness, shaft_axial_stiffness
from ..physics.effects.resonance import Resonance
from ..physics.effects.thermal_viscosity import ThermalViscosity

#: Drawn range of the amplitude change over one stroke at the reference load (fraction).
STIFFNESS_CHANGE_RANGE = (0.05, 0.30)
#: Drawn range of the frequency ratio r = n f_S / f_r at the plan's top forward speed.
RESONANCE_RATIO_RANGE = (0.5, 0.9)
#: Drawn range of the damping ratio of the structural mode.
RESONANCE_DAMPING_RANGE = (0.02, 0.10)
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

    def __init__(self, **laws):
        """Keep the laws that are not None, each checked against its effect's law type."""
        known = effect_ids()
        self._laws = {}
        for name, law in laws.items():
            if name not in known:
                raise ConfigError(f'effects: unknown effect {name!r}; known: {", ".join(known)}')
            if law is None:
                continue
            if not isinstance(law, law_type(name)):
                raise ConfigError(f'effects: {name} must be a {law_type(name).__name__}, got {law!r}')
            self._laws[name] = law

    def __getattr__(self, name):
        """The law of effect ``name`` or None when it is off."""
        if name.startswith('_'):
            raise AttributeError(name)
        if name in effect_ids():
            return self._laws.get(name)
        raise AttributeError(f'no effect {name!r}')

    def __eq__(self, other):
        """Same effects with equal laws."""
        return isinstance(other, Effects) and self._laws == other._laws

    def __repr__(self):
        """``Effects(name=law, ...)``."""
        return 'Effects(' + ', '.join(f'{k}={v!r}' for k, v in self._laws.items()) + ')'

    @property
    def active(self) -> tuple[str, ...]:
        """IDs of the effects that are on, in the registry's order."""
        return tuple(name for name in effect_ids() if name in self._laws)

    def as_dict(self) -> dict:
        """``{effect_id: parameters or None}`` for ``truth.json``."""
        result = {}
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
    def from_dict(cls, mapping: dict | None) -> 'Effects':
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


def draw_position_dependent_stiffness(rng: np.random.Generator, *, youngs_modulus: float,
                                      root_diameter: float, stroke: float, fixed_end_offset: float,
                                      reference_load: float) -> PositionDependentStiffness:
    """Random shaft-compliance effect: 5-30 % amplitude fall over the stroke at reference_load.

    The fixed bearing lies fixed_end_offset (m) beyond the end of the stroke,
    so ``L(0) = stroke + fixed_end_offset`` and ``L(stroke) = fixed_end_offset``.
    With rho0 = k_c / k_s(0) the relative fall is
    ``c = rho0 (1 - L(stroke)/L(0)) / (1 + rho0)``; c is drawn uniformly from
    :data:`STIFFNESS_CHANGE_RANGE` and rho0 solved from it.
    """
    length_start = stroke + fixed_end_offset
    shrink = 1.0 - fixed_end_offset / length_start
    change = rng.uniform(*STIFFNESS_CHANGE_RANGE)
    if change >= shrink:
        raise ConfigError(f'position_dependent_stiffness: a {change:.0%} change is impossible with '
                          f'fixed_end_offset {fixed_end_offset} m')
    ratio = change / (shrink - change)
    contact = ratio * float(shaft_axial_stiffness(youngs_modulus, root_diameter, length_start))
    return PositionDependentStiffness(contact_stiffness=contact, reference_load=reference_load,
                                      youngs_modulus=youngs_modulus, root_diameter=root_diameter,
                                      free_length_at_start=length_start)


def draw_resonance(rng: np.random.Generator, *, order: float, top_speed: float) -> Resonance:
    """Random resonance: r at top_speed (rad/s) in :data:`RESONANCE_RATIO_RANGE`, zeta in its range."""
    ratio = rng.uniform(*RESONANCE_RATIO_RANGE)
    damping = rng.uniform(*RESONANCE_DAMPING_RANGE)
    natural = order * abs(top_speed) / (2.0 * math.pi) / ratio
    return Resonance(order=float(order), natural_frequency=float(natural), damping_ratio=float(damping))


def draw_thermal_viscosity(rng: np.random.Generator, *,
                           viscosity_temperature_coefficient: float) -> ThermalViscosity:
    """Random warming: dT and tau uniform in their documented ranges; beta (1/K) is the oil's."""
    return ThermalViscosity(temperature_rise=float(rng.uniform(*TEMPERATURE_RISE_RANGE)),
                            time_constant=float(rng.uniform(*THERMAL_TIME_CONSTANT_RANGE)),
                            viscosity_temperature_coefficient=float(viscosity_temperature_coefficient))


def draw_lubricant_depletion(rng: np.random.Generator, *, session_revolutions: float) -> LubricantDepletion:
    """Random depletion: theta falls by 5-25 % over session_revolutions (one bag)."""
    fall = rng.uniform(*DEPLETION_FALL_RANGE)
    return LubricantDepletion(depletion_revolutions=float(session_revolutions / -math.log1p(-fall)))


def draw_background_vibration(rng: np.random.Generator, *,
                              reference_amplitude: float) -> BackgroundVibration:
    """Random background: B = 50-150 % of reference_amplitude (m/s^2, thread contacts at the lowest speed)."""
    fraction = rng.uniform(*BACKGROUND_FRACTION_RANGE)
    return BackgroundVibration(rms=float(fraction * reference_amplitude))
