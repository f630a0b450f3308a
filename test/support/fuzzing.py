# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Mutations of valid recordings and what a command does with one: shared by the fuzz test and benchmark."""
import math
from pathlib import Path
import random
import shutil
import struct
import zlib

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


def seed_simulated(folder: Path) -> list:
    """Rig-simulator recordings of 2 speeds x 2 loads (26 s; steady windows, assessable and calibratable).

    As the simulator writes them: a bare ``.mcap`` whose chunks carry CRC 0
    and a sqlite3 bag (blobs without checksums): ``[(path, kind)]`` as
    :func:`seed_recordings` gives them.
    """
    from prsm_lube_ros.simulation.recordings import simulate_endurance
    from prsm_lube_ros.simulation.rig_config import ExperimentPlan
    rpm = 2 * math.pi / 60
    plan = ExperimentPlan(speeds=(300 * rpm, 600 * rpm), loads=(100.0, 300.0), stroke=0.1, ramp_travel=0.004,
                          standstill=0.5, rewind_speed=900 * rpm)
    folder.mkdir(parents=True, exist_ok=True)
    bare = simulate_endurance(folder / 'simulated.mcap', 26.0, plan=plan, storage='mcap-file')
    bag = simulate_endurance(folder / 'simulated_sqlite3', 26.0, plan=plan, storage='sqlite3')
    return [(bare, 'contract')] + [(file, f'bag:{bag.name}') for file in sorted(bag.glob('*.db3'))]


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


# -- targeted mutations: the kinds of damage the plain byte flips rarely reach -----------------------

#: Recording mutation kinds besides ``random`` (:func:`mutate`), and calibration ones.
RECORDING_KINDS = ('random', 'chunk_length', 'opcode', 'sample_rate', 'sample_count', 'sample_value', 'index_time')
CALIBRATION_KINDS = ('random', 'calibration_structure', 'calibration_value')
#: The vibration rate of the seeds (bagfactory and the rig simulator), as it is serialized.
_RATE = struct.pack('<d', 4000.0)
_OP_FOOTER, _OP_MESSAGE, _OP_CHUNK, _OP_MESSAGE_INDEX, _OP_CHUNK_INDEX, _OP_DATA_END = 2, 5, 6, 7, 8, 15


def mutate_as(data: bytes, rng: random.Random, kind: str) -> tuple[bytes, str]:
    """``data`` damaged as ``kind`` says; ``(mutant, kind done)`` -- ``random`` when the file has no such place."""
    if kind in ('calibration_structure', 'calibration_value'):
        return _mutate_calibration(data, rng, kind), kind
    target = {'chunk_length': _chunk_length, 'opcode': _opcode, 'sample_rate': _sample_rate,
              'sample_count': _sample_count, 'sample_value': _sample_value,
              'index_time': _index_time}.get(kind)
    mutant = target(bytearray(data), rng) if target else None
    if mutant is None:
        return mutate(data, rng), 'random'
    return bytes(mutant), kind


def _records(data, start: int, stop: int):
    """``(position, opcode, length)`` of the records in ``data[start:stop]`` that fit."""
    pos, out = start, []
    while pos + 9 <= stop:
        opcode, length = struct.unpack_from('<BQ', data, pos)
        if pos + 9 + length > stop:
            break
        out.append((pos, opcode, length))
        pos += 9 + length
    return out


def _data_records(data):
    """Top-level records of an MCAP file (empty for anything else)."""
    if not bytes(data[:8]) == b'\x89MCAP0\r\n':
        return []
    return _records(data, 8, len(data))


def _chunk_records(data, chunk_pos: int):
    """``(records_start, records_end, records)`` of an uncompressed chunk at ``chunk_pos``; None if compressed."""
    content = chunk_pos + 9      # start and end time, uncompressed size, CRC, compression name, compressed size
    name_length = struct.unpack_from('<I', data, content + 28)[0]
    name_end = content + 32 + name_length
    if name_length or name_end + 8 > len(data):
        return None
    size = struct.unpack_from('<Q', data, name_end)[0]
    start = name_end + 8
    return start, start + size, _records(data, start, start + size)


def _uncompressed_chunks(data):
    """``(chunk position, records start, records end, records)`` of every uncompressed chunk."""
    out = []
    for pos, opcode, _ in _data_records(data):
        if opcode == _OP_CHUNK:
            inner = _chunk_records(data, pos)
            if inner and inner[2]:
                out.append((pos,) + inner)
    return out


