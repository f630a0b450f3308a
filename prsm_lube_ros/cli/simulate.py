# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube simulate``: contract recordings of the paper's experiment from the rig simulator."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import argparse

    from ..simulation.rig_config import ExperimentPlan, RigConfig


__all__ = ['add_command', 'run']


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``simulate`` to the ``prsm-lube`` subcommands."""
    from ..physics.effects import effect_ids
    parser = subparsers.add_parser(
        'simulate', help='write recordings of the paper\'s experiment with the rig simulator',
        description='Write contract recordings (rosbag2) of the paper\'s experiment: the default actuator on a '
        '180 mm rig, 3 speeds x 2 loads after each lubrication stage, 4 kHz acceleration, joint states, load '
        'and temperature; one bag per stage and a truth.json beside them. Seeded and reproducible.')
    parser.add_argument('out', metavar='OUT_DIR', help='folder for the bags and truth.json')
    parser.add_argument('--seed', type=int, default=0, help='random seed (default 0)')
    parser.add_argument('--stages', type=float, nargs='+', metavar='THETA',
                        help='true theta_oil per lubrication stage (default 0.72 0.83 1.0)')
    parser.add_argument('--storage', choices=('mcap', 'sqlite3', 'mcap-file'), default='mcap',
                        help='rosbag2 folder with mcap (default) or sqlite3 storage, or a bare .mcap file')
    parser.add_argument('--compression', choices=('zstd',), default=None,
                        help='compress mcap chunks (default: none, as rosbag2 records by default)')
    parser.add_argument('--run-order', choices=('fixed', 'random'), default=None,
                        help='order of the six conditions in each stage (default: the plan\'s, fixed)')
    parser.add_argument('--effect', action='append', default=[], metavar='EFFECT', choices=effect_ids(),
                        help='add a physical effect the paper\'s model leaves out, strength drawn from the seed '
                        f'({", ".join(effect_ids())}); repeatable; nothing in the bags names it')
    parser.add_argument('--endurance', type=float, default=0.0, metavar='SECONDS',
                        help='instead of the experiment, one bag cycling the six conditions for this long')
    parser.add_argument('--config', default=None, metavar='YAML',
                        help='rig simulator configuration (default config/rig_simulator.yaml values)')
    parser.add_argument('--fleet', type=int, default=0, metavar='K',
                        help='instead of the experiment, K actuators in service (one short recording a day each, '
                        'oil depleting with use, relubrications at known times) with truth.json and a reference '
                        'recording at theta_oil 1 for the calibration')
    parser.add_argument('--days', type=int, default=10, metavar='D', help='days of service with --fleet (default 10)')
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Write contract recordings of the paper's experiment (or one long endurance recording)."""
    from ..recording.writer import bag_path
    from ..simulation.recordings import draw_effects, simulate_endurance, simulate_experiment
    from ..simulation.rig_config import load_experiment_plan, load_rig_config
    from .common import progress_bar
    rig = load_rig_config(args.config)
    plan = load_experiment_plan(args.config)
    effects = draw_effects(args.effect, seed=args.seed, rig=rig, plan=plan) if args.effect else None
    if args.fleet:
        return _simulate_fleet(args, rig, plan)
    bar = progress_bar(100, 'simulating')
    done = [0]

    def progress(done_s: float, total_s: float) -> None:
        step = int(100 * done_s / total_s) if total_s > 0 else 100
        if step > done[0]:
            bar.update(step - done[0])
            done[0] = step

    try:
        if args.endurance:
            paths = [simulate_endurance(bag_path(args.out, 'endurance', args.storage), args.endurance, plan=plan,
                                        rig=rig, seed=args.seed, effects=effects, storage=args.storage,
                                        theta_oil=args.stages[0] if args.stages else 1.0, progress=progress,
                                        compression=args.compression)]
        else:
            paths = simulate_experiment(args.out, plan=plan, rig=rig, seed=args.seed, effects=effects,
                                        storage=args.storage, run_order=args.run_order,
                                        stage_thetas=args.stages, progress=progress,
                                        compression=args.compression)
    finally:
        bar.close()
    for path in paths:
        print(path)
    return 0


def _simulate_fleet(args: argparse.Namespace, rig: RigConfig, plan: ExperimentPlan) -> int:
    """``--fleet K --days D``: the fleet's recordings, truth.json and the reference recording."""
    from ..simulation.fleet import FleetPlan, simulate_fleet
    from ..validation import require
    from .common import progress_bar
    require(not args.effect and not args.endurance and args.stages is None,
            '--fleet cannot be combined with --effect, --endurance or --stages')
    fleet = FleetPlan(actuators=args.fleet, days=args.days)
    bar = progress_bar(fleet.actuators * fleet.days, 'simulating the fleet', unit='recording')
    try:
        paths = simulate_fleet(args.out, fleet=fleet, rig=rig, plan=plan, seed=args.seed, storage=args.storage,
                               progress=lambda done, total: bar.update(done - bar.n))
    finally:
        bar.close()
    print(f'wrote {len(paths)} recordings of {fleet.actuators} actuators over {fleet.days} days to {args.out} '
          '(one folder per actuator), truth.json and the reference recording "reference"')
    return 0
