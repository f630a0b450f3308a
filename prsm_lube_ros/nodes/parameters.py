# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Node parameters declared from a table, with descriptions, ranges and one-line errors.

Both nodes describe their parameters as ``{name: (default, type, description,
bounds, read_only)}``; :func:`declare_parameter_table` declares them so that
``ros2 param describe`` shows the description and range, and turns a value a
user passed (``--ros-args -p``, a params file) that breaks its range or type
into an :class:`InputError` naming the parameter, instead of a traceback.
"""
from __future__ import annotations

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType
from rclpy.exceptions import ParameterException

from ..errors import InputError

DOUBLE = ParameterType.PARAMETER_DOUBLE
INTEGER = ParameterType.PARAMETER_INTEGER


def parameter_descriptor(name: str, ptype: int, description: str, bounds, read_only: bool) -> ParameterDescriptor:
    """Descriptor with the description, read-only flag and (for numbers) the inclusive range ``bounds``."""
    descriptor = ParameterDescriptor(name=name, type=ptype, description=description, read_only=read_only)
    if bounds and ptype == DOUBLE:
        descriptor.floating_point_range = [FloatingPointRange(from_value=float(bounds[0]),
                                                              to_value=float(bounds[1]))]
    elif bounds and ptype == INTEGER:
        descriptor.integer_range = [IntegerRange(from_value=int(bounds[0]), to_value=int(bounds[1]), step=1)]
    return descriptor


def declare_parameter_table(node, table: dict) -> dict:
    """Declare every parameter of ``table`` on ``node``; return their values by name.

    Raises :class:`InputError` (one line naming the parameter, its value and
    its range) when an override does not fit.
    """
    for name, (default, ptype, description, bounds, read_only) in table.items():
        try:
            node.declare_parameter(name, default, parameter_descriptor(name, ptype, description, bounds,
                                                                       read_only))
        except ParameterException as exc:
            raise InputError(f'parameter {name}: {_reason(exc, name)}') from None
    return {name: node.get_parameter(name).value for name in table}


def _reason(exc: ParameterException, name: str) -> str:
    """rclpy's explanation without its boilerplate: 'out of range Min: 0.05, Max: 60.0, value: -1.0'."""
    text = str(exc).strip()
    if 'Reason:' in text:
        text = text.split('Reason:', 1)[1].strip()
    if text.endswith(f': {name}'):
        text = text[:-len(name) - 2]
    return text.replace(f'Parameter {name} ', '').replace(f"Trying to set parameter '{name}' to ", 'value ')
