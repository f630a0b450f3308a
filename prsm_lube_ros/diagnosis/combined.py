# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Two effects at once: to test whether each adds anything given the other, and to name both."""
from __future__ import annotations

from typing import Any, Mapping, TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .effects import Effect

if TYPE_CHECKING:
    from .table import Columns, WindowTable


__all__ = ['CombinedEffect', 'GRID']

#: Starts of each effect paired in the multi-start grid of a joint fit.
GRID = 3


class CombinedEffect(Effect):
    """Eq. 22 extended by two effects: film factors multiply, gains add (``second`` sees the first's gain).

    ``added`` is the effect passed second (the one tried on top of the other),
    whatever the order the gains are applied in; the combination's ``form`` is
    its form.  ``first_start`` / ``second_start``: the internal parameters an
    effect had when fitted alone; the multi-start begins there (paired with
    each start of an effect without one), then tries a few of the grid of
    both effects' starts.
    """

    def __init__(self, first: Effect, second: Effect, first_start: npt.ArrayLike | None = None,
                 second_start: npt.ArrayLike | None = None) -> None:
        """Combine ``first`` and ``second``; a law that adds power (:attr:`.effects.Effect.adds_power`) goes second."""
        self.added = second
        self._anchors = {id(first): first_start, id(second): second_start}
        if first.adds_power and not second.adds_power:
            first, second = second, first
        self.first, self.second = first, second
        self.id = f'{first.id}+{second.id}'
        self.title = f'{first.title} and {second.title}'
        self.form = self.added.form
        self.parameter_names = first.parameter_names + second.parameter_names
        self.trades_load_excitation = first.trades_load_excitation or second.trades_load_excitation
        self._split = len(first.parameter_names)

    def applicable(self, table: WindowTable) -> str:
        """Both must be testable."""
        return self.first.applicable(table) or self.second.applicable(table)

    def scales(self, table: WindowTable) -> dict[str, dict[str, Any]]:
        """Both effects' scales."""
        return {'first': self.first.scales(table), 'second': self.second.scales(table)}

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Both effects' bounds, concatenated."""
        (lo1, hi1), (lo2, hi2) = self.first.bounds(), self.second.bounds()
        return np.r_[lo1, lo2], np.r_[hi1, hi2]

    def starts(self) -> list[np.ndarray]:
        """Both effects at their own fits where given, then a few of the grid of both effects' starts."""
        grid = [np.r_[a, b] for a in list(self.first.starts())[:GRID] for b in list(self.second.starts())[:GRID]]
        first = self._anchors[id(self.first)]
        second = self._anchors[id(self.second)]
        if first is None and second is None:
            return grid
        firsts = [np.asarray(first, dtype=float)] if first is not None else list(self.first.starts())
        seconds = [np.asarray(second, dtype=float)] if second is not None else list(self.second.starts())
        return [np.r_[a, b] for a in firsts for b in seconds] + grid[:GRID - 1]

    def to_params(self, p: npt.ArrayLike, scales: dict[str, Any]) -> dict[str, dict[str, Any]]:
        """``{'first': params, 'second': params}``."""
        p = np.asarray(p, dtype=float)
        return {'first': self.first.to_params(p[:self._split], scales['first']),
                'second': self.second.to_params(p[self._split:], scales['second'])}

    def params_of(self, params: dict[str, Any], effect: Effect) -> dict[str, Any]:
        """The parameters of ``effect`` (one of the two) in :meth:`to_params`' mapping."""
        return params['first' if effect is self.first else 'second']

    def film_factor(self, params: Mapping[str, Any], covariates: Columns) -> float | np.ndarray:
        """Product of both film factors."""
        return (self.first.film_factor(params['first'], covariates)
                * self.second.film_factor(params['second'], covariates))

    def log_gain(self, params: Mapping[str, Any], covariates: Columns,
                 ln_a22: float | np.ndarray) -> float | np.ndarray:
        """Sum of both gains."""
        gain = self.first.log_gain(params['first'], covariates, ln_a22)
        return gain + self.second.log_gain(params['second'], covariates, ln_a22 + gain)

    def measured_against(self, table: WindowTable, params: dict[str, Any],
                         predicted: np.ndarray | None = None) -> str:
        """What a measurement says against either effect's part of the joint fit (empty when nothing)."""
        return (self.first.measured_against(table, params['first'], predicted)
                or self.second.measured_against(table, params['second'], predicted))

    def describe(self, params: dict[str, Any]) -> str:
        """Both effects in words."""
        return (self.first.describe(params['first']) + ' Together with: '
                + self.second.describe(params['second']))
