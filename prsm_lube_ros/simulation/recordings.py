# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Contract recordings of the simulated rig: the paper's experiment, endurance bags, ``truth.json``."""
from __future__ import annotations

from dataclasses import asdict, replace
import json
import math
from pathlib import Path
from collections.abc import Callable, Sequence

import numpy as np

from ..estimation.conditioning import DEFAULT_BAND
from ..physics.effects import effect_ids, simulation, SimulationContext
from ..recording.writer import bag_path, check_storage, ContractBagWriter
from ..validation import as_number, require
from .drive import DriveProgram, schedule_session, Stroke
from .effects import Effects
from .nuisances import RecordingNuisances
from .rig_config import CHUNK_DURATION, ExperimentPlan, ProgressCallback, RigConfig
from .rig_acceleration import RigStream, thread_contact_amplitude


__all__ = ['draw_effects', 'session_revolutions', 'simulation_context', 'simulate_endurance', 'simulate_experiment']


# ---------------------------------------------------------------------------------------------
# Recording
# ---------------------------------------------------------------------------------------------
def _latencies(rng: np.random.Generator, rig: RigConfig, count: int) -> np.ndarray:
    seconds = rig.transport_latency + (rng.exponential(rig.latency_jitter, count)
                                       if rig.latency_jitter > 0 else np.zeros(count))
    return np.rint(seconds * 1e9).astype(np.int64)


def _record(path: Path, storage: str, stream: RigStream, first_block: int, stop_block: int,
            theta_oil: float, latency_rng: np.random.Generator,
            progress: Callable[[int], None] | None, compression: str | None = None,
            nuisances: RecordingNuisances | None = None, nuisance_rng: np.random.Generator | None = None) -> None:
    """Write blocks ``[first_block, stop_block)`` of the stream to a new bag, with the recording nuisances."""
    rig = stream.rig
    nuisances = nuisances or RecordingNuisances()
    nuisance_rng = nuisance_rng if nuisance_rng is not None else np.random.default_rng(0)
    step = max(1, int(round(CHUNK_DURATION / rig.vibration_block)))
    block_ns = int(round(rig.vibration_block * 1e9))

    def stamped(true_ns: np.ndarray, rate: float, repeats: bool = False) -> np.ndarray:
        """Header stamps of messages taken at ``true_ns``: jittered, with repeats if ``repeats``."""
        stamps = nuisances.jitter(nuisance_rng, true_ns, 1.0 / rate)
        return nuisances.repeat(nuisance_rng, stamps) if repeats else stamps

    with ContractBagWriter(path, storage=storage, namespace=rig.namespace, compression=compression) as writer:
        for start in range(first_block, stop_block, step):
            stop = min(start + step, stop_block)
            chunk = stream.advance(start, stop, theta_oil)
            kept = nuisances.kept_blocks(nuisance_rng, len(chunk.block_stamps))
            blocks = chunk.block_stamps[kept]
            writer.add_vibration(stamped(blocks, 1.0 / rig.vibration_block),
                                 blocks + block_ns + _latencies(latency_rng, rig, len(blocks)),
                                 chunk.sample_rate, chunk.samples[kept], rig.vibration_frame_id)
            writer.add_joint_states(stamped(chunk.joint_stamps, rig.joint_state_rate, True), chunk.joint_stamps
                                    + _latencies(latency_rng, rig, chunk.joint_stamps.size),
                                    chunk.joint_angles, chunk.joint_speeds)
            writer.add_axial_loads(stamped(chunk.load_stamps, rig.load_rate, True), chunk.load_stamps
                                   + _latencies(latency_rng, rig, chunk.load_stamps.size),
                                   chunk.loads, rig.load_frame_id)
            writer.add_temperatures(stamped(chunk.temperature_stamps, rig.temperature_rate),
                                    chunk.temperature_stamps
                                    + _latencies(latency_rng, rig, chunk.temperature_stamps.size),
                                    chunk.temperatures, rig.temperature_noise ** 2, rig.temperature_frame_id)
            writer.flush(stream.origin_ns + stop * block_ns)
            if progress is not None:
                progress(stop - start)


def _blocks(seconds: float, rig: RigConfig) -> int:
    """Whole vibration blocks covering ``seconds`` (rounded up)."""
    return int(math.ceil(seconds / rig.vibration_block - 1e-9))


def _streams(seed: int) -> tuple[np.random.SeedSequence, np.random.Generator, np.random.Generator,
                                 np.random.Generator]:
    """Rig seed, latency, run order and nuisance streams (SeedSequence children: adding one keeps the others)."""
    rig_seed, latency_seed, order_seed, nuisance_seed = np.random.SeedSequence(seed).spawn(4)
    return (rig_seed, np.random.default_rng(latency_seed), np.random.default_rng(order_seed),
            np.random.default_rng(nuisance_seed))


