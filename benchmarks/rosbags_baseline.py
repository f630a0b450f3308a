#!/usr/bin/env python3
# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The obvious alternative to ``prsm-lube assess``: a short rosbags script (one RMS per second, nothing else).

Usage: ``python benchmarks/rosbags_baseline.py BAG``.  It reads every
``/prsm/vibration`` message with rosbags, deserializes it and prints the RMS
of each second: less than assessment does (no speed, load, runs or theta).
"""
from pathlib import Path
import sys

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.typesys import get_types_from_msg, get_typestore, Stores

store = get_typestore(Stores.ROS2_JAZZY)
definition = (Path(__file__).resolve().parents[1] / 'msg' / 'VibrationBlock.msg').read_text()
store.register(get_types_from_msg(definition, 'prsm_lube_ros/msg/VibrationBlock'))
sums, counts = {}, {}
with AnyReader([Path(sys.argv[1])], default_typestore=store) as reader:
    connections = [c for c in reader.connections if c.topic == '/prsm/vibration']
    for connection, _, raw in reader.messages(connections=connections):
        msg = reader.deserialize(raw, connection.msgtype)
        second = msg.header.stamp.sec
        sums[second] = sums.get(second, 0.0) + float(np.dot(msg.samples, msg.samples))
        counts[second] = counts.get(second, 0) + msg.samples.size
print(len(sums), 'seconds, mean RMS', np.mean([np.sqrt(sums[s] / counts[s]) for s in sums]))
