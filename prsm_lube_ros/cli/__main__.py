# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``python -m prsm_lube_ros.cli``: the same as ``prsm-lube``."""
import sys

from . import main

sys.exit(main())
