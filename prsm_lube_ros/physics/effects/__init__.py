# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Physical laws the paper's model leaves out: one module per effect, its file name its ID.

Each module states the physics of one effect, the equation by which it
changes Eq. 22, the law as numpy functions, and a frozen dataclass of its
physical parameters (SI) with the factor it applies.  The rig simulator makes
signals with these laws (:mod:`prsm_lube_ros.simulation`); the diagnosis fits
them (:mod:`prsm_lube_ros.diagnosis.effects`) and assessment applies a fitted
one (:mod:`prsm_lube_ros.estimation.assessment`).  Nothing else writes them.

The modules present *are* the registry: :func:`effect_ids` lists them without
importing any (so ``prsm-lube --help`` stays fast), and a new effect is a new
file here.  Imports only numpy, scipy, the physics layer and the base layer.

Each module also carries its simulation hook, a subclass of :class:`Simulation`
named ``Simulation``: how to draw the law over the module's documented ranges
(the one set of ranges every simulator and study uses), how the law changes the
rig's thread-contact amplitude, what it adds to the recorded power, and, where
the effect has a waveform of its own, a :class:`Waveform` that shapes or adds to
the samples.  The simulators loop over the registry and call these hooks; none
names an effect.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
import importlib
import math
import pkgutil
from typing import Any, ClassVar, TYPE_CHECKING, TypeVar

from ...errors import ConfigError

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence
    from types import ModuleType

    from _typeshed import DataclassInstance
    import numpy as np
    import numpy.typing as npt

    from ..actuator import Actuator

#: The order the contract lists the effects in (others follow alphabetically).
#: Append new effects at the end: the simulators spawn one random stream per effect in this order, so the
#: streams of the effects listed before stay as they were.
CONTRACT_ORDER = ('position_dependent_stiffness', 'resonance', 'thermal_viscosity', 'lubricant_depletion',
                  'background_vibration', 'surface_defect')


@lru_cache(maxsize=1)
def effect_ids() -> tuple[str, ...]:
    """IDs of the effects (the modules of this package), contract order first; listed once per process."""
    names = {module.name for module in pkgutil.iter_modules(__path__) if not module.name.startswith('_')}
    return tuple(n for n in CONTRACT_ORDER if n in names) + tuple(sorted(names - set(CONTRACT_ORDER)))


def effect_module(effect_id: str) -> ModuleType:
    """The module of effect ``effect_id``; :class:`ConfigError` naming the known ones otherwise."""
    if effect_id not in effect_ids():
        raise ConfigError(f'unknown effect {effect_id!r}; known: {", ".join(effect_ids())}')
    return importlib.import_module(f'{__name__}.{effect_id}')


def law_type(effect_id: str) -> type[DataclassInstance]:
    """The parameter dataclass of effect ``effect_id`` (its module's ``Law``)."""
    return effect_module(effect_id).Law


class Extension:
    """How an effect extends Eq. 22, given its fitted physical parameters (a dict of floats, SI).

    The extended model is ``ln A = ln A_22(theta f) + gain``: ``film_factor``
    f multiplies theta_Oil in Eq. 22's film term (the film thickness, Eq. 9-12,
    changes); ``log_gain`` is added to ``ln A_0`` (the response to the same
    excitation changes, or vibration from elsewhere adds to it).  Covariates
    come from any object with the window table's attribute names (``speed``,
    ``load``, ``position``, ``revolutions``, ``temperature``, ``time``).
    Each effect module subclasses this as ``Extension``; the diagnosis adds
    how to fit it.

    Types: ``params`` maps names to floats (a combination of effects in the
    diagnosis nests one such mapping per effect, hence ``Any`` values);
    ``covariates`` is ``Any`` because it is duck-typed (a window table, a
    namespace of arrays, or an object with just the attribute one effect
    reads); the laws broadcast, so factors and gains are arrays, or floats for
    scalar covariates.
    """

    #: Effect ID (the module name).
    id: str = ''

    def film_factor(self, params: Mapping[str, Any], covariates: Any) -> np.ndarray | float:
        """Factor on theta_Oil in Eq. 22's film term (1 = none)."""
        return 1.0

    def log_gain(self, params: Mapping[str, Any], covariates: Any, ln_a22: np.ndarray | float) -> np.ndarray | float:
        """Term added to ln A_0 (0 = none); ``ln_a22`` is Eq. 22's ln amplitude."""
        return 0.0

    def eq22_amplitude(self, params: Mapping[str, Any], covariates: Any, rms: npt.ArrayLike) -> np.ndarray | float:
        """The measured RMS mapped back to the amplitude Eq. 22 describes, m/s^2.

        Default: remove a multiplicative gain that does not depend on the amplitude itself.
        """
        import numpy as np
        rms = np.asarray(rms, dtype=float)
        return rms * np.exp(-np.asarray(self.log_gain(params, covariates, np.log(rms)), dtype=float))

    def assessment_film_factor(self, params: Mapping[str, Any], covariates: Any) -> np.ndarray | float:
        """Factor dividing Eq. 23's theta_Oil so it reports the oil supply (default: :meth:`film_factor`)."""
        return self.film_factor(params, covariates)


