# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube``: simulate, calibrate, assess and diagnose recordings from the command line.

User errors (a missing or broken recording, data that cannot calibrate, a bad
option) end with one line on stderr naming the input and a non-zero status;
there is no traceback for them.
"""
from __future__ import annotations

import argparse
import importlib
import json
import math
from pathlib import Path
import sys

from .errors import InputError

EXIT_USER_ERROR = 2

#: Modules that add a subcommand: each has ``add_command(subparsers)`` which adds
#: its parser with ``set_defaults(func=handler)``; handlers return the exit status.
#: They must import nothing heavy (rclpy, scipy) at module level.
PLUGIN_COMMANDS = (
    'prsm_lube_ros.diagnosis.cli',
    'prsm_lube_ros.nodes.run_cli',
)


def _progress_bar(total: int, description: str):
    """A tqdm bar on stderr that hides itself when stderr is not a terminal."""
    from tqdm import tqdm
    return tqdm(total=total, desc=description, unit='%', disable=None, leave=False,
                bar_format='{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}')


def _read_recordings(paths, args, *, spectra: bool = False):
    """Windows of each recording, with a progress bar and problems on stderr."""
    from .actuator import load_actuator
    from .analysis import recording_windows
    from .windowing import WindowSettings
    actuator = load_actuator(args.actuator)
    settings = WindowSettings(window_length=args.window, spectrum_segment=256 if spectra else 0)
    recordings = []
    for path in paths:
        bar = _progress_bar(100, Path(path).name)
        last = [0]

        def progress(fraction, bar=bar, last=last):
            step = int(100 * fraction)
            if step > last[0]:
                bar.update(step - last[0])
                last[0] = step

        try:
            recordings.append(recording_windows(
                path, lead=actuator.lead, settings=settings, namespace=args.namespace,
                on_problem=lambda line: print(f'warning: {line}', file=sys.stderr), progress=progress))
        finally:
            bar.close()
    return recordings, actuator


def _add_common(parser):
    parser.add_argument('--namespace', default='/prsm', help='topic namespace of the actuator (default /prsm)')
    parser.add_argument('--window', type=float, default=1.0, metavar='S',
                        help='window length in s for the RMS (default 1.0)')
    parser.add_argument('--actuator', default=None, metavar='YAML',
                        help='actuator geometry (default: the contract\'s default actuator)')


def cmd_calibrate(args) -> int:
    """Fit the constants on reference recordings and write the calibration file."""
    from .analysis import calibrate_recordings
    from .calibration_file import save_calibration
    theta = args.theta if args.theta > 0 else 1.0
    recordings, _ = _read_recordings(args.bags, args)
    calibration = calibrate_recordings(recordings, theta)
    save_calibration(calibration, args.out)
    c = calibration.constants
    print(f'C_sys    = {c.c_sys:.6g} +/- {calibration.c_sys_std:.2g} m N^(1/3)')
    print(f'C_F      = {c.c_f:.6g} +/- {calibration.c_f_std:.2g} 1/N')
    print(f'C_lambda = {c.c_lambda:.6g} +/- {calibration.c_lambda_std:.2g} (rad/s)^-0.68 N^0.073')
    print(f'fit: relative RMS error {100 * calibration.fit_rmse:.2f} % on {calibration.windows_used} windows '
          f'({len(calibration.speed_levels)} speeds x {len(calibration.load_levels)} loads); wrote {args.out}')
    return 0


def cmd_assess(args) -> int:
    """theta_Oil for every steady window and run; table on stdout, JSON if asked."""
    from .analysis import assess_recording, assessment_json
    from .calibration_file import load_calibration
    calibration = load_calibration(args.calibration)
    recordings, _ = _read_recordings(args.bags, args)
    results = [assess_recording(rec, calibration) for rec in recordings]
    print(f'{"recording":<28} {"run":>4} {"speed r/min":>11} {"load N":>8} {"RMS m/s^2":>10} '
          f'{"theta_oil":>9} {"+/-":>6}')
    for rec in results:
        for run in rec.runs:
            theta = f'{run.theta_oil:9.3f} {run.theta_oil_std:6.3f}' if not run.reason else f'{"NaN":>9}  {run.reason}'
            print(f'{Path(rec.path).name[:28]:<28} {run.run_index:>4} {run.screw_speed * 60 / (2 * math.pi):>11.1f} '
                  f'{run.axial_load:>8.1f} {run.vibration_rms:>10.4f} {theta}')
    if args.json:
        document = assessment_json(results, calibration)
        _write_json(args.json, document)
        print(f'wrote {args.json}: {len(document["runs"])} runs, {len(document["windows"])} windows')
    return 0


def _write_json(path, document):
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(json.dumps(document, indent=1, allow_nan=False))
    except OSError as exc:
        raise InputError(f'{path}: cannot write ({exc.strerror or exc})') from None


def cmd_simulate(args) -> int:
    """Write contract recordings of the paper's experiment (or one long endurance recording)."""
    from .rig_simulator import (draw_effects, load_experiment_plan, load_rig_config, simulate_endurance,
                                simulate_experiment)
    rig = load_rig_config(args.config)
    plan = load_experiment_plan(args.config)
    effects = draw_effects(args.effect, seed=args.seed, rig=rig, plan=plan) if args.effect else None
    bar = _progress_bar(100, 'simulating')
    done = [0]

    def progress(done_s, total_s):
        step = int(100 * done_s / total_s) if total_s > 0 else 100
        if step > done[0]:
            bar.update(step - done[0])
            done[0] = step

    try:
        if args.endurance:
            paths = [simulate_endurance(Path(args.out) / 'endurance', args.endurance, plan=plan, rig=rig,
                                        seed=args.seed, effects=effects, storage=args.storage,
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


def cmd_demo(args) -> int:
    """Simulate, calibrate on stage 3, assess stages 1 and 2, print the table, write figures."""
    from .demo import run_demo
    return run_demo(Path(args.out), seed=args.seed, stages=args.stages, window=args.window,
                    storage=args.storage)


def build_parser() -> argparse.ArgumentParser:
    """The ``prsm-lube`` argument parser."""
    parser = argparse.ArgumentParser(prog='prsm-lube', description=(
        'Lubrication assessment of planetary roller screws (theta_Oil) from nut vibration, '
        'screw speed and axial load.'))
    sub = parser.add_subparsers(dest='command', required=True, metavar='COMMAND')

    cal = sub.add_parser('calibrate', help='fit C_sys, C_F, C_lambda from reference recordings',
                         description='Fit C_sys, C_F and C_lambda by least squares on recordings at a known '
                         'lubrication state (theta_oil) and write them with their uncertainties.')
    cal.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    cal.add_argument('--theta', type=float, default=1.0, help='theta_oil of the recordings (default 1.0)')
    cal.add_argument('--out', required=True, metavar='CALIB.yaml', help='calibration file to write')
    _add_common(cal)
    cal.set_defaults(func=cmd_calibrate)

    ass = sub.add_parser('assess', help='theta_oil for every steady window and run',
                         description='Assess theta_oil for every steady window and every run of the recordings.')
    ass.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    ass.add_argument('--calibration', required=True, metavar='CALIB.yaml')
    ass.add_argument('--json', metavar='OUT.json', help='write runs and windows as JSON')
    _add_common(ass)
    ass.set_defaults(func=cmd_assess)

    sim = sub.add_parser('simulate', help='write recordings of the paper\'s experiment with the rig simulator',
                         description='Write contract recordings (rosbag2) of the paper\'s experiment: the default '
                         'actuator on a 180 mm rig, 3 speeds x 2 loads after each lubrication stage, 4 kHz '
                         'acceleration, joint states, load and temperature; one bag per stage and a truth.json '
                         'beside them. Seeded and reproducible.')
    sim.add_argument('out', metavar='OUT_DIR', help='folder for the bags and truth.json')
    sim.add_argument('--seed', type=int, default=0, help='random seed (default 0)')
    sim.add_argument('--stages', type=float, nargs='+', metavar='THETA',
                     help='true theta_oil per lubrication stage (default 0.72 0.83 1.0)')
    sim.add_argument('--storage', choices=('mcap', 'sqlite3', 'mcap-file'), default='mcap',
                     help='rosbag2 folder with mcap (default) or sqlite3 storage, or a bare .mcap file')
    sim.add_argument('--compression', choices=('zstd',), default=None,
                     help='compress mcap chunks (default: none, as rosbag2 records by default)')
    sim.add_argument('--run-order', choices=('fixed', 'random'), default=None,
                     help='order of the six conditions in each stage (default: the plan\'s, fixed)')
    sim.add_argument('--effect', action='append', default=[], metavar='EFFECT',
                     help='add a physical effect the paper\'s model leaves out, strength drawn from the seed '
                     '(position_dependent_stiffness, resonance, thermal_viscosity, lubricant_depletion, '
                     'background_vibration); repeatable; nothing in the bags names it')
    sim.add_argument('--endurance', type=float, default=0.0, metavar='SECONDS',
                     help='instead of the experiment, one bag cycling the six conditions for this long')
    sim.add_argument('--config', default=None, metavar='YAML',
                     help='rig simulator configuration (default config/rig_simulator.yaml values)')
    sim.set_defaults(func=cmd_simulate)

    demo = sub.add_parser('demo', help='the paper\'s experiment end to end, with table and figures',
                          description='Simulate the paper\'s experiment, calibrate on the third lubrication '
                          'stage, assess the first two, print a table per condition and stage and write '
                          'figures like the paper\'s Fig. 5.')
    demo.add_argument('--out', default='out/demo', help='output folder (default out/demo)')
    demo.add_argument('--seed', type=int, default=7)
    demo.add_argument('--stages', type=float, nargs=3, default=(0.72, 0.83, 1.0), metavar='THETA',
                      help='true theta_oil of the three lubrication stages (default 0.72 0.83 1.0)')
    demo.add_argument('--window', type=float, default=1.0, metavar='S', help='window length in s')
    demo.add_argument('--storage', choices=('mcap', 'sqlite3', 'mcap-file'), default='mcap')
    demo.set_defaults(func=cmd_demo)

    for module_name in PLUGIN_COMMANDS:
        module = importlib.import_module(module_name)
        module.add_command(sub)
    return parser


def main(argv=None) -> int:
    """Entry point; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except InputError as exc:
        print(f'prsm-lube {args.command}: error: {exc}', file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print(f'prsm-lube {args.command}: interrupted', file=sys.stderr)
        return 130


if __name__ == '__main__':
    sys.exit(main())
