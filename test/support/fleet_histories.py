# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Assessed recordings and recording points built by hand for history and trend tests (defects too)."""
import dataclasses
import datetime
import math

import numpy as np

from prsm_lube_ros.estimation.assessment import RunAssessment, WindowAssessment
from prsm_lube_ros.estimation.condition_indicators import ConditionIndicators, EnvelopePeak
from prsm_lube_ros.estimation.defect_screen import DefectFinding, RunCondition
from prsm_lube_ros.estimation.pipeline import RecordingAssessment
from prsm_lube_ros.estimation.windowing import Window
from prsm_lube_ros.fleet.forecast import DAY, RecordingPoint
from prsm_lube_ros.fleet.history import add_assessment, content_hash

START = datetime.datetime(2026, 3, 4, 10, 0, tzinfo=datetime.UTC).timestamp()
#: what the screen says of a spalled screw raceway
SPALL = DefectFinding(True, 'impulsive (kurtosis 9.1, crest factor 8.0; healthy up to 4.0); envelope line at '
                      '6.25x screw speed, 24 dB over the floor: screw raceway defect suspected', 'screw raceway', 6.25)
HEALTHY = DefectFinding(False, '')


def assessment(path, theta, runs=2):
    """A recording's assessment with ``runs`` runs of three windows each at ``theta``."""
    windows, run_list = [], []
    for run in range(1, runs + 1):
        for k in range(3):
            t = START + 10 * run + k
            window = Window(t, t + 1, 1.5, 4000, 1.0, 20.9, 0.01, 200.0, 30.0, 0.05, 1.0, run)
            windows.append(WindowAssessment(window, theta, 0.01))
        run_list.append(RunAssessment(str(path), run, START + 10 * run, START + 10 * run + 3, 20.9, 200.0, 1.5,
                                      theta, 0.005, 3, 30.0))
    return RecordingAssessment(str(path), windows, run_list)


def screened(path, theta=0.9, flagged_runs=(2,), days=0.0):
    """:func:`assessment` with indicators on every run and window, ``flagged_runs`` flagged, ``days`` later."""
    plain = assessment(path, theta)
    shift = days * 86400.0
    peaks = (EnvelopePeak(6.25, 24.0, 'screw raceway'),)
    runs = []
    for run in plain.runs:
        flagged = run.run_index in flagged_runs
        condition = RunCondition(9.1 if flagged else 3.1, 8.0 if flagged else 4.2, peaks, 3, 0.05)
        runs.append(dataclasses.replace(run, start=run.start + shift, end=run.end + shift, condition=condition,
                                        defect=SPALL if flagged else HEALTHY))
    windows = []
    for item in plain.windows:
        flagged = item.window.run_index in flagged_runs
        condition = ConditionIndicators(9.5 if flagged else 3.0, 8.2 if flagged else 4.1, peaks, 0.4,
                                        (2000.0, 6000.0), 0.05)
        window = dataclasses.replace(item.window, start=item.window.start + shift, end=item.window.end + shift,
                                     condition=condition)
        windows.append(WindowAssessment(window, item.theta_oil, item.theta_oil_std,
                                        defect=SPALL if flagged else HEALTHY))
    return RecordingAssessment(plain.path, windows, runs)


def recording(folder, name, content=b'bag bytes'):
    """A file standing for a recording (its bytes are its content hash)."""
    path = folder / name
    path.write_bytes(content)
    return path


def write(history, path, found, actuator='A01'):
    """Add an assessment of the recording at ``path`` to ``history``; its folder."""
    return add_assessment(history, found, actuator_id=actuator, content=content_hash(path), calibration='c0ffee')


def exponential_points(tau_days=40.0, days=10, relubricate_at=None, noise=0.0, seed=0):
    """One recording a day of theta = a exp(-t / tau); relubricated to 0.98 at ``relubricate_at`` days."""
    rng = np.random.default_rng(seed)
    points = []
    for day in range(days):
        t = day + 0.5
        if relubricate_at is not None and t > relubricate_at:
            theta = 0.98 * math.exp(-(t - relubricate_at) / tau_days)
        else:
            theta = 0.95 * math.exp(-t / tau_days)
        points.append(RecordingPoint(t * DAY, theta + noise * rng.standard_normal(), max(noise, 1e-4)))
    return points
