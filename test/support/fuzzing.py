# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Mutations of valid recordings and what a command does with one: shared by the fuzz test and benchmark."""
from pathlib import Path
import random
import struct

from prsm_lube_ros.recording.reader import list_topics, open_recording, raw_messages


def mutate(data: bytes, rng: random.Random) -> bytes:
    """One of: flipped bytes, a truncation, or an overwritten uint64/uint32 (a length, mostly)."""
    data = bytearray(data)
    how = rng.randrange(4)
    if how == 0:
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    elif how == 1:
        del data[rng.randrange(len(data)):]
    elif how == 2 and len(data) > 8:
        value = rng.choice([0, 1, 2**63 - 1, 2**63, 2**64 - 1, len(data), len(data) - rng.randrange(64),
                            rng.getrandbits(64)])
        data[rng.randrange(len(data) - 8):][:8] = struct.pack('<Q', value)
    elif len(data) > 4:
        at = rng.randrange(len(data) - 4)
        data[at:at + 4] = struct.pack('<I', rng.choice([0, 2**32 - 1, 2**31, rng.getrandbits(32)]))
    return bytes(data)


def exercise(path: Path, contract: bool):
    """Everything a command does with a recording; returns normally or raises InputError."""
    list(raw_messages(path))
    list_topics(path)
    if contract:
        recording = open_recording(path)
        recording.describe()
        for _ in recording.slices(on_problem=lambda line: None):
            pass