def extension(effect_id: str) -> Extension:
    """The :class:`Extension` of effect ``effect_id``."""
    return effect_module(effect_id).Extension()


_T = TypeVar('_T')


def choose(rng: np.random.Generator, options: Sequence[_T], chosen: _T | None = None) -> _T:
    """``chosen`` when given (checked against ``options``), else one of ``options`` at random."""
    if chosen is None:
        return options[int(rng.integers(len(options)))]
    if chosen not in options:
        raise ConfigError(f'effects: {chosen!r} is not one of {", ".join(map(str, options))}')
    return chosen


def simulation(effect_id: str) -> Simulation:
    """The :class:`Simulation` hook of effect ``effect_id``."""
    return effect_module(effect_id).Simulation()


# ---------------------------------------------------------------------------------------------
# Simulation hooks
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SimulationContext:
    """What an effect's parameters are drawn against: the rig's actuator and the plan it runs (SI).

    ``speeds`` (rad/s) and ``loads`` (N) are the plan's conditions, ``stroke``
    the nut travel of a run (m), ``session_revolutions`` the screw revolutions
    of one session (one bag), ``reference_amplitude`` the thread-contact RMS
    (m/s^2) at the lowest speed, highest load and theta_Oil = 1,
    ``sample_rate`` the accelerometer's rate (Hz) and ``band_high`` the upper
    edge (Hz) of the band the recording's window RMS holds.
    """

    actuator: Actuator
    speeds: tuple[float, ...]
    loads: tuple[float, ...]
    stroke: float
    session_revolutions: float
    reference_amplitude: float
    sample_rate: float
    band_high: float


@dataclass(frozen=True)
class ContactState:
    """Where the rig is when its thread-contact amplitude is taken (arrays or floats, one per sample or run).

    ``speed`` screw speed (rad/s, signed), ``load`` the load the contacts carry
    (N, preload as floor), ``nut_position`` m from the start of the stroke,
    ``temperature`` degC (None: ambient, not simulated), ``ambient_temperature``
    degC, ``revolutions`` since the last lubrication.
    """

    speed: npt.ArrayLike
    load: npt.ArrayLike
    nut_position: npt.ArrayLike
    temperature: npt.ArrayLike | None
    ambient_temperature: float
    revolutions: npt.ArrayLike


@dataclass(frozen=True)
class SampleState:
    """The rig at each sample of a chunk.

    ``times`` s, screw ``angles`` rad, ``speeds`` rad/s, applied ``loads`` N,
    ``revolutions`` since the last lubrication (either direction) and
    ``contact_amplitude`` the thread-contact RMS (m/s^2) the samples are scaled to.
    """

    times: np.ndarray
    angles: np.ndarray
    speeds: np.ndarray
    loads: np.ndarray
    revolutions: np.ndarray
    contact_amplitude: np.ndarray


@dataclass(frozen=True)
class ContactBroadband:
    """The thread contacts' random (broadband) part of a simulated recording's contact signal.

    White contact force through the contacts' own mode: ``frequency`` (Hz)
    and ``damping`` (ratio) of that mode, ``share`` of the unit contact
    signal's mean square it carries (the rest are rotation orders).  A
    structural mode the same force drives rings by it (resonance).
    """

    share: float
    frequency: float
    damping: float


@dataclass(frozen=True)
class StreamRandom:
    """Random streams of one simulated recording that a :class:`Waveform` may draw from (all from its seed).

    ``phases``: drawn from once, when the stream starts (the harmonics' phases
    come first); ``added``: a stream of its own for vibration added to the
    signal, shared by the effects in registry order; :meth:`keyed` makes a
    stream keyed off the seed without spawning from it, so an effect's own
    stream leaves every other stream as it was.  ``contact``: what drives the
    contacts' broadband (None: not known, no effect is driven by it).
    """

    sequence: np.random.SeedSequence
    phases: np.random.Generator
    added: np.random.Generator
    contact: ContactBroadband | None = None

    def keyed(self, key: int) -> np.random.Generator:
        """A generator keyed off the recording's seed by ``key`` (an integer the effect owns)."""
        import numpy as np
        return np.random.default_rng(np.random.SeedSequence(self.sequence.entropy,
                                                            spawn_key=tuple(self.sequence.spawn_key) + (1000, key)))


