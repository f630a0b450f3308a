#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Long fuzz run: mutated recordings and calibration files, each read as assess and calibrate read them.

Seeds are small valid files of every container and layout the reader takes
(``test/support/fuzzing.py`` ``seed_recordings``: bare MCAP unchunked, with
lz4 and zstd chunks, one message per chunk, chunks reversed, a bare ``.db3``,
rosbag2 folders with mcap and sqlite3 storage), two rig-simulator recordings
of 2 speeds x 2 loads as the simulator writes them (chunk CRC 0, sqlite3
blobs: no checksums; ``seed_simulated``), the MCAP conformance files, and a
calibration YAML.  Mutation kinds, in turn (``fuzzing.mutate_as``):

* ``random``: flipped bytes, a truncation, an overwritten 64/32-bit value;
* ``chunk_length``: a record length inside a chunk (its CRC cleared);
* ``opcode``: a DataEnd/Footer or other opcode in the middle of the data or of a chunk;
* ``sample_rate``, ``sample_count``: a VibrationBlock header field (1e-6 Hz, NaN, 2**32 - 1 samples ...);
* ``sample_value``: a vibration sample no accelerometer gives (3e36 m/s^2, NaN ...);
* ``index_time``: a MessageIndex or ChunkIndex time;
* ``calibration_structure``, ``calibration_value``: nesting 5,000 deep, alias bombs,
  wrong types; NaN, inf, signs, C_sys x 1e-6 ...

Each mutant is read as ``assess`` and ``calibrate`` read it (windows,
theta_Oil of every run, constants) and compared with its clean file.
Outcomes: ``refused`` (one InputError line naming the file), ``warned`` (read,
with problem lines), ``same`` (read in silence, the clean file's result),
``undetectable`` (read in silence, different, but nothing a reader can
detect: only sensor values within the sensors' range, or stamps by less than
a second, changed in a file without checksums; or a valid MCAP file, which
the ``mcap`` library reads, CRCs checked, with the messages read here), and
the failures: ``silent_difference`` (read in silence, a different result
otherwise), ``traceback``, ``unnamed_refusal`` (a refusal
not naming the file), ``numpy_warning`` (a RuntimeWarning reached the user),
``hang`` (past the time limit), ``memory`` (past the address-space limit).
Peak resident memory of each worker is measured.

Usage: ``python benchmarks/fuzz_recordings.py [--mutations 10000] [--seed 1] [--jobs 1]``;
results in ``benchmarks/results/fuzz_recordings.{json,md}``.

``--hostile N`` runs N cases of the hostile kinds instead (issue 36,
``benchmarks/hostile_cases.py``: special files, links out of the allowed root
inside bag folders, size bounds, truncated calibrations, concurrent history
writers, full disks, a FIFO sent to the calibrate service's request path),
each in a worker with the same time and address-space limits; results in
``benchmarks/results/fuzz_hostile.{json,md}`` (0 tracebacks, 0 escapes, 0
wedged, peak memory).
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
import warnings

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / 'test' / 'support'))
sys.path.insert(0, str(ROOT / 'benchmarks'))
RESULTS = ROOT / 'benchmarks' / 'results'
CONFORMANCE = ROOT / 'test' / 'data' / 'conformance' / 'mcap'
#: Per-mutation limits: seconds and address space (bytes).
TIME_LIMIT = 30
MEMORY_LIMIT = 1 << 31
#: The bound the issue sets on the peak resident memory of a worker, bytes.
MEMORY_GOAL = 500 << 20
FAILURES = ('silent_difference', 'traceback', 'unnamed_refusal', 'numpy_warning', 'hang', 'memory')
OUTCOMES = ('refused', 'warned', 'same', 'undetectable') + FAILURES


def seeds(folder: Path) -> list[tuple[Path, str]]:
    """(path, kind) of every seed file, the recordings 4 times and the calibration 16 times (mutated that often).

    kind is 'contract', 'bag:<folder>', 'mcap' or 'calibration'.
    """
    from fuzzing import seed_calibration, seed_recordings, seed_simulated
    recordings = seed_recordings(folder) + seed_simulated(folder / 'simulated')
    out = recordings * 4 + [(p, 'mcap') for p in sorted(CONFORMANCE.glob('*/*.mcap'))[::8]]
    return out + [(seed_calibration(folder / 'calibration.yaml'), 'calibration')] * 16


