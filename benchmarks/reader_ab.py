#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The recording reader of this checkout against an older commit's, interleaved, on the same recordings.

On a shared machine the load changes between two benchmark runs more than a
change to the reader does; this runs both readers in turn (fresh processes,
the order alternating each round) so that both see the same load.  Per
recording and reader: the bare read (every message read, decompressed and
split, nothing decoded) and open + decode of every slice, in CPU seconds of
the process (``time.process_time``: waiting for a core the other sessions hold
does not count, as wall time would), best and median of ``--rounds``.  The
older commit's package is unpacked with ``git archive``.  Recordings: the
one-hour endurance bag of ``benchmarks/assess_throughput.py`` (mcap, and
with zstd chunks) and a five-minute sqlite3 bag simulated once.

Usage: ``python benchmarks/reader_ab.py [--commit 7c2826a] [--rounds 8] [--data /tmp/prsm_lube_bench]``;
results in ``benchmarks/results/reader_ab.{json,md}``.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import statistics
import subprocess
import sys
import tempfile

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'
CHILD = r'''
import json, sys, time
sys.path.insert(0, sys.argv[1])
from prsm_lube_ros.recording.reader import bare_read, open_recording
from prsm_lube_ros.recording.typestore import contract_typestore
contract_typestore()
start = time.process_time()
bare_read(sys.argv[2])
bare = time.process_time() - start
start = time.process_time()
for _ in open_recording(sys.argv[2]).slices():
    pass
print(json.dumps([bare, time.process_time() - start]))
'''


def recordings(data: Path) -> dict:
    """{label: path} of the recordings, simulated once into ``data``."""
    from read_memory import endurance_bag   # beside this file
    wanted = {'1 h mcap': (3600.0, 'mcap', None), '1 h mcap, zstd chunks': (3600.0, 'mcap', 'zstd'),
              '5 min sqlite3': (300.0, 'sqlite3', None)}
    return {label: endurance_bag(data, seconds, storage, compression)
            for label, (seconds, storage, compression) in wanted.items()}


def unpack(commit: str, into: Path) -> Path:
    """The package, msg and srv folders of ``commit`` under ``into``."""
    archive = subprocess.run(['git', 'archive', commit, 'prsm_lube_ros', 'msg', 'srv'], cwd=ROOT, check=True,
                             capture_output=True).stdout
    subprocess.run(['tar', '-x', '-C', str(into)], input=archive, check=True)
    return into


def run(root: Path, path: Path) -> list:
    """[bare read, open + decode] CPU s of the reader in ``root`` on ``path``, in a fresh process."""
    env = dict(os.environ, PYTHONPATH=str(root))
    out = subprocess.run([sys.executable, '-c', CHILD, str(root), str(path)], check=True, capture_output=True,
                         text=True, env=env, cwd=root).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> int:
    """Measure, write the results, print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--commit', default='7c2826a', help='the older commit (default: before issue 11 part 2)')
    parser.add_argument('--rounds', type=int, default=8)
    parser.add_argument('--data', type=Path, default=Path('/tmp/prsm_lube_bench'))
    args = parser.parse_args()
    files = recordings(args.data)
    rows = []
    with tempfile.TemporaryDirectory(prefix='reader_ab_') as scratch:
        readers = {args.commit: unpack(args.commit, Path(scratch)), 'this checkout': ROOT}
        for label, path in files.items():
            times = {name: [] for name in readers}
            for round_index in range(args.rounds):
                order = list(readers.items())
                for name, root in (order if round_index % 2 == 0 else order[::-1]):
                    times[name].append(run(root, path))
            for name, values in times.items():
                bare, decode = [v[0] for v in values], [v[1] for v in values]
                rows.append({'recording': label, 'reader': name, 'bare_best_s': min(bare),
                             'bare_median_s': statistics.median(bare), 'decode_best_s': min(decode),
                             'decode_median_s': statistics.median(decode)})
            print(f'{label}: done', file=sys.stderr, flush=True)
    load = os.getloadavg()[0]
    document = {'benchmark': 'reader_ab', 'command': f'python benchmarks/reader_ab.py --commit {args.commit}',
                'rounds': args.rounds, 'load_average_1min_at_end': load, 'rows': rows}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'reader_ab.json').write_text(json.dumps(document, indent=1))
    lines = [f'# Reader A/B (`{document["command"]}`)', '',
             f'{args.rounds} rounds, readers alternating, a fresh process each; 1-min load {load:.1f} at the end.', '',
             'CPU seconds of the reading process.', '',
             '| recording | reader | bare read best s | bare read median s | open + decode best s '
             '| open + decode median s |', '|---|---|---|---|---|---|']
    lines += [f'| {r["recording"]} | {r["reader"]} | {r["bare_best_s"]:.3f} | {r["bare_median_s"]:.3f} | '
              f'{r["decode_best_s"]:.3f} | {r["decode_median_s"]:.3f} |' for r in rows]
    (RESULTS / 'reader_ab.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
