# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Service logs beside the history: relubrications and odometer readings, as CSV.

``actuator,time`` lines for relubrications and ``actuator,time,revolutions``
for an odometer (cumulative screw revolutions), time in ISO 8601 (UTC when no
zone is given) or s since the epoch; an optional header line and ``#``
comments.  A bad line is one :class:`ConfigError` naming the file and line.
"""
from __future__ import annotations

import csv
import datetime
import math

from ..errors import ConfigError


def read_relubrications(path) -> dict[str, list[float]]:
    """``{actuator: [s since the epoch]}`` from a CSV of ``actuator,time`` lines (a header line is allowed)."""
    result: dict[str, list[float]] = {}
    for actuator, seconds in _csv_rows(path, ('actuator', 'time')):
        result.setdefault(actuator, []).append(seconds)
    return result


def read_odometer(path) -> dict[str, tuple[list[float], list[float]]]:
    """``{actuator: (times, revolutions)}`` from a CSV of ``actuator,time,revolutions`` lines."""
    result: dict[str, tuple[list[float], list[float]]] = {}
    for actuator, seconds, revolutions in _csv_rows(path, ('actuator', 'time', 'revolutions')):
        times, readings = result.setdefault(actuator, ([], []))
        times.append(seconds)
        readings.append(revolutions)
    return result


def _csv_rows(path, columns):
    """Rows of ``columns`` (an id, a time as ISO 8601 or s since the epoch, then numbers); one-line errors."""
    try:
        with open(path, newline='', encoding='utf-8') as stream:
            lines = list(csv.reader(stream))
    except OSError as exc:
        raise ConfigError(f'{path}: cannot read ({exc.strerror or exc})') from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f'{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason})') from None
    except csv.Error as exc:
        raise ConfigError(f'{path}: not a CSV file ({exc})') from None
    for number, row in enumerate(lines, start=1):
        if not row or row[0].strip().startswith('#') or (number == 1 and row[0].strip() == columns[0]):
            continue
        if len(row) < len(columns):
            raise ConfigError(f'{path}:{number}: expected "{",".join(columns)}", got {",".join(row)!r}')
        values = [row[0].strip()]
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
                    stamp = stamp.replace(tzinfo=datetime.timezone.utc)
                value = stamp.timestamp()
            if not math.isfinite(value):
                raise ConfigError(f'{path}:{number}: {name} {text!r} is not finite')
            values.append(value)
        yield tuple(values)
