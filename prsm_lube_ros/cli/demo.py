# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube demo``: the paper's experiment end to end (see :mod:`prsm_lube_ros.experiments.paper_demo`)."""
from __future__ import annotations


def add_command(subparsers) -> None:
    """Add ``demo`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'demo', help='the paper\'s experiment end to end, with table and figures',
        description='Simulate the paper\'s experiment, calibrate on the third lubrication stage, assess the '
        'first two, print a table per condition and stage and write figures like the paper\'s Fig. 5.')
    parser.add_argument('--out', default='out/demo', help='output folder (default out/demo)')
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--stages', type=float, nargs=3, default=(0.72, 0.83, 1.0), metavar='THETA',
                        help='true theta_oil of the three lubrication stages (default 0.72 0.83 1.0)')
    parser.add_argument('--window', type=float, default=1.0, metavar='S', help='window length in s')
    parser.add_argument('--storage', choices=('mcap', 'sqlite3', 'mcap-file'), default='mcap')
    parser.set_defaults(func=run)


def run(args) -> int:
    """Simulate, calibrate on stage 3, assess stages 1 and 2, print the table, write figures."""
    from pathlib import Path
    from ..experiments.paper_demo import run_demo
    return run_demo(Path(args.out), seed=args.seed, stages=args.stages, window=args.window,
                    storage=args.storage)