def session_revolutions(plan: ExperimentPlan, rig: RigConfig) -> float:
    """Screw revolutions of one session (all conditions, forward and rewind)."""
    return 2.0 * len(plan.conditions) * plan.stroke / rig.actuator.lead


def simulation_context(rig: RigConfig | None = None, plan: ExperimentPlan | None = None) -> SimulationContext:
    """What effects are drawn against on this rig and plan (:class:`~prsm_lube_ros.physics.effects.SimulationContext`).

    The plan's conditions, stroke and one session's revolutions; the
    thread-contact amplitude at the lowest speed, highest load and theta = 1;
    the rig's sample rate and the upper edge of the default analysis band at it.
    """
    rig, plan = rig or RigConfig(), plan or ExperimentPlan()
    return SimulationContext(
        actuator=rig.actuator, speeds=tuple(plan.speeds), loads=tuple(plan.loads), stroke=plan.stroke,
        session_revolutions=session_revolutions(plan, rig),
        reference_amplitude=float(thread_contact_amplitude(min(plan.speeds), max(plan.loads), 1.0, rig)),
        sample_rate=rig.vibration_rate, band_high=DEFAULT_BAND.resolved(rig.vibration_rate).high)


def draw_effects(names: Sequence[str], *, seed: int = 0, rig: RigConfig | None = None,
                 plan: ExperimentPlan | None = None) -> Effects:
    """Effects ``names`` (see :func:`~prsm_lube_ros.physics.effects.effect_ids`), parameters drawn in physical ranges.

    Each effect's own simulation hook draws it (``Simulation.draw`` of its
    module, over the ranges documented there) against :func:`simulation_context`,
    from its own random stream: one ``SeedSequence(seed)`` child per registered
    effect, by registry index, so adding an effect at the end of the registry
    leaves the others' draws as they were.
    """
    unknown = sorted(set(names) - set(effect_ids()))
    require(not unknown, f'effects: unknown effect(s) {", ".join(unknown)}; known: {", ".join(effect_ids())}')
    rngs = dict(zip(effect_ids(), (np.random.default_rng(s) for s in
                                   np.random.SeedSequence(seed).spawn(len(effect_ids())))))
    context = simulation_context(rig, plan)
    return Effects(**{name: simulation(name).draw(rngs[name], context) for name in names})


def _truth(rig: RigConfig, plan: ExperimentPlan | None, seed: int, effects: Effects, storage: str,
           bags: list[dict], nuisances: RecordingNuisances | None = None) -> dict:
    return {'generator': 'prsm_lube_ros.simulation', 'seed': seed, 'storage': storage,
            'constants': asdict(rig.constants), 'rig': rig.as_dict(),
            'plan': plan.as_dict() if plan is not None else None,
            'effects': effects.as_dict(), 'nuisances': (nuisances or RecordingNuisances()).as_dict(),
            'bags': bags}


def _origin_seconds(stream: RigStream) -> float:
    return stream.origin_ns * 1e-9


#: One lubrication stage of an experiment: bag name, true theta_Oil, first and stop block, its strokes.
_Stage = tuple[str, float, int, int, list[Stroke]]


def _stage_schedule(plan: ExperimentPlan, rig: RigConfig,
                    order_rng: np.random.Generator) -> tuple[DriveProgram, list[_Stage]]:
    """The drive program of all stages (each starting on a whole block, ``plan.stage_pause`` apart) and the stages."""
    program = DriveProgram()
    schedule, now = [], 0.0
    for number, theta in enumerate(plan.stage_thetas, start=1):
        conditions = plan.conditions
        if plan.run_order == 'random':
            conditions = [conditions[k] for k in order_rng.permutation(len(conditions))]
        first_block = _blocks(now, rig)
        strokes, end = schedule_session(program, first_block * rig.vibration_block, conditions, plan, rig)
        stop_block = _blocks(end, rig)
        schedule.append((f'stage_{number}', theta, first_block, stop_block, strokes))
        now = stop_block * rig.vibration_block + plan.stage_pause
    return program, schedule


