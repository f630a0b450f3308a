# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The contract's message layouts for rosbags, without a ROS install.

``msg/*.msg`` and ``srv/*.srv`` at the package root are the single source of
truth: this module reads them (installed copies under ``share/`` or the source
tree) and registers them in a :mod:`rosbags` typestore next to the standard
ROS 2 types, so recordings can be written and read on any machine.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path
import sys
from typing import Any

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from ..contract import PACKAGE


__all__ = ['contract_typestore', 'interface_dir', 'message_definition']


def interface_dir() -> Path:
    """Folder holding ``msg/`` and ``srv/``.

    A source checkout has them beside the package; colcon and pip installs put
    them under ``<prefix>/share/prsm_lube_ros``.
    """
    here = Path(__file__).resolve().parent.parent
    candidates = [here.parent, Path(sys.prefix) / 'share' / PACKAGE]
    if len(here.parents) > 3:  # <prefix>/lib/pythonX.Y/site-packages/prsm_lube_ros
        candidates.insert(1, here.parents[3] / 'share' / PACKAGE)
    for candidate in candidates:
        if (candidate / 'msg' / 'VibrationBlock.msg').is_file():
            return candidate
    raise FileNotFoundError(
        'msg/VibrationBlock.msg of prsm_lube_ros not found in ' + ', '.join(map(str, candidates)))


def message_definition(name: str) -> str:
    """Text of ``msg/<name>.msg``."""
    return (interface_dir() / 'msg' / f'{name}.msg').read_text()


@lru_cache(maxsize=None)
def contract_typestore(store: Stores = Stores.ROS2_JAZZY) -> Any:
    """A rosbags typestore with the standard ROS 2 types and the contract's messages.

    A ``rosbags.typesys.store.Typestore``, annotated ``Any``: its ``deserialize_cdr``
    types messages as ``object``, and the readers use their fields (a writer
    that wants the precise type annotates its own variable).
    """
    typestore = get_typestore(store)
    types = {}
    for name in ('VibrationBlock', 'LubricationState'):
        types.update(get_types_from_msg(message_definition(name), f'{PACKAGE}/msg/{name}'))
    typestore.register(types)
    return typestore
