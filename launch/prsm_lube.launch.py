# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Bring-up: the lifecycle sensor bridge and the lifecycle lubrication estimator with the package's config/*.yaml.

    ros2 launch prsm_lube_ros prsm_lube.launch.py [namespace:=/rig/left] [log_level:=debug]
        [use_sim_time:=true] [params_file:=/path/site.yaml] [autostart:=false] [bridge:=false]
        [estimator_config:=/path/estimator.yaml] [bridge_config:=/path/sensor_bridge.yaml]

What the arguments mean and how they are checked is in prsm_lube_ros.nodes.launch_arguments
(plain Python, tested without launch).  It composes: included under ``PushRosNamespace('/robot/left')``
the nodes come up at ``/robot/left/...`` (the ``namespace`` argument's default '' adds none of its
own); with nothing pushed they keep their built-in ``/prsm``.  ``autostart`` is a parameter of both
nodes: true (default) and each configures and activates itself; false and both wait unconfigured for a
lifecycle manager (``ros2 lifecycle set``, ``nav2_lifecycle_manager`` with their node names).
Machines without ``ros2 launch`` run ``prsm-lube run`` instead.
"""
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch_ros.actions import Node
from prsm_lube_ros.nodes.launch_arguments import bringup_plan, LAUNCH_ARGUMENTS

PACKAGE = 'prsm_lube_ros'


def node_action(plan):
    """The launch_ros Node of one NodePlan: no namespace of its own when the plan has none (see the docstring)."""
    return Node(package=PACKAGE, executable=plan.executable, name=plan.name, namespace=plan.namespace or None,
                output='screen', parameters=list(plan.parameters), ros_arguments=list(plan.ros_arguments))


def launch_setup(context):
    """The actions for the arguments' values (see bringup_plan)."""
    config = get_package_share_directory(PACKAGE) + '/config'
    plan = bringup_plan(context.launch_configurations, config)
    return [node_action(node) for node in (plan.estimator, plan.bridge) if node is not None]


def generate_launch_description():
    """The launch arguments, then the nodes they ask for."""
    return LaunchDescription([DeclareLaunchArgument(name, default_value=default, description=description)
                              for name, default, description in LAUNCH_ARGUMENTS]
                             + [OpaqueFunction(function=launch_setup)])
