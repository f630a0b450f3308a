# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The contract's message layouts for rosbags, without a ROS install.

``msg/*.msg`` and ``srv/*.srv`` at the package root are the single source of
truth: this module reads them (installed copies under ``share/`` or the source
tree) and registers them in a :mod:`rosbags` typestore next to the standard
ROS 2 types, so recordings can be written and read on any machine.

Checking a recording's layout needs only the field definitions of the
contract's messages and the standard types its topics use
(:func:`contract_fielddef`); those are parsed alone, so reading a recording
does not import rosbags' store of every ROS 2 type (its largest start-up cost)
unless a layout names another type.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path
import sys
from typing import Any

from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from ..contract import PACKAGE


__all__ = ['CONTRACT_MESSAGES', 'STANDARD_DEFINITIONS',
           'contract_fielddef', 'contract_typestore', 'interface_dir', 'message_definition']

#: The standard ROS 2 types the contract's topics and messages use, as their ``.msg`` text (unchanged since ROS 2's
#: first release; a test compares them with rosbags' store).
STANDARD_DEFINITIONS = {
    'builtin_interfaces/msg/Time': 'int32 sec\nuint32 nanosec\n',
    'std_msgs/msg/Header': 'builtin_interfaces/Time stamp\nstring frame_id\n',
    'sensor_msgs/msg/JointState': 'std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\n'
                                  'float64[] effort\n',
    'geometry_msgs/msg/Vector3': 'float64 x\nfloat64 y\nfloat64 z\n',
    'geometry_msgs/msg/Wrench': 'geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n',
    'geometry_msgs/msg/WrenchStamped': 'std_msgs/Header header\ngeometry_msgs/Wrench wrench\n',
    'sensor_msgs/msg/Temperature': 'std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n'}
#: The contract's own messages (``msg/<name>.msg``).
CONTRACT_MESSAGES = ('VibrationBlock', 'LubricationState')


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
    typestore.register(_contract_types())
    return typestore


def _contract_types() -> dict[str, Any]:
    """Field definitions of the contract's messages, parsed from ``msg/``."""
    types: dict[str, Any] = {}
    for name in CONTRACT_MESSAGES:
        types.update(get_types_from_msg(message_definition(name), f'{PACKAGE}/msg/{name}'))
    return types


@lru_cache(maxsize=1)
def _light_fielddefs() -> dict[str, Any]:
    types = _contract_types()
    for typename, text in STANDARD_DEFINITIONS.items():
        types.update(get_types_from_msg(text, typename))
    return types


def contract_fielddef(typename: str) -> Any:
    """``contract_typestore().fielddefs.get(typename)``, without building the store for the contract's types.

    The contract's messages and :data:`STANDARD_DEFINITIONS` are answered
    from their parsed text; any other type from the full store (None when it
    has none either).
    """
    found = _light_fielddefs().get(typename)
    return found if found is not None else contract_typestore().fielddefs.get(typename)
