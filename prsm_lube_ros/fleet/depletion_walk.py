# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Depletion as a random walk: ln theta_Oil falls by ``k dt`` with diffusion ``q dt`` between relubrications.

The statistics behind :mod:`.forecast`: the increments of ln theta between
consecutive recordings of one lubrication cycle and their covariance, the
Gaussian likelihood of drift ``k`` and diffusion ``q`` (generalised least
squares), the fleet's relative usage scatter ``s`` (q = s k^2, upper 95 %
profile-likelihood bound over all actuators) and the Kalman filter of
(ln theta, k) that gives the state at the last recording.

The scatter is estimated over several spans (:data:`STRIDES`: the increments
between consecutive recordings, every second, fourth and eighth of a cycle)
and the largest kept (:func:`usage_scatter_over_strides`).  A walk is the
right law only if the variance grows in proportion to the span; usage whose
rate holds over part of a day or over weeks grows faster than the one-day
increments say, and a forecast for 30 days needs the long-span figure.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
import math
from typing import cast, TypeGuard
from collections.abc import Sequence

import numpy as np


__all__ = ['Increments', 'PROFILE_DROP', 'STRIDES', 'STRIDE_MIN_INCREMENTS', 'USAGE_SCATTER_GRID', 'depletion_state',
           'drift_and_diffusion', 'fleet_usage_scatter', 'increments', 'strided_increments',
           'usage_scatter_over_strides']


@dataclass(frozen=True)
class Increments:
    """Changes of ln theta between consecutive recordings of one lubrication cycle, and their covariance."""

    steps: np.ndarray          # days
    changes: np.ndarray        # of ln theta
    measurement: np.ndarray    # covariance from the recordings' own uncertainty

    @cached_property
    def without_diffusion(self) -> tuple[float, float, float] | None:
        """:func:`_walk_likelihood` at q = 0, worked out once (the usage-scatter search asks for it per grid point)."""
        return _walk_likelihood(self, 0.0)


def increments(days: np.ndarray, y: np.ndarray, sigma: np.ndarray, cycles: np.ndarray) -> Increments | None:
    """The increments of ln theta ``y`` within cycles; neighbours sharing a recording correlate by -sigma^2.

    Steps of zero days (recordings starting at the same time: one recording
    assessed as MCAP and as sqlite3, or copies) are left out: they carry no
    drift.  None with fewer than two increments.
    """
    pairs = np.array([j for j in range(len(y) - 1) if cycles[j] == cycles[j + 1] and days[j + 1] > days[j]],
                     dtype=int)
    if pairs.size < 2:
        return None
    measurement = np.diag(sigma[pairs] ** 2 + sigma[pairs + 1] ** 2)
    for a in range(pairs.size - 1):
        if pairs[a + 1] == pairs[a] + 1:
            measurement[a, a + 1] = measurement[a + 1, a] = -sigma[pairs[a + 1]] ** 2
    return Increments(days[pairs + 1] - days[pairs], y[pairs + 1] - y[pairs], measurement)


def _walk_likelihood(data: Increments, q: float) -> tuple[float, float, float] | None:
    """Gaussian log-likelihood, GLS drift k (1/day) and its variance for diffusion ``q`` (1/day).

    None when the increments carry no information on the drift.
    """
    covariance = data.measurement + np.diag(q * data.steps)
    try:
        inverse = np.linalg.inv(covariance)
    except np.linalg.LinAlgError:
        return None
    information = float(data.steps @ inverse @ data.steps)
    if not information > 0 or not math.isfinite(information):
        return None
    k = -float(data.steps @ inverse @ data.changes) / information
    residual = data.changes + k * data.steps
    _, logdet = np.linalg.slogdet(covariance)
    return -0.5 * (logdet + float(residual @ inverse @ residual)), k, 1.0 / information


#: fall of the log-likelihood at the 95 % bound of one parameter (chi-square 3.84 / 2)
PROFILE_DROP = 1.92
#: grid of the relative day-to-day usage variance searched by :func:`fleet_usage_scatter`
USAGE_SCATTER_GRID = np.concatenate(([0.0], np.logspace(-4, 0, 81)))


def _diffusion(data: Increments, usage_scatter: float) -> float:
    """q = usage_scatter k^2: a relative scatter s of each day's revolutions spreads ln theta by s k per day."""
    assert data.without_diffusion is not None  # called on informative increments only
    k = data.without_diffusion[1]
    for _ in range(2):
        k = (_walk_likelihood(data, usage_scatter * k ** 2) or (0.0, k))[1]
    return usage_scatter * k ** 2


def _informative(data: Increments | None) -> TypeGuard[Increments]:
    """True when ``data`` determines a drift (increments with information on it)."""
    return data is not None and data.without_diffusion is not None


