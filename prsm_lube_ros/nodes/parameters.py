# Copyright 2026 prsm_lube_ros developers
# SPDX-License-Identifier: Apache-2.0
"""Node parameters declared from a table, with descriptions, ranges and one-line errors.

Both nodes describe their parameters as ``{name: ParameterSpec(default, type,
description, bounds=..., read_only=...)}``; :func:`declare_parameter_table` declares them so that
``ros2 param describe`` shows the description and range, and turns a value a
user passed (``--ros-args -p``, a params file) that breaks its range or type
into an :class:`InputError` naming the parameter, instead of a traceback.

Read-only parameters (``read_only`` in the table, ``ParameterDescriptor.read_only``
on the graph, so ``ros2 param describe`` says so) are fixed after start-up.
rclpy refuses every set of a read-only parameter before any callback runs, even
one to its current value, so ``ros2 param load`` of a node's own ``ros2 param
dump`` failed on each of them (and on rclpy's own ``start_type_description_service``).
:class:`ReadOnlyAfterStartUp`, mixed in before the rclpy node class, takes
those sets first, in ``set_parameters_atomically`` (what the ``set_parameters``
and ``set_parameters_atomically`` services call): a read-only parameter set to
its current value passes without effect, a change is refused with its reason,
and the other parameters go on to rclpy and the node's own callback.
"""
from __future__ import annotations

import copy
from typing import Any, NamedTuple, TYPE_CHECKING
from collections.abc import Callable

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType, \
    SetParametersResult
from rclpy.exceptions import ParameterException
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from rclpy.qos_overriding_options import QoSOverridingOptions

from ..errors import InputError

__all__ = ['DEFAULT_DIAGNOSTIC_PERIOD', 'DOUBLE', 'FORMER_DIAGNOSTIC_PERIOD', 'INTEGER', 'OVERRIDABLE',
           'ParameterSpec', 'ReadOnlyAfterStartUp', 'declare_parameter_table', 'diagnostic_period', 'own_qos',
           'parameter_descriptor', 'resolved_names', 'same_value', 'value_problem']

if TYPE_CHECKING:
    from rclpy.impl.rcutils_logger import RcutilsLogger
    from rclpy.node import Node
    _NodeBase = Node              # the mixin goes before an rclpy Node: its methods are there
else:
    _NodeBase = object

DOUBLE = ParameterType.PARAMETER_DOUBLE
INTEGER = ParameterType.PARAMETER_INTEGER
#: s between /diagnostics messages when neither diagnostic_period nor its former name diagnostics_period is given.
DEFAULT_DIAGNOSTIC_PERIOD = 1.0
#: Every publisher and subscription of the nodes offers the standard
#: ``qos_overrides.<topic>.<publisher|subscription>.<policy>`` parameters (history, depth, reliability), read
#: when the entity is created, as ros2_control, nav2 and drivers do (rclpy ``QoSOverridingOptions``).
OVERRIDABLE = QoSOverridingOptions.with_default_policies()


class ParameterSpec(NamedTuple):
    """One row of a node's parameter table."""

    #: value when none is given at start-up
    default: Any
    #: ``rcl_interfaces.msg.ParameterType`` constant
    type: int
    #: what ``ros2 param describe`` shows
    description: str
    #: inclusive (low, high) of a number; None: any value of the type
    bounds: tuple | None = None
    #: fixed after start-up (see :class:`ReadOnlyAfterStartUp`)
    read_only: bool = False


#: Both nodes' former name of ``diagnostic_period`` (see :func:`diagnostic_period`).
FORMER_DIAGNOSTIC_PERIOD = ParameterSpec(
    DEFAULT_DIAGNOSTIC_PERIOD, DOUBLE,
    'former name of diagnostic_period, still honoured when diagnostic_period is left at its default',
    bounds=(0.05, 60.0), read_only=True)


def parameter_descriptor(name: str, ptype: int, description: str, bounds: tuple | None,
                         read_only: bool) -> ParameterDescriptor:
    """Descriptor with the description, read-only flag and (for numbers) the inclusive range ``bounds``."""
    descriptor = ParameterDescriptor(name=name, type=ptype, description=description, read_only=read_only)
    if bounds and ptype == DOUBLE:
        descriptor.floating_point_range = [FloatingPointRange(from_value=float(bounds[0]),
                                                              to_value=float(bounds[1]))]
    elif bounds and ptype == INTEGER:
        descriptor.integer_range = [IntegerRange(from_value=int(bounds[0]), to_value=int(bounds[1]), step=1)]
    return descriptor


