# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The layout checks' field definitions without rosbags' full type store, the same as the store's."""
import subprocess
import sys

from prsm_lube_ros.recording.cdr import KINDS
from prsm_lube_ros.recording.typestore import contract_fielddef, contract_typestore, STANDARD_DEFINITIONS


def test_light_definitions_equal_the_stores():
    store = contract_typestore().fielddefs
    names = set(STANDARD_DEFINITIONS) | set(KINDS.values()) | {'prsm_lube_ros/msg/LubricationState'}
    for name in sorted(names):
        assert contract_fielddef(name) == store[name], name


def test_other_types_come_from_the_store():
    assert contract_fielddef('geometry_msgs/msg/Twist') == contract_typestore().fielddefs['geometry_msgs/msg/Twist']
    assert contract_fielddef('nobody/msg/Nothing') is None


def test_layout_check_does_not_build_the_store():
    code = ('import sys\n'
            'from prsm_lube_ros.recording.cdr import check_layout, KINDS\n'
            'from prsm_lube_ros.recording.typestore import message_definition\n'
            "assert check_layout('vibration', KINDS['vibration'], 'ros2msg', message_definition('VibrationBlock')) "
            'is None\n'
            "for kind in KINDS: assert check_layout(kind, KINDS[kind], '', '') is None\n"
            "print(sorted(m for m in sys.modules if m.startswith('rosbags.typesys.stores.')))\n")
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == '[]'
