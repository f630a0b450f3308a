#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""CPU per input message on the estimator's input path: rclpy's message against the raw CDR decode.

The live estimator's CPU goes mostly to rclpy (taking and deserializing
messages) rather than to the windows.  This measures the part of it the raw
subscription changes, without DDS timing, so it holds on a loaded machine: for
a 4 kHz block of 0.1 s (400 float32 samples), the time to turn its serialized
bytes into the window builder's batch, (a) as before: ``deserialize_message``
(what rclpy does for a typed subscription) and
``ros_convert.vibration_batch``; (b) as now: ``raw_inputs.decode_block`` on
the bytes a ``raw=True`` subscription hands over, and the one-block batch.
The same for a ``JointState`` (the ``screw`` entry: ``screw_batch`` against
``raw_screw_converter``) and a ``WrenchStamped`` (``load_batch`` against
``raw_load_converter``), of which an actuator sends 100 and 50 a second
against 10 blocks.  The paths alternate, ``--rounds`` times, each round timing
``--blocks`` messages (process CPU time); the medians, their ratios and the CPU
per actuator-second they add up to are printed and written to
``benchmarks/results/input_decode.{json,md}``.

Usage: ``python benchmarks/input_decode.py [--blocks 20000] [--rounds 7] [--samples 400]``
(after ``source .env-jazzy.sh``).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path
import platform
import statistics
import sys
import time

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / 'benchmarks' / 'results'


def main() -> int:
    """Alternate the two paths, print and write the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--blocks', type=int, default=20000, help='messages timed per round and input')
    parser.add_argument('--rounds', type=int, default=7)
    parser.add_argument('--samples', type=int, default=400, help='samples per block (400: 0.1 s at 4 kHz)')
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    import numpy as np
    from rclpy.serialization import deserialize_message, serialize_message
    from prsm_lube_ros.msg import VibrationBlock
    from geometry_msgs.msg import WrenchStamped
    from sensor_msgs.msg import JointState
    from prsm_lube_ros.nodes.raw_inputs import decode_block, raw_load_converter, raw_screw_converter
    from prsm_lube_ros.nodes.ros_convert import (joint_state_msg, load_batch, screw_batch, vibration_batch,
                                                 vibration_block_msg, wrench_msg)
    from prsm_lube_ros.recording.batches import VibrationBatch

    samples = np.random.default_rng(0).normal(size=args.samples).astype(np.float32)
    data = serialize_message(vibration_block_msg(1_700_000_000.1, 4000.0, samples, frame_id='nut_accel'))

    def typed() -> VibrationBatch:
        return vibration_batch(deserialize_message(data, VibrationBlock), '/prsm/vibration')

    def raw() -> VibrationBatch:
        block = decode_block(data, '/prsm/vibration')
        return VibrationBatch.single(block.stamp, block.sample_rate, block.samples)

    first, second = typed(), raw()
    assert first.stamps[0] == second.stamps[0] and np.array_equal(first.samples, second.samples)
    joint_data = serialize_message(joint_state_msg(1_700_000_000.01, 1.25, 20.0))
    load_data = serialize_message(wrench_msg(1_700_000_000.02, -150.0))
    screw, load = raw_screw_converter('/prsm/joint_states', 'screw'), raw_load_converter('/prsm/axial_load')
    #: input: (messages per actuator-second, typed path, raw path)
    inputs = {'vibration block': (10, typed, raw),
              'joint state': (100, lambda: screw_batch(deserialize_message(joint_data, JointState)),
                              lambda: screw(joint_data)),
              'axial load': (50, lambda: load_batch(deserialize_message(load_data, WrenchStamped)),
                             lambda: load(load_data))}
    times: dict[str, dict[str, list[float]]] = {name: {'typed': [], 'raw': []} for name in inputs}
    for _ in range(args.rounds):
        for name, (_, typed_path, raw_path) in inputs.items():
            for kind, path in (('typed', typed_path), ('raw', raw_path)):
                start = time.process_time()
                for _ in range(args.blocks):
                    path()
                times[name][kind].append((time.process_time() - start) / args.blocks)
    medians = {name: {kind: statistics.median(values) for kind, values in paths.items()}
               for name, paths in times.items()}
    per_actuator = {kind: sum(inputs[name][0] * medians[name][kind] for name in inputs) for kind in ('typed', 'raw')}
    document = {'benchmark': 'input_decode', 'command': 'python benchmarks/input_decode.py '
                + ' '.join(sys.argv[1:]), 'python': platform.python_version(), 'samples_per_block': args.samples,
                'us_per_message': {name: {kind: 1e6 * v for kind, v in paths.items()}
                                   for name, paths in medians.items()},
                'rounds_us': {name: {kind: [1e6 * v for v in values] for kind, values in paths.items()}
                              for name, paths in times.items()},
                'ms_per_actuator_second': {kind: 1e3 * value for kind, value in per_actuator.items()}}
    lines = [f'# Input message to batch, CPU per message (`{document["command"]}`)', '',
             f'Python {document["python"]}; {args.samples} float32 samples a block; process CPU time, median of '
             f'{args.rounds} alternating rounds of {args.blocks} messages.', '',
             '| input | per actuator-second | typed message us | raw CDR us | typed / raw |', '|---|---|---|---|---|']
    lines += [f'| {name} | {inputs[name][0]} | {1e6 * m["typed"]:.1f} | {1e6 * m["raw"]:.1f} | '
              f'{m["typed"] / m["raw"]:.1f} |' for name, m in medians.items()]
    lines += ['', f'Per actuator-second: {1e3 * per_actuator["typed"]:.2f} ms typed, '
              f'{1e3 * per_actuator["raw"]:.2f} ms raw (the conversion only; taking the message from the queue '
              'comes on top of both).']
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / 'input_decode.json').write_text(json.dumps(document, indent=1))
    (RESULTS / 'input_decode.md').write_text('\n'.join(lines) + '\n')
    print('\n'.join(lines))
    return 0


if __name__ == '__main__':
    sys.exit(main())
