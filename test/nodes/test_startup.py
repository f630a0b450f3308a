# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""startup.freeze_startup_objects: start-up objects leave the collector's generations, later cycles do not."""
import gc
import weakref

from prsm_lube_ros.nodes.startup import freeze_startup_objects


class _Cycle:
    pass


def test_start_up_objects_are_frozen_and_cycles_made_later_are_still_collected():
    try:
        freeze_startup_objects()
        assert gc.get_freeze_count() > 0
        frozen = gc.get_freeze_count()
        cycle = _Cycle()
        cycle.self = cycle
        alive = weakref.ref(cycle)
        del cycle
        gc.collect()
        assert alive() is None                       # made after the freeze: collected as before
        assert gc.get_freeze_count() == frozen       # what was frozen stays out of the generations
    finally:
        gc.unfreeze()                                # the other tests in this process as they were
