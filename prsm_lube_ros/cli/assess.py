# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube assess``: theta_Oil for every steady window and run of recordings."""
from __future__ import annotations

from .common import add_recording_options


def add_command(subparsers) -> None:
    """Add ``assess`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'assess', help='theta_oil for every steady window and run',
        description='Assess theta_oil for every steady window and every run of the recordings.')
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    parser.add_argument('--calibration', required=True, metavar='CALIB.yaml')
    parser.add_argument('--json', metavar='OUT.json', help='write runs and windows as JSON')
    add_recording_options(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    """theta_Oil for every steady window and run; table on stdout, JSON if asked."""
    import math
    from pathlib import Path
    from ..estimation.calibration_file import load_calibration
    from ..estimation.pipeline import assess_recording, assessment_json
    from .common import read_recordings, write_json
    calibration = load_calibration(args.calibration)
    recordings, _ = read_recordings(args.bags, args)
    results = [assess_recording(rec, calibration) for rec in recordings]
    flagged = []
    for flag in calibration.flags:
        print(f'warning: calibration {args.calibration}: {flag}')
    print(f'{"recording":<28} {"run":>4} {"speed r/min":>11} {"load N":>8} {"RMS m/s^2":>10} '
          f'{"theta_oil":>9} {"+/-":>6}')
    for rec in results:
        for run_result in rec.runs:
            theta = (f'{run_result.theta_oil:9.3f} {run_result.theta_oil_std:6.3f}' if not run_result.reason
                     else f'{"NaN":>9}  {run_result.reason}')
            if run_result.flag:
                flagged.append((Path(rec.path).name, run_result.run_index, run_result.flag))
                theta += ' !'
            print(f'{Path(rec.path).name[:28]:<28} {run_result.run_index:>4} '
                  f'{run_result.screw_speed * 60 / (2 * math.pi):>11.1f} '
                  f'{run_result.axial_load:>8.1f} {run_result.vibration_rms:>10.4f} {theta}')
    for name, run_index, flag in flagged:
        print(f'! {name} run {run_index}: {flag}')
    if args.json:
        document = assessment_json(results, calibration)
        write_json(args.json, document)
        print(f'wrote {args.json}: {len(document["runs"])} runs, {len(document["windows"])} windows')
    return 0
