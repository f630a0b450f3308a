# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Bring-up: the lifecycle sensor bridge and the lubrication estimator with the package's config/*.yaml.

    ros2 launch prsm_lube_ros prsm_lube.launch.py [namespace:=/rig/left] [log_level:=debug]
        [use_sim_time:=true] [params_file:=/path/site.yaml] [autostart:=false] [bridge:=false]
        [estimator_config:=/path/estimator.yaml] [bridge_config:=/path/sensor_bridge.yaml]

What the arguments mean and how they are checked is in prsm_lube_ros.nodes.launch_arguments
(plain Python, tested without launch).  With autostart (the default) launch's lifecycle event
handlers configure the bridge once its process runs and activate it once it is inactive; the
bridge logs each transition.  Machines without ``ros2 launch`` run ``prsm-lube run`` instead.
"""
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, EmitEvent, OpaqueFunction, RegisterEventHandler
from launch.event_handlers import OnProcessStart
from launch.events import matches_action
from launch_ros.actions import LifecycleNode, Node
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from lifecycle_msgs.msg import Transition
from prsm_lube_ros.nodes.launch_arguments import bringup_plan, LAUNCH_ARGUMENTS

PACKAGE = 'prsm_lube_ros'


def change_state(node, transition_id):
    """The event asking launch to move ``node`` (a LifecycleNode action) through a transition."""
    return EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(node), transition_id=transition_id))


def launch_setup(context):
    """The actions for the arguments' values (see bringup_plan)."""
    config = get_package_share_directory(PACKAGE) + '/config'
    plan = bringup_plan(context.launch_configurations, config)
    estimator = plan.estimator
    actions = [Node(package=PACKAGE, executable=estimator.executable, name=estimator.name,
                    namespace=estimator.namespace, output='screen', parameters=list(estimator.parameters),
                    ros_arguments=list(estimator.ros_arguments))]
    if plan.bridge is not None:
        bridge = LifecycleNode(package=PACKAGE, executable=plan.bridge.executable, name=plan.bridge.name,
                               namespace=plan.bridge.namespace, output='screen',
                               parameters=list(plan.bridge.parameters), ros_arguments=list(plan.bridge.ros_arguments))
        actions.append(bridge)
        if plan.autostart:
            actions += [
                RegisterEventHandler(OnProcessStart(target_action=bridge, on_start=[
                    change_state(bridge, Transition.TRANSITION_CONFIGURE)])),
                RegisterEventHandler(OnStateTransition(target_lifecycle_node=bridge, start_state='configuring',
                                                       goal_state='inactive', entities=[
                                                           change_state(bridge, Transition.TRANSITION_ACTIVATE)])),
            ]
    return actions


def generate_launch_description():
    """The launch arguments, then the nodes they ask for."""
    return LaunchDescription([DeclareLaunchArgument(name, default_value=default, description=description)
                              for name, default, description in LAUNCH_ARGUMENTS]
                             + [OpaqueFunction(function=launch_setup)])
