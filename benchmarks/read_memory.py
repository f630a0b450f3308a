#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Peak memory and time of reading a one-hour recording whose chunks are in time order, reversed, or shuffled.

The recording is the rig simulator's one-hour endurance bag (the one
``benchmarks/assess_throughput.py`` uses: 4 kHz vibration in 0.1 s blocks,
joint states 100 Hz, load 50 Hz, temperature 1 Hz, 1 MiB chunks).  Its MCAP
file is rewritten with the same chunks in reversed and in shuffled order
(``test/support/bagfactory.py`` ``reorder_chunks``), and with one message per
chunk (the writer's own option, in time order).  Each file is read by a fresh
subprocess that opens it and decodes every slice (what every command does
before windowing); it reports its wall time, peak resident memory
(``VmHWM``) and a checksum of the decoded values, so equal checksums show
that every order gives the same data.  ``--root`` points the subprocess at
another checkout (e.g. an older commit) for a before/after comparison.

Usage: ``python benchmarks/read_memory.py [--data /tmp/prsm_lube_bench] [--repeat 2] [--root DIR]
[--orders 'time order' reversed ...]``;
results in ``benchmarks/results/read_memory.{json,md}``.
"""
from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
import platform
import resource
import subprocess
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'


def peak_rss_mib() -> float:
    """This process's peak resident memory, MiB.

    ``VmHWM`` of /proc, not ``ru_maxrss``: Linux keeps ``ru_maxrss`` across
    fork and exec, so a child would report its parent's peak when larger.
    """
    try:
        for line in Path('/proc/self/status').read_text().splitlines():
            if line.startswith('VmHWM:'):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def child(path: str) -> None:
    """Open and decode every slice of ``path`` in this process; print one JSON line."""
    import numpy as np
    from prsm_lube_ros.recording.reader import open_recording
    from prsm_lube_ros.recording.typestore import contract_typestore
    contract_typestore()
    baseline = peak_rss_mib()
    start = time.perf_counter()
    slices = messages = 0
    checksum = 0.0
    problems = []
    for batches in open_recording(path).slices(on_problem=problems.append):
        slices += 1
        for batch in batches:
            messages += len(batch)
            for value in vars(batch).values():
                if value.dtype.kind == 'f':
                    checksum += float(np.nansum(value, dtype=np.float64))
    elapsed = time.perf_counter() - start
    peak = peak_rss_mib()
    print(json.dumps({'seconds': elapsed, 'peak_rss_mib': peak, 'rss_after_imports_mib': baseline,
                      'slices': slices, 'messages': messages, 'checksum': checksum, 'problems': problems}))


def best_of_children(argv: list[str], repeat: int, env: dict | None = None, cwd: Path | None = None) -> dict:
    """Run ``argv`` ``repeat`` times as fresh processes, each printing a JSON line last.

    Returns the fastest run's record (by ``seconds``) with ``peak_rss_mib`` the
    largest among all runs.
    """
    runs = []
    for _ in range(repeat):
        out = subprocess.run(argv, check=True, capture_output=True, text=True, env=env, cwd=cwd).stdout
        runs.append(json.loads(out.strip().splitlines()[-1]))
    best = min(runs, key=lambda run: run['seconds'])
    best['peak_rss_mib'] = max(run['peak_rss_mib'] for run in runs)
    return best


def measure(path: Path, repeat: int, root: Path) -> dict:
    """Best time of ``repeat`` fresh subprocesses; the largest peak memory among them."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get('PYTHONPATH', '')]))
    return best_of_children([sys.executable, __file__, '--child', str(path)], repeat, env=env, cwd=root)


def endurance_bag(data: Path, seconds: float, storage: str = 'mcap', compression: str | None = None) -> Path:
    """The rig simulator's endurance recording (4 kHz, seed 1) in ``data``, simulated the first time only.

    Shared by the benchmarks so that each finds the same bag under the same name.
    """
    sys.path.insert(0, str(ROOT))
    from prsm_lube_ros.simulation.recordings import simulate_endurance
    name = f'endurance_{int(seconds)}s' + (f'_{storage}' if storage != 'mcap' else '') + \
        (f'_{compression}' if compression else '')
    path = Path(data) / name
    if not path.exists():
        print(f'simulating {seconds:g} s at 4 kHz into {path} ...', file=sys.stderr, flush=True)
        simulate_endurance(path, seconds, seed=1, storage=storage, compression=compression)
    return path


def prepare(data: Path) -> dict:
    """The hour in time order, reversed, shuffled and one message per chunk: {label: path}."""
    sys.path.insert(0, str(ROOT / 'test' / 'support'))
    import numpy as np
    import bagfactory
    (plain,) = sorted(endurance_bag(data, 3600.0).glob('*.mcap'))
    files = {'time order': plain}
    for label, order in (('reversed', lambda n: range(n)[::-1]),
                         ('shuffled', np.random.default_rng(1).permutation)):
        target = data / f'endurance_3600s_{label}.mcap'
        if not target.exists():
            bagfactory.reorder_chunks(plain, target, order)
        files[label] = target
    target = data / 'endurance_3600s_one_message_per_chunk.mcap'
    if not target.exists():
        print(f'rewriting the hour with one message per chunk into {target} ...', file=sys.stderr, flush=True)
        one_message_per_chunk(plain, target)
    files['one message per chunk'] = target
    return files


def one_message_per_chunk(source: Path, target: Path):
    """Rewrite ``source`` with the ``mcap`` writer, chunks closed after every message (``chunk_size=1``)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer
    with open(source, 'rb') as stream_in, open(target, 'wb') as stream_out:
        reader = make_reader(stream_in)
        summary = reader.get_summary()
        writer = Writer(stream_out, chunk_size=1, compression=CompressionType.NONE)
        writer.start('ros2', 'read_memory')
        schemas = {key: writer.register_schema(s.name, s.encoding, s.data) for key, s in summary.schemas.items()}
        channels = {key: writer.register_channel(c.topic, c.message_encoding, schemas.get(c.schema_id, 0),
                                                 c.metadata) for key, c in summary.channels.items()}
        for _, channel, message in reader.iter_messages(log_time_order=False):
            writer.add_message(channels[channel.id], message.log_time, message.data, message.publish_time,
                               message.sequence)
        writer.finish()


def main() -> int:
    """Measure, write the results, print the table."""
    if len(sys.argv) > 2 and sys.argv[1] == '--child':
        child(sys.argv[2])
        return 0
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=2)
    parser.add_argument('--data', type=Path, default=Path('/tmp/prsm_lube_bench'),
                        help='where the recordings are cached (default /tmp/prsm_lube_bench)')
    parser.add_argument('--root', type=Path, default=ROOT, help='checkout whose reader is measured')
    parser.add_argument('--out', default='read_memory', help='results file name, without suffix')
    parser.add_argument('--orders', nargs='*', help='measure only these chunk orders (labels of the table)')
    args = parser.parse_args()
    files = {label: path for label, path in prepare(args.data).items() if not args.orders or label in args.orders}
    rows = []
    for label, path in files.items():
        result = measure(path, args.repeat, args.root.resolve())
        rows.append({'chunk order': label, 'size_mib': path.stat().st_size / 2 ** 20, **result})
        print(f'{label}: {result["seconds"]:.2f} s, peak {result["peak_rss_mib"]:.0f} MiB', file=sys.stderr)
    load = os.getloadavg()[0]
    document = {'benchmark': 'read_memory', 'command': 'python benchmarks/read_memory.py',
                'machine': {'python': platform.python_version(), 'cpus': len(os.sched_getaffinity(0)),
                            'load_average_1min': load},
                'root': str(args.root), 'repeat': args.repeat, 'rows': rows}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f'{args.out}.json').write_text(json.dumps(document, indent=1))
    lines = ['# Reading one hour in any chunk order (`python benchmarks/read_memory.py`)', '',
             f'Python {document["machine"]["python"]}, {document["machine"]["cpus"]} CPUs, 1-min load '
             f'{load:.1f} at the end, best of {args.repeat} fresh processes (peak: the largest), reader of '
             f'{"this checkout" if args.root.resolve() == ROOT else args.root}.  Open + decode every slice; the '
             'checksum (sum of all decoded values) is equal when the data are.', '',
             '| chunk order | size MiB | read + decode s | peak RSS MiB | RSS after imports MiB | slices | messages '
             '| checksum | problems |', '|---|---|---|---|---|---|---|---|---|']
    for r in rows:
        lines.append(f'| {r["chunk order"]} | {r["size_mib"]:.0f} | {r["seconds"]:.2f} | {r["peak_rss_mib"]:.0f} | '
                     f'{r["rss_after_imports_mib"]:.0f} | {r["slices"]} | {r["messages"]} | {r["checksum"]:.6e} | '
                     f'{len(r["problems"])} |')
    (RESULTS / f'{args.out}.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
