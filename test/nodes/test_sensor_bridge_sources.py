# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The sensor bridge's ROS-free parts: exact stamps, event order, pacing, and NI-DAQmx through a fake module."""
import math
import sys
import threading
import time

import numpy as np
import pytest

from prsm_lube_ros.errors import InputError
from prsm_lube_ros.recording.batches import AxialLoadBatch, ScrewStateBatch, VibrationBatch
from prsm_lube_ros.nodes.bridge_sources import batch_events, Pacer, rig_block_events, stamps_ns
from prsm_lube_ros.nodes.daq import DaqSettings, NiDaqAccelerometer, STANDARD_GRAVITY
from prsm_lube_ros.simulation.rig_config import RigConfig
from prsm_lube_ros.simulation.rig_acceleration import RigSignalGenerator

T0 = 1767225600.0


def ros_seconds(ns):
    """What a ROS reader computes from (sec, nanosec): sec + nanosec * 1e-9 (as ros_convert does)."""
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return sec + nanosec * 1e-9


def test_recorded_float_stamps_come_back_bit_for_bit():
    rng = np.random.default_rng(1)
    stamps = np.concatenate([T0 + rng.uniform(0, 3600, 5000), T0 + 0.1 * np.arange(100),
                             [T0 + 0.9999999, 1.5, 0.0]])
    ns = stamps_ns(stamps)
    assert all(ros_seconds(n) == s for n, s in zip(ns, stamps))
    # and within the float's own resolution (0.24 us near 2026) of its value
    assert np.max(np.abs(ns - stamps * 1e9)) < 300
    assert stamps_ns([T0 + 0.25])[0] == 1767225600_250000000


def test_batch_events_merge_topics_in_delivery_order():
    """A block is due after its last sample; joint and load messages at their stamps; values kept."""
    vib = VibrationBatch(np.array([T0, T0 + 0.1]), np.array([1000.0, 1000.0]), np.array([0, 100, 200]),
                         np.arange(200, dtype=np.float32))
    screw = ScrewStateBatch(np.array([T0 + 0.05, T0 + 0.15]), np.array([1.0, 2.0]), np.array([10.0, 11.0]))
    load = AxialLoadBatch(np.array([T0 + 0.12, math.nan]), np.array([-150.0, -151.0]))
    events = batch_events([vib, screw, load])
    kinds = [e[1] for e in events]
    assert kinds == ['joint_states', 'vibration', 'axial_load', 'joint_states', 'vibration']
    assert [e[0] - T0 for e in events] == pytest.approx([0.05, 0.1, 0.12, 0.15, 0.2])
    first_block = events[1]
    assert ros_seconds(first_block[2]) == T0 and first_block[3][0] == 1000.0
    np.testing.assert_array_equal(first_block[3][1], np.arange(100))
    assert events[0][3] == (1.0, 10.0) and events[2][3] == (-150.0,)    # the NaN-stamped load is left out


@pytest.mark.parametrize('rate', [1e-3, 1e-6, 5e-324, 0.0, math.nan])
def test_a_played_block_with_a_rate_no_sensor_gives_does_not_pace_the_replay_for_days(rate):
    """4000 samples at 1e-3 Hz would make the playback wait 46 days for the block (issue 18); it goes out now."""
    vib = VibrationBatch(np.array([T0, T0 + 0.1]), np.array([rate, 4000.0]), np.array([0, 4000, 4400]),
                         np.ones(4400, dtype=np.float32))
    events = batch_events([vib])
    assert [e[0] - T0 for e in events] == pytest.approx([0.0, 0.2])
    assert events[0][3][0] == rate or math.isnan(rate)      # passed on as recorded: the estimator says why not


def test_rig_block_events_carry_the_simulator_stamps_exactly():
    generator = RigSignalGenerator(RigConfig(), seed=2, start_stamp_ns=1767225600_000000000)
    generator.set_speed(10.0)
    events = rig_block_events(generator.next_block()) + rig_block_events(generator.next_block())
    blocks = [e for e in events if e[1] == 'vibration']
    assert [b[2] for b in blocks] == [1767225600_000000000, 1767225600_100000000]   # 0.1 s blocks
    assert all(b[3][0] == 4000.0 and b[3][1].size == 400 for b in blocks)
    joints = [e for e in events if e[1] == 'joint_states']
    assert len(joints) == 20                                                   # 100 Hz over 0.2 s
    dues = [e[0] for e in events]
    assert dues == sorted(dues)


