# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""One actuator id, one piece of hardware: recordings of one actuator cannot overlap in time.

An actuator records one thing at a time, so two recordings filed under one
actuator id whose spans (first run start to last run end) overlap must come
from two actuators: the id merges distinct hardware, and its trend would
invent relubrications.  The same content again (a re-assessment) is no
clash, nor is the same span to within :data:`SAME_RECORDING` (one recording
stored twice, as MCAP and as sqlite3).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import datetime
from typing import TYPE_CHECKING
from collections.abc import Callable

if TYPE_CHECKING:
    import pyarrow as pa

    from ..estimation.pipeline import RecordingAssessment

__all__ = ['SAME_RECORDING', 'Span', 'Timeline', 'assessment_span', 'clash_line', 'table_spans']

#: s: spans whose start and end agree to within this are one recording stored twice
SAME_RECORDING = 1.0


@dataclass(frozen=True)
class Span:
    """A recording's time span (s since the epoch), content hash and path."""

    start: float
    end: float
    content: str
    path: str

    def clashes_with(self, other: Span) -> bool:
        """True when ``other`` is another recording whose span overlaps this one."""
        if self.content == other.content:
            return False
        if abs(self.start - other.start) <= SAME_RECORDING and abs(self.end - other.end) <= SAME_RECORDING:
            return False
        return self.start < other.end and other.start < self.end


def assessment_span(assessment: RecordingAssessment, content: str) -> Span | None:
    """The span of an assessed recording's runs, None without runs."""
    runs = assessment.runs
    if not runs:
        return None
    return Span(min(r.start for r in runs), max(r.end for r in runs), content, str(assessment.path))


def table_spans(runs: pa.Table) -> list[Span]:
    """One span per content hash of a history ``runs`` table."""
    found: dict[str, tuple] = {}
    for content, path, start, end in zip(*(runs.column(name).to_pylist() for name in
                                           ('content_hash', 'recording_path', 'start', 'end'))):
        if start is None or end is None:
            continue
        low, high, _ = found.get(content, (start, end, path))
        found[content] = (min(low, start), max(high, end), path)
    return [Span(low.timestamp(), high.timestamp(), content, path) for content, (low, high, path) in found.items()]


@dataclass
class Timeline:
    """Spans of each actuator: those already in the history (``load(key)``, read once) and those added since."""

    load: Callable[[str], list[Span]]
    known: dict[str, list[Span]] = field(default_factory=dict)

    def clash(self, key: str, span: Span) -> Span | None:
        """The first recording of actuator ``key`` whose span overlaps ``span``, if any."""
        if key not in self.known:
            self.known[key] = self.load(key)
        return next((other for other in self.known[key] if span.clashes_with(other)), None)

    def add(self, key: str, span: Span) -> None:
        """Record ``span`` under actuator ``key`` (replacing an earlier span of its content)."""
        self.known[key] = [s for s in self.known.get(key, []) if s.content != span.content] + [span]


def clash_line(span: Span, other: Span, actuator: str) -> str:
    """The one line refusing ``span``: which recording it overlaps and what to do."""
    def utc(seconds: float) -> str:
        return datetime.datetime.fromtimestamp(seconds, datetime.UTC).isoformat(timespec='seconds')
    return (f'{span.path}: not added to the history: it overlaps {other.path} in time ({utc(span.start)} .. '
            f'{utc(span.end)} against {utc(other.start)} .. {utc(other.end)}) under actuator {actuator!r}, so they '
            'come from two actuators; give each its own id (--actuator-id ID or folder)')
