# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Random cases of the diagnosis study: operating plan, recording set-up and nuisances, effects.

Every case of :mod:`.diagnose_study` (random design) is drawn here from its
own seed, over the ranges CONTRACT.md's "Rates seen in practice" and the
issue name:

* plan: 3-6 screw speeds (lowest 60-120 r/min, top 1.5-3 times the lowest)
  and 2-5 axial loads (lowest 60-150 N, top 1.5-4 times the lowest), levels
  spread evenly on a log scale and listed in random order, runs in random
  order, two sessions (bags) at theta_Oil = 1;
* recording: vibration at 1-20 kHz in blocks of 5-200 ms (a whole number of
  samples), joint states 50-1000 Hz, load 10-1000 Hz, temperature 1-10 Hz;
* nuisances (:class:`~prsm_lube_ros.simulation.nuisances.RecordingNuisances`):
  stamp jitter 0-1 ms, 0-5 % repeated joint-state and load stamps, 0-3 %
  lost vibration blocks;
* set-up scatter of a real rig: every traverse's amplitude factor log-normal
  with a standard deviation drawn in 0-4 %, a slow wander of 0-1 % RMS, and
  in half the cases the return traverse run back at the same speed and load
  (out and back, both measured);
* effects: drawn by :func:`~prsm_lube_ros.simulation.recordings.draw_effects`
  (the ``draw_*`` functions' own physical ranges and forms), for the case's
  plan and rig.

The rig's contact mode is kept below 0.4 times the sample rate (it must lie
below Nyquist); nothing else of the rig changes.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
import math

import numpy as np

from ..simulation.nuisances import RecordingNuisances
from ..simulation.rig_config import ExperimentPlan, RigConfig, RPM

__all__ = ['BLOCK_LENGTHS', 'CONTACT_MODE_SHARE', 'CaseSetup', 'JOINT_STATE_RATES', 'LOAD_COUNTS', 'LOAD_RATES',
           'LOAD_SPAN', 'LOST_BLOCKS', 'LOWEST_LOAD', 'LOWEST_SPEED_RPM', 'REPEATED_STAMPS', 'RUN_SCATTER',
           'RUN_WANDER', 'SAMPLE_RATES', 'SPEED_COUNTS', 'SPEED_SPAN', 'STAMP_JITTER', 'TEMPERATURE_RATES',
           'draw_setup', 'recording_pairs']

#: Vibration sample rates drawn from, Hz (1-20 kHz, as data acquisition cards offer them).
SAMPLE_RATES = (1000.0, 2000.0, 2560.0, 4000.0, 5000.0, 8000.0, 10000.0, 12800.0, 20000.0)
#: Vibration block lengths drawn from, s (5-200 ms); pairs giving a fractional block size are skipped.
BLOCK_LENGTHS = (0.005, 0.01, 0.02, 0.025, 0.05, 0.1, 0.2)
#: Joint-state, load and temperature rate ranges, Hz (drawn log-uniform).
JOINT_STATE_RATES = (50.0, 1000.0)
LOAD_RATES = (10.0, 1000.0)
TEMPERATURE_RATES = (1.0, 10.0)
#: Counts of screw speeds and axial loads in a plan.
SPEED_COUNTS = (3, 6)
LOAD_COUNTS = (2, 5)
#: Lowest speed (r/min) and top/lowest ratio; lowest load (N) and top/lowest ratio.
LOWEST_SPEED_RPM = (60.0, 120.0)
SPEED_SPAN = (1.5, 3.0)
LOWEST_LOAD = (60.0, 150.0)
LOAD_SPAN = (1.5, 4.0)
#: Nuisance ranges: stamp jitter s, repeated-stamp share, lost-block share.
STAMP_JITTER = (0.0, 0.001)
REPEATED_STAMPS = (0.0, 0.05)
LOST_BLOCKS = (0.0, 0.03)
#: Set-up scatter: std of a traverse's ln amplitude factor, RMS of the slow wander.
RUN_SCATTER = (0.0, 0.04)
RUN_WANDER = (0.0, 0.01)
#: Highest contact-mode frequency relative to the sample rate.
CONTACT_MODE_SHARE = 0.4


