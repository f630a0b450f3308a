# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``python -m prsm_lube_ros.cli``: the same as ``prsm-lube`` (guarded: spawned workers re-import it)."""

from . import main
from ..stopping import exit_now, stop_at_once

if __name__ == '__main__':
    stop_at_once()      # SIGINT/SIGTERM before and after the command: one line, 130/143
    exit_now(main())