class Waveform:
    """An effect's own contribution to the samples, carrying its state (filters, phases) across chunks.

    :meth:`shape` transforms the unit thread-contact signal before it is scaled
    to the contact amplitude (a mode the contacts drive); :meth:`add` returns
    the acceleration (m/s^2) added to the scaled signal (vibration from
    elsewhere, impacts).  Both are called once per chunk, in registry order.
    """

    def shape(self, mix: np.ndarray, state: SampleState) -> np.ndarray:
        """The unit contact signal with the effect in it (default: unchanged)."""
        return mix

    def add(self, state: SampleState) -> np.ndarray | float:
        """Acceleration added to the samples, m/s^2 (default: none)."""
        return 0.0


class Simulation:
    """How the rig simulator makes an effect: draw its law, change the contact amplitude, add to the samples.

    Subclassed as ``Simulation`` in each effect module; every method has a
    neutral default, so an effect overrides only what it does.  The draw
    uses the module's documented ranges, the one set every simulator and
    study uses.
    """

    #: Effect ID (the module name).
    id: ClassVar[str] = ''
    #: Film factors compose on theta_Oil in ascending rank (registry order among equals): the order keeps the
    #: products, and so the simulated recordings, bit-identical with the simulators before the hooks.
    film_rank: ClassVar[int] = 0

    def draw(self, rng: np.random.Generator, context: SimulationContext) -> Any:
        """The effect's law (its module's ``Law``) with parameters drawn in the documented ranges."""
        raise NotImplementedError(f'{self.id}: no simulation draw')

    def film_factor(self, law: Any, state: ContactState) -> np.ndarray | float:
        """Factor on theta_Oil in Eq. 22's film term (1 = none)."""
        return 1.0

    def amplitude_factor(self, law: Any, state: ContactState) -> np.ndarray | float:
        """Factor on the thread-contact amplitude of Eq. 22 (1 = none)."""
        return 1.0

    def added_power(self, law: Any, state: ContactState) -> np.ndarray | float:
        """Mean square (m/s^2)^2 the effect adds to the recorded signal beside the contacts (0 = none)."""
        return 0.0

    def heating(self, law: Any) -> tuple[float, float] | None:
        """``(temperature rise K, time constant s)`` of nut and oil while running, or None (no heating)."""
        return None

    def waveform(self, law: Any, sample_rate: float, random: StreamRandom) -> Waveform | None:
        """The effect's own waveform in a recording at ``sample_rate`` Hz, or None (amplitude only)."""
        return None

    def window_indicators(self, law: Any, state: ContactState, contact_power: np.ndarray
                          ) -> dict[str, np.ndarray]:
        """Condition indicators of windows at ``state`` whose contact power is ``contact_power`` ((m/s^2)^2).

        For the window-level simulator: ``kurtosis`` (3 = Gaussian), ``defect_db``
        (envelope peak at a defect order over the floor, dB) and ``defect_order``
        where the effect changes them, and ``impulsive_power`` ((m/s^2)^2), the
        power the effect adds that is not Gaussian (it leaves the window's
        measured Gaussian RMS); empty (the default) when it changes none.
        """
        return {}

    def form_words(self, params: Mapping[str, Any], speeds: Sequence[float]) -> list[str]:
        """Words for the drawn law's physical form beyond its text-valued parameters (for study rows).

        ``params`` is the law as ``truth.json`` holds it, ``speeds`` the plan's (rad/s).  Default: none.
        """
        return []

    def extension_params(self, law: Any, context: SimulationContext) -> dict[str, float]:
        """The law as the parameters of its module's ``Extension`` (for window-level simulation), SI."""
        raise NotImplementedError(f'{self.id}: no window-level parameters')


def resonator_energy(b: npt.ArrayLike, a: npt.ArrayLike, tolerance: float = 1e-14) -> float:
    """Energy sum(h[n]^2) of a stable IIR filter's impulse response: its output variance for unit white input."""
    import numpy as np
    from scipy.signal import lfilter
    length = 1024
    while True:
        impulse = np.zeros(length)
        impulse[0] = 1.0
        response = lfilter(b, a, impulse)
        energy = float(np.sum(response ** 2))
        if np.sum(response[-length // 4:] ** 2) <= tolerance * energy:
            return energy
        length *= 2


def log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    """One draw log-uniform in [low, high] (both > 0)."""
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))
