# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Serial, process-parallel and Dask assessment give identical outcomes; a bad recording is one line."""
import pytest

from prsm_lube_ros.estimation.calibration_file import load_calibration
from prsm_lube_ros.fleet.parallel import assess_bags, BagJob


def comparable(outcomes):
    """Every number of every outcome, for exact comparison."""
    result = []
    for outcome in outcomes:
        runs = [(r.run_index, r.theta_oil, r.theta_oil_std, r.vibration_rms) for r in outcome.assessment.runs] \
            if outcome.assessment else None
        windows = [(w.window.start, w.theta_oil) for w in outcome.assessment.windows] if outcome.assessment else None
        result.append((outcome.path, outcome.content, outcome.error, runs, windows))
    return repr(result)     # repr: NaN equals NaN, and every float to the last bit


@pytest.fixture(scope='module')
def job(small_fleet):
    return BagJob(load_calibration(small_fleet['calibration']), 0.005, hash_content=True)


def test_processes_and_a_local_dask_cluster_equal_the_serial_run(small_fleet, job, tmp_path):
    bags = small_fleet['bags'][:6]
    broken = tmp_path / 'broken.mcap'
    broken.write_bytes(b'not an mcap file')
    paths = [bags[0], str(broken)] + bags[1:]
    done = []
    serial = assess_bags(paths, job, on_done=done.append)
    assert len(done) == len(paths)
    assert [o.path for o in serial] == paths
    assert serial[1].error and str(broken) in serial[1].error and '\n' not in serial[1].error
    assert all(o.assessment is not None and len(o.content) == 64 for i, o in enumerate(serial) if i != 1)
    assert comparable(assess_bags(paths, job, jobs=2)) == comparable(serial)
    pytest.importorskip('distributed')
    assert comparable(assess_bags(paths, job, jobs=2, scheduler='local')) == comparable(serial)


def test_an_unreachable_scheduler_is_one_line(job, small_fleet):
    from prsm_lube_ros.errors import InputError
    pytest.importorskip('distributed')
    with pytest.raises(InputError, match='--scheduler tcp://127.0.0.1:9'):
        assess_bags(small_fleet['bags'][:1], job, scheduler='tcp://127.0.0.1:9')


def test_jobs_must_be_a_positive_whole_number(job, small_fleet):
    from prsm_lube_ros.errors import InputError
    with pytest.raises(InputError, match='--jobs'):
        assess_bags(small_fleet['bags'][:1], job, jobs=0)
