# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The checks every layer applies to numbers, written once.

Finite-or-None for JSON and messages, positive-and-finite for physical
parameters, a number from YAML, and the contract's reference-theta rule.
Failures raise :class:`~prsm_lube_ros.errors.ConfigError` (or the class the
caller names) with one line naming the value.  Imports only :mod:`.errors`.
"""
from __future__ import annotations

import datetime
import math
from typing import Any

from .errors import ConfigError, InputError


__all__ = ['as_number', 'finite_or_none', 'is_positive_number', 'reference_theta', 'require', 'require_all_positive',
           'require_positive', 'utc_or_none']

# The values checked here come from YAML, JSON, messages and callers alike, so the checks take any object;
# the two that hand it to ``float()`` take ``Any`` (``float`` accepts more than one protocol, and whatever it
# rejects is caught and reported).


def is_positive_number(value: object) -> bool:
    """True for a real number (not a bool) that is finite and > 0."""
    return (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value) and value > 0)


def finite_or_none(value: Any) -> float | None:
    """``float(value)`` when it is a finite number, else ``None`` (JSON has no NaN)."""
    if value is None:
        return None
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def utc_or_none(seconds: object) -> datetime.datetime | None:
    """The UTC time of ``seconds`` since the epoch when it is a finite number, else ``None``."""
    seconds = finite_or_none(seconds)
    return None if seconds is None else datetime.datetime.fromtimestamp(seconds, datetime.UTC)


def _real(name: str, value: Any, error: type[InputError], what: str) -> float:
    """``value`` as a float, or ``error`` saying ``name must be <what>`` for bools and text."""
    if isinstance(value, bool):
        raise error(f'{name} must be {what}, got {value!r}')
    try:
        return float(value)
    except (TypeError, ValueError):
        raise error(f'{name} must be {what}, got {value!r}') from None


def as_number(name: str, value: object, error: type[InputError] = ConfigError) -> float:
    """``value`` as a finite float; ``error`` naming ``name`` for bools, text, NaN and infinities."""
    number = _real(name, value, error, 'a number')
    if not math.isfinite(number):
        raise error(f'{name} must be finite, got {value!r}')
    return number


def require_positive(name: str, value: object, error: type[InputError] = ConfigError) -> float:
    """``value`` as a float when it is a finite number > 0; else ``error`` naming ``name``."""
    number = _real(name, value, error, 'a positive number')
    if not (math.isfinite(number) and number > 0):
        raise error(f'{name} must be a positive number, got {value!r}')
    return number


def require_all_positive(owner: str, **values: object) -> None:
    """:func:`require_positive` for each keyword, named ``<owner> <keyword>``."""
    for name, value in values.items():
        require_positive(f'{owner} {name}', value)


def reference_theta(value: object, name: str = 'reference theta') -> float:
    """The contract's rule for a reference theta_Oil: 0 means 1.0; else it must be finite and > 0.

    Used by ``prsm-lube calibrate`` / ``diagnose --theta`` and the calibrate
    service alike, so none of them can turn a bad value into 1.0.
    """
    if isinstance(value, (int, float)) and not isinstance(value, bool) and value == 0:
        return 1.0
    return require_positive(name, value)


def require(condition: object, message: str, error: type[InputError] = ConfigError) -> None:
    """Raise ``error(message)`` unless ``condition`` holds."""
    if not condition:
        raise error(message)
