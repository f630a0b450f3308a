# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""How a recording is made, apart from the physics: stamp jitter, repeated stamps, lost blocks.

CONTRACT.md ("Rates seen in practice"): stamps come from the publisher's clock
and can jitter or repeat, and blocks can be lost.  :class:`RecordingNuisances`
says how much of each the rig simulator puts into a bag; sample rates, block
lengths and topic rates are :class:`~.rig_config.RigConfig` fields.  None of it
changes the physics: the nuisances draw from their own random stream, so the
same seed gives the same vibration whatever nuisances are applied.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..validation import require


__all__ = ['RecordingNuisances']


@dataclass(frozen=True)
class RecordingNuisances:
    """Recording faults the simulator adds (all off by default).

    ``stamp_jitter`` s: standard deviation of the publisher-clock error on
    every header stamp (vibration blocks, joint states, load, temperature),
    kept below half the smallest message period so stamps stay in order;
    ``repeated_stamp_fraction``: share of joint-state and load messages whose
    header stamp repeats the one before (a coarse publisher clock);
    ``lost_block_fraction``: share of vibration blocks never recorded.
    """

    stamp_jitter: float = 0.0
    repeated_stamp_fraction: float = 0.0
    lost_block_fraction: float = 0.0

    def __post_init__(self) -> None:
        """Check the ranges."""
        require(self.stamp_jitter >= 0, f'nuisances stamp_jitter must be >= 0 s, got {self.stamp_jitter!r}')
        for name in ('repeated_stamp_fraction', 'lost_block_fraction'):
            value = getattr(self, name)
            require(0 <= value < 0.5, f'nuisances {name} must lie in [0, 0.5), got {value!r}')

    @property
    def active(self) -> bool:
        """Whether any nuisance is on."""
        return bool(self.stamp_jitter or self.repeated_stamp_fraction or self.lost_block_fraction)

    def as_dict(self) -> dict:
        """Plain mapping (for ``truth.json``)."""
        return asdict(self)

    def jitter(self, rng: np.random.Generator, stamps_ns: np.ndarray, period: float) -> np.ndarray:
        """``stamps_ns`` (int ns) moved by the clock error, clipped to +-0.4 ``period`` (s) to keep the order."""
        stamps_ns = np.asarray(stamps_ns, dtype=np.int64)
        if not self.stamp_jitter or stamps_ns.size == 0:
            return stamps_ns
        bound = 0.4 * period
        error = np.clip(rng.normal(0.0, self.stamp_jitter, stamps_ns.size), -bound, bound)
        return stamps_ns + np.rint(error * 1e9).astype(np.int64)

    def repeat(self, rng: np.random.Generator, stamps_ns: np.ndarray) -> np.ndarray:
        """``stamps_ns`` with a share of them replaced by the stamp before (never the first)."""
        stamps_ns = np.array(stamps_ns, dtype=np.int64)
        if not self.repeated_stamp_fraction or stamps_ns.size < 2:
            return stamps_ns
        hit = np.flatnonzero(rng.random(stamps_ns.size - 1) < self.repeated_stamp_fraction) + 1
        hit = hit[np.diff(np.r_[-2, hit]) > 1]     # no runs of repeats: each repeats a fresh stamp
        stamps_ns[hit] = stamps_ns[hit - 1]
        return stamps_ns

    def kept_blocks(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """Mask of the ``count`` vibration blocks that reach the recording."""
        if not self.lost_block_fraction:
            return np.ones(count, dtype=bool)
        return rng.random(count) >= self.lost_block_fraction
