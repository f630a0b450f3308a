# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube diagnose``: find the physics the paper's model leaves out, name it, model it, refit, show it.

Public API::

    table = table_from_windows([rec.windows for rec in recordings], theta=1.0)
    result = diagnose_table(table)           # Diagnosis: verdict, baseline, candidates, best, location
    result.named_effects()                    # (effect, form, params) of each named effect (0, 1 or 2)
    result.as_json()                          # the contract's diagnose document (plus ``effects``, ``form``)
    result.calibration()                      # Calibration with the first named effect in ``extension``
    write_report(result, 'out/report', recordings)   # PNG figures and index.md / index.html

Owns: the window table (``table``), locating the mismatch (``locate``), fitting
the model with candidate effects (``fitting``, ``combined``), the verdict
(``engine``), the reports (``report``; ``condition_report``, also
``assess --report``'s page) and the candidates (``effects/``, one per
law of :mod:`prsm_lube_ros.physics.effects`).  May import the base layer,
:mod:`..physics`, :mod:`..recording` and :mod:`..estimation`; no ROS.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..estimation.windowing import DEFAULT_DEFECT_ORDERS, MIN_AXIAL_LOAD
from .effects import Effect, candidate_ids, get_effect, register, registered
from .engine import ADEQUATE, AMBIGUOUS, Candidate, diagnose_table, Diagnosis, UNEXPLAINED, Verdict
from .rules import DEFAULT_RULES, DiagnosisRules
from .table import band_of, table_from_windows, WindowTable

if TYPE_CHECKING:
    from pathlib import Path

    from ..estimation.pipeline import RecordingWindows

__all__ = ['ADEQUATE', 'AMBIGUOUS', 'DEFAULT_RULES', 'UNEXPLAINED', 'Candidate', 'Diagnosis', 'DiagnosisRules',
           'Effect', 'Verdict', 'WindowTable', 'diagnose_recordings', 'diagnose_table', 'candidate_ids', 'get_effect',
           'register', 'registered', 'table_from_windows', 'write_report']


def diagnose_recordings(recordings: Sequence[RecordingWindows], theta: float = 1.0,
                        min_axial_load: float = MIN_AXIAL_LOAD, rules: DiagnosisRules = DEFAULT_RULES) -> Diagnosis:
    """Diagnose :class:`~prsm_lube_ros.estimation.pipeline.RecordingWindows` taken at lubrication state ``theta``.

    Recordings ``prsm-lube calibrate`` refuses are refused here with the same line: the calibration is fitted
    first, and its flags (what the fit cannot vouch for) are carried into the diagnosis.  ``rules``: the
    policy every decision is taken by (:class:`.rules.DiagnosisRules`).
    """
    from ..estimation.pipeline import calibrate_recordings
    calibration = calibrate_recordings(recordings, theta, min_axial_load)
    table = table_from_windows([rec.windows for rec in recordings], theta=theta, min_axial_load=min_axial_load,
                               sources=[rec.path for rec in recordings], band=band_of(recordings),
                               defect_orders=recordings[0].defect_orders if recordings else DEFAULT_DEFECT_ORDERS)
    result = diagnose_table(table, rules=rules)
    result.calibration_flags = list(calibration.flags)
    return result


def write_report(diagnosis: Diagnosis, folder: str | Path,
                 recordings: Sequence[RecordingWindows] | None = None) -> Path:
    """Figures and a one-page report of ``diagnosis`` in ``folder`` (see :mod:`.report`).

    Given the diagnosed ``recordings``, the page holds their condition figures too (:mod:`.condition_report`).
    """
    from .report import write_report as _write
    return _write(diagnosis, folder, recordings)
