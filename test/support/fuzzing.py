# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Mutations of valid recordings and what a command does with one: shared by the fuzz test and benchmark."""
from pathlib import Path
import random
import shutil
import struct

from prsm_lube_ros.recording.reader import list_topics, open_recording, raw_messages, topic_messages


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


def seed_recordings(folder: Path) -> list:
    """Small valid recordings of every container and layout the reader takes: ``[(path, kind)]``.

    ``kind`` is ``'contract'`` (the contract's topics, read end to end) or
    ``'bag:<name>'`` (one file of a rosbag2 folder: mutate it inside a copy of
    the folder).  Bare MCAP unchunked, lz4 and zstd chunks, one message per
    chunk (gathered), chunks reversed (read by seeking), a bare ``.db3``,
    and rosbag2 folders with mcap and sqlite3 storage (plain, and zstd
    message and file compression).
    """
    import bagfactory as bf
    folder.mkdir(parents=True, exist_ok=True)
    entries = bf.contract_entries(seconds=2.0, block=100)
    lz4 = bf.write_mcap_library(folder / 'lz4.mcap', entries, compression='lz4', chunk_size=4096)
    out = [(bf.write_bare_mcap(folder / 'bare.mcap', entries), 'contract'), (lz4, 'contract'),
           (bf.write_mcap_library(folder / 'zstd.mcap', entries, compression='zstd', chunk_size=4096), 'contract'),
           (bf.write_mcap_library(folder / 'tiny_chunks.mcap', entries, compression='none', chunk_size=1),
            'contract'),
           (bf.reorder_chunks(lz4, folder / 'reversed.mcap', lambda n: range(n)[::-1]), 'contract')]
    for storage, mode in (('mcap', None), ('sqlite3', None), ('sqlite3', 'message'), ('sqlite3', 'file')):
        bag = folder / f'bag_{storage}_{mode or "plain"}'
        bf.write_rosbag2(bag, entries, storage=storage, zstd=mode is not None, zstd_mode=mode or 'storage')
        for file in sorted(p for p in bag.iterdir() if p.suffix in ('.mcap', '.db3', '.yaml', '.zstd')):
            out.append((file, f'bag:{bag.name}'))
    db3 = next((folder / 'bag_sqlite3_plain').glob('*.db3'))
    out.append((Path(shutil.copy(db3, folder / 'bare.db3')), 'contract'))
    return out


def seed_calibration(path: Path) -> Path:
    """A valid calibration file fitted to noisy Eq. 22 amplitudes at three speeds and two loads."""
    import numpy as np
    from prsm_lube_ros.estimation.calibration import fit_constants
    from prsm_lube_ros.estimation.calibration_file import save_calibration
    speed = np.repeat([10.0, 15.0, 20.0], 20)
    load = np.tile(np.repeat([100.0, 200.0], 10), 3)
    rms = 0.08 * speed ** 2 * load ** (-1 / 3) * np.exp(1e-3 * load - 0.3 * speed ** 0.68 * load ** -0.073)
    save_calibration(fit_constants(speed, load, rms * np.exp(np.random.default_rng(1).normal(0, 0.01, rms.size)),
                                   1.0), path)
    return path


def exercise(path: Path, contract: bool):
    """Everything a command does with a recording; returns normally or raises InputError."""
    if path.is_file() and path.suffix == '.mcap':
        list(raw_messages(path))
    list(topic_messages(path))
    list_topics(path)
    if contract:
        recording = open_recording(path)
        recording.describe()
        for _ in recording.slices(on_problem=lambda line: None):
            pass
