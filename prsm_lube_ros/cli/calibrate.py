# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube calibrate``: fit C_sys, C_F and C_lambda on reference recordings and write them."""
from __future__ import annotations

from typing import TYPE_CHECKING

from .common import add_band_option, add_recording_options

if TYPE_CHECKING:
    import argparse


__all__ = ['add_command', 'run']


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``calibrate`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'calibrate', help='fit C_sys, C_F, C_lambda from reference recordings',
        description='Fit C_sys, C_F and C_lambda by least squares on recordings at a known lubrication state '
        '(theta_oil) and write them with their uncertainties.')
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    parser.add_argument('--theta', type=float, default=1.0,
                        help='theta_oil of the recordings (default 1.0; 0 means 1.0)')
    parser.add_argument('--out', required=True, metavar='CALIB.yaml', help='calibration file to write')
    add_recording_options(parser)
    add_band_option(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Fit the constants on reference recordings and write the calibration file."""
    from ..estimation.calibration_file import save_calibration
    from ..estimation.pipeline import calibrate_recordings
    from ..validation import reference_theta
    from .common import read_recordings
    theta = reference_theta(args.theta, '--theta')
    recordings, _ = read_recordings(args.bags, args)
    calibration = calibrate_recordings(recordings, theta)
    save_calibration(calibration, args.out)
    c = calibration.constants
    print(f'C_sys    = {calibration.c_sys_text} m N^(1/3)')
    print(f'C_F      = {c.c_f:.6g} +/- {calibration.c_f_std:.2g} 1/N')
    print(f'C_lambda = {c.c_lambda:.6g} +/- {calibration.c_lambda_std:.2g} (rad/s)^-0.68 N^0.073')
    print(f'fit: relative RMS error {100 * calibration.fit_rmse:.2f} % on {calibration.windows_used} windows '
          f'({calibration.plan_summary}, {calibration.runs} runs); wrote {args.out}')
    print(f'standard errors: {calibration.standard_errors}')
    assert calibration.band is not None and calibration.domain is not None  # the CLI always analyses in a band
    print(f'band: {calibration.band.text}; domain: {calibration.domain.text}')
    for flag in calibration.flags:
        print(f'warning: {flag}')
    return 0
