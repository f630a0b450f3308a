# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""A suspected surface defect in an actuator's history: from when on its theta_Oil is no lubrication measure.

The assessment screens every run for a surface defect
(:mod:`prsm_lube_ros.estimation.defect_screen`; the history keeps
``defect_suspected`` and the evidence per run).  A spall raises the band RMS
as oil loss does, so while one is there theta_Oil reads damage, not oil, and
a depletion forecast from it would send oil where an inspection is needed.

The rule.  An actuator's defect is suspected from the start of the first run
(of any recording made by the as-of date) the screen flagged, and it stays:
the damage does not heal, and neither a relubrication nor a later recording
the screen passes ends it (a growing spall is impulsive in some runs and not
in others).  Only a repair ends it, and the history knows of none: an
actuator whose screw was replaced needs a new actuator id.  Recordings from
the onset on are left out of the fleet's usage scatter, which describes how
oil is used up, not how spalls grow.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import TYPE_CHECKING
from collections.abc import Mapping, Sequence

from ..validation import utc_or_none

if TYPE_CHECKING:
    import pyarrow as pa

    from .forecast import RecordingPoint

__all__ = ['NO_COMPONENT', 'DefectMark', 'DefectOnset', 'before_onsets', 'defect_marks', 'defect_onset',
           'defect_onsets']

#: the component named when the screen found the vibration impulsive without an envelope line at a defect order
NO_COMPONENT = 'no defect order identified (impulsive vibration)'


@dataclass(frozen=True)
class DefectMark:
    """One recording with at least one run the defect screen flagged.

    ``time`` is the start of its first flagged run, ``recording_start`` that
    of its first run (s since the epoch); ``component``, ``order`` and
    ``evidence`` are the first flagged run's (or the first naming a
    component); ``flagged`` of ``runs`` runs were flagged.
    """

    time: float
    recording_start: float
    recording_path: str
    component: str
    order: float
    evidence: str
    flagged: int
    runs: int


@dataclass(frozen=True)
class DefectOnset:
    """An actuator's suspected defect as of a date: since when, where, why and how often seen since."""

    since: float                    # s since the epoch: start of the first flagged run
    since_recording: float          # s since the epoch: start of the recording holding it
    recording_path: str
    component: str                  # '' when no envelope line named one
    order: float                    # x screw speed, NaN without a line
    evidence: str
    recordings: int                 # recordings flagged from the onset to the as-of date

    @property
    def since_utc(self) -> str:
        """The onset in ISO 8601 UTC to the minute."""
        stamp = utc_or_none(self.since)
        return '' if stamp is None else stamp.isoformat(timespec='minutes')

    @property
    def reason(self) -> str:
        """Why the actuator has no lubrication forecast, in the trend's words."""
        return (f'surface defect suspected since {self.since_utc}: {self.component or NO_COMPONENT}; '
                'theta_Oil is no lubrication measure, no lubrication forecast')

    def as_json(self) -> dict:
        """The defect fields of an actuator in trend.json."""
        return {'defect_suspected': True, 'defect_since': self.since, 'defect_since_utc': self.since_utc,
                'defect_component': self.component, 'defect_order': self.order if math.isfinite(self.order) else None,
                'defect_evidence': self.evidence, 'defect_recording': self.recording_path,
                'defect_recordings': self.recordings}


def defect_marks(runs: pa.Table) -> dict[str, list[DefectMark]]:
    """Per actuator, in time order, each recording of a history ``runs`` table with a flagged run.

    Runs without theta_Oil count too (the damage is there whether Eq. 23 had
    a value or not).  A table without the defect columns (read by other
    means than :func:`~.history.read_table`) has no marks.
    """
    if 'defect_suspected' not in runs.column_names:
        return {}
    names = ('actuator', 'recording', 'recording_path', 'start', 'defect_suspected', 'defect_component',
             'defect_order', 'defect_evidence')
    columns = {name: runs.column(name).to_pylist() if name in runs.column_names else [None] * runs.num_rows
               for name in names}
    recordings: dict[tuple[str, str], list[tuple]] = {}
    for actuator, recording, path, start, flagged, component, order, evidence in zip(*columns.values()):
        if start is not None:
            recordings.setdefault((actuator, recording or path), []).append(
                (start.timestamp(), bool(flagged), path or '', component or '', order, evidence or ''))
    marks: dict[str, list[DefectMark]] = {}
    for (actuator, _), rows in recordings.items():
        flagged = sorted(row for row in rows if row[1])
        if not flagged:
            continue
        named = next((row for row in flagged if row[3]), flagged[0])
        order = named[4] if named[4] is not None else math.nan
        marks.setdefault(actuator, []).append(DefectMark(flagged[0][0], min(row[0] for row in rows), flagged[0][2],
                                                         named[3], float(order), named[5] or flagged[0][5],
                                                         len(flagged), len(rows)))
    return {actuator: sorted(items, key=lambda m: m.time) for actuator, items in sorted(marks.items())}


def defect_onset(marks: Sequence[DefectMark], as_of: float | None = None) -> DefectOnset | None:
    """The suspected defect of one actuator from its marks made by ``as_of`` (all without it); None if none."""
    seen = [m for m in marks if as_of is None or m.time <= as_of]
    if not seen:
        return None
    first = seen[0]
    named = next((m for m in seen if m.component), first)
    return DefectOnset(first.time, first.recording_start, first.recording_path, named.component, named.order,
                       named.evidence if named.component else first.evidence, len(seen))


def defect_onsets(marks: Mapping[str, Sequence[DefectMark]], as_of: float | None = None) -> dict[str, DefectOnset]:
    """:func:`defect_onset` of every actuator that has one by ``as_of``."""
    found = {name: defect_onset(items, as_of) for name, items in marks.items()}
    return {name: onset for name, onset in found.items() if onset is not None}


def before_onsets(points: Mapping[str, Sequence[RecordingPoint]],
                  onsets: Mapping[str, DefectOnset]) -> dict[str, list[RecordingPoint]]:
    """Each actuator's recording points made before the recording its defect was first seen in.

    What the fleet's usage scatter may learn from: theta_Oil as a lubrication
    measure.  Actuators without a defect keep all their points; those left
    with none are left out.
    """
    kept = {}
    for name, items in points.items():
        onset = onsets.get(name)
        before = list(items) if onset is None else [p for p in items if p.time < onset.since_recording]
        if before or onset is None:
            kept[name] = before
    return kept
