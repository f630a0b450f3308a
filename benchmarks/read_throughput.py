#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Micro benchmark of the recording reader on a one-hour, 4 kHz recording.

The recording (written once with rosbags' Writer, storage mcap, its defaults:
1 MiB chunks, no compression; ``--zstd`` writes chunk-compressed storage):
36,000 VibrationBlocks of 400 float32 samples, JointState at 100 Hz,
WrenchStamped at 50 Hz, Temperature at 1 Hz.  Timed, best of ``--repeat``:

* ``file read``: the file's bytes into memory, nothing else;
* ``bare read``: :func:`prsm_lube_ros.recording.reader.bare_read` -- every chunk read,
  decompressed and split into messages, no decoding;
* ``open``: :func:`open_recording` (summary, layouts);
* ``decode``: open + every slice of :meth:`Recording.slices`, all values decoded.

Usage: ``python benchmarks/read_throughput.py [--path /tmp/prsm_hour.mcap] [--zstd] [--repeat 5]``
"""
from __future__ import annotations

import argparse
from pathlib import Path
import shutil
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test' / 'support'))

import bagfactory  # noqa: E402  (test helper: writes contract recordings)
from prsm_lube_ros.recording.reader import bare_read, open_recording  # noqa: E402
from prsm_lube_ros.contract import VIBRATION_BLOCK  # noqa: E402

HOUR = 3600.0


def write_hour(path: Path, zstd: bool):
    """One hour of the contract's topics at 4 kHz (synthetic signal), streamed to the writer."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode
    store = bagfactory.typestore()
    rng = np.random.default_rng(1)
    rates = {'vibration': 10.0, 'joint_states': 100.0, 'axial_load': 50.0, 'temperature': 1.0}
    types = {'vibration': VIBRATION_BLOCK, 'joint_states': 'sensor_msgs/msg/JointState',
             'axial_load': 'geometry_msgs/msg/WrenchStamped', 'temperature': 'sensor_msgs/msg/Temperature'}
    events = []
    for topic, rate in rates.items():
        n = int(HOUR * rate)
        events.append(np.stack([np.arange(n) / rate, np.full(n, list(rates).index(topic)), np.arange(n)], 1))
    events = np.concatenate(events)
    events = events[np.lexsort((events[:, 1], events[:, 0]))]
    with tempfile.TemporaryDirectory(dir=path.parent) as scratch:
        bag = Path(scratch) / 'hour'
        writer = Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP)
        if zstd:
            writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        with writer:
            connections = {topic: writer.add_connection(f'/prsm/{topic}', types[topic], typestore=store)
                           for topic in rates}
            names = list(rates)
            for seconds, which, index in events:
                topic, index = names[int(which)], int(index)
                if topic == 'vibration':
                    message = bagfactory.vibration_message(store, VIBRATION_BLOCK, index)
                    message.samples[:] = rng.normal(0.0, 1.0, 400).astype(np.float32)
                elif topic == 'joint_states':
                    message = bagfactory.joint_message(store, index)
                elif topic == 'axial_load':
                    message = bagfactory.wrench_message(store, index)
                else:
                    message = bagfactory.temperature_message(store, index)
                log_time = bagfactory.T0_SEC * 10**9 + int(round(seconds * 1e9)) + 1000
                writer.write(connections[topic], log_time, store.serialize_cdr(message, types[topic]))
        shutil.move(str(bag / 'hour.mcap'), path)


def best_of(repeat: int, function):
    """Minimum wall time of ``repeat`` calls, and the last result."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def decode_all(path: Path):
    """Open and decode every slice; returns (messages, samples)."""
    messages = samples = 0
    for batches in open_recording(path).slices():
        for batch in batches:
            messages += len(batch)
            samples += getattr(batch, 'samples', np.empty(0)).size
    return messages, samples


def main(argv=None):
    """Run the benchmark and print one line per measurement."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--path', type=Path, default=None)
    parser.add_argument('--zstd', action='store_true', help='chunk compression zstd (default: none)')
    parser.add_argument('--repeat', type=int, default=5)
    args = parser.parse_args(argv)
    path = args.path or Path(tempfile.gettempdir()) / ('prsm_hour_zstd.mcap' if args.zstd else 'prsm_hour.mcap')
    if not path.exists():
        print(f'writing {path} (one hour at 4 kHz) ...', flush=True)
        start = time.perf_counter()
        write_hour(path, args.zstd)
        print(f'  written in {time.perf_counter() - start:.1f} s', flush=True)
    size = path.stat().st_size
    print(f'{path}: {size / 1e6:.1f} MB')
    file_time, _ = best_of(args.repeat, lambda: len(path.read_bytes()))
    bare_time, count = best_of(args.repeat, lambda: bare_read(path))
    open_time, _ = best_of(args.repeat, lambda: open_recording(path))
    decode_time, (messages, samples) = best_of(args.repeat, lambda: decode_all(path))
    print(f'file read   {file_time * 1e3:8.1f} ms')
    print(f'bare read   {bare_time * 1e3:8.1f} ms  ({count} messages)')
    print(f'open        {open_time * 1e3:8.1f} ms')
    print(f'decode      {decode_time * 1e3:8.1f} ms  ({messages} messages, {samples} samples) '
          f'= {HOUR / decode_time:,.0f}x real time, {decode_time / bare_time:.2f}x bare read')


if __name__ == '__main__':
    main()
