# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What ``launch/prsm_lube.launch.py`` does with its arguments, without launch (testable anywhere).

The launch file declares :data:`LAUNCH_ARGUMENTS` and hands their values to
:func:`bringup_plan`, which checks them (one :class:`InputError` line naming
the argument) and says, per node, the namespace, the parameter files in the
order they apply, the ``--ros-args`` and whether the nodes configure and
activate themselves (their ``autostart`` parameter).  Plain Python: no ROS import.

The namespace composes as nav2's and ros2_control's bring-ups do: its default
'' gives the nodes no namespace of their own, so an enclosing launch's
``PushRosNamespace('/robot/left')`` puts them at ``/robot/left/...``, and with
nothing pushed they keep their built-in ``/prsm`` (the contract's names).  A
value is relative to whatever is pushed (``prsm`` under ``/robot/left``:
``/robot/left/prsm``) or absolute (``/rig/left``: there, pushed or not).
"""
from __future__ import annotations

from dataclasses import dataclass
import os

from ..errors import InputError

__all__ = ['BRIDGE_EXECUTABLE', 'BringupPlan', 'ESTIMATOR_EXECUTABLE', 'LAUNCH_ARGUMENTS', 'LOG_LEVELS', 'NodePlan',
           'bringup_plan', 'flag']

#: (name, default, description) of each launch argument.
LAUNCH_ARGUMENTS = (
    ('namespace', '', 'namespace of both nodes: their topics, services and actions are relative names in it; '
     "'' (default): the enclosing launch's pushed namespace, /prsm when nothing is pushed; relative values are "
     'put below the pushed namespace, absolute ones (e.g. /rig/left) are used as they are'),
    ('log_level', 'info', 'log level of both nodes: debug, info, warn, error or fatal'),
    ('use_sim_time', 'false', 'run the nodes on /clock (bag replay, simulation)'),
    ('params_file', '', 'one more parameter file for both nodes, applied after the package\'s '
     '(keys /**/lubrication_estimator, /**/sensor_bridge); empty: none'),
    ('autostart', 'true', 'the autostart parameter of both lifecycle nodes: they configure and activate '
     'themselves at start-up; false: they wait unconfigured for a lifecycle manager (ros2 lifecycle set, '
     'nav2_lifecycle_manager)'),
    ('bridge', 'true', 'start the sensor bridge (false: inputs come from elsewhere)'),
    ('estimator_config', '', 'parameter file of the lubrication_estimator node (empty: config/estimator.yaml)'),
    ('bridge_config', '', 'parameter file of the sensor_bridge node (empty: config/sensor_bridge.yaml)'),
)
LOG_LEVELS = ('debug', 'info', 'warn', 'error', 'fatal')
#: Executables started (installed to lib/prsm_lube_ros by CMakeLists.txt).
ESTIMATOR_EXECUTABLE = 'lubrication_estimator'
BRIDGE_EXECUTABLE = 'sensor_bridge_managed'


@dataclass(frozen=True)
class NodePlan:
    """One node of the bring-up."""

    executable: str
    name: str
    namespace: str             # '': none of its own (the pushed namespace, else the node's /prsm)
    parameters: tuple          # parameter files in the order they apply, then {'use_sim_time', 'autostart'}
    ros_arguments: tuple


@dataclass(frozen=True)
class BringupPlan:
    """The nodes to start and whether they bring themselves to active."""

    estimator: NodePlan
    bridge: NodePlan | None
    autostart: bool


def flag(name: str, value: str) -> bool:
    """A launch argument that must be true or false (as launch's IfCondition reads them)."""
    text = str(value).strip().lower()
    if text in ('true', '1'):
        return True
    if text in ('false', '0'):
        return False
    raise InputError(f'launch argument {name}:={value!r} must be true or false')


def bringup_plan(arguments: dict, config_dir: str) -> BringupPlan:
    """The bring-up for launch argument values ``arguments`` (missing ones take their defaults)."""
    values = {name: default for name, default, _ in LAUNCH_ARGUMENTS}
    values.update({k: str(v) for k, v in arguments.items() if k in values})
    level = values['log_level'].strip().lower()
    if level not in LOG_LEVELS:
        raise InputError(f'launch argument log_level:={values["log_level"]!r} is not one of {", ".join(LOG_LEVELS)}')
    namespace = values['namespace'].strip()
    if namespace and (namespace == '/' or not all(part.replace('_', 'a').isalnum() and not part[0].isdigit()
                                                  for part in namespace.strip('/').split('/'))):
        raise InputError(f'launch argument namespace:={values["namespace"]!r} is not a ROS namespace '
                         '(letters, digits, _ and /, e.g. /rig/left)')
    params_file = values['params_file'].strip()
    if params_file and not os.path.isfile(os.path.expanduser(params_file)):
        raise InputError(f'launch argument params_file:={params_file}: no such file')
    autostart = flag('autostart', values['autostart'])
    sim_time = {'use_sim_time': flag('use_sim_time', values['use_sim_time']), 'autostart': autostart}
    ros_arguments = ('--log-level', level)

    def files(own: str, default: str) -> tuple:
        return tuple(f for f in (own.strip() or os.path.join(config_dir, default),
                                 os.path.expanduser(params_file) if params_file else '') if f)

    estimator = NodePlan(ESTIMATOR_EXECUTABLE, 'lubrication_estimator', namespace,
                         files(values['estimator_config'], 'estimator.yaml') + (sim_time,), ros_arguments)
    bridge = None
    if flag('bridge', values['bridge']):
        bridge = NodePlan(BRIDGE_EXECUTABLE, 'sensor_bridge', namespace,
                          files(values['bridge_config'], 'sensor_bridge.yaml') + (sim_time,), ros_arguments)
    return BringupPlan(estimator, bridge, autostart)
