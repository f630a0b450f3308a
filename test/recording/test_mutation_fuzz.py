# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Seeded, time-bounded mutation fuzzing of small MCAP files: success or one InputError line, nothing else."""

from pathlib import Path
import random
import shutil
import struct
import time
import zlib

import pytest

import bagfactory as bf
from fuzzing import (command_result, decoded_inputs, exercise, mutate, mutate_as, only_values_differ,
                     RECORDING_KINDS, same_result, seed_calibration, seed_recordings, valid_to_the_reference)
from prsm_lube_ros.errors import ConfigError, InputError
from prsm_lube_ros.estimation.calibration_file import load_calibration
from prsm_lube_ros.recording import mcap_file
from prsm_lube_ros.recording.cdr import check_layout
from prsm_lube_ros.recording.reader import open_recording

CONFORMANCE = Path(__file__).resolve().parents[1] / 'data' / 'conformance' / 'mcap'
MUTATIONS = 300
SECONDS = 60.0


def test_mutated_recordings_give_data_or_one_input_error_line(tmp_path):
    """Every container and layout (bare MCAP, small and reversed chunks, .db3, rosbag2 folders), and conformance."""
    seeds = [(path, kind) for path, kind in seed_recordings(tmp_path / 'seeds')]
    seeds = seeds * 4 + [(path, 'mcap') for path in sorted(CONFORMANCE.glob('*/*.mcap'))[::20]]
    rng = random.Random(20261123)
    deadline = time.monotonic() + SECONDS
    done = 0
    kinds = set()
    while done < MUTATIONS and time.monotonic() < deadline:
        source, kind = seeds[done % len(seeds)]
        work = tmp_path / f'mutant_{done}'
        if kind.startswith('bag:'):
            shutil.copytree(source.parent, work)
            target = path = work / source.name
        else:
            work.mkdir()
            target = path = work / source.name
        mutant = mutate(source.read_bytes(), rng)
        target.write_bytes(mutant)
        try:
            exercise(work if kind.startswith('bag:') else path, kind != 'mcap')
        except InputError as err:
            assert '\n' not in str(err)
        except Exception as err:  # pragma: no cover - the failure report
            pytest.fail(f'mutation {done} of {source.name} (crc {zlib.crc32(mutant)}): '
                        f'{type(err).__name__}: {err}')
        shutil.rmtree(work)
        kinds.add(kind.split(':')[0] + source.suffix)
        done += 1
    assert done >= min(MUTATIONS, 50)
    assert {'contract.mcap', 'contract.db3', 'bag.mcap', 'bag.db3', 'bag.zstd', 'bag.yaml', 'mcap.mcap'} <= kinds


def test_mutated_calibration_files_give_a_calibration_or_one_config_error_line(tmp_path):
    source = seed_calibration(tmp_path / 'calibration.yaml')
    rng = random.Random(11)
    target = tmp_path / 'mutant.yaml'
    outcomes = {'read': 0, 'refused': 0}
    for index in range(150):
        target.write_bytes(mutate(source.read_bytes(), rng))
        try:
            load_calibration(target)
            outcomes['read'] += 1
        except ConfigError as err:
            assert '\n' not in str(err) and str(target) in str(err)
            outcomes['refused'] += 1
        except Exception as err:  # pragma: no cover - the failure report
            pytest.fail(f'calibration mutation {index}: {type(err).__name__}: {err}')
    assert outcomes['read'] and outcomes['refused']


def test_corrupt_lengths_in_unindexed_records_are_left_out_not_raised():
    bad = [struct.pack('<BQ', mcap_file.OP_MESSAGE, 2**64 - 1) + b'x' * 30,
           struct.pack('<BQ', mcap_file.OP_MESSAGE, 22) + struct.pack('<HIQQ', 1, 1, 2**64 - 1, 0),
           struct.pack('<BQ', mcap_file.OP_MESSAGE, 2**63) + b'x' * 40]
    for buf in bad:
        chunk, used = mcap_file.split_sequential(buf, 0, 0, lambda *args: None)
        assert 0 <= used <= len(buf)


def test_a_chunk_whose_crc_does_not_match_is_left_out_in_one_line(tmp_path):
    path = bf.write_mcap_library(tmp_path / 'crc.mcap', bf.contract_entries(seconds=2.0, block=100),
                                 compression='none', chunk_size=4096)
    data = bytearray(path.read_bytes())
    first = data.index(bytes([mcap_file.OP_CHUNK]), 8)
    data[first + 9 + 8 + 8 + 8 + 4 + 4 + 8 + 40] ^= 0xFF     # a byte of the first chunk's records
    path.write_bytes(bytes(data))
    problems = []
    list(open_recording(path).slices(on_problem=problems.append))
    assert any('CRC' in line for line in problems)


