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
file here.  Imports only numpy, :mod:`..vibration_model` and the base layer.
"""
from __future__ import annotations

from functools import lru_cache
import importlib
import pkgutil
from typing import Any, TYPE_CHECKING

from ...errors import ConfigError

if TYPE_CHECKING:
    from collections.abc import Mapping
    from types import ModuleType

    from _typeshed import DataclassInstance
    import numpy as np
    import numpy.typing as npt

#: The order the contract lists the effects in (others follow alphabetically).
CONTRACT_ORDER = ('position_dependent_stiffness', 'resonance', 'thermal_viscosity', 'lubricant_depletion',
                  'background_vibration')


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