def _clear_crc(data, chunk_pos: int):
    """Set a chunk's uncompressed_crc to 0 (as the simulator's writer does): the damage must be found otherwise."""
    data[chunk_pos + 9 + 24:chunk_pos + 9 + 28] = b'\0\0\0\0'


def _chunk_length(data, rng):
    """A record length inside a chunk (CRC cleared), or a top-level one when there is no plain chunk."""
    chunks = _uncompressed_chunks(data)
    if chunks:
        chunk_pos, start, stop, records = rng.choice(chunks)
        _clear_crc(data, chunk_pos)
        pos, _, length = rng.choice(records)
        room = stop - pos - 9
    else:
        records = [r for r in _data_records(data) if r[1] == _OP_MESSAGE]
        if not records:
            return None
        pos, _, length = rng.choice(records)
        room = len(data) - pos - 9
    value = rng.choice([2**64 - 1, 2**63, room + 1, length + 1, length + rng.randint(2, 4096), max(length - 1, 0),
                        rng.randrange(23), rng.getrandbits(64)])
    data[pos + 1:pos + 9] = struct.pack('<Q', value)
    return data


def _opcode(data, rng):
    """An end record (DataEnd, Footer) or another opcode in the middle: top-level, or inside a plain chunk."""
    inner = _uncompressed_chunks(data)
    top = [r for r in _data_records(data) if r[1] in (_OP_CHUNK, _OP_MESSAGE, _OP_MESSAGE_INDEX)]
    if inner and rng.random() < 0.4:
        chunk_pos, _, _, records = rng.choice(inner)
        _clear_crc(data, chunk_pos)
        pos = rng.choice(records)[0]
    elif top:
        pos = rng.choice(top[:-1] or top)[0]
    else:
        return None
    data[pos] = rng.choice([_OP_DATA_END, _OP_FOOTER, _OP_DATA_END, 0x00, _OP_CHUNK, _OP_MESSAGE_INDEX,
                            rng.randrange(256)])
    return data


def _rate_positions(data):
    positions, at = [], data.find(_RATE)
    while at >= 0:
        positions.append(at)
        at = data.find(_RATE, at + 1)
    return positions


def _sample_rate(data, rng):
    """One VibrationBlock's sample_rate replaced by a value no sensor gives (or a plausible wrong one)."""
    positions = _rate_positions(data)
    if not positions:
        return None
    value = rng.choice([1e-3, 1e-4, 1e-6, 1e-9, 5e-324, 0.0, -4000.0, math.nan, math.inf, -math.inf, 1e12, 1e300,
                        0.5, 2e6, 10 ** rng.uniform(-12, 12)])
    at = rng.choice(positions)
    data[at:at + 8] = struct.pack('<d', value)
    return data


def _sample_count(data, rng):
    """The sample count after a sample_rate (the float32[] length) replaced."""
    positions = [p for p in _rate_positions(data) if p + 12 <= len(data)]
    if not positions:
        return None
    at = rng.choice(positions) + 8
    count = struct.unpack_from('<I', data, at)[0]
    value = rng.choice([0, 1, count + 1, count - 1, count * 2, 2**31, 2**32 - 1, rng.getrandbits(32)])
    data[at:at + 4] = struct.pack('<I', value & 0xFFFFFFFF)
    return data


