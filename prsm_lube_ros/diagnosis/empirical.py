# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Physics outside the catalogue: an empirical term in the covariate that carries the mismatch.

When the located shape is one no catalogue effect has a law for, the engine
fits Eq. 22 extended by a term of the shape's own form in the located
covariate, scores it on held-out runs like a candidate, and reports it as
``empirical`` (the verdict stays ``unexplained``: the term describes, it does
not explain).  Forms, each ``ln A = ln A_22 + g`` with g:

* ``step`` / ``stretch`` in time: ``g = s`` on the runs after a step (or
  inside a stretch) found in recording order by
  :func:`~.locate.time_segment` (the place is estimated on all runs, the size
  ``s`` is fitted with the constants);
* ``direction factor``: ``g = d`` on runs back (``direction`` -1, the
  return traverse), ``exp(d)`` the ratio of return to out amplitude;
* ``smooth`` in a continuous covariate x (position, revolutions, time,
  temperature, ln speed, load): ``g = a z + b (z^2 - 1/3)``, ``z`` the
  covariate scaled to [-1, 1] over the data.

Each form comes with the physical causes that produce such a shape
(:data:`CAUSES`), so the user knows where to look.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .effects import Effect
from .locate import Location, time_segment

if TYPE_CHECKING:
    from .table import Columns, WindowTable

__all__ = ['CAUSES', 'EmpiricalTerm', 'LOG_BOUND', 'causes', 'empirical_terms']

#: Causes of each shape, in words.
CAUSES = {
    'step': ('a step in time is what a change of the set-up between two runs gives: the accelerometer re-seated, '
             're-glued or its cable moved, the nut re-mounted or its preload re-set, the oil or a part exchanged'),
    'stretch': ('a stretch of runs apart from the others is a temporary change of the set-up: a loosened sensor '
                'mount fixed again, a warm-up, another fixture or operator for those runs'),
    'direction': ('a ratio between the two directions of travel at the same speed and load comes from the thread '
                  'flanks: the other flank carries the load (flank loading, unequal flank finish or wear), '
                  'backlash or a preload that differs by direction, or a load path through the bearings, the '
                  'load cell or a misaligned nut that changes with the sign of the feed'),
    'position': ('a shape along the stroke other than the shaft stiffness: a worn or dented track, straightness '
                 'or runout of the screw, a support or guide whose stiffness changes along the travel'),
    'revolutions': ('a change with revolutions other than oil depletion: running-in or wear of the flanks, oil '
                    'ageing, debris'),
    'time': 'a drift in time: the sensor or its amplifier drifting, the ambient or the supply changing',
    'temperature': ('a temperature dependence other than the oil viscosity: the sensor\'s own sensitivity, '
                    'preload changing with thermal expansion'),
    'speed': ('a speed dependence Eq. 22 and the catalogue lack: structural response of the mounting, an '
              'excitation that does not scale as the contact law'),
    'load': 'a load dependence Eq. 22 lacks: preload, contact stiffness or the load path changing with load',
}
#: Bound of an empirical log term (a factor e^1.5 = 4.5 either way).
LOG_BOUND = 1.5