def test_pacer_scales_time_and_does_not_wait_for_stamps_going_back():
    pacer = Pacer(rate=10.0)
    start = time.monotonic()
    assert pacer.wait(100.0)           # anchors: published at once
    assert pacer.wait(100.5)           # 0.5 s of stamps at 10x: 0.05 s
    assert pacer.wait(99.0)            # back: no wait
    elapsed = time.monotonic() - start
    assert 0.04 < elapsed < 1.0
    pacer.stop.set()
    assert not pacer.wait(200.0)       # stopped: returns at once with False


# -- NI-DAQmx through a fake module (test/support/fake_nidaqmx.py, fixture fake_daq in conftest) ----------
def test_without_nidaqmx_the_accelerometer_refuses_in_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, 'nidaqmx', None)        # import fails as if not installed
    with pytest.raises(InputError) as err:
        NiDaqAccelerometer(DaqSettings())
    assert 'nidaqmx is not installed' in str(err.value) and '\n' not in str(err.value)


def test_the_card_is_set_up_as_in_the_paper_and_blocks_are_stamped_by_sample_count(fake_daq):
    settings = DaqSettings(channel='Dev1/ai0', sample_rate=4000.0, block_size=400)
    with NiDaqAccelerometer(settings, clock_ns=lambda: 1767225600_000000000) as card:
        blocks = [card.read_block() for _ in range(3)]
    task = fake_daq.instances[0]
    args = task.channel_args
    assert args['physical_channel'] == 'Dev1/ai0'
    assert args['units'] == 'AccelUnits.G' and args['sensitivity'] == 100.0
    assert args['sensitivity_units'] == 'AccelSensitivityUnits.M_VOLTS_PER_G'
    assert args['current_excit_source'] == 'ExcitationSource.INTERNAL' and args['current_excit_val'] == 0.004
    assert (args['min_val'], args['max_val']) == (-50.0, 50.0)
    assert task.channel.ai_coupling == 'Coupling.AC'
    assert task.timing_args == (4000.0, 'AcquisitionType.CONTINUOUS', 40000)   # 10 s ring buffer
    assert task.started and task.stopped and task.closed
    assert [stamp for stamp, _ in blocks] == [1767225600_000000000, 1767225600_100000000, 1767225600_200000000]
    stamp, samples = blocks[2]
    assert samples.dtype == np.float32 and samples.size == 400
    assert samples[0] == pytest.approx(2.0 * 9.80665) and samples[399] == pytest.approx(2.399 * 9.80665)
    assert STANDARD_GRAVITY == 9.80665


def test_external_conditioning_switches_excitation_off(fake_daq):
    with NiDaqAccelerometer(DaqSettings(iepe_current=0.0, sensitivity=10.2)):
        pass
    args = fake_daq.instances[0].channel_args
    assert args['current_excit_source'] == 'ExcitationSource.NONE' and args['sensitivity'] == 10.2
    assert not hasattr(fake_daq.instances[0].channel, 'ai_coupling')


@pytest.mark.parametrize('where, words', [('create', 'Could not find an installation of NI-DAQmx.'),
                                          ('channel', 'Device identifier is invalid: Dev7/ai3')])
def test_no_driver_or_no_card_is_one_line(fake_daq, where, words):
    fake_daq.fail_on = where
    with pytest.raises(InputError) as err:
        NiDaqAccelerometer(DaqSettings(channel='Dev7/ai3'))
    text = str(err.value)
    assert text == f'source hardware: NI-DAQmx cannot acquire from Dev7/ai3: {words}'
    assert all(task.closed for task in fake_daq.instances)


def test_a_failing_read_is_one_line(fake_daq):
    fake_daq.fail_on = 'read'
    card = NiDaqAccelerometer(DaqSettings())
    card.read_block()
    with pytest.raises(InputError, match='reading Dev1/ai0 failed: The application is not able to keep up'):
        card.read_block()
    card.close()
    card.close()


@pytest.mark.parametrize('field, value', [('sample_rate', 0.0), ('block_size', 0), ('sensitivity', -1.0),
                                          ('channel', ' '), ('buffer_seconds', 0.01)])
def test_bad_settings_are_refused(field, value):
    with pytest.raises(InputError, match=field):
        DaqSettings(**{field: value})


def test_pacer_stop_from_another_thread():
    pacer = Pacer(rate=1.0)
    pacer.wait(0.0)
    threading.Timer(0.05, pacer.stop.set).start()
    start = time.monotonic()
    assert not pacer.wait(60.0)
    assert time.monotonic() - start < 5.0
