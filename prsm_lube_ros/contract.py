# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""The names ``CONTRACT.md`` fixes: interface types, topic leaves, the screw joint, and how topics are named.

This is the one place where a contract name is spelled; everything else
imports it from here.  It imports nothing of the package.

Topic names: an actuator's topics are ``<namespace>/<leaf>`` (``/prsm`` +
``vibration`` -> ``/prsm/vibration``).  A namespace that ends in ``_`` or
``/`` is a prefix (``/rig/left_`` -> ``/rig/left_vibration``), as some stacks
name their topics; a leaf that starts with ``/`` is already absolute; an empty
namespace leaves the leaf relative (ROS resolves it in the node's namespace).

Node namespaces: the nodes use relative names in their own namespace, ``/prsm``
(:data:`DEFAULT_NAMESPACE`) unless remapped, so the contract's ``/prsm/...`` is
what the default namespace gives and ``-r __ns:=/ema_left`` moves every name.
"""
from __future__ import annotations


__all__ = ['AXIAL_LOAD_TOPIC', 'CALIBRATE', 'CALIBRATE_SERVICE', 'DEFAULT_NAMESPACE', 'DIAGNOSTICS_TOPIC',
           'JOINT_STATE', 'JOINT_STATES_TOPIC', 'LUBRICATION_STATE', 'LUBRICATION_STATE_TOPIC', 'LUBRICATION_TASK',
           'PACKAGE', 'SCREW_JOINT', 'SOURCE_TASK', 'SURFACE_TASK', 'TEMPERATURE', 'TEMPERATURE_TOPIC',
           'VIBRATION_BLOCK', 'VIBRATION_BLOCK_LAYOUT', 'VIBRATION_TOPIC', 'WRENCH_STAMPED', 'namespace_of',
           'status_name', 'topic_name']

PACKAGE = 'prsm_lube_ros'
VIBRATION_BLOCK = f'{PACKAGE}/msg/VibrationBlock'
LUBRICATION_STATE = f'{PACKAGE}/msg/LubricationState'
CALIBRATE = f'{PACKAGE}/srv/Calibrate'
JOINT_STATE = 'sensor_msgs/msg/JointState'
WRENCH_STAMPED = 'geometry_msgs/msg/WrenchStamped'
TEMPERATURE = 'sensor_msgs/msg/Temperature'

#: Field names and types of VibrationBlock, as the contract fixes them.
VIBRATION_BLOCK_LAYOUT = (('header', 'std_msgs/msg/Header'),
                          ('sample_rate', 'float64'),
                          ('samples', 'float32[]'))

#: Default namespace of an actuator's topics, and of the nodes (their names are relative).
DEFAULT_NAMESPACE = '/prsm'
#: Topic leaves below the namespace.
VIBRATION_TOPIC = 'vibration'
JOINT_STATES_TOPIC = 'joint_states'
AXIAL_LOAD_TOPIC = 'axial_load'
TEMPERATURE_TOPIC = 'temperature'
LUBRICATION_STATE_TOPIC = 'lubrication_state'
CALIBRATE_SERVICE = 'calibrate'
DIAGNOSTICS_TOPIC = '/diagnostics'
#: Name of the screw's entry in ``JointState``.
SCREW_JOINT = 'screw'


#: Tasks of the diagnostic statuses on ``/diagnostics`` (see :func:`status_name`).
LUBRICATION_TASK = 'lubrication'
SOURCE_TASK = 'sensor source'
#: The estimator's second status per actuator: the surface defect screen (theta_Oil is withheld while it is ERROR).
SURFACE_TASK = 'surface condition'


def status_name(node_name: str, namespace: str, task: str) -> str:
    """diagnostic_updater style status name ``'<node name>: <namespace> <task>'``.

    ``config/diagnostic_aggregator.yaml`` claims the statuses by ``' <task>'``.
    """
    return f'{node_name}: {namespace} {task}'


def topic_name(namespace: str, leaf: str) -> str:
    """Topic ``leaf`` of the actuator in ``namespace`` (see the module's rules)."""
    if leaf.startswith('/'):
        return leaf
    if not namespace:
        return leaf
    if not namespace.startswith('/'):
        namespace = '/' + namespace
    if namespace.endswith(('/', '_')):
        return namespace + leaf
    return f'{namespace}/{leaf}'


def namespace_of(topic: str, leaf: str = VIBRATION_TOPIC) -> str | None:
    """The namespace whose ``leaf`` topic is ``topic`` (inverse of :func:`topic_name`); None if it is not one."""
    if topic.endswith('/' + leaf):
        return topic[:-len(leaf) - 1]
    if topic.endswith('_' + leaf):
        return topic[:-len(leaf)]
    return None
