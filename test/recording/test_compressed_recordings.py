# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Chunk-compressed (zstd) recordings give the same windows as uncompressed ones."""
from prsm_lube_ros.physics.actuator import Actuator
from prsm_lube_ros.estimation.pipeline import recording_windows
from prsm_lube_ros.simulation.recordings import simulate_experiment
from prsm_lube_ros.simulation.rig_config import ExperimentPlan


def test_zstd_chunks_read_back_to_the_same_windows(tmp_path):
    plan = ExperimentPlan(stage_thetas=(0.9,), loads=(150.0,))
    plain = simulate_experiment(tmp_path / 'plain', plan=plan, seed=4)[0]
    packed = simulate_experiment(tmp_path / 'zstd', plan=plan, seed=4, compression='zstd')[0]
    size = lambda path: sum(p.stat().st_size for p in path.rglob('*.mcap'))  # noqa: E731
    assert size(packed) < 0.95 * size(plain)
    a = recording_windows(plain, lead=Actuator().lead)
    b = recording_windows(packed, lead=Actuator().lead)
    assert a.problems == [] and b.problems == []
    assert [(w.start, w.vibration_rms, w.screw_speed, w.reason) for w in a.windows] == \
        [(w.start, w.vibration_rms, w.screw_speed, w.reason) for w in b.windows]
