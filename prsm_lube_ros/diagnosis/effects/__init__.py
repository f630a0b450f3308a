# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Catalogue of candidate physics the paper's model leaves out: one module per effect.

Each module in this package defines an :class:`~.base.Effect` subclass and
registers itself with :func:`~.base.register`; every module here is imported
when the package is, so a new candidate is a new file and nothing else.
Effects defined elsewhere register the same way once imported.
"""
from __future__ import annotations

import importlib
import pkgutil

from ...errors import InputError
from .base import Effect, register, registered

__all__ = ['Effect', 'register', 'registered', 'get_effect', 'effect_ids']

for _module in pkgutil.iter_modules(__path__):
    if _module.name != 'base':
        importlib.import_module(f'{__name__}.{_module.name}')


def effect_ids() -> tuple[str, ...]:
    """IDs of the registered effects."""
    return tuple(registered())


def get_effect(effect_id: str) -> Effect:
    """The registered effect with this ID; :class:`InputError` naming the known ones otherwise."""
    effects = registered()
    if effect_id not in effects:
        raise InputError(f'unknown effect {effect_id!r}; known: {", ".join(effects)}')
    return effects[effect_id]