def fleet_usage_scatter(sets: Sequence[Increments | None]) -> float:
    """Relative variance of a day's revolutions: upper 95 % profile-likelihood bound over all actuators.

    Each actuator's diffusion is ``q = s k^2`` with its own drift k: the
    usage scatter ``s`` is a property of how the fleet is operated, which one
    actuator's few recordings cannot pin down alone.  Daily recordings with
    a few per mille of noise hardly see it, so the largest value the
    likelihood does not reject (a drop of at most ``PROFILE_DROP``) is taken
    rather than its maximum, which sits at zero.
    """
    sets = [data for data in sets if _informative(data)]
    if not sets:
        return 0.0
    # informative increments have a likelihood at every diffusion (a None would raise here as before)
    totals = np.array([sum(cast('tuple[float, float, float]', _walk_likelihood(data, _diffusion(data, scatter)))[0]
                           for data in cast('list[Increments]', sets))   # filtered above
                       for scatter in USAGE_SCATTER_GRID])
    return float(USAGE_SCATTER_GRID[np.flatnonzero(totals >= totals.max() - PROFILE_DROP)[-1]])


#: strides of recordings (within a lubrication cycle) whose increments each estimate the usage scatter
STRIDES = (1, 2, 4, 8)
#: increments a stride needs over the fleet for its estimate to count
STRIDE_MIN_INCREMENTS = 20


def strided_increments(days: np.ndarray, y: np.ndarray, sigma: np.ndarray, cycles: np.ndarray,
                       stride: int) -> Increments | None:
    """:func:`increments` between every ``stride``-th recording of each cycle (from the cycle's first)."""
    position = np.zeros(len(y), dtype=int)
    for j in range(1, len(y)):
        position[j] = position[j - 1] + 1 if cycles[j] == cycles[j - 1] else 0
    keep = position % stride == 0
    return increments(days[keep], y[keep], sigma[keep], cycles[keep])


def usage_scatter_over_strides(sets_by_stride: Sequence[Sequence[Increments | None]]) -> float:
    """The largest :func:`fleet_usage_scatter` over strides with :data:`STRIDE_MIN_INCREMENTS` increments or more.

    ``sets_by_stride``: per stride (the first: every recording, always
    counted), each actuator's increments.
    """
    found = []
    for number, sets in enumerate(sets_by_stride):
        count = sum(data.steps.size for data in sets if data is not None)
        if number == 0 or count >= STRIDE_MIN_INCREMENTS:
            found.append(fleet_usage_scatter(sets))
    return max(found, default=0.0)


def drift_and_diffusion(data: Increments | None, usage_scatter: float | None = None
                        ) -> tuple[float, float, float, int] | None:
    """Depletion as a random walk: ln theta falls by ``k dt`` plus noise of variance ``q dt`` (usage scatter).

    ``k`` by generalised least squares on the increments; ``q`` from the
    fleet's relative ``usage_scatter`` (q = s k^2) or, without it, by maximum
    likelihood on this actuator alone.  Returns (k 1/day, variance of k,
    q 1/day, degrees of freedom) or None without increments.
    """
    if not _informative(data):
        return None
    if usage_scatter is None:
        q = max((walk[0], q) for q in np.concatenate(([0.0], np.logspace(-9, -2, 57)))
                if (walk := _walk_likelihood(data, q)) is not None)[1]
    else:
        q = _diffusion(data, usage_scatter)
    _, k, k_variance = cast('tuple[float, float, float]', _walk_likelihood(data, q))
    return k, k_variance, q, max(data.steps.size - 1, 1)


def depletion_state(days: np.ndarray, y: np.ndarray, sigma: np.ndarray, cycles: np.ndarray,
                    q: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Kalman filter of (ln theta, k): level falls by k dt with diffusion q dt, reset at relubrications.

    Returns the state at the last recording, its covariance (scaled by the
    innovations' chi-square per degree of freedom when above 1) and the
    degrees of freedom of that scale (0 when not scaled).
    """
    diffuse = 1e4
    state = np.array([y[0], 0.0])
    cov = np.diag([diffuse, diffuse])
    chi2, count = 0.0, 0
    for j in range(len(y)):
        if j > 0:
            dt = days[j] - days[j - 1]
            transition = np.array([[1.0, -dt], [0.0, 1.0]])
            state = transition @ state
            cov = transition @ cov @ transition.T + np.diag([q * dt, 0.0])
            if cycles[j] != cycles[j - 1]:
                state[0], cov[0, :], cov[:, 0] = y[j], 0.0, 0.0
                cov[0, 0] = diffuse
        innovation_var = cov[0, 0] + sigma[j] ** 2
        innovation = y[j] - state[0]
        if cov[0, 0] < diffuse / 10 and cov[1, 1] < diffuse / 10:
            chi2 += innovation ** 2 / innovation_var
            count += 1
        gain = cov[:, 0] / innovation_var
        state = state + gain * innovation
        cov = cov - np.outer(gain, cov[0, :])
    dof = count
    if dof and chi2 / dof > 1.0:
        return state, cov * (chi2 / dof), dof
    return state, cov, 0
