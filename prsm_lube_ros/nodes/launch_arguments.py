# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""What ``launch/prsm_lube.launch.py`` does with its arguments, without launch (testable anywhere).

The launch file declares :data:`LAUNCH_ARGUMENTS` and hands their values to
:func:`bringup_plan`, which checks them (one :class:`InputError` line naming
the argument) and says, per node, the namespace, the parameter files in the
order they apply, the ``--ros-args`` and whether the lifecycle bridge is
brought to active.  Plain Python: no ROS import.
"""
from __future__ import annotations

from dataclasses import dataclass
import os

from ..errors import InputError

__all__ = ['BRIDGE_EXECUTABLE', 'BringupPlan', 'ESTIMATOR_EXECUTABLE', 'LAUNCH_ARGUMENTS', 'LOG_LEVELS', 'NodePlan',
           'bringup_plan', 'flag']

#: (name, default, description) of each launch argument.
LAUNCH_ARGUMENTS = (
    ('namespace', 'prsm', 'namespace of both nodes: their topics, services and actions are relative names in it '
     '(prsm: the contract\'s /prsm/...; e.g. /rig/left)'),
    ('log_level', 'info', 'log level of both nodes: debug, info, warn, error or fatal'),
    ('use_sim_time', 'false', 'run the nodes on /clock (bag replay, simulation)'),
    ('params_file', '', 'one more parameter file for both nodes, applied after the package\'s '
     '(keys /**/lubrication_estimator, /**/sensor_bridge); empty: none'),
    ('autostart', 'true', 'bring the lifecycle sensor bridge to active (configure, then activate) at launch; '
     'false: it waits unconfigured for ros2 lifecycle set'),
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
    namespace: str
    parameters: tuple          # parameter files in the order they apply, then {'use_sim_time': bool}
    ros_arguments: tuple


@dataclass(frozen=True)
class BringupPlan:
    """The nodes to start and whether the lifecycle bridge is brought to active."""

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
    if not namespace or not all(part.replace('_', 'a').isalnum() and not part[0].isdigit()
                                for part in namespace.strip('/').split('/')):
        raise InputError(f'launch argument namespace:={values["namespace"]!r} is not a ROS namespace '
                         '(letters, digits, _ and /, e.g. /rig/left)')
    params_file = values['params_file'].strip()
    if params_file and not os.path.isfile(os.path.expanduser(params_file)):
        raise InputError(f'launch argument params_file:={params_file}: no such file')
    sim_time = {'use_sim_time': flag('use_sim_time', values['use_sim_time'])}
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
    return BringupPlan(estimator, bridge, flag('autostart', values['autostart']))
