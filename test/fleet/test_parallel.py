# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Serial, process-parallel and Dask assessment give identical outcomes; a bad recording is one line."""
import pytest

from prsm_lube_ros.estimation.calibration_file import load_calibration
from prsm_lube_ros.fleet.parallel import assess_bags, BagJob, BagOutcome, outcomes_fingerprint


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
    assert outcomes_fingerprint(assess_bags(paths, job, jobs=2)) == outcomes_fingerprint(serial)
    pytest.importorskip('distributed')
    assert outcomes_fingerprint(assess_bags(paths, job, jobs=2, scheduler='local')) == outcomes_fingerprint(serial)


def test_an_unreachable_scheduler_is_one_line(job, small_fleet):
    from prsm_lube_ros.errors import InputError
    pytest.importorskip('distributed')
    with pytest.raises(InputError, match='--scheduler tcp://127.0.0.1:9'):
        assess_bags(small_fleet['bags'][:1], job, scheduler='tcp://127.0.0.1:9')


def test_jobs_must_be_a_positive_whole_number(job, small_fleet):
    from prsm_lube_ros.errors import InputError
    with pytest.raises(InputError, match='--jobs'):
        assess_bags(small_fleet['bags'][:1], job, jobs=0)


@pytest.mark.parametrize('bad', ['foo', 'http://x', 'tcp://'])
def test_a_malformed_scheduler_address_is_one_line(job, small_fleet, bad):
    from prsm_lube_ros.errors import InputError
    pytest.importorskip('distributed')
    with pytest.raises(InputError, match=f'--scheduler {bad}') as caught:
        assess_bags(small_fleet['bags'][:1], job, scheduler=bad)
    assert '\n' not in str(caught.value)


def test_the_fingerprint_sees_every_number_of_runs_and_windows(job, small_fleet):
    import dataclasses
    outcome = assess_bags(small_fleet['bags'][:1], job)[0]
    first, run = outcome.assessment.windows[0], outcome.assessment.runs[0]
    before = outcomes_fingerprint([outcome])
    changed_window = dataclasses.replace(first, window=dataclasses.replace(
        first.window, nut_position=0.1234567890123))
    changed_run = dataclasses.replace(run, axial_load=0.1234567890123)
    for windows, runs in (([changed_window] + outcome.assessment.windows[1:], outcome.assessment.runs),
                          (outcome.assessment.windows, [changed_run] + outcome.assessment.runs[1:])):
        other = BagOutcome(outcome.path, dataclasses.replace(outcome.assessment, windows=windows, runs=runs),
                           outcome.content)
        assert outcomes_fingerprint([other]) != before
    assert outcomes_fingerprint([dataclasses.replace(outcome, content='0' * 64)]) != before
