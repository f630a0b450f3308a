# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Which effects act on the simulated rig: the :class:`Effects` container of active laws.

The laws, and how each is drawn in its documented physical ranges and made by
the rig simulator, live in :mod:`prsm_lube_ros.physics.effects` (one module per
effect, shared with the diagnosis; its ``Simulation`` hook).  This module holds
the container written to ``truth.json`` (recordings carry no label of them).
All effects are off by default.
"""
from __future__ import annotations

from dataclasses import asdict, fields
from typing import Any, TYPE_CHECKING
from collections.abc import Iterator

from ..errors import ConfigError
from ..physics.effects import effect_ids, law_type, simulation, Simulation

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

__all__ = ['Effects']


class Effects:
    """Which physical effects act on the simulated rig, by ID, each with its law (absent = off).

    ``Effects(resonance=ResonanceLaw(...))``; ``effects.resonance`` is the law or
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

    def hooks(self) -> Iterator[tuple[Simulation, Any]]:
        """``(simulation hook, law)`` of each effect that is on, in the registry's order."""
        for name in self.active:
            yield simulation(name), self._laws[name]

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
