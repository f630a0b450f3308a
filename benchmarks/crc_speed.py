#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""CRC-32 speed of the chunk checks: ISA-L's (the ``isal`` wheel, what the reader uses) against zlib's.

Both compute the same CRC (MCAP's, zlib's polynomial); the check asserts it.
The data are 120 MiB of the rig simulator's kind of bytes (float32 samples
with noise, which compress as badly as real chunks' payloads), hashed in
1 MiB pieces like chunks; best of ``--repeat`` runs, machine load said.

Usage: ``python benchmarks/crc_speed.py [--mib 120] [--repeat 5]``;
results in ``benchmarks/results/crc_speed.{json,md}``.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import time
import zlib

import numpy as np

RESULTS = Path(__file__).resolve().parents[1] / 'benchmarks' / 'results'
PIECE = 1 << 20


def best_time(crc32, pieces, repeat: int) -> tuple[float, int]:
    """Least wall time of ``repeat`` passes of ``crc32`` over every piece, and the last CRCs' sum."""
    best, total = float('inf'), 0
    for _ in range(repeat):
        started = time.perf_counter()
        total = sum(crc32(piece) for piece in pieces)
        best = min(best, time.perf_counter() - started)
    return best, total


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--mib', type=int, default=120)
    parser.add_argument('--repeat', type=int, default=5)
    args = parser.parse_args()
    from isal.isal_zlib import crc32 as isal_crc32
    rng = np.random.default_rng(0)
    data = rng.normal(0.0, 3.0, args.mib * PIECE // 4).astype(np.float32).tobytes()
    pieces = [data[i:i + PIECE] for i in range(0, len(data), PIECE)]
    isal_s, isal_sum = best_time(isal_crc32, pieces, args.repeat)
    zlib_s, zlib_sum = best_time(zlib.crc32, pieces, args.repeat)
    assert isal_sum == zlib_sum, 'ISA-L and zlib disagree on the CRC'
    result = {'mib': args.mib, 'repeat': args.repeat, 'isal_s': isal_s, 'zlib_s': zlib_s,
              'speedup': zlib_s / isal_s, 'zlib_version': zlib.ZLIB_RUNTIME_VERSION,
              'load_average_1min': os.getloadavg()[0]}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'crc_speed.json').write_text(json.dumps(result, indent=2) + '\n')
    (RESULTS / 'crc_speed.md').write_text(
        f'# CRC-32 of {args.mib} MiB in 1 MiB pieces (best of {args.repeat})\n\n'
        f'| implementation | s | MiB/s |\n|---|---|---|\n'
        f'| ISA-L (isal) | {isal_s:.4f} | {args.mib / isal_s:,.0f} |\n'
        f'| zlib {zlib.ZLIB_RUNTIME_VERSION} | {zlib_s:.4f} | {args.mib / zlib_s:,.0f} |\n\n'
        f'ISA-L is {zlib_s / isal_s:.1f}x zlib here; load average {result["load_average_1min"]:.1f}.\n')
    print((RESULTS / 'crc_speed.md').read_text())
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
