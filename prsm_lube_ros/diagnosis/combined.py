# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Two effects at once: used to test whether each adds anything given the other."""
from __future__ import annotations

import numpy as np

from .effects import Effect


class CombinedEffect(Effect):
    """Eq. 22 extended by two effects: film factors multiply, gains add (``second`` sees the first's gain)."""

    def __init__(self, first: Effect, second: Effect):
        """Combine ``first`` and ``second``; an amplitude-dependent gain (background) should come second."""
        if second.id == 'background_vibration':
            pass
        elif first.id == 'background_vibration':
            first, second = second, first
        self.first, self.second = first, second
        self.id = f'{first.id}+{second.id}'
        self.title = f'{first.title} and {second.title}'
        self.parameter_names = first.parameter_names + second.parameter_names
        self._split = len(first.parameter_names)

    def scales(self, table):
        """Both effects' scales."""
        return {'first': self.first.scales(table), 'second': self.second.scales(table)}

    def bounds(self):
        """Both effects' bounds, concatenated."""
        (lo1, hi1), (lo2, hi2) = self.first.bounds(), self.second.bounds()
        return np.r_[lo1, lo2], np.r_[hi1, hi2]

    def starts(self):
        """Pairs of both effects' starts."""
        return [np.r_[a, b] for a in self.first.starts() for b in self.second.starts()]

    def to_params(self, p, scales):
        """``{'first': params, 'second': params}``."""
        p = np.asarray(p, dtype=float)
        return {'first': self.first.to_params(p[:self._split], scales['first']),
                'second': self.second.to_params(p[self._split:], scales['second'])}

    def film_factor(self, params, covariates):
        """Product of both film factors."""
        return (self.first.film_factor(params['first'], covariates)
                * self.second.film_factor(params['second'], covariates))

    def log_gain(self, params, covariates, ln_a22):
        """Sum of both gains."""
        gain = self.first.log_gain(params['first'], covariates, ln_a22)
        return gain + self.second.log_gain(params['second'], covariates, ln_a22 + gain)
