# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""``prsm-lube run``: the sensor bridge and the lubrication estimator in one process.

For machines without ``ros2 launch`` (a venv with ROS 2 from wheels): it does
what ``launch/prsm_lube.launch.py`` does.  Parameters come from the package's
``config/estimator.yaml`` and ``config/sensor_bridge.yaml`` (or ``--config``
files), then ``--param NAME:=VALUE`` overrides for the estimator; anything after
``--ros-args`` goes to ROS as usual.  The bridge is started when
:mod:`prsm_lube_ros.nodes.sensor_bridge` is installed and ``--no-bridge`` is not
given; that module provides ``create_node(**node_kwargs)`` or a ``SensorBridge``
node class.

Nothing from ROS is imported until the command runs (``prsm-lube`` must start
on machines without ROS).
"""
from __future__ import annotations

import argparse
import importlib
from pathlib import Path
import sys

from ..errors import InputError

__all__ = ['BRIDGE_MODULE', 'CONFIG_FILES', 'add_command', 'cmd_run', 'default_config_files', 'parse_override']

BRIDGE_MODULE = 'prsm_lube_ros.nodes.sensor_bridge'
CONFIG_FILES = ('estimator.yaml', 'sensor_bridge.yaml')


def default_config_files() -> list[Path]:
    """The package's config files that exist (source tree or installed share folder)."""
    from ..recording.typestore import interface_dir
    try:
        folder = interface_dir() / 'config'
    except FileNotFoundError:
        return []
    return [folder / name for name in CONFIG_FILES if (folder / name).is_file()]


def parse_override(text: str):
    """``NAME:=VALUE`` (or ``NAME=VALUE``) as ``(name, value)`` with the value read as YAML."""
    for separator in (':=', '='):
        if separator in text:
            name, raw = text.split(separator, 1)
            break
    else:
        raise InputError(f'--param {text!r}: expected NAME:=VALUE')
    name = name.strip()
    if not name:
        raise InputError(f'--param {text!r}: the parameter name is empty')
    import yaml
    try:
        value = yaml.safe_load(raw) if raw.strip() else ''
    except yaml.YAMLError:
        value = raw
    if value is None:
        value = ''
    return name, value


def add_command(subparsers) -> None:
    """Add ``run`` to the ``prsm-lube`` subcommands."""
    parser = subparsers.add_parser(
        'run', help='start the sensor bridge and the lubrication estimator in one process',
        description='Start the sensor bridge and the lubrication estimator in one process, with the '
        'package\'s config/*.yaml, for machines without ros2 launch. Ctrl-C stops both.')
    parser.add_argument('--config', action='append', metavar='YAML',
                        help='ROS parameter file (repeatable; default: the package\'s config/estimator.yaml '
                        'and config/sensor_bridge.yaml)')
    parser.add_argument('--param', '-p', action='append', default=[], metavar='NAME:=VALUE',
                        help='estimator parameter, e.g. -p "actuators:=[/ema_left/prsm]" (repeatable)')
    parser.add_argument('--no-bridge', action='store_true',
                        help='start only the estimator (inputs come from another publisher)')
    parser.add_argument('--use-sim-time', action='store_true', help='run both nodes on /clock')
    parser.add_argument('--ros-args', dest='ros_args', nargs=argparse.REMAINDER, default=[],
                        help='the rest of the line goes to ROS (remappings, log levels, ...)')
    parser.set_defaults(func=cmd_run)


def _bridge_factory():
    """The bridge's node factory, or None when the bridge module is not installed."""
    try:
        module = importlib.import_module(BRIDGE_MODULE)
    except ModuleNotFoundError as exc:
        if exc.name in (BRIDGE_MODULE, BRIDGE_MODULE.rsplit('.', 1)[0]):
            return None
        raise
    factory = getattr(module, 'create_node', None) or getattr(module, 'SensorBridge', None)
    if factory is None:
        raise InputError(f'{BRIDGE_MODULE} has neither create_node() nor SensorBridge; start it with --no-bridge')
    return factory


def cmd_run(args) -> int:
    """Start the nodes and spin until Ctrl-C; returns the exit status."""
    configs = [Path(p) for p in args.config] if args.config else default_config_files()
    for path in configs:
        if not path.is_file():
            raise InputError(f'{path}: parameter file not found')
    overrides = [parse_override(text) for text in args.param]
    if args.use_sim_time:
        overrides.append(('use_sim_time', True))
    bridge_factory = None if args.no_bridge else _bridge_factory()

    import rclpy
    from rclpy.parameter import Parameter
    from ..nodes.lubrication_estimator import LubricationEstimator
    from ..nodes.startup import init_ros, spin_until_stopped

    ros_args = ['--ros-args']
    for path in configs:
        ros_args += ['--params-file', str(path)]
    init_ros(['prsm-lube'] + ros_args + [a for a in args.ros_args if a != '--ros-args'])
    nodes = []
    try:
        parameters = [Parameter(name, value=value) for name, value in overrides]
        nodes.append(LubricationEstimator(parameter_overrides=parameters))
        if bridge_factory is not None:
            sim = [Parameter('use_sim_time', value=True)] if args.use_sim_time else []
            nodes.append(bridge_factory(parameter_overrides=sim) if sim else bridge_factory())
        elif not args.no_bridge:
            print('prsm-lube run: no sensor bridge installed; running the estimator alone', file=sys.stderr)
    except BaseException:
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
        raise
    spin_until_stopped(nodes)
    return 0