def test_check_layout_without_definitions_is_a_reason_not_an_exception():
    assert 'without a stored definition' in check_layout('vibration', None, None, None)
    assert 'without a stored definition' in check_layout('axial_load', 'x/Y', None, None)


def test_a_calibration_file_of_random_bytes_is_one_config_error(tmp_path):
    rng = random.Random(7)
    for index, data in enumerate([bytes(rng.getrandbits(8) for _ in range(300)), b'abc', b'[1, 2]', b'{a: 1}']):
        path = tmp_path / f'{index}.yaml'
        path.write_bytes(data)
        with pytest.raises(ConfigError, match=str(path)):
            load_calibration(path)


@pytest.mark.parametrize('kind', [k for k in RECORDING_KINDS if k != 'random'])
def test_targeted_damage_is_refused_or_said_never_a_silently_different_result(tmp_path, kind):
    """Lengths inside chunks, opcodes, sample_rate, sample counts and values, index times (issue 18).

    Each mutant is read as assess and calibrate read it; a result that differs
    from the clean file's must come with a problem line (or a one-line
    refusal naming the file), unless nothing a reader could check changed.
    """
    from prsm_lube_ros.estimation.calibration import Calibration
    from prsm_lube_ros.physics.vibration_model import ModelConstants
    import numpy as np
    calibration = Calibration(ModelConstants(0.08, 1e-3, 0.3), np.diag([1e-4, 1e-10, 1e-4]), 0.01, 0.01, 10, 1.0)
    seeds = [(p, k) for p, k in seed_recordings(tmp_path / 'seeds') if p.suffix in ('.mcap', '.db3')]
    rng = random.Random(kind)
    done = 0
    for index in range(24):
        source, seed_kind = seeds[index % len(seeds)]
        mutant, how = mutate_as(source.read_bytes(), rng, kind)
        if how != kind:
            continue
        clean_dir, work = tmp_path / f'clean_{index}', tmp_path / f'mutant_{index}'
        if seed_kind.startswith('bag:'):
            shutil.copytree(source.parent, clean_dir)
            shutil.copytree(source.parent, work)
            (work / source.name).write_bytes(mutant)
            clean_path, path = clean_dir, work
        else:
            clean_dir.mkdir()
            work.mkdir()
            clean_path = Path(shutil.copy(source, clean_dir))
            path = work / source.name
            path.write_bytes(mutant)
        try:
            problems, result = command_result(path, True, calibration)
        except InputError as err:
            assert '\n' not in str(err) and str(work) in str(err), str(err)
            continue
        if not problems and not same_result(result, command_result(clean_path, True, calibration)[1]):
            assert only_values_differ(decoded_inputs(clean_path), decoded_inputs(path)) or \
                valid_to_the_reference(path), f'{kind} #{index} of {source.name}: a different result in silence'
        done += 1
    assert done >= 8


@pytest.mark.parametrize('kind', ['calibration_structure', 'calibration_value'])
def test_damaged_calibration_structure_and_values_are_one_line_naming_the_file_and_no_warning(tmp_path, kind):
    """Nesting 5,000 deep, alias bombs, wrong types; NaN, inf, signs, C_sys x 1e-6 (issue 18)."""
    import warnings
    source = seed_calibration(tmp_path / 'calibration.yaml')
    rng = random.Random(kind)
    target = tmp_path / 'mutant.yaml'
    refused = 0
    for index in range(60):
        mutant, how = mutate_as(source.read_bytes(), rng, kind)
        assert how == kind
        target.write_bytes(mutant)
        with warnings.catch_warnings():
            warnings.simplefilter('error')          # a numpy RuntimeWarning would reach the user
            try:
                calibration = load_calibration(target)
            except ConfigError as err:
                assert '\n' not in str(err) and str(target) in str(err), str(err)
                refused += 1
                continue
        assert calibration.constants.c_sys > 0 and calibration.constants.c_lambda > 0
        assert np_finite(calibration.covariance), index
    # About half the mutants are refused; the rest touch keys a loader may lose (optional band, domain, run
    # scatter, sources) and load as documented.
    assert refused >= 25


def np_finite(array) -> bool:
    import numpy as np
    return bool(np.all(np.isfinite(array)))
