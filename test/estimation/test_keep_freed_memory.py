# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Streaming keeps freed array memory for the next slice: arrays of a few MB come from the heap and stay there."""
import ctypes

import numpy as np
import pytest

from prsm_lube_ros.estimation.pipeline import HEAP_ARRAY_BYTES, keep_freed_memory, KEPT_FREE_BYTES


class MallInfo2(ctypes.Structure):
    """glibc's ``struct mallinfo2`` (2.33 on)."""

    _fields_ = [(name, ctypes.c_size_t) for name in
                ('arena', 'ordblks', 'smblks', 'hblks', 'hblkhd', 'usmblks', 'fsmblks', 'uordblks', 'fordblks',
                 'keepcost')]


def mallinfo2():
    try:
        function = ctypes.CDLL(None).mallinfo2
    except (OSError, AttributeError):
        pytest.skip('the C library has no mallinfo2 (not glibc 2.33 or later)')
    function.restype = MallInfo2
    return function()


def test_an_array_of_a_slice_is_served_from_the_heap_and_its_memory_kept_when_freed():
    keep_freed_memory()
    size = 4 << 20     # a 60 s slice of 4 kHz samples in float64 is 1.9 MB; its spectra as much again
    assert size < HEAP_ARRAY_BYTES < KEPT_FREE_BYTES
    before = mallinfo2()
    block = np.ones(size // 8)
    during = mallinfo2()
    assert during.hblkhd - before.hblkhd < size, 'the array got a memory map of its own'
    assert during.uordblks - before.uordblks >= size
    del block
    after = mallinfo2()
    assert after.arena >= during.arena - 4096, 'the freed array was returned to the system'
    assert after.fordblks - during.fordblks >= size - 4096


def test_keeping_twice_changes_nothing():
    keep_freed_memory()
    keep_freed_memory()
    block = np.ones(1 << 20)
    assert block.sum() == 1 << 20
