# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""IMU samples grouped into VibrationBlocks: uniform blocks, and every stamp problem closes a block once reported."""
import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.nodes.imu_blocks import check_axis, ImuBlockAssembler

T0 = 1_767_225_600_000_000_000      # 2026-01-01 in ns
MS = 1_000_000


def feed(assembler, stamps, values=None):
    """Push every (stamp, value); the blocks that came out."""
    values = np.arange(len(stamps), dtype=float) if values is None else values
    blocks = []
    for stamp, value in zip(stamps, values):
        blocks += assembler.push(int(stamp), value)
    return blocks


def recorder():
    """on_problem callback and the list of (kind, line) it fills."""
    lines = []
    return lines, lambda kind, line: lines.append((kind, line))


def test_regular_samples_make_full_blocks_stamped_with_their_first_sample():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, on_problem=on_problem)
    blocks = feed(assembler, T0 + MS * np.arange(1000))
    assert len(blocks) == 10 and lines == []
    for k, block in enumerate(blocks):
        assert block.stamp_ns == T0 + 100 * k * MS and block.sample_rate == 1000.0
        assert block.samples.dtype == np.float32
        assert block.samples.tolist() == list(range(100 * k, 100 * k + 100))


def test_rate_zero_takes_the_measured_rate_without_complaint():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.05, sample_rate=0.0, on_problem=on_problem)
    stamps = T0 + np.round(np.arange(1000) * 1e9 / 800.0).astype(np.int64)     # 800 Hz, 1.25 ms
    blocks = feed(assembler, stamps)
    assert lines == []
    assert all(b.sample_rate == pytest.approx(800.0, rel=1e-6) for b in blocks)
    assert [len(b.samples) for b in blocks] == [40] * 25
    assert blocks[0].stamp_ns == T0


def test_a_gap_closes_the_block_counts_the_lost_samples_and_is_reported_once():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, on_problem=on_problem)
    stamps = T0 + MS * np.concatenate([np.arange(150), np.arange(200, 400), np.arange(410, 500)])
    blocks = feed(assembler, stamps)
    # 100 | 50 (closed by the gap) | 100 | 100 (ends at 399) | closed by the gap of 10 | 90 left open
    assert [len(b.samples) for b in blocks] == [100, 50, 100, 100]
    assert [b.stamp_ns for b in blocks] == [T0, T0 + 100 * MS, T0 + 200 * MS, T0 + 300 * MS]
    assert assembler.lost_samples == 50 + 10          # 149 -> 200 ms and 399 -> 410 ms
    assert assembler.problems['gap'] == 2
    assert [kind for kind, _ in lines] == ['gap']
    assert 'about 50 lost at 1000 Hz' in lines[0][1]
    rest = assembler.flush()
    assert len(rest) == 1 and rest[0].stamp_ns == T0 + 410 * MS and len(rest[0].samples) == 90


def test_a_pause_of_the_bridge_is_no_gap():
    """Deactivated for 2 s: the partial block comes out at the pause and nothing counts as lost."""
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, on_problem=on_problem)
    blocks = feed(assembler, T0 + MS * np.arange(150))
    paused = assembler.pause()
    assert [len(b.samples) for b in blocks + paused] == [100, 50]
    after = feed(assembler, T0 + MS * np.arange(2150, 2350))
    assert [b.stamp_ns for b in after] == [T0 + 2150 * MS, T0 + 2250 * MS]
    assert assembler.lost_samples == 0 and assembler.problems['gap'] == 0 and lines == []


def test_stamps_going_back_close_the_block_and_start_over():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, on_problem=on_problem)
    stamps = T0 + MS * np.concatenate([np.arange(130), np.arange(130)])      # a clock reset after 130
    blocks = feed(assembler, stamps)
    assert [len(b.samples) for b in blocks] == [100, 30, 100]
    assert blocks[2].stamp_ns == T0
    assert [kind for kind, _ in lines] == ['backwards'] and assembler.problems['backwards'] == 1


def test_jitter_beyond_the_tolerance_closes_the_block():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, jitter_tolerance=0.25,
                                  on_problem=on_problem)
    offsets = MS * np.arange(200)
    offsets[60:] += 400_000                  # one interval of 1.4 ms: not a gap, but 0.4 periods off
    rng = np.random.default_rng(3)
    offsets[120:] += rng.integers(-100_000, 100_000, 80)    # +-0.1 periods: inside the tolerance
    blocks = feed(assembler, T0 + offsets)
    assert [len(b.samples) for b in blocks] == [60, 100]
    assert [kind for kind, _ in lines] == ['jitter'] and assembler.lost_samples == 0


def test_a_wrong_sample_rate_parameter_is_reported_and_the_measured_rate_used():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=4000.0, on_problem=on_problem)
    blocks = feed(assembler, T0 + MS * np.arange(300))                   # a 1 kHz IMU
    assert [kind for kind, _ in lines] == ['rate']
    assert '1000 Hz' in lines[0][1] and '4000 Hz' in lines[0][1]
    assert all(b.sample_rate == pytest.approx(1000.0) for b in blocks)
    assert [len(b.samples) for b in blocks] == [100, 100, 100]          # the warm-up block kept its samples
    assert assembler.lost_samples == 0


def test_a_rate_change_later_closes_the_block_and_is_followed():
    lines, on_problem = recorder()
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=1000.0, on_problem=on_problem)
    first = T0 + MS * np.arange(250)
    second = first[-1] + 2 * MS * np.arange(1, 301)                      # the driver drops to 500 Hz
    blocks = feed(assembler, np.concatenate([first, second]))
    assert 'rate' in [kind for kind, _ in lines]
    assert blocks[-1].sample_rate == pytest.approx(500.0) and len(blocks[-1].samples) == 50
    assert blocks[1].sample_rate == 1000.0


def test_without_a_measured_rate_a_broken_warm_up_is_dropped_and_counted():
    assembler = ImuBlockAssembler(block_length=0.1, sample_rate=0.0)
    stamps = T0 + MS * np.concatenate([np.arange(5), np.arange(2, 200)])
    blocks = feed(assembler, stamps)
    assert assembler.dropped_samples == 5
    assert blocks[0].stamp_ns == T0 + 2 * MS and blocks[0].sample_rate == pytest.approx(1000.0)


@pytest.mark.parametrize('kwargs', [{'block_length': 0.0}, {'block_length': 0.1, 'sample_rate': -1.0},
                                    {'block_length': 0.1, 'rate_tolerance': 0.0},
                                    {'block_length': 0.1, 'jitter_tolerance': 0.6}])
def test_bad_settings_are_one_line(kwargs):
    with pytest.raises(InputError, match='parameter'):
        ImuBlockAssembler(**kwargs)


def test_axis_names():
    assert check_axis(' Z ') == 'z'
    with pytest.raises(InputError, match="imu_axis: 'w' is not one of x, y, z"):
        check_axis('w')
