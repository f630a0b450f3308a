# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Catalogue of candidate physics the paper's model leaves out: one module per effect.

For every effect of :mod:`prsm_lube_ros.physics.effects` (the one registry of
effect IDs) the module of the same name here defines the candidate: an
:class:`~.base.Effect` subclass of the law's ``Extension`` with what a fit
needs, registered with :func:`~.base.register` when the package is imported.
"""
from __future__ import annotations

import importlib

from ...errors import ConfigError
from ...physics.effects import effect_ids as physics_effect_ids
from .base import Effect, register, registered

__all__ = ['Effect', 'register', 'registered', 'get_effect', 'candidate_ids']

for _effect_id in physics_effect_ids():
    importlib.import_module(f'{__name__}.{_effect_id}')


def candidate_ids() -> tuple[str, ...]:
    """IDs of the registered diagnosis candidates (:func:`..physics.effects.effect_ids` lists the effects' modules)."""
    return tuple(registered())


def get_effect(effect_id: str) -> Effect:
    """The registered effect with this ID; :class:`InputError` naming the known ones otherwise."""
    effects = registered()
    if effect_id not in effects:
        raise ConfigError(f'unknown effect {effect_id!r}; known: {", ".join(effects)}')
    return effects[effect_id]
