# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``python -m prsm_lube_ros.cli``: the same as ``prsm-lube`` (guarded: spawned workers re-import it)."""
import sys

from . import main

if __name__ == '__main__':
    sys.exit(main())