def _alarm(signum, frame):
    raise TimeoutError


_STATE: dict = {}


def _start_worker(calibration_path: str):
    """Worker set-up: the address-space limit, and the clean results (computed once per seed, lazily)."""
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    _STATE['calibration'] = load_calibration(calibration_path)
    _STATE['clean'] = {}


def _placed(source: Path, kind: str, work: Path, data: bytes) -> Path:
    """Write ``data`` as a copy of ``source`` in ``work`` (a bag seed: inside a copy of its folder); the path."""
    if kind.startswith('bag:'):
        bag = work / 'bag'
        shutil.copytree(source.parent, bag)
        (bag / source.name).write_bytes(data)
        return bag
    target = work / source.name
    target.write_bytes(data)
    return target


def _clean(source: Path, kind: str, contract: bool):
    """The clean seed's result and decoded inputs (cached per worker)."""
    key = str(source)
    if key not in _STATE['clean']:
        from fuzzing import command_result, decoded_inputs
        work = Path(tempfile.mkdtemp(prefix='fuzz_clean_'))
        try:
            path = _placed(source, kind, work, source.read_bytes())
            problems, result = command_result(path, contract, _STATE['calibration'])
            inputs = decoded_inputs(path) if contract else None
            _STATE['clean'][key] = (result, inputs)
        finally:
            shutil.rmtree(work, ignore_errors=True)
    return _STATE['clean'][key]


def run_one(job: tuple[str, str, int, int, str]) -> tuple[str, str, str, int]:
    """Mutate one seed and read it in this worker: (outcome, mutation kind, detail, peak RSS in bytes)."""
    from fuzzing import (command_result, decoded_inputs, mutate_as, only_payloads_differ, only_values_differ,
                         same_result, valid_to_the_reference)
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.estimation.calibration_file import load_calibration
    source, kind, seed, index, how = job
    source = Path(source)
    rng = random.Random(seed * 1_000_003 + index)
    contract = kind == 'contract' or kind.startswith('bag:')
    work = Path(tempfile.mkdtemp(prefix='fuzz_'))
    label = f'{kind} {source.name} #{index}'
    try:
        signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(TIME_LIMIT)
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter('always')
                clean = _clean(source, kind, contract) if kind != 'calibration' else None
                mutant, how = mutate_as(source.read_bytes(), rng, how)
                path = _placed(source, kind, work, mutant)
                label = f'{how} of {label}'
                try:
                    if kind == 'calibration':
                        load_calibration(path)
                        outcome, detail = 'same', ''
                    else:
                        problems, result = command_result(path, contract, _STATE['calibration'])
                        if problems:
                            outcome, detail = 'warned', ''
                        elif same_result(result, clean[0]) if contract else result == clean[0]:
                            outcome, detail = 'same', ''
                        elif (only_values_differ(clean[1], decoded_inputs(path)) if contract
                              else only_payloads_differ(clean[0], result)) or valid_to_the_reference(path):
                            outcome, detail = 'undetectable', label
                        else:
                            outcome, detail = 'silent_difference', label
                except InputError as err:
                    text = str(err)
                    if '\n' in text:
                        outcome, detail = 'traceback', f'{label}: multi-line error: {text!r}'
                    elif str(path) not in text and str(path.parent) not in text:
                        outcome, detail = 'unnamed_refusal', f'{label}: {text}'
                    else:
                        outcome, detail = 'refused', ''
            numpy_warnings = [w for w in caught if issubclass(w.category, RuntimeWarning)]
            if numpy_warnings and outcome not in FAILURES:
                outcome, detail = 'numpy_warning', f'{label}: {numpy_warnings[0].message}'
        except TimeoutError:
            outcome, detail = 'hang', label
        except MemoryError:
            outcome, detail = 'memory', label
        except Exception as err:  # the bug this benchmark looks for
            outcome, detail = 'traceback', f'{label}: {type(err).__name__}: {err}'[:300]
        finally:
            signal.alarm(0)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return outcome, how, detail, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def hostile_seeds(folder: Path) -> dict:
    """What the hostile cases copy: a contract bag, a calibratable bag, a calibration, a 300 M-row Parquet file."""
    import bagfactory as bf
    import pyarrow as pa
    import pyarrow.parquet as pq
    from fuzzing import seed_calibration, seed_simulated
    folder.mkdir(parents=True, exist_ok=True)
    bag = bf.write_rosbag2(folder / 'bag', bf.contract_entries(seconds=2.0, block=100))
    simulated = next(path for path, kind in seed_simulated(folder / 'simulated') if kind.startswith('bag:')).parent
    pq.write_table(pa.table({'x': pa.nulls(300_000_000)}), folder / 'huge_rows.parquet')
    return {'bag': str(bag), 'calibratable': str(simulated), 'calibration': str(seed_calibration(folder / 'c.yaml')),
            'huge_parquet': str(folder / 'huge_rows.parquet')}