@dataclass(frozen=True)
class CaseSetup:
    """Everything of one study case except its effects."""

    plan: ExperimentPlan
    rig: RigConfig
    nuisances: RecordingNuisances

    def as_dict(self) -> dict:
        """What the study records of the set-up (for ``results.json``)."""
        return {'speeds_rpm': [round(s / RPM, 1) for s in self.plan.speeds],
                'loads_n': [round(f, 1) for f in self.plan.loads],
                'sample_rate': self.rig.vibration_rate, 'block': self.rig.vibration_block,
                'joint_state_rate': self.rig.joint_state_rate, 'load_rate': self.rig.load_rate,
                'temperature_rate': self.rig.temperature_rate, 'nuisances': self.nuisances.as_dict(),
                'run_scatter': self.rig.run_scatter, 'run_wander': self.rig.run_wander,
                'return_under_load': self.plan.return_under_load, 'mount_step': self.rig.mount_step,
                'mount_step_at': self.rig.mount_step_at, 'return_factor': self.rig.return_factor,
                'initial_temperature_offset': self.rig.initial_temperature_offset,
                'cool_down_pause': self.plan.cool_down_pause, 'cool_down_every': self.plan.cool_down_every}


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _levels(rng: np.random.Generator, count_range: tuple[int, int], lowest_range: tuple[float, float],
            span_range: tuple[float, float]) -> tuple[float, ...]:
    count = int(rng.integers(count_range[0], count_range[1] + 1))
    lowest = rng.uniform(*lowest_range)
    top = lowest * rng.uniform(*span_range)
    levels = np.geomspace(lowest, top, count)
    return tuple(float(v) for v in levels[rng.permutation(count)])


def recording_pairs() -> list[tuple[float, float]]:
    """(sample rate, block length) pairs with a whole number of samples per block."""
    pairs = []
    for rate in SAMPLE_RATES:
        for block in BLOCK_LENGTHS:
            size = rate * block
            if abs(size - round(size)) < 1e-6 and round(size) >= 8:
                pairs.append((rate, block))
    return pairs


def draw_setup(rng: np.random.Generator, *, sessions: int = 2, quick: bool = False) -> CaseSetup:
    """Plan, rig recording set-up and nuisances of one case (``quick``: the smallest plan, 3 speeds x 2 loads)."""
    speeds = _levels(rng, SPEED_COUNTS if not quick else (3, 3), LOWEST_SPEED_RPM, SPEED_SPAN)
    loads = _levels(rng, LOAD_COUNTS if not quick else (2, 2), LOWEST_LOAD, LOAD_SPAN)
    plan = ExperimentPlan(speeds=tuple(s * RPM for s in speeds), loads=loads, stage_thetas=(1.0,) * sessions,
                          run_order='random')
    pairs = recording_pairs()
    rate, block = pairs[int(rng.integers(len(pairs)))]
    base = RigConfig()
    rig = replace(base, vibration_rate=rate, vibration_block=block,
                  contact_mode_frequency=min(base.contact_mode_frequency, CONTACT_MODE_SHARE * rate),
                  joint_state_rate=round(_log_uniform(rng, *JOINT_STATE_RATES)),
                  load_rate=round(_log_uniform(rng, *LOAD_RATES)),
                  temperature_rate=round(_log_uniform(rng, *TEMPERATURE_RATES), 1))
    nuisances = RecordingNuisances(stamp_jitter=float(rng.uniform(*STAMP_JITTER)),
                                   repeated_stamp_fraction=float(rng.uniform(*REPEATED_STAMPS)),
                                   lost_block_fraction=float(rng.uniform(*LOST_BLOCKS)))
    # Drawn last, so the draws above stay those of the study before set-up scatter was added.
    rig = replace(rig, run_scatter=float(rng.uniform(*RUN_SCATTER)), run_wander=float(rng.uniform(*RUN_WANDER)))
    plan = replace(plan, return_under_load=bool(rng.integers(2)))
    return CaseSetup(plan, rig, nuisances)