class EmpiricalTerm(Effect):
    """A term of a located shape added to ln A_0 (see module doc); not in the catalogue."""

    id = 'empirical'
    title = 'empirical term (physics outside the catalogue)'
    physics = 'a term of the located shape fitted without a physical law'
    equations = 'ln A = ln A_22 + g(covariate)'

    def __init__(self, covariate: str, form: str, *, runs: npt.ArrayLike = (),
                 scale: tuple[float, float] = (0.0, 1.0)) -> None:
        """``form`` 'step', 'stretch', 'direction' or 'smooth'; ``runs`` the run numbers the step/stretch covers."""
        self.covariate, self.form = covariate, form
        self.runs = np.asarray(runs, dtype=np.int64)
        self.scale = scale
        self.parameter_names = ('a', 'b') if form == 'smooth' else ('s',)

    def _x(self, covariates: Columns) -> np.ndarray:
        values = np.asarray(getattr(covariates, self.covariate), dtype=float)
        if self.covariate == 'speed':
            values = np.log(np.abs(values))
        return (values - self.scale[0]) / self.scale[1]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Each coefficient within :data:`LOG_BOUND`."""
        k = len(self.parameter_names)
        return np.full(k, -LOG_BOUND), np.full(k, LOG_BOUND)

    def starts(self) -> list[np.ndarray]:
        """Zero and small terms either way."""
        k = len(self.parameter_names)
        return [np.zeros(k), np.full(k, 0.1), np.full(k, -0.1)]

    def to_params(self, p: np.ndarray, scales: dict[str, Any]) -> dict[str, float]:
        """The coefficients (dimensionless: changes of ln A)."""
        return {name: float(v) for name, v in zip(self.parameter_names, p)}

    def log_gain(self, params: Mapping[str, float], covariates: Columns, ln_a22: float | np.ndarray) -> np.ndarray:
        """g of the form (module doc)."""
        if self.form in ('step', 'stretch'):
            return params['s'] * np.isin(np.asarray(covariates.run), self.runs)
        if self.form == 'direction':
            return params['s'] * (np.asarray(covariates.direction, dtype=float) < 0)
        z = np.nan_to_num(self._x(covariates))
        return params['a'] * z + params['b'] * (z * z - 1.0 / 3.0)

    def describe(self, params: dict[str, float]) -> str:
        """The fitted term in words."""
        if self.form in ('step', 'stretch'):
            where = 'after the step' if self.form == 'step' else 'in the stretch'
            return f'amplitude {math.exp(params["s"]):.3f} times as high {where} as on the other runs'
        if self.form == 'direction':
            return f'amplitude {math.exp(params["s"]):.3f} times as high on the return traverses as out'
        return (f'ln A changes by {params["a"]:+.3f} z {params["b"]:+.3f} (z^2 - 1/3), z the {self.covariate} '
                'scaled to [-1, 1]')


def empirical_terms(table: WindowTable, residual: np.ndarray, location: Location,
                    significance: float, min_segment_runs: int) -> list[EmpiricalTerm]:
    """The empirical terms of every shape the location found significant (time segment, direction, smooth).

    ``significance`` and ``min_segment_runs``: the locate test's (:class:`.rules.DiagnosisRules`).
    """
    terms = []
    for test in location.tests:
        if not test.p_value < significance:
            continue
        if test.kind == 'segment of runs':
            segment = time_segment(table, residual, min_segment_runs)
            if segment is None:
                continue
            inside = segment['inside']
            step = segment['first'] == 0 or segment['stop'] == inside.size
            covered = segment['runs'][~inside] if segment['first'] == 0 else segment['runs'][inside]
            terms.append(EmpiricalTerm('time', 'step' if step else 'stretch', runs=covered))
        elif test.kind == 'paired by direction':
            terms.append(EmpiricalTerm('direction', 'direction'))
        elif test.covariate in ('position', 'revolutions', 'time', 'temperature', 'speed', 'load'):
            values = np.asarray(getattr(table, test.covariate), dtype=float)
            if test.covariate == 'speed':
                values = np.log(np.abs(values))
            values = values[np.isfinite(values)]
            if values.size and np.ptp(values) > 0:
                lo, hi = float(values.min()), float(values.max())
                terms.append(EmpiricalTerm(test.covariate, 'smooth', scale=(0.5 * (lo + hi), 0.5 * (hi - lo))))
    unique: dict[tuple[str, str], EmpiricalTerm] = {}
    for term in terms:
        unique.setdefault((term.covariate, term.form), term)
    return list(unique.values())


def causes(term: EmpiricalTerm) -> str:
    """What produces the shape, in words."""
    return CAUSES['step' if term.form == 'step' else 'stretch' if term.form == 'stretch'
                  else 'direction' if term.form == 'direction' else term.covariate]
