# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Oil flung out of the contacts as the screw turns: theta_Oil decays with revolutions.

Physics: the paper notes centrifugal loss of oil (Sec. 2.2); between
lubrications the supply factor falls with the revolutions run,

    theta_eff = theta_Oil exp(-N_rev / N_d)

so the film term of Eq. 22 carries the factor ``exp(-N_rev / N_d)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import Extension as EffectExtension
from ...validation import require_all_positive


def theta_factor(revolutions, depletion_per_revolution):
    """``exp(-N_rev / N_d)`` for revolutions N_rev since the last lubrication, rate 1/N_d per revolution."""
    return np.exp(-np.asarray(depletion_per_revolution, dtype=float) * np.asarray(revolutions, dtype=float))


@dataclass(frozen=True)
class LubricantDepletion:
    """Oil flung out of the contacts: ``theta_eff = theta_Oil exp(-N_rev / N_d)``.

    N_rev is the screw revolutions (either direction) run since the last
    lubrication, i.e. since the start of the bag.
    """

    depletion_revolutions: float   # N_d, revolutions

    def __post_init__(self):
        """Reject non-physical parameters."""
        require_all_positive('lubricant_depletion', **self.__dict__)

    def theta_factor(self, revolutions):
        """``exp(-N_rev / N_d)`` for revolutions N_rev since the last lubrication."""
        return theta_factor(revolutions, 1.0 / self.depletion_revolutions)


Law = LubricantDepletion


class Extension(EffectExtension):
    """theta_Oil in Eq. 22 times ``exp(-N_rev depletion_per_revolution)``."""

    id = 'lubricant_depletion'

    def film_factor(self, params, covariates):
        """``exp(-N_rev / N_d)``."""
        revolutions = np.nan_to_num(np.asarray(covariates.revolutions, dtype=float))
        return theta_factor(revolutions, params['depletion_per_revolution'])

    def assessment_film_factor(self, params, covariates):
        """1: depletion is a real fall of theta_Oil, which assessment must report."""
        return np.ones_like(np.asarray(covariates.speed, dtype=float))
