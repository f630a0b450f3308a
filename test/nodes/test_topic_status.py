# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Input rate and stamp statuses (prsm_lube_ros.nodes.topic_status): diagnostic_updater's semantics, no ROS."""
import math
from pathlib import Path
import xml.etree.ElementTree as ElementTree

import pytest
import yaml

from prsm_lube_ros.estimation.health import ERROR, OK, WARN
from prsm_lube_ros.nodes.topic_status import FrequencyStatus, merge, RateSettings, StampSettings, TaskStatus, \
    TimeStampStatus, TopicStatus

CONFIG = Path(__file__).resolve().parents[2] / 'config'


def beat(status, rate, periods, start=0.0, period=1.0):
    """``periods`` diagnostic periods of ``rate`` messages per s; the status of each period, and the end time."""
    out, t = [], start
    for _ in range(periods):
        status.tick(int(round(rate * period)))
        t += period
        out.append(status.status(t))
    return out, t


def test_the_rate_is_measured_over_the_window_and_judged_against_the_expected_one():
    frequency = FrequencyStatus(RateSettings(expected=10.0, tolerance=0.1, window=5), now=0.0)
    statuses, t = beat(frequency, 10.0, 8)
    assert [s.level for s in statuses] == [OK] * 8
    assert {s.message for s in statuses} == {'Desired frequency met'}
    values = dict(statuses[-1].values)
    assert values['Duration of window (s)'] == 5.0 and values['Events in window'] == 50
    assert values['Actual frequency (Hz)'] == 10.0 and values['Minimum acceptable frequency (Hz)'] == 9.0
    statuses, t = beat(frequency, 5.0, 8, start=t)
    assert statuses[0].level == OK                                  # 45 of 50 in the window: 9 Hz, on the edge
    assert statuses[-1].level == WARN and statuses[-1].message == 'Frequency too low.'
    assert dict(statuses[-1].values)['Actual frequency (Hz)'] == 5.0
    statuses, _ = beat(frequency, 0.0, 6, start=t)
    assert statuses[-1].level == ERROR and statuses[-1].message == 'No events recorded.'


def test_a_maximum_rate_and_an_optional_input():
    frequency = FrequencyStatus(RateSettings(expected=10.0, max_rate=10.0, window=1), now=0.0)
    statuses, _ = beat(frequency, 20.0, 2)
    assert statuses[-1].level == WARN and statuses[-1].message == 'Frequency too high.'
    optional = TopicStatus('/prsm/temperature', RateSettings(expected=0.0), StampSettings(), now=0.0)
    status = optional.status(1.0)
    assert status.level == OK and status.message == 'No events expected.; No data since last update.'
    assert dict(status.values)['topic'] == '/prsm/temperature'


def test_stamps_from_the_future_the_past_and_zero_are_errors_for_the_window():
    stamps = TimeStampStatus(StampSettings(max_age=5.0, max_future=1.0), window=3)
    assert stamps.status().level == WARN                              # nothing yet
    stamps.tick(99.9, 100.0, now=100.2)
    first = stamps.status()
    assert first.level == OK and first.message == 'Timestamps are reasonable.'
    assert dict(first.values)['Earliest timestamp delay (s)'] == pytest.approx(0.2)
    assert dict(first.values)['Latest timestamp delay (s)'] == pytest.approx(0.3)
    stamps.tick(102.0, 102.0, now=100.5)                              # 1.5 s ahead
    assert stamps.status().message == 'Timestamps too far in future seen.'
    stamps.tick(90.0, 90.0, now=100.6)                                # 10.6 s old
    status = stamps.status()
    assert status.level == ERROR
    assert status.message == 'Timestamps too far in future seen. Timestamps too far in past seen.'
    for _ in range(2):
        stamps.tick(100.7, 100.7, now=100.8)
        stamps.status()
    stamps.tick(100.9, 100.9, now=101.0)
    assert stamps.status().level == OK                                # the window moved past them
    assert dict(stamps.status().values)['Early diagnostic update count'] == 1
    stamps.tick(0.0, 0.0, now=101.0)
    assert stamps.status().message == 'Zero timestamp seen.'


def test_a_slow_input_does_not_flap_between_periods_with_and_without_a_message():
    """1 message per 2 periods: the stamp status judges the window, so it stays OK."""
    # 2 or 3 messages in a 5 s window: 0.4 or 0.6 per s, inside a 30 % tolerance of 0.5
    topic = TopicStatus('/prsm/temperature', RateSettings(expected=0.5, tolerance=0.3, window=5), StampSettings(),
                        now=0.0)
    levels, messages = [], set()
    for k in range(1, 21):
        if k % 2 == 0:
            topic.tick(1, k - 0.1, k - 0.1, now=float(k))
        status = topic.status(float(k))
        if k > 5:
            levels.append(status.level)
            messages.add(status.message)
    assert set(levels) == {OK} and messages == {'Desired frequency met; Timestamps are reasonable.'}


def test_merge_keeps_the_highest_level_and_its_messages():
    merged = merge([TaskStatus(WARN, 'a.', [('x', 1)]), TaskStatus(OK, 'b.', [('y', 2)]),
                    TaskStatus(WARN, 'c.', [])])
    assert merged.level == WARN and merged.message == 'a.; c.' and merged.values == [('x', 1), ('y', 2)]
    assert math.isnan(dict(TimeStampStatus(StampSettings()).status().values)['Earliest timestamp delay (s)'])


def test_the_sros2_policy_lets_only_the_trusted_enclave_call_calibrate():
    root = ElementTree.parse(CONFIG / 'sros2_policy.xml').getroot()
    assert root.tag == 'policy' and root.get('version') == '0.2.0'
    callers, servers = set(), set()
    for enclave in root.iter('enclave'):
        for profile in enclave.iter('profile'):
            for services in profile.iter('services'):
                names = {s.text for s in services.iter('service')}
                if services.get('request') == 'ALLOW' and any(n.endswith('calibrate') for n in names):
                    callers.add(enclave.get('path'))
                if services.get('reply') == 'ALLOW' and 'calibrate' in names:
                    servers.add((enclave.get('path'), profile.get('ns'), profile.get('node')))
            for actions in profile.iter('actions'):
                if actions.get('call') == 'ALLOW':
                    callers.add(enclave.get('path'))
    assert callers == {'/prsm/maintenance'}
    assert servers == {('/prsm/lubrication_estimator', '/prsm', 'lubrication_estimator')}


def test_the_ros2_control_example_relays_the_broadcasters_topics():
    stack = yaml.safe_load((CONFIG / 'ros2_control_stack.yaml').read_text())
    bridge = stack['/**/sensor_bridge']['ros__parameters']
    assert bridge['relay_joint_states'] == '/joint_states'
    assert bridge['relay_axial_load'] == '/force_torque_sensor_broadcaster/wrench'
    assert bridge['source'] == 'imu' and bridge['imu_topic'] == '/imu_sensor_broadcaster/imu'
    estimator = stack['/**/lubrication_estimator']['ros__parameters']
    assert estimator['actuators'] == [''] and estimator['temperature_rate'] == 0.0
