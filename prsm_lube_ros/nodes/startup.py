# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Starting a node from an entry point: bad configuration is one line on stderr, never a traceback."""
from __future__ import annotations

import sys
from typing import Callable, Optional

import rclpy

from ..errors import InputError

#: Exit status of a node whose configuration or source cannot be used.
EXIT_BAD_INPUT = 2


def build_node(factory: Callable[[], object], node_name: str) -> Optional[object]:
    """``factory()``; on :class:`InputError` print ``<node_name>: error: <line>``, shut rclpy down, return None."""
    try:
        return factory()
    except InputError as exc:
        print(f'{node_name}: error: {exc}', file=sys.stderr)
        rclpy.try_shutdown()
        return None
