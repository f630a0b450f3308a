#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The floor under ``prsm-lube assess``: read a recording's bytes once with numpy, nothing decoded.

Usage: ``python benchmarks/bytes_floor.py BAG`` (a rosbag2 folder or a file).
It reads every file of the recording into a numpy array and sums the bytes,
so each byte is touched once; as a whole process (interpreter and numpy
start-up included) it is what no reader of the file can beat by much.
"""
from pathlib import Path
import sys

import numpy as np

root = Path(sys.argv[1])
total = 0
for path in sorted(root.rglob('*') if root.is_dir() else [root]):
    if path.is_file():
        total += int(np.fromfile(path, dtype=np.uint8).sum(dtype=np.uint64))
print(total)