def simulate_experiment(out_dir: str | Path, *, plan: ExperimentPlan | None = None,
                        rig: RigConfig | None = None, seed: int = 0, effects: Effects | None = None,
                        storage: str = 'mcap', run_order: str | None = None,
                        stage_thetas: Sequence[float] | None = None,
                        progress: ProgressCallback | None = None, compression: str | None = None,
                        nuisances: RecordingNuisances | None = None) -> list[Path]:
    """Record the paper's experiment: one bag per lubrication stage in ``out_dir``, plus ``truth.json``.

    Bags are named ``stage_1``, ``stage_2``, ... (storage per
    :data:`bag_writer.STORAGE_FORMATS`); each holds the plan's conditions as
    forward runs with rewinds in between.  ``run_order`` (``'fixed'`` or
    ``'random'``, seeded) and ``stage_thetas`` (true theta_Oil per stage)
    override the plan's.  Stages follow each other after
    ``plan.stage_pause``.  ``progress(done_s, total_s)`` is called with simulated
    seconds.  ``compression='zstd'`` compresses the mcap chunks.  ``nuisances``
    adds stamp jitter, repeated stamps and lost blocks (the physics stays that
    of ``seed``).  Returns the bag paths.
    """
    rig, plan, effects = rig or RigConfig(), plan or ExperimentPlan(), effects or Effects()
    check_storage(storage)
    if run_order is not None:
        plan = replace(plan, run_order=run_order)
    if stage_thetas is not None:
        plan = replace(plan, stage_thetas=tuple(stage_thetas))
    out_dir = Path(out_dir)
    rig_seed, latency_rng, order_rng, nuisance_rng = _streams(seed)

    program, schedule = _stage_schedule(plan, rig, order_rng)
    paths = [bag_path(out_dir, name, storage) for name, *_ in schedule]
    for path in paths + [out_dir / 'truth.json']:
        require(not path.exists(), f'{path}: exists already, not overwriting')

    stream = RigStream(rig, program, seed=rig_seed, effects=effects)
    total = sum(stop - first for _, _, first, stop, _ in schedule)
    done = 0

    def advance(blocks: int) -> None:
        nonlocal done
        done += blocks
        if progress is not None:
            progress(done * rig.vibration_block, total * rig.vibration_block)

    bags = []
    origin = _origin_seconds(stream)
    for (name, theta, first, stop, strokes), path in zip(schedule, paths):
        stream.relubricate()
        _record(path, storage, stream, first, stop, theta, latency_rng, advance, compression, nuisances, nuisance_rng)
        bags.append({'name': name, 'path': path.name, 'theta_oil': theta,
                     'start': origin + first * rig.vibration_block,
                     'end': origin + stop * rig.vibration_block,
                     'runs': [_run_truth(stroke, origin, theta, rig) for stroke in strokes]})
    out_dir.mkdir(parents=True, exist_ok=True)
    truth = _truth(rig, plan, seed, effects, storage, bags, nuisances)
    (out_dir / 'truth.json').write_text(json.dumps(truth, indent=2))
    return paths


def _run_truth(stroke: Stroke, origin: float, theta: float, rig: RigConfig) -> dict:
    result = stroke.as_dict(origin)
    result['eq22_amplitude'] = float(thread_contact_amplitude(stroke.speed, stroke.load, theta, rig))
    return result


def simulate_endurance(path: str | Path, duration: float, *, plan: ExperimentPlan | None = None,
                       rig: RigConfig | None = None, seed: int = 0, effects: Effects | None = None,
                       storage: str = 'mcap', theta_oil: float = 1.0, truth_path: str | Path | None = None,
                       progress: ProgressCallback | None = None, compression: str | None = None) -> Path:
    """One long bag at ``path``: the plan's conditions cycled (with rewinds) for ``duration`` s.

    For benchmarks and long-term effects; lubricated once at the start with
    ``theta_oil``.  Writes the truth to ``truth_path`` if given; ``compression='zstd'``
    compresses the mcap chunks.  Returns ``path``.
    """
    rig, plan, effects = rig or RigConfig(), plan or ExperimentPlan(), effects or Effects()
    check_storage(storage)
    duration = as_number('duration', duration)
    require(duration > 0, f'duration must be > 0 s, got {duration}')
    path = Path(path)
    rig_seed, latency_rng, _, _ = _streams(seed)
    program = DriveProgram()
    strokes, now = [], 0.0
    while now < duration:
        more, now = schedule_session(program, now, plan.conditions, plan, rig)
        now -= plan.standstill  # sessions join with a single standstill
        strokes += more
    stop_block = _blocks(duration, rig)
    stream = RigStream(rig, program, seed=rig_seed, effects=effects)
    total = stop_block * rig.vibration_block
    done = 0

    def advance(blocks: int) -> None:
        nonlocal done
        done += blocks
        if progress is not None:
            progress(done * rig.vibration_block, total)

    _record(path, storage, stream, 0, stop_block, theta_oil, latency_rng, advance, compression)
    if truth_path is not None:
        origin = _origin_seconds(stream)
        kept = [stroke for stroke in strokes if stroke.start < total]
        bag = {'name': path.stem, 'path': path.name, 'theta_oil': theta_oil, 'start': origin,
               'end': origin + total, 'runs': [_run_truth(s, origin, theta_oil, rig) for s in kept]}
        Path(truth_path).write_text(json.dumps(_truth(rig, plan, seed, effects, storage, [bag]), indent=2))
    return path
