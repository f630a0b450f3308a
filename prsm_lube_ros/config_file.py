# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Reading the package's YAML files into dataclasses, with one-line errors that name the file.

:func:`read_yaml` parses a file, :func:`read_section` finds a mapping in it
(``actuator:``, ``rig_simulator: rig:``), and :func:`coerce_fields` turns that
mapping into keyword arguments of a dataclass, typed by the fields' defaults.
Every failure is a :class:`~prsm_lube_ros.errors.ConfigError` naming the file.
Imports only :mod:`.errors`, :mod:`.input_file` and :mod:`.validation`.
"""
from __future__ import annotations

from dataclasses import fields, MISSING
from pathlib import Path
from typing import Any, cast, TYPE_CHECKING, TypeVar
from collections.abc import Callable, Iterable

from .errors import ConfigError, InputError
from .input_file import read_text
from .validation import as_number

if TYPE_CHECKING:
    from _typeshed import DataclassInstance


__all__ = ['MAX_YAML_BYTES', 'MAX_YAML_NESTING', 'build', 'coerce_fields', 'nesting_depth', 'parse_yaml',
           'read_section', 'read_yaml']

#: Largest YAML file read, bytes, and deepest nesting of mappings and lists it may have: configuration and
#: calibration files are a few kB and a few levels deep; these bounds keep a hostile file from costing
#: memory, time or the interpreter's recursion limit.
MAX_YAML_BYTES = 8 << 20
MAX_YAML_NESTING = 32

_T = TypeVar('_T')


def read_yaml(path: str | Path, what: str) -> Any:
    """The parsed document of ``path``; :class:`ConfigError` naming the file (``what`` says which kind).

    A missing file, an unreadable one, one that is not a regular file (a FIFO,
    a device, ``/dev/stdin``), invalid YAML, text that is not UTF-8, a file
    over :data:`MAX_YAML_BYTES` and nesting deeper than
    :data:`MAX_YAML_NESTING` each give one line; nothing beyond the bound is
    read (:mod:`.input_file`).
    """
    return parse_yaml(read_text(path, what, max_bytes=MAX_YAML_BYTES, error=ConfigError), path, what)


def parse_yaml(text: str, path: str | Path, what: str) -> Any:
    """The parsed document of ``text`` read from ``path``: :func:`read_yaml` for text already read."""
    import yaml
    try:
        document = yaml.safe_load(text)
    except RecursionError:
        raise ConfigError(f'{path}: {what} is nested too deeply (more than {MAX_YAML_NESTING} levels)') from None
    except yaml.YAMLError as exc:
        raise ConfigError(f'{path}: not valid YAML ({exc.__class__.__name__})') from None
    if nesting_depth(document) > MAX_YAML_NESTING:
        raise ConfigError(f'{path}: {what} is nested too deeply (more than {MAX_YAML_NESTING} levels)')
    return document


def nesting_depth(document: object) -> int:
    """Levels of mappings and lists in a parsed YAML document (a scalar: 0), without recursion.

    Shared (aliased) nodes are measured once, so a small file of aliases that
    would expand to billions of nodes costs no more than its own size.
    """
    heights: dict[int, int] = {}
    stack = [(document, False)]
    while stack:
        node, done = stack.pop()
        if not isinstance(node, (dict, list)) or (id(node) in heights and not done):
            continue
        children = [c for c in (node.values() if isinstance(node, dict) else node) if isinstance(c, (dict, list))]
        if done:
            heights[id(node)] = 1 + max((heights.get(id(c), 0) for c in children), default=0)
            continue
        heights[id(node)] = 0     # on the stack: a cycle (YAML allows one) stops here
        stack.append((node, True))
        stack.extend((c, False) for c in children if id(c) not in heights)
    return heights.get(id(document), 0)


def read_section(path: str | Path, keys: Iterable[str], what: str) -> dict:
    """The mapping under ``keys`` (outermost first) of a YAML file; a missing section is empty.

    The outermost key may be left out (a file holding just the inner mapping).
    """
    path = Path(path)
    keys = list(keys)
    document = read_yaml(path, what)
    node = document if document is not None else {}
    if isinstance(node, dict) and keys and keys[0] in node:
        node = node[keys[0]]
    if node is None:
        node = {}
    if not isinstance(node, dict):
        raise ConfigError(f'{path}: expected a mapping under "{keys[0]}:"')
    for depth, key in enumerate(keys[1:], start=2):
        node = node.get(key) or {}
        if not isinstance(node, dict):
            raise ConfigError(f'{path}: expected a mapping under "{": ".join(keys[:depth])}:"')
    return node


def coerce_fields(path: str | Path, kind: type[DataclassInstance], values: dict, skip: Iterable[str] = (),
                  label: str = '') -> dict[str, Any]:
    """Keyword arguments of dataclass ``kind`` from a YAML mapping, each typed like its field's default.

    Unknown keys, a list where a number belongs, text where a number belongs,
    a fraction for a whole-number field: one :class:`ConfigError` naming the file and key
    (``label`` names the section in messages; default the dataclass's name).
    """
    skip = set(skip)
    known = {f.name: f for f in fields(kind)}
    unknown = sorted(set(values) - set(known) - skip)
    if unknown:
        raise ConfigError(f'{path}: unknown {label or kind.__name__} field(s) {", ".join(map(str, unknown))}')
    result: dict[str, Any] = {}
    for key, value in values.items():
        if key in skip:
            continue
        default = known[key].default
        if default is MISSING and known[key].default_factory is not MISSING:
            default = cast(Callable[[], Any], known[key].default_factory)()
        name = f'{path}: {key}'
        if isinstance(default, tuple):
            if not isinstance(value, (list, tuple)):
                raise ConfigError(f'{name} must be a list, got {value!r}')
            result[key] = tuple(value)
        elif isinstance(default, bool):
            if not isinstance(value, bool):
                raise ConfigError(f'{name} must be true or false, got {value!r}')
            result[key] = value
        elif isinstance(default, str):
            result[key] = str(value)
        elif isinstance(default, int):
            number = as_number(name, value)
            if number != int(number):
                raise ConfigError(f'{name} must be a whole number, got {value!r}')
            result[key] = int(number)
        else:
            result[key] = as_number(name, value)
    return result


def build(path: str | Path, kind: Callable[..., _T], values: dict, **extra: Any) -> _T:
    """``kind(**values, **extra)``; a validation error of the dataclass is prefixed with the file."""
    try:
        return kind(**values, **extra)
    except InputError as exc:
        raise ConfigError(f'{path}: {exc}') from None
