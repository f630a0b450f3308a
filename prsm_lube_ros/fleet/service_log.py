# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Service logs beside the history: relubrications and odometer readings, as CSV.

``actuator,time`` lines for relubrications and ``actuator,time,revolutions``
for an odometer (cumulative screw revolutions), time in ISO 8601 (UTC when no
zone is given) or s since the epoch; an optional header line and ``#``
comments (the header may follow them).  A bad line is one :class:`ConfigError`
naming the file and line; an odometer that goes backwards or names an
actuator the history does not have is a ``file:line`` problem
(:func:`odometer_problems`).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
import datetime
import io
import math
from typing import Any, TYPE_CHECKING
from collections.abc import Callable, Iterator

from ..errors import ConfigError
from ..input_file import read_bytes

if TYPE_CHECKING:
    from pathlib import Path


__all__ = ['MAX_LOG_BYTES', 'OdometerReading', 'odometer_problems', 'odometer_readings', 'read_odometer',
           'read_relubrications']

#: Largest service log (relubrications, odometer readings) read, bytes: a fleet's decades of entries are a few MB.
MAX_LOG_BYTES = 64 << 20


def read_relubrications(path: str | Path) -> dict[str, list[float]]:
    """``{actuator: [s since the epoch]}`` from a CSV of ``actuator,time`` lines (a header line is allowed)."""
    result: dict[str, list[float]] = {}
    for _, (actuator, seconds) in _csv_rows(path, ('actuator', 'time')):
        result.setdefault(actuator, []).append(seconds)
    return result


@dataclass(frozen=True)
class OdometerReading:
    """One odometer line: where it is, when (s since the epoch) and the cumulative screw revolutions."""

    line: int
    time: float
    revolutions: float


def odometer_readings(path: str | Path) -> dict[str, list[OdometerReading]]:
    """``{actuator: [readings in time order]}`` from a CSV of ``actuator,time,revolutions`` lines."""
    result: dict[str, list[OdometerReading]] = {}
    for number, (actuator, seconds, revolutions) in _csv_rows(path, ('actuator', 'time', 'revolutions')):
        result.setdefault(actuator, []).append(OdometerReading(number, seconds, revolutions))
    return {actuator: sorted(items, key=lambda r: r.time) for actuator, items in result.items()}


def read_odometer(path: str | Path) -> dict[str, tuple[list[float], list[float]]]:
    """``{actuator: (times, revolutions)}`` from a CSV of ``actuator,time,revolutions`` lines."""
    return {actuator: ([r.time for r in items], [r.revolutions for r in items])
            for actuator, items in odometer_readings(path).items()}


def odometer_problems(path: str | Path, readings: dict[str, list[OdometerReading]], known: set[str],
                      key: Callable[[str], str] = lambda actuator: actuator) -> dict[str, str]:
    """``{actuator: "file:line: what is wrong"}``: readings that go backwards in time, ids not in ``known``.

    ``key`` maps an id of the file to the form ``known`` holds (the history's
    partition key).
    """
    problems = {}
    for actuator, items in readings.items():
        if key(actuator) not in known:
            problems[actuator] = f'{path}:{items[0].line}: actuator {actuator!r} is not in the history'
            continue
        for before, after in zip(items, items[1:]):
            if after.revolutions < before.revolutions:
                problems[actuator] = (f'{path}:{after.line}: odometer of {actuator} goes backwards '
                                      f'({after.revolutions:g} rev after {before.revolutions:g} rev at line '
                                      f'{before.line})')
                break
    return problems


def _csv_rows(path: str | Path, columns: tuple[str, ...]) -> Iterator[tuple[int, tuple[Any, ...]]]:
    """Rows of ``columns`` (an id, a time as ISO 8601 or s since the epoch, then numbers); one-line errors."""
    try:
        data = read_bytes(path, 'service log', max_bytes=MAX_LOG_BYTES, error=ConfigError)   # a regular file, bounded
        lines = list(csv.reader(io.StringIO(data.decode('utf-8'), newline='')))
    except UnicodeDecodeError as exc:
        raise ConfigError(f'{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason})') from None
    except csv.Error as exc:
        raise ConfigError(f'{path}: not a CSV file ({exc})') from None
    header_possible = True
    for number, row in enumerate(lines, start=1):
        if not row or not ''.join(row).strip() or row[0].strip().startswith('#'):
            continue
        if header_possible and row[0].strip() == columns[0]:
            header_possible = False
            continue
        header_possible = False
        if len(row) < len(columns):
            raise ConfigError(f'{path}:{number}: expected "{",".join(columns)}", got {",".join(row)!r}')
        values: list[str | float] = [row[0].strip()]
        for name, text in zip(columns[1:], (cell.strip() for cell in row[1:])):
            try:
                value = float(text)
            except ValueError:
                if name != 'time':
                    raise ConfigError(f'{path}:{number}: {name} {text!r} is not a number') from None
                try:
                    stamp = datetime.datetime.fromisoformat(text.replace('Z', '+00:00'))
                except ValueError:
                    raise ConfigError(f'{path}:{number}: time {text!r} is neither ISO 8601 nor seconds '
                                      'since the epoch') from None
                if stamp.tzinfo is None:
                    stamp = stamp.replace(tzinfo=datetime.UTC)
                value = stamp.timestamp()
            if not math.isfinite(value):
                raise ConfigError(f'{path}:{number}: {name} {text!r} is not finite')
            values.append(value)
        yield number, tuple(values)
