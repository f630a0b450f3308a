# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Reading the package's YAML files with one-line errors that name the file."""
from __future__ import annotations

from pathlib import Path

import yaml

from .errors import InputError


def read_yaml(path: str | Path, what: str):
    """The parsed document of ``path``; :class:`InputError` naming the file (``what`` says which kind).

    A missing file, an unreadable one and invalid YAML each give one line.
    """
    path = Path(path)
    try:
        return yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise InputError(f'{path}: {what} not found') from None
    except OSError as exc:
        raise InputError(f'{path}: cannot read {what} ({exc.strerror or exc})') from None
    except yaml.YAMLError as exc:
        raise InputError(f'{path}: not valid YAML ({exc.__class__.__name__})') from None