def declare_parameter_table(node: Node, table: dict, resolve: dict | None = None) -> dict:
    """Declare every parameter of ``table`` on ``node``; return their values by name.

    ``resolve`` maps names of read-only parameters that hold ROS names to a
    function giving the resolved name(s) of a value: such a parameter is
    declared, set to what its value resolves to in this node (``calibrate`` ->
    ``/prsm/calibrate``, or ``/ema_left/calibrate`` after ``-r __ns:=/ema_left``),
    and only then made read-only, so ``ros2 param get`` reports the names the
    node uses.  Raises :class:`InputError` (one line naming the parameter, its
    value and its range, or type) when a value given at start-up does not fit.
    """
    resolve = resolve or {}
    for name, (default, ptype, description, bounds, read_only) in table.items():
        # Declared first with any type and no range, so that a value given at start-up is checked here in
        # our words (rclpy's exceptions carry only text); the real descriptor follows once it fits.
        value = node.declare_parameter(name, default, ParameterDescriptor(
            name=name, description=description, dynamic_typing=True)).value
        problem = value_problem(value, ptype, bounds)
        if problem:
            raise InputError(f'parameter {name}: {problem}')
        try:
            if name in resolve:
                resolved = resolve[name](value)
                if resolved != value:
                    node.set_parameters([Parameter(name, value=resolved)])
            node.set_descriptor(name, parameter_descriptor(name, ptype, description, bounds, read_only))
        except ParameterException as exc:
            raise InputError(f'parameter {name}: {value!r} refused by rclpy ({type(exc).__name__})') from None
    return {name: node.get_parameter(name).value for name in table}


def value_problem(value: Any, ptype: int, bounds: tuple | None) -> str | None:
    """Why ``value`` does not fit a parameter of type ``ptype`` and inclusive range ``bounds`` (None: it fits)."""
    given = Parameter.Type.from_parameter_value(value)
    if given.value != ptype:
        expected = Parameter.Type(ptype).name.lower().replace('_', ' ')
        return f'{value!r} is of type {given.name.lower().replace("_", " ")}, expected {expected}'
    if bounds and ptype in (DOUBLE, INTEGER) and not bounds[0] <= value <= bounds[1]:
        return f'{value!r} is out of its range {bounds[0]:g} to {bounds[1]:g}'
    return None


def same_value(parameter: Parameter, current: Parameter) -> bool:
    """Whether a parameter being set holds the value (and type) it has now."""
    if parameter.type_ != current.type_:
        return False
    new, old = parameter.value, current.value
    if isinstance(new, (list, tuple)) or isinstance(old, (list, tuple)) or hasattr(new, 'tolist'):
        return list(new) == list(old)
    return new == old


class ReadOnlyAfterStartUp(_NodeBase):
    """Mixin before an rclpy ``Node``: read-only parameters set to their value pass; a change gets its reason.

    See the module docstring.  ``fixed_reasons`` (name: why) adds why a
    parameter is fixed to the refusal, e.g. what a change would let a caller do.
    """

    fixed_reasons: dict = {}

    @property
    def log(self) -> RcutilsLogger:
        """The node's logger (rclpy's ``get_logger``, which carries no annotations, called as a Node's)."""
        node: Node = self
        return node.get_logger()

    def set_parameters_atomically(self, parameter_list: list[Parameter]) -> SetParametersResult:
        """rclpy's, after taking the read-only parameters out: unchanged ones pass, a change refuses all."""
        changing = []
        for parameter in parameter_list:
            if not (self.has_parameter(parameter.name) and self.describe_parameter(parameter.name).read_only):
                changing.append(parameter)
                continue
            current = self.get_parameter(parameter.name)
            if not same_value(parameter, current):
                why = self.fixed_reasons.get(parameter.name, '')
                return SetParametersResult(successful=False, reason=(
                    f'parameter {parameter.name} is read-only after start-up{": " + why if why else ""}; it stays '
                    f'{current.value!r} (restart the node with the new value)'))
        if not changing:
            return SetParametersResult(successful=True)
        return super().set_parameters_atomically(changing)

    def set_parameters(self, parameter_list: list[Parameter]) -> list[SetParametersResult]:
        """One :meth:`set_parameters_atomically` per parameter, as rclpy's own does."""
        return [self.set_parameters_atomically([parameter]) for parameter in parameter_list]


def resolved_names(node: Node) -> Callable[[str], str]:
    """A resolver for :func:`declare_parameter_table`: a service or topic name resolved in ``node``."""
    return lambda value: node.resolve_service_name(value) if str(value).strip() else value


def own_qos(profile: QoSProfile) -> QoSProfile:
    """A copy of ``profile`` for one entity: rclpy writes the entity's QoS overrides into the profile it is given."""
    return copy.copy(profile)


def diagnostic_period(values: dict) -> float:
    """``diagnostic_period``; the former name ``diagnostics_period`` when only that one was changed."""
    if values['diagnostic_period'] == DEFAULT_DIAGNOSTIC_PERIOD:
        return float(values['diagnostics_period'])
    return float(values['diagnostic_period'])
