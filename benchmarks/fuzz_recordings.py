#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Long fuzz run: mutated recordings and calibration files, each in a bounded child, counted by outcome.

Seeds are small valid files of every container and layout the reader takes
(``test/support/fuzzing.py`` ``seed_recordings``: bare MCAP unchunked, with
lz4 and zstd chunks, one message per chunk, chunks reversed, a bare ``.db3``,
rosbag2 folders with mcap and sqlite3 storage), the MCAP conformance files,
and calibration YAML.  Each
mutation (byte flips, truncation, overwritten 64/32-bit values, mostly
lengths: ``test/support/fuzzing.py``) is read as a command would read it.  An
outcome is ``read`` (data or problem lines), ``refused`` (one InputError
line), ``traceback`` (any other exception: a bug), ``hang`` (past the time
limit) or ``memory`` (past the address-space limit: an allocation the file
cannot justify).  Mutations run in worker processes with ``RLIMIT_AS``.

Usage: ``python benchmarks/fuzz_recordings.py [--mutations 10000] [--seed 1]``;
results in ``benchmarks/results/fuzz_recordings.{json,md}``.
"""
from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
import json
from pathlib import Path
import random
import resource
import shutil
import signal
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'test' / 'support'))
RESULTS = ROOT / 'benchmarks' / 'results'
CONFORMANCE = ROOT / 'test' / 'data' / 'conformance' / 'mcap'
#: Per-mutation limits: seconds and address space (bytes).
TIME_LIMIT = 20
MEMORY_LIMIT = 1 << 31


def seeds(folder: Path) -> list[tuple[Path, str]]:
    """(path, kind) of every seed file; kind is 'contract', 'mcap' or 'calibration'."""
    from fuzzing import seed_calibration, seed_recordings
    out = seed_recordings(folder)
    out += [(p, 'mcap') for p in sorted(CONFORMANCE.glob('*/*.mcap'))[::8]]
    out.append((seed_calibration(folder / 'calibration.yaml'), 'calibration'))
    return out


def _alarm(signum, frame):
    raise TimeoutError


def run_one(job: tuple[str, str, int, int]) -> tuple[str, str]:
    """Mutate one seed and read it in this worker; (outcome, detail)."""
    from fuzzing import exercise, mutate
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    source, kind, seed, index = job
    rng = random.Random(seed * 1_000_003 + index)
    work = Path(tempfile.mkdtemp(prefix='fuzz_'))
    try:
        if kind.startswith('bag:'):
            bag = work / 'bag'
            shutil.copytree(Path(source).parent, bag)
            target = bag / Path(source).name
            target.write_bytes(mutate(Path(source).read_bytes(), rng))
            path, contract = bag, True
        else:
            target = work / Path(source).name
            target.write_bytes(mutate(Path(source).read_bytes(), rng))
            path, contract = target, kind == 'contract'
        signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(TIME_LIMIT)
        try:
            if kind == 'calibration':
                load_calibration(path)
            else:
                exercise(path, contract)
            return 'read', ''
        except InputError as err:
            return ('refused', '') if '\n' not in str(err) else ('traceback', f'multi-line error: {err!r}')
        except TimeoutError:
            return 'hang', f'{kind} {Path(source).name} #{index}'
        except MemoryError:
            return 'memory', f'{kind} {Path(source).name} #{index}'
        except Exception as err:  # the bug this benchmark looks for
            return 'traceback', f'{kind} {Path(source).name} #{index}: {type(err).__name__}: {err}'[:300]
        finally:
            signal.alarm(0)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _limit_memory():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def main() -> int:
    """Run the mutations, write the counts, exit 1 if any traceback, hang or memory blow-up."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--mutations', type=int, default=10000)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--workers', type=int, default=2)
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix='fuzz_seeds_'))
    files = seeds(folder)
    jobs = [(str(files[i % len(files)][0]), files[i % len(files)][1], args.seed, i) for i in range(args.mutations)]
    counts: dict[str, int] = {}
    examples: dict[str, list[str]] = {}
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers, initializer=_limit_memory) as pool:
        for outcome, detail in pool.map(run_one, jobs, chunksize=16):
            counts[outcome] = counts.get(outcome, 0) + 1
            if detail and len(examples.setdefault(outcome, [])) < 20:
                examples[outcome].append(detail)
    elapsed = time.perf_counter() - start
    shutil.rmtree(folder, ignore_errors=True)
    document = {'benchmark': 'fuzz_recordings', 'command': 'python benchmarks/fuzz_recordings.py',
                'mutations': args.mutations, 'seed': args.seed, 'seconds': elapsed,
                'limits': {'seconds_per_mutation': TIME_LIMIT, 'address_space_bytes': MEMORY_LIMIT},
                'seed_files': len(files), 'counts': counts, 'examples': examples}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'fuzz_recordings.json').write_text(json.dumps(document, indent=1))
    lines = ['# Fuzzing recordings and calibration files (`python benchmarks/fuzz_recordings.py`)', '',
             f'{args.mutations} mutations of {len(files)} seed files, seed {args.seed}, {elapsed:.0f} s; '
             f'limits {TIME_LIMIT} s and {MEMORY_LIMIT >> 30} GiB address space per mutation.', '',
             '| outcome | count |', '|---|---|']
    lines += [f'| {k} | {counts.get(k, 0)} |' for k in ('read', 'refused', 'traceback', 'hang', 'memory')]
    for outcome, items in examples.items():
        lines += ['', f'{outcome}:'] + [f'- {item}' for item in items]
    (RESULTS / 'fuzz_recordings.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 1 if any(counts.get(k) for k in ('traceback', 'hang', 'memory')) else 0


if __name__ == '__main__':
    sys.exit(main())
