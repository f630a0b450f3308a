# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The bridge's own health level: STALE before and after blocks, WARN on losses and a low rate, ERROR on failure."""
import math

import pytest

from prsm_lube_ros.estimation.health import ERROR, OK, STALE, WARN
from prsm_lube_ros.nodes.bridge_health import RATE_SPAN, SourceHealth


def run(health, start, stop, period, sample_rate=4000.0):
    """Blocks every ``period`` s from ``start`` to ``stop``; returns the last block time."""
    t = start
    while t < stop:
        health.block(t, sample_rate)
        t += period
    return t - period


def test_levels_follow_the_blocks():
    health = SourceHealth('hardware', stale_timeout=2.0, expected_block_rate=10.0)
    assert health.status(0.0).level == STALE and health.status(0.0).message == 'no block published yet'
    last = run(health, 0.0, 20.0, 0.1)
    status = health.status(last + 0.05)
    assert status.level == OK and status.message == 'publishing'
    values = dict(status.values)
    assert values['blocks published'] == 200 and values['sample rate [Hz]'] == 4000.0
    assert values['block rate [1/s]'] == pytest.approx(10.0, rel=0.02)
    assert health.status(last + 2.5).level == STALE


def test_a_rate_below_the_expected_one_warns_once_settled():
    health = SourceHealth('imu', stale_timeout=2.0, expected_block_rate=10.0)
    last = run(health, 0.0, 5.0, 0.2)                 # half the expected rate, but less than RATE_SPAN in
    assert health.status(last).level == OK
    last = run(health, last + 0.2, RATE_SPAN + 5.0, 0.2)
    status = health.status(last)
    assert status.level == WARN and status.message == 'block rate below the expected one'
    assert dict(status.values)['expected block rate [1/s]'] == 10.0


def test_losses_warn_for_a_while_and_failure_is_an_error():
    health = SourceHealth('imu', stale_timeout=2.0)
    last = run(health, 0.0, 3.0, 0.1)
    health.loss(last, samples=50, why='gap of 0.05 s')
    status = health.status(last)
    assert status.level == WARN and dict(status.values)['last error'] == 'gap of 0.05 s'
    assert dict(status.values)['lost samples'] == 50
    last = run(health, last + 0.1, last + RATE_SPAN + 1.0, 0.1)
    assert health.status(last).level == OK                          # the loss is no longer recent
    assert dict(health.status(last).values)['last error'] == 'gap of 0.05 s'
    health.fail('reading Dev1/ai0 failed: overrun')
    assert health.status(last).level == ERROR
    assert health.status(last).message == 'source imu failed: reading Dev1/ai0 failed: overrun'


def test_no_expected_rate_never_warns_on_rate():
    health = SourceHealth('playback', stale_timeout=2.0)
    last = run(health, 0.0, 30.0, 1.0)
    assert health.status(last).level == OK
    assert math.isnan(dict(health.status(last).values)['expected block rate [1/s]'])


def test_the_message_changes_only_with_the_state():
    """Rates that wobble (10 and 10.1 blocks/s) and losses with new reasons leave the message as it was."""
    health = SourceHealth('hardware', stale_timeout=2.0, expected_block_rate=10.0)
    last = run(health, 0.0, 12.0, 0.1)
    messages = set()
    for extra in range(5):                            # one more block now and then: the rate moves, the state not
        health.block(last + 0.01 * (extra + 1), 4000.0)
        status = health.status(last + 0.05 * (extra + 1))
        assert status.level == OK
        messages.add(status.message)
    rates = set()
    for k in range(3):
        health.loss(last + 0.3 + k * 0.1, samples=10 + k, why=f'gap {k}')
        status = health.status(last + 0.35 + k * 0.1)
        assert status.level == WARN
        messages.add(status.message)
        rates.add(dict(status.values)['last error'])
    assert len(messages) == 2 and len(rates) == 3