def _sample_value(data, rng):
    """A vibration sample set to a value no accelerometer gives (3e36, NaN, 1e6 m/s^2 ...)."""
    positions = [p for p in _rate_positions(data) if p + 16 <= len(data)]
    if not positions:
        return None
    at = rng.choice(positions)
    count = struct.unpack_from('<I', data, at + 8)[0]
    k = rng.randrange(max(1, min(count, (len(data) - at - 16) // 4)))
    value = rng.choice([3e36, -3e36, math.nan, math.inf, 1e6, -2e5, 1e30])
    data[at + 12 + 4 * k:at + 16 + 4 * k] = struct.pack('<f', value)
    return data


def _index_time(data, rng):
    """A MessageIndex entry's time, or a ChunkIndex's start/end time, changed."""
    places = []
    for pos, opcode, length in _data_records(data):
        if opcode == _OP_MESSAGE_INDEX and length >= 6 + 16:
            entries = struct.unpack_from('<I', data, pos + 11)[0]
            places += [pos + 15 + 16 * i for i in range(min(entries, length - 6) // 16)]
        elif opcode == _OP_CHUNK_INDEX and length >= 16:
            places += [pos + 9, pos + 17]
    if not places:
        return None
    at = rng.choice(places)
    time = struct.unpack_from('<Q', data, at)[0]
    value = rng.choice([0, 2**63 - 1, 2**64 - 1, time + 10**9 * rng.randint(1, 3600), max(time - 10**9 * 60, 0),
                        time + rng.randint(1, 10**6), rng.getrandbits(64)])
    data[at:at + 8] = struct.pack('<Q', value)
    return data


def _mutate_calibration(data: bytes, rng: random.Random, kind: str) -> bytes:
    """A calibration YAML with its structure or one of its values damaged."""
    import yaml
    try:
        document = yaml.safe_load(data.decode())
    except Exception:
        return mutate(data, rng)
    if kind == 'calibration_structure':
        how = rng.randrange(6)
        if how == 0:
            depth = rng.choice([20, 40, 100, 1000, 5000])
            return ('[' * depth + '1' + ']' * depth).encode() if rng.random() < 0.5 else (
                ''.join(' ' * i + f'k{i}:\n' for i in range(depth)) + ' ' * depth + '1\n').encode()
        if how == 1:
            lines = ['a0: &a0 [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0]']
            lines += [f'a{i}: &a{i} [' + ', '.join([f'*a{i - 1}'] * 10) + ']' for i in range(1, 9)]
            return ('\n'.join(lines) + '\n' + data.decode()).encode()
        key = rng.choice(sorted(document))
        if how == 2:
            del document[key]
        elif how == 3:
            document[key] = rng.choice([[1, 2, 3], 'text', None, 7, {'x': {'y': [1]}}])
        elif how == 4:
            document = rng.choice([[document], {'calibration': document}, list(document.values())])
        else:
            section = document.get(rng.choice(['fit', 'constants', 'extension', 'std']))
            if isinstance(section, dict) and section:
                section[rng.choice(sorted(section))] = rng.choice([[], {}, [[1.0]], 'x', None])
        return yaml.safe_dump(document, sort_keys=False).encode()
    leaves = []

    def collect(node, parent=None, key=None):
        if isinstance(node, dict):
            for k, v in node.items():
                collect(v, node, k)
        elif isinstance(node, list):
            for i, v in enumerate(node):
                collect(v, node, i)
        elif isinstance(node, (int, float)) and not isinstance(node, bool) and parent is not None:
            leaves.append((parent, key, node))
    if rng.random() < 0.25:
        document['extension'] = {'effect': rng.choice(['thermal_viscosity', 'resonance', 'lubricant_depletion']),
                                 'params': {'a': 1.0, 'b': 2.0}}
    collect(document)
    parent, key, value = rng.choice(leaves)
    parent[key] = rng.choice([math.nan, math.inf, -math.inf, 0, -value, value * 1e-6, value * 1e6, 1e308,
                              -1e-300, 'text', True, None, [value]])
    return yaml.safe_dump(document, sort_keys=False).encode()


# -- what a command gives for a recording: compared between a mutant and its clean file ----------------

def command_result(path: Path, contract: bool, calibration) -> tuple:
    """Everything ``assess`` and ``calibrate`` do with one recording: ``(problem lines, result)``.

    ``result`` holds the windows (start, steadiness, run, RMS, speed, load),
    the runs' theta_Oil and the calibration's constants or the kind of
    refusal; raises InputError when the recording is refused.
    """
    from prsm_lube_ros.errors import InputError
    from prsm_lube_ros.estimation.pipeline import assess_recording, calibrate_recordings, recording_windows
    problems = []
    if not contract:    # any MCAP file: its messages as read, and what the reader said
        messages = [(topic, sequence, log_time, zlib.crc32(data))
                    for topic, sequence, log_time, data in raw_messages(path, problems.append)]
        list(topic_messages(path, problems.append))
        list_topics(path)
        return problems, messages
    exercise(path, contract)
    recording = recording_windows(path, lead=0.005, on_problem=problems.append)
    assessment = assess_recording(recording, calibration)
    try:
        constants = calibrate_recordings([recording]).constants
        fitted = (constants.c_sys, constants.c_f, constants.c_lambda)
    except InputError as err:
        fitted = type(err).__name__
    windows = [(round(w.start, 6), w.reason_kind, w.run_index, w.vibration_rms, w.screw_speed, w.axial_load)
               for w in recording.windows]
    runs = [(run.theta_oil, run.theta_oil_std, run.reason) for run in assessment.runs]
    return problems, (windows, runs, fitted)


def same_result(a, b, rtol: float = 1e-3) -> bool:
    """True when two :func:`command_result` results agree (numbers within ``rtol``)."""
    import numpy as np

    def flat(result):
        numbers, words = [], []
        stack = [result]
        while stack:
            item = stack.pop()
            if isinstance(item, (list, tuple)):
                stack.extend(item)
            elif isinstance(item, (int, float)) and not isinstance(item, bool):
                numbers.append(float(item))
            else:
                words.append(item)
        return np.array(numbers), words
    (na, wa), (nb, wb) = flat(a), flat(b)
    return wa == wb and na.shape == nb.shape and bool(np.allclose(na, nb, rtol=rtol, atol=1e-9, equal_nan=True))


def only_payloads_differ(clean: list, mutant: list) -> bool:
    """True when two message lists of :func:`command_result` (any MCAP file) differ only in message bytes.

    The same topics, sequences and log times: a payload byte changed where no
    checksum covers it, which no reader can detect.
    """
    return len(clean) == len(mutant) and all(a[:3] == b[:3] for a, b in zip(clean, mutant))


def _mcap_files(path: Path) -> list:
    return [path] if path.suffix == '.mcap' else sorted(path.glob('*.mcap')) if path.is_dir() else []


def valid_to_the_reference(path: Path) -> bool:
    """True when the ``mcap`` library accepts every MCAP file of ``path`` and finds the messages read here.

    Both of its readers (by the index, and from start to end) must read it
    without error, CRCs checked, with the same topics, sequences, log times
    and bytes as this package.

    Such a mutant is a valid, different file -- a sequence number, a topic
    name or a payload changed where nothing covers it -- and reading it in
    silence is right: there is no corruption to detect.
    """
    from mcap.reader import NonSeekingReader, SeekingReader
    files = _mcap_files(path)
    if not files:
        return False
    for file in files:
        ours = sorted((topic, sequence, log_time, zlib.crc32(data)) for topic, sequence, log_time, data
                      in raw_messages(file))
        for reader in (SeekingReader, NonSeekingReader):     # by the index, and from start to end
            try:
                with open(file, 'rb') as stream:
                    theirs = sorted((channel.topic, message.sequence, message.log_time, zlib.crc32(message.data))
                                    for _, channel, message in reader(stream, validate_crcs=True)
                                    .iter_messages(log_time_order=False))
            except Exception:   # the reference refuses the file: it is corrupt
                return False
            if ours != theirs:
                return False
    return True


def decoded_inputs(path: Path) -> dict:
    """Every batch of a recording, concatenated per kind: ``{kind: {column: array}}``."""
    import numpy as np
    from prsm_lube_ros.recording.reader import open_recording
    columns = {}
    for batches in open_recording(path).slices(on_problem=lambda line: None):
        for batch in batches:
            kind = type(batch).__name__
            values = dict(vars(batch))
            if 'offsets' in values:
                values['counts'] = np.diff(values.pop('offsets'))
            for name, array in values.items():
                columns.setdefault(kind, {}).setdefault(name, []).append(np.asarray(array, float))
    return {kind: {name: np.concatenate(parts) for name, parts in table.items()} for kind, table in columns.items()}


#: Columns that carry sensor values (the rest, stamps, rates and counts, are header fields).
VALUE_COLUMNS = {'samples', 'angles', 'speeds', 'forces', 'temperatures'}


def only_values_differ(clean: dict, mutant: dict) -> bool:
    """True when two :func:`decoded_inputs` differ only where no reader can tell: values and small stamp shifts.

    The same messages with the same rates and sample counts; sensor values
    may differ (within the sensors' range, else the windows report them) and
    header stamps by at most ``STAMP_SPIKE_SECONDS`` (jitter a reader must
    accept).  Such a change (a payload byte in a file without checksums: the
    rig simulator writes CRC 0, sqlite blobs have none) leaves nothing to detect.
    """
    import numpy as np
    from prsm_lube_ros.recording.plausibility import STAMP_SPIKE_SECONDS
    if clean.keys() != mutant.keys():
        return False
    for kind, table in clean.items():
        other = mutant[kind]
        if table.keys() != other.keys():
            return False
        for name, array in table.items():
            if array.shape != other[name].shape:
                return False
            if name == 'stamps':
                with np.errstate(invalid='ignore'):
                    if not np.all(np.abs(array - other[name]) <= STAMP_SPIKE_SECONDS):
                        return False
            elif name not in VALUE_COLUMNS and not np.array_equal(array, other[name], equal_nan=True):
                return False
    return True
