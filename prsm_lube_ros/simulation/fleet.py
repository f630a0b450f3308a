# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A simulated fleet in service: K actuators over D days, oil depleting with use, relubrications at known times.

Each actuator turns its screw ``u_d`` revolutions on day ``d`` (its own mean
rate times a log-normal day-to-day factor, spread evenly over the day), so the
revolutions since its last lubrication ``N(t)`` grow piecewise linearly.  The
oil is flung out as the screw turns (``physics.effects.lubricant_depletion``):

    theta_Oil(t) = theta_r exp(-N(t) / N_d)

with theta_r the supply factor just after the relubrication and N_d the
actuator's depletion revolutions.  Once a day, at a random hour of the working
day, a short contract recording is made (one forward run at the fleet's test
condition and its rewind) at the theta_Oil of that moment.  The operator
relubricates an actuator shortly after a recording whose true theta_Oil is
below ``relubricate_below`` (never after the last recording).  Habits vary
when the plan says so: each operator's own ``relubricate_below`` drawn from
``relubricate_below_range`` (down past the error level), due relubrications
put off (``relubrication_put_off``) and days without a recording
(``recording_missed``).

``odometer.csv`` lists each actuator's cumulative screw revolutions at each
recording (``actuator,time,revolutions``), as a drive's revolution counter or a
maintenance log would; ``truth.json`` beside the recordings gives, per actuator, the law's
parameters, every relubrication, every recording's true theta_Oil and the
times (and odometer readings) the last lubrication cycle crosses given thresholds (the usage process
continued past the last day without further relubrication), so a forecast made
from the recordings can be checked.  A reference recording of the whole
experiment plan at theta_Oil = 1 (``reference``) calibrates the fleet (all
actuators are of the rig's type).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
import datetime
import json
import math
from pathlib import Path
from typing import Any
from collections.abc import Callable, Sequence

import numpy as np

from ..physics.effects.lubricant_depletion import theta_factor
from ..recording.writer import bag_path, check_storage
from ..validation import require
from .drive import DriveProgram, schedule_session
from .recordings import _blocks, _record, _streams, simulate_experiment
from .rig_config import ExperimentPlan, RigConfig
from .rig_acceleration import RigStream

__all__ = ['ActuatorService', 'DAY', 'FleetPlan', 'ODOMETER_DAYS', 'simulate_fleet']

DAY = 86400.0   # s
#: each actuator's odometer reads this many days of its mean usage at the fleet's epoch
ODOMETER_DAYS = 365


@dataclass(frozen=True)
class FleetPlan:
    """How the simulated fleet is used and recorded (SI units; days where the name says so)."""

    actuators: int = 20
    days: int = 10
    #: each actuator's mean screw revolutions per day, drawn uniformly in this range
    revolutions_per_day: tuple[float, float] = (2000.0, 6000.0)
    #: sigma of the log-normal day-to-day factor of the revolutions
    usage_scatter: float = 0.15
    #: days a full lubrication (theta_r = 1) lasts until theta_Oil falls to ``depletion_reference``, drawn
    #: uniformly in this range times ``days``; sets N_d
    days_to_reference: tuple[float, float] = (0.5, 1.5)
    depletion_reference: float = 0.85
    #: theta_Oil just after a relubrication, drawn uniformly
    relubricated_theta: tuple[float, float] = (0.95, 1.0)
    #: true theta_Oil at the first day, drawn uniformly (the revolutions since the last lubrication follow)
    initial_theta: tuple[float, float] = (0.82, 1.0)
    #: the operator relubricates after a recording whose true theta_Oil is below this
    relubricate_below: float = 0.78
    #: relubrication habits: when given, each actuator's operator has its own ``relubricate_below`` drawn
    #: uniformly in this range (below the error level 0.70 lets the error level be reached and recorded)
    relubricate_below_range: tuple[float, float] | None = None
    #: probability that a due relubrication is put off at a recording (the oil keeps depleting until a later one)
    relubrication_put_off: float = 0.0
    #: probability that a day's recording is not made (gaps in the recording; the operator only acts on recordings)
    recording_missed: float = 0.0
    #: s after that recording when the oil is injected
    relubrication_delay: float = 3600.0
    #: recordings are made between these hours of the day (UTC)
    recording_hours: tuple[float, float] = (8.0, 16.0)
    #: the test condition of every recording: screw speed rad/s, axial load N
    condition: tuple[float, float] = (200 * 2 * math.pi / 60, 200.0)
    #: days the usage is continued past the last recording to find the true threshold crossings
    horizon_days: int = 200

    def __post_init__(self) -> None:
        """Reject plans that cannot be simulated."""
        require(int(self.actuators) >= 1, f'fleet actuators must be >= 1, got {self.actuators!r}')
        require(int(self.days) >= 1, f'fleet days must be >= 1, got {self.days!r}')
        object.__setattr__(self, 'actuators', int(self.actuators))
        object.__setattr__(self, 'days', int(self.days))
        require(0 < self.revolutions_per_day[0] <= self.revolutions_per_day[1],
                f'fleet revolutions_per_day must be an increasing positive range, got {self.revolutions_per_day}')
        require(0 < self.depletion_reference < min(self.relubricated_theta),
                'fleet depletion_reference must lie below the relubricated theta')
        require(self.relubricate_below_range is None
                or 0 < self.relubricate_below_range[0] <= self.relubricate_below_range[1] < 1,
                f'fleet relubricate_below_range must be an increasing range in (0, 1), got '
                f'{self.relubricate_below_range}')
        require(0 <= self.relubrication_put_off < 1 and 0 <= self.recording_missed < 1,
                'fleet relubrication_put_off and recording_missed must be probabilities below 1')


@dataclass
class ActuatorService:
    """One actuator's drawn law and usage: cumulative revolutions piecewise linear over whole days."""

    actuator_id: str
    revolutions_per_day: float       # mean, rev/day
    depletion_revolutions: float     # N_d, rev
    daily_revolutions: np.ndarray    # rev on each day from day 0 to the horizon
    start_revolutions: float         # rev since the last lubrication at t = 0

    def revolutions(self, t: float) -> float:
        """Cumulative revolutions since t = 0 at ``t`` s after the fleet epoch."""
        edges = np.concatenate(([0.0], np.cumsum(self.daily_revolutions)))
        days = np.arange(edges.size) * DAY
        return np.interp(t, days, edges)

    def time_at(self, revolutions: float) -> float:
        """Inverse of :meth:`revolutions` (s), inf past the horizon."""
        edges = np.concatenate(([0.0], np.cumsum(self.daily_revolutions)))
        if revolutions > edges[-1]:
            return math.inf
        return float(np.interp(revolutions, edges, np.arange(edges.size) * DAY))


def _iso(seconds: float) -> str:
    return datetime.datetime.fromtimestamp(seconds, datetime.UTC).isoformat(timespec='seconds')


def _reference(out_dir: Path, rig: RigConfig, plan: ExperimentPlan, seed: int, storage: str) -> None:
    """The plan's six conditions at theta_Oil = 1 as ``out_dir/reference`` (truth in reference_truth.json)."""
    simulate_experiment(out_dir / 'reference_session', plan=replace(plan, stage_thetas=(1.0,)), rig=rig,
                        seed=seed, storage=storage)
    bag_path(out_dir / 'reference_session', 'stage_1', storage).rename(bag_path(out_dir, 'reference', storage))
    (out_dir / 'reference_session' / 'truth.json').rename(out_dir / 'reference_truth.json')
    (out_dir / 'reference_session').rmdir()


def _short_recording(path: Path, *, rig: RigConfig, plan: ExperimentPlan, condition: tuple[float, float],
                     theta: float, start_seconds: float, seed: int, storage: str) -> None:
    """One forward run at ``condition`` and its rewind, recorded from ``start_seconds`` (epoch s)."""
    rig_seed, latency_rng, *_ = _streams(seed)
    program = DriveProgram()
    _, end = schedule_session(program, 0.0, [condition], plan, rig)
    stream = RigStream(rig, program, seed=rig_seed, origin_ns=int(round(start_seconds * 1e9)))
    _record(path, storage, stream, 0, _blocks(end, rig), theta, latency_rng, None)


def _draw_service(actuator_id: str, fleet: FleetPlan, usage_rng: np.random.Generator) -> tuple[ActuatorService, float]:
    """An actuator's usage (revolutions a day and their daily scatter) and oil life, and its initial theta_Oil."""
    rate = usage_rng.uniform(*fleet.revolutions_per_day)
    days_to_reference = usage_rng.uniform(*fleet.days_to_reference) * fleet.days
    depletion = rate * days_to_reference / math.log(1.0 / fleet.depletion_reference)
    daily = rate * usage_rng.lognormal(-0.5 * fleet.usage_scatter ** 2, fleet.usage_scatter,
                                       fleet.days + fleet.horizon_days)
    initial_theta = usage_rng.uniform(*fleet.initial_theta)
    service = ActuatorService(actuator_id, rate, depletion, daily,
                              start_revolutions=depletion * math.log(1.0 / initial_theta))
    return service, initial_theta


def _true_crossings(service: ActuatorService, thresholds: Sequence[float], theta_r: float, cycle_start_revs: float,
                    epoch: float, odometer_start: float) -> dict[str, dict[str, Any]]:
    """When theta_Oil truly crosses each level after the last relubrication (to theta ``theta_r``), by level."""
    crossings = {}
    for level in thresholds:
        revs = (cycle_start_revs + service.depletion_revolutions * math.log(theta_r / level) if level < theta_r
                else -math.inf)
        crossing = service.time_at(max(revs, 0.0)) if revs > 0 else 0.0
        known = math.isfinite(crossing)
        crossings[f'{level:g}'] = {'time': epoch + crossing if known else None,
                                   'time_utc': _iso(epoch + crossing) if known else None,
                                   'odometer': odometer_start + float(service.revolutions(crossing)) if known
                                   else None}
    return crossings


@dataclass
class _FleetRecorder:
    """Names (and with ``write`` writes) the fleet's daily recordings, in order; counts them for ``progress``."""

    out_dir: Path
    fleet: FleetPlan
    rig: RigConfig
    plan: ExperimentPlan
    storage: str
    epoch: float                 # s since the Unix epoch of the fleet's t = 0
    write: bool
    progress: Callable[[int, int], None] | None
    paths: list[Path] = field(default_factory=list)

    def record(self, actuator_id: str, t: float, theta: float, seed: int) -> Path:
        """The recording of ``actuator_id`` at ``t`` s after the epoch, true theta_Oil ``theta``: its path."""
        path = bag_path(self.out_dir / actuator_id, datetime.datetime.fromtimestamp(
            self.epoch + t, datetime.UTC).strftime('%Y%m%dT%H%M%S'), self.storage)
        if self.write:
            require(not path.exists(), f'{path}: exists already, not overwriting')
            path.parent.mkdir(parents=True, exist_ok=True)
            _short_recording(path, rig=self.rig, plan=self.plan, condition=self.fleet.condition, theta=theta,
                             start_seconds=self.epoch + t, seed=seed, storage=self.storage)
        self.paths.append(path)
        return path

    def count(self) -> None:
        """Report the recordings made so far to ``progress``."""
        if self.progress is not None:
            self.progress(len(self.paths), self.fleet.actuators * self.fleet.days)


def _simulate_actuator(recorder: _FleetRecorder, actuator_id: str, sequence: np.random.SeedSequence,
                       thresholds: Sequence[float]) -> tuple[dict[str, Any], list[tuple[str, str, float]]]:
    """One actuator in service: its law, daily recordings and relubrications; its truth and odometer rows."""
    fleet, epoch, out_dir = recorder.fleet, recorder.epoch, recorder.out_dir
    # the third stream (habits) is spawned after the first two: those two draw what they always drew
    usage_sequence, recording_sequence, habit_sequence = sequence.spawn(3)
    usage_rng, habit_rng = np.random.default_rng(usage_sequence), np.random.default_rng(habit_sequence)
    service, initial_theta = _draw_service(actuator_id, fleet, usage_rng)
    rate, depletion, daily = service.revolutions_per_day, service.depletion_revolutions, service.daily_revolutions
    relubricate_below = (fleet.relubricate_below if fleet.relubricate_below_range is None
                         else float(habit_rng.uniform(*fleet.relubricate_below_range)))
    theta_r, cycle_start_revs, cycle_start_time = 1.0, -service.start_revolutions, None
    recordings: list[dict[str, Any]]
    relubrications: list[dict[str, Any]]
    relubrications, recordings = [], []
    seeds = recording_sequence.generate_state(fleet.days)
    for day in range(fleet.days):
        hour = usage_rng.uniform(*fleet.recording_hours)
        t = day * DAY + hour * 3600.0
        missed = fleet.recording_missed > 0 and habit_rng.random() < fleet.recording_missed
        if missed and 0 < day < fleet.days - 1:       # the first and last day are always recorded
            continue
        theta = theta_r * float(theta_factor(service.revolutions(t) - cycle_start_revs, 1.0 / depletion))
        path = recorder.record(actuator_id, t, theta, int(seeds[day]))
        recordings.append({'path': str(path.relative_to(out_dir)), 'start': epoch + t,
                           'start_utc': _iso(epoch + t), 'theta_oil': theta,
                           'revolutions_since_lubrication': float(service.revolutions(t) - cycle_start_revs)})
        recorder.count()
        put_off = fleet.relubrication_put_off > 0 and habit_rng.random() < fleet.relubrication_put_off
        if theta < relubricate_below and day < fleet.days - 1 and not put_off:
            cycle_start_time = t + fleet.relubrication_delay
            cycle_start_revs = float(service.revolutions(cycle_start_time))
            theta_r = usage_rng.uniform(*fleet.relubricated_theta)
            relubrications.append({'time': epoch + cycle_start_time, 'time_utc': _iso(epoch + cycle_start_time),
                                   'theta_oil_after': theta_r})
    odometer_start = round(rate * ODOMETER_DAYS)
    crossings = _true_crossings(service, thresholds, theta_r, cycle_start_revs, epoch, odometer_start)
    odometer_rows = [(actuator_id, r['start_utc'], odometer_start + float(service.revolutions(r['start'] - epoch)))
                     for r in recordings]
    truth = {
        'actuator_id': actuator_id, 'revolutions_per_day': rate, 'depletion_revolutions': depletion,
        'initial_theta': initial_theta, 'last_relubrication_theta': theta_r, 'relubricate_below': relubricate_below,
        'last_relubrication': None if cycle_start_time is None else epoch + cycle_start_time,
        'relubrications': relubrications, 'recordings': recordings, 'crossings': crossings,
        'daily_revolutions': [float(v) for v in daily[:fleet.days]]}
    return truth, odometer_rows


def simulate_fleet(out_dir: str | Path, *, fleet: FleetPlan | None = None, rig: RigConfig | None = None,
                   plan: ExperimentPlan | None = None, seed: int = 0, storage: str = 'mcap',
                   thresholds: Sequence[float] = (0.85, 0.70),
                   progress: Callable[[int, int], None] | None = None, write_recordings: bool = True) -> list[Path]:
    """Write the fleet's recordings to ``out_dir/<actuator>/<UTC time>`` and ``out_dir/truth.json``.

    Also ``out_dir/reference``: the plan's six conditions at theta_Oil = 1 for
    the calibration.  ``thresholds`` are the theta_Oil levels whose crossing
    times the truth lists (default: the estimator's warn and error levels).
    ``progress(done, total)`` counts recordings.  Returns the fleet's recording
    paths (not the reference), in time order per actuator.  With
    ``write_recordings=False`` only ``truth.json`` is written (the same truth:
    the random streams do not depend on it), for checks of the forecast alone.
    """
    fleet, rig, plan = fleet or FleetPlan(), rig or RigConfig(), plan or ExperimentPlan()
    check_storage(storage)
    out_dir = Path(out_dir)
    require(not (out_dir / 'truth.json').exists(), f'{out_dir / "truth.json"}: exists already, not overwriting')
    epoch = rig.epoch_ns * 1e-9
    sequences = np.random.SeedSequence(seed).spawn(fleet.actuators + 1)
    recorder = _FleetRecorder(out_dir, fleet, rig, plan, storage, epoch, write_recordings, progress)
    truth_actuators: list[dict[str, Any]] = []
    odometer_rows: list[tuple[str, str, float]] = []
    if write_recordings:
        _reference(out_dir, rig, plan, int(sequences[-1].generate_state(1)[0]), storage)
    for number, sequence in enumerate(sequences[:-1], start=1):
        truth, rows = _simulate_actuator(recorder, f'A{number:02d}', sequence, thresholds)
        odometer_rows += rows
        truth_actuators.append(truth)
    document = {'generator': 'prsm_lube_ros.simulation.fleet', 'seed': seed, 'storage': storage,
                'epoch': epoch, 'law': 'theta_oil = theta_r exp(-N_rev / N_d), N_rev since the last lubrication',
                'fleet': {**asdict(fleet)},
                'thresholds': [float(v) for v in thresholds], 'reference': bag_path(Path('.'), 'reference',
                                                                                    storage).name,
                'actuators': truth_actuators}
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / 'truth.json').write_text(json.dumps(document, indent=1))
    (out_dir / 'odometer.csv').write_text('actuator,time,revolutions\n' + ''.join(
        f'{name},{time},{revolutions:.1f}\n' for name, time, revolutions in odometer_rows))
    return recorder.paths
