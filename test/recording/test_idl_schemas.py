# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``ros2idl`` schemas with ``#include`` lines (what rosbag2 stores when no .msg exists) are understood."""

import pytest

import bagfactory as bf
from prsm_lube_ros.errors import RecordingError
from prsm_lube_ros.recording.cdr import check_layout
from prsm_lube_ros.recording.reader import open_recording

SEPARATOR = '=' * 80 + '\n'
GENERATED = ('// generated from rosidl_adapter/resource/msg.idl.em\n'
             '// generated code does not contain a copyright notice\n')
TIME = GENERATED + '''
module builtin_interfaces {
  module msg {
    struct Time {
      int32 sec;
      uint32 nanosec;
    };
  };
};
'''
HEADER = GENERATED + '''
#include "builtin_interfaces/msg/Time.idl"

module std_msgs {
  module msg {
    struct Header {
      builtin_interfaces::msg::Time stamp;
      string frame_id;
    };
  };
};
'''
VIBRATION = GENERATED + '''
#include "std_msgs/msg/Header.idl"

module prsm_lube_ros {
  module msg {
    @verbatim (language="comment", text=
      "Consecutive samples from one accelerometer axis.")
    struct VibrationBlock {
      @unit (value="0")
      std_msgs::msg::Header header;
      double sample_rate;
      sequence<float> samples;
    };
  };
};
'''
VECTOR3 = GENERATED + '''
module geometry_msgs {
  module msg {
    struct Vector3 {
      double x;
      double y;
      double z;
    };
  };
};
'''
WRENCH = GENERATED + '''
#include "geometry_msgs/msg/Vector3.idl"

module geometry_msgs {
  module msg {
    struct Wrench {
      geometry_msgs::msg::Vector3 force;
      geometry_msgs::msg::Vector3 torque;
    };
  };
};
'''
WRENCH_STAMPED = GENERATED + '''
#include "geometry_msgs/msg/Wrench.idl"
#include "std_msgs/msg/Header.idl"

module geometry_msgs {
  module msg {
    struct WrenchStamped {
      std_msgs::msg::Header header;
      geometry_msgs::msg::Wrench wrench;
    };
  };
};
'''


def ros2idl(root, *dependencies):
    """A schema as rosbag2 stores it: the root's IDL, then each dependency after a separator line."""
    return root + ''.join(f'{SEPARATOR}IDL: {name}\n{text}' for name, text in dependencies)


SCHEMAS = {
    'prsm_lube_ros/msg/VibrationBlock': ('ros2idl', ros2idl(
        VIBRATION, ('std_msgs/msg/Header', HEADER), ('builtin_interfaces/msg/Time', TIME))),
    'geometry_msgs/msg/WrenchStamped': ('ros2idl', ros2idl(
        WRENCH_STAMPED, ('geometry_msgs/msg/Wrench', WRENCH), ('geometry_msgs/msg/Vector3', VECTOR3),
        ('std_msgs/msg/Header', HEADER), ('builtin_interfaces/msg/Time', TIME))),
}


def test_idl_schemas_with_includes_read_like_msg_schemas(tmp_path):
    entries = bf.contract_entries(seconds=3.0)
    plain = bf.write_mcap_library(tmp_path / 'msg.mcap', entries, compression='none', chunk_size=16 * 1024)
    idl = bf.write_mcap_library(tmp_path / 'idl.mcap', entries, compression='none', chunk_size=16 * 1024,
                                schemas=SCHEMAS)
    recording = open_recording(idl)
    assert all(topic.layout_problem is None for topic in recording.topics.values())
    want = list(open_recording(plain).slices(slice_seconds=1.0))
    got = list(recording.slices(slice_seconds=1.0))
    bf.assert_same_slices(want, got, at_least=3)


def test_an_idl_root_with_a_separator_line_before_it_also_parses():
    text = SEPARATOR + 'IDL: prsm_lube_ros/msg/VibrationBlock\n' + SCHEMAS['prsm_lube_ros/msg/VibrationBlock'][1]
    assert check_layout('vibration', 'prsm_lube_ros/msg/VibrationBlock', 'ros2idl', text) is None


def test_an_idl_schema_of_another_layout_is_refused_in_one_line(tmp_path):
    wrong = {'prsm_lube_ros/msg/VibrationBlock': ('ros2idl', ros2idl(
        VIBRATION.replace('double sample_rate;', 'float sample_rate;'), ('std_msgs/msg/Header', HEADER)))}
    path = bf.write_mcap_library(tmp_path / 'wrong.mcap', bf.contract_entries(seconds=1.0), schemas=wrong)
    with pytest.raises(RecordingError, match='sample_rate float32') as raised:
        open_recording(path)
    assert '\n' not in str(raised.value)
