# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube diagnose``: find the physics the paper's model leaves out (see :mod:`prsm_lube_ros.diagnosis`)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import argparse


__all__ = ['add_command', 'candidate_lines', 'run']


def add_command(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``diagnose`` to the ``prsm-lube`` subcommands."""
    from .common import add_band_option, add_recording_options
    parser = subparsers.add_parser(
        'diagnose', help='find the physics the model leaves out, model it, refit and show the gain',
        description='Recordings at one known lubrication state: fit the paper\'s model, locate where recording '
        'and model disagree, fit every candidate effect with the constants, rank them on held-out runs and '
        'say which one the recording needs (or that the model is adequate).')
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 folder or .mcap file')
    parser.add_argument('--theta', type=float, default=1.0, help='theta_oil of the recordings (default 1.0)')
    parser.add_argument('--json', required=True, metavar='OUT.json', help='write the diagnosis as JSON')
    parser.add_argument('--report', metavar='DIR', help='write figures and a one-page report to DIR, with the '
                        'condition figures (order and envelope spectra, waterfalls, indicator trends)')
    parser.add_argument('--calibration-out', metavar='CALIB.yaml',
                        help='write the calibration of the chosen model (effect in its extension)')
    add_recording_options(parser)
    add_band_option(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Handler of ``prsm-lube diagnose``; returns the exit status."""
    from ..validation import reference_theta
    from .common import read_recordings, write_json
    from ..diagnosis import diagnose_recordings
    theta = reference_theta(args.theta, '--theta')
    recordings, _ = read_recordings(args.bags, args, spectra=True)
    result = diagnose_recordings(recordings, theta)
    document = result.as_json()
    write_json(args.json, document)
    base = result.baseline
    print(f'paper\'s model: relative RMS error {100 * base.rmse:.2f} %, on held-out runs {100 * base.cv_rmse:.2f} %')
    print(f'located: {result.location.summary}')
    lof = result.baseline_fit_test
    if lof is not None:
        print(f'lack of fit: {lof.sentence}')
    for flag in result.calibration_flags:
        print(f'warning: {flag}')
    print(f'{"candidate":<30} {"status":<13} {"cv_rmse":>8} {"gain":>7} {"dBIC":>7}')
    for line in candidate_lines(result.candidates):
        print(line)
    print(f'verdict: {result.verdict}' + (f' (tied: {", ".join(result.tied)})' if result.tied else ''))
    for rank, (effect, form, text) in enumerate(result.named_descriptions()):
        print(f'{("effect", "second effect")[rank]}: {effect.id}, form: {form}')
        print(text)
    for note in result.notes:
        print(f'note: {note}')
    if result.what_to_record:
        print(f'record: {result.what_to_record}')
    if args.calibration_out:
        from ..estimation.calibration_file import save_calibration
        save_calibration(result.calibration(), args.calibration_out)     # with the band and domain it was fitted in
        print(f'wrote {args.calibration_out}')
    if args.report:
        from ..atomic_file import staged_folder
        from ..diagnosis import write_report
        from pathlib import Path
        with staged_folder(Path(args.report)) as staged:     # each file of the report moved into place whole
            page = Path(args.report) / write_report(result, staged, recordings).relative_to(staged)
        print(f'wrote {page}')
    print(f'wrote {args.json}')
    return 0


def candidate_lines(candidates: list) -> list[str]:
    """The terminal table's rows, best held-out first: scores, and the reason where the scores do not say it.

    A fitted candidate rejected by a rule other than the scores' own (a
    measurement its fit contradicts, unphysical constants) may have the best
    scores of all, and one named by a rule that scores it against another
    reference (the paper's model held physical, a located law) may have poor
    ones against the paper's model; its row then carries the reason.
    """
    from ..diagnosis.engine import Status
    lines = []
    for cand in sorted(candidates, key=lambda c: c.fit.cv_rmse if c.fit else math.inf):
        if cand.fit is None:
            lines.append(f'{cand.effect.id:<30} {cand.status:<13} {cand.reason}')
            continue
        line = (f'{cand.effect.id:<30} {cand.status:<13} {100 * cand.fit.cv_rmse:7.2f}% {100 * cand.gain:6.1f}% '
                f'{cand.delta_bic:7.1f}')
        if cand.status in (Status.REJECTED, Status.EARNS) and cand.decisions[-1].rule != 'bic_margin':
            line += f'  ({cand.reason})'
        lines.append(line)
    return lines