def run_hostile(job: tuple[dict, str, int, int]) -> tuple[str, str, str, int]:
    """One hostile case in this worker: (outcome, kind, detail, peak RSS of the worker and its children)."""
    import hostile_cases
    seeds, kind, seed, index = job
    work = Path(tempfile.mkdtemp(prefix='hostile_'))
    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(TIME_LIMIT * 4)
    try:
        outcome, detail = hostile_cases.CASES[kind](work, seeds, random.Random(seed * 1_000_003 + index))
    except TimeoutError:
        outcome, detail = 'wedged', 'past the time limit'
    except MemoryError:
        outcome, detail = 'memory', ''
    except Exception as err:  # the bug this benchmark looks for
        outcome, detail = 'traceback', f'{type(err).__name__}: {err}'[:300]
    finally:
        signal.alarm(0)
        shutil.rmtree(work, ignore_errors=True)
    peak = max(resource.getrusage(who).ru_maxrss for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return outcome, kind, f'{kind} #{index}: {detail}' if detail else '', peak * 1024


def hostile_main(args: argparse.Namespace) -> int:
    """Run ``args.hostile`` hostile cases, write fuzz_hostile.{json,md}; exit 1 on a failure or memory over goal."""
    import hostile_cases
    folder = Path(tempfile.mkdtemp(prefix='hostile_seeds_'))
    seeds = hostile_seeds(folder)
    kinds = hostile_cases.KINDS
    jobs = [(seeds, kinds[i % len(kinds)], args.seed, i) for i in range(args.hostile)]
    counts: dict[str, int] = {}
    by_kind: dict[str, dict[str, int]] = {}
    examples: dict[str, list[str]] = {}
    peak = 0
    start = time.perf_counter()
    with ProcessPoolExecutor(args.jobs, initializer=_limit_memory) as pool:
        for outcome, kind, detail, rss in pool.map(run_hostile, jobs):
            counts[outcome] = counts.get(outcome, 0) + 1
            by_kind.setdefault(kind, {})[outcome] = by_kind.get(kind, {}).get(outcome, 0) + 1
            peak = max(peak, rss)
            if detail and len(examples.setdefault(outcome, [])) < 10:
                examples[outcome].append(detail)
    elapsed = time.perf_counter() - start
    shutil.rmtree(folder, ignore_errors=True)
    failures = ('traceback', 'escape', 'silent', 'damaged_output', 'unnamed_refusal', 'wedged', 'memory')
    document = {'benchmark': 'fuzz_hostile', 'command': f'python benchmarks/fuzz_recordings.py --hostile '
                f'{args.hostile} --seed {args.seed} --jobs {args.jobs}', 'cases': args.hostile, 'seconds': elapsed,
                'limits': {'seconds_per_case': TIME_LIMIT * 4, 'address_space_bytes': MEMORY_LIMIT,
                           'request_seconds': hostile_cases.WEDGE_SECONDS},
                'peak_rss_bytes': peak, 'memory_goal_bytes': MEMORY_GOAL, 'counts': counts, 'by_kind': by_kind,
                'examples': examples}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'fuzz_hostile.json').write_text(json.dumps(document, indent=1))
    outcomes = ('refused', 'ok') + failures
    lines = [f'# Hostile inputs (`{document["command"]}`)', '',
             f'{args.hostile} cases of {len(kinds)} kinds (benchmarks/hostile_cases.py), {elapsed:.0f} s; a request '
             f'that takes over {hostile_cases.WEDGE_SECONDS:g} s counts as wedged; peak resident memory of a worker '
             f'or a process it started {peak / 2**20:.0f} MiB (goal < {MEMORY_GOAL >> 20} MiB).', '',
             '| outcome | count | ' + ' | '.join(kinds) + ' |', '|---|---|' + '---|' * len(kinds)]
    lines += [f'| {k} | {counts.get(k, 0)} | ' + ' | '.join(str(by_kind.get(h, {}).get(k, 0)) for h in kinds) + ' |'
              for k in outcomes]
    for outcome, items in examples.items():
        lines += ['', f'{outcome}:'] + [f'- {item}' for item in items]
    (RESULTS / 'fuzz_hostile.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 1 if any(counts.get(k) for k in failures) or peak > MEMORY_GOAL else 0


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def jobs_for(files: list[tuple[Path, str]], mutations: int, seed: int) -> list[tuple]:
    """Mutation ``i`` of seed file ``i mod n``, of the kinds that file type takes in turn."""
    from fuzzing import CALIBRATION_KINDS, RECORDING_KINDS
    out = []
    for i in range(mutations):
        path, kind = files[i % len(files)]
        kinds = CALIBRATION_KINDS if kind == 'calibration' else RECORDING_KINDS
        out.append((str(path), kind, seed, i, kinds[(i // len(files)) % len(kinds)]))
    return out


def main() -> int:
    """Run the mutations, write the counts, exit 1 on any failure outcome or a worker over the memory goal."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--mutations', type=int, default=10000)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--jobs', type=int, default=1, help='worker processes (default 1)')
    parser.add_argument('--hostile', type=int, default=0, metavar='N',
                        help='run N cases of the hostile kinds (benchmarks/hostile_cases.py) instead of mutations')
    args = parser.parse_args()
    if args.hostile:
        return hostile_main(args)
    folder = Path(tempfile.mkdtemp(prefix='fuzz_seeds_'))
    files = seeds(folder)
    calibration = next(str(path) for path, kind in files if kind == 'calibration')
    jobs = jobs_for(files, args.mutations, args.seed)
    counts: dict[str, int] = {}
    by_kind: dict[str, dict[str, int]] = {}
    examples: dict[str, list[str]] = {}
    peak = 0
    start = time.perf_counter()
    with ProcessPoolExecutor(args.jobs, initializer=_start_worker, initargs=(calibration,)) as pool:
        for outcome, how, detail, rss in pool.map(run_one, jobs, chunksize=8):
            counts[outcome] = counts.get(outcome, 0) + 1
            row = by_kind.setdefault(how, {})
            row[outcome] = row.get(outcome, 0) + 1
            peak = max(peak, rss)
            if detail and len(examples.setdefault(outcome, [])) < 20:
                examples[outcome].append(detail)
    elapsed = time.perf_counter() - start
    shutil.rmtree(folder, ignore_errors=True)
    document = {'benchmark': 'fuzz_recordings', 'command': 'python benchmarks/fuzz_recordings.py',
                'mutations': args.mutations, 'seed': args.seed, 'jobs': args.jobs, 'seconds': elapsed,
                'limits': {'seconds_per_mutation': TIME_LIMIT, 'address_space_bytes': MEMORY_LIMIT},
                'peak_worker_rss_bytes': peak, 'memory_goal_bytes': MEMORY_GOAL,
                'seed_files': len(files), 'counts': counts, 'by_kind': by_kind, 'examples': examples}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'fuzz_recordings.json').write_text(json.dumps(document, indent=1))
    kinds = sorted(by_kind)
    lines = ['# Fuzzing recordings and calibration files (`python benchmarks/fuzz_recordings.py`)', '',
             f'{args.mutations} mutations of {len(files)} seed files, seed {args.seed}, {args.jobs} worker(s), '
             f'{elapsed:.0f} s; limits {TIME_LIMIT} s and {MEMORY_LIMIT >> 30} GiB address space per mutation; '
             f'peak resident memory of a worker {peak / 2**20:.0f} MiB (goal < {MEMORY_GOAL >> 20} MiB).', '',
             '| outcome | count | ' + ' | '.join(kinds) + ' |', '|---|---|' + '---|' * len(kinds)]
    lines += [f'| {k} | {counts.get(k, 0)} | ' + ' | '.join(str(by_kind[h].get(k, 0)) for h in kinds) + ' |'
              for k in OUTCOMES]
    for outcome, items in examples.items():
        lines += ['', f'{outcome}:'] + [f'- {item}' for item in items]
    (RESULTS / 'fuzz_recordings.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 1 if any(counts.get(k) for k in FAILURES) or peak > MEMORY_GOAL else 0


if __name__ == '__main__':
    sys.exit(main())
