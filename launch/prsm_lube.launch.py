# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Bring-up: the sensor bridge and the lubrication estimator with the package's config/*.yaml.

    ros2 launch prsm_lube_ros prsm_lube.launch.py [bridge:=false] [use_sim_time:=true]
        [estimator_config:=/path/estimator.yaml] [bridge_config:=/path/sensor_bridge.yaml]

Machines without ``ros2 launch`` run ``prsm-lube run`` instead (same nodes, same files).
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

PACKAGE = 'prsm_lube_ros'


def generate_launch_description():
    """The two nodes, each with its parameter file and use_sim_time."""
    config = os.path.join(get_package_share_directory(PACKAGE), 'config')
    use_sim_time = LaunchConfiguration('use_sim_time')
    return LaunchDescription([
        DeclareLaunchArgument('estimator_config', default_value=os.path.join(config, 'estimator.yaml'),
                              description='parameter file of the lubrication_estimator node'),
        DeclareLaunchArgument('bridge_config', default_value=os.path.join(config, 'sensor_bridge.yaml'),
                              description='parameter file of the sensor_bridge node'),
        DeclareLaunchArgument('bridge', default_value='true',
                              description='start the sensor bridge (false: inputs come from elsewhere)'),
        DeclareLaunchArgument('use_sim_time', default_value='false',
                              description='run the nodes on /clock (bag replay, simulation)'),
        Node(package=PACKAGE, executable='sensor_bridge', name='sensor_bridge', output='screen',
             condition=IfCondition(LaunchConfiguration('bridge')),
             parameters=[LaunchConfiguration('bridge_config'), {'use_sim_time': use_sim_time}]),
        Node(package=PACKAGE, executable='lubrication_estimator', name='lubrication_estimator',
             output='screen',
             parameters=[LaunchConfiguration('estimator_config'), {'use_sim_time': use_sim_time}]),
    ])
