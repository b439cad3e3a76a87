# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Declare a node's parameters from the declarations and validate them with the core's checks.

Each parameter the executable reads is declared once, typed, with its description and range,
read-only except those a node lets change while it runs (the reference's shape, origin and
speed), which that node checks itself when they are set. Optional parameters without a value
(``start.positions`` when the start is random, ``sensing_radii`` when every robot has
``sensing_radius``) are declared only when given, and
``reference.origin`` / ``reference.velocity`` with their zero defaults, so ``ros2 param dump``
and ``ros2 param get`` answer for every declared parameter.
"""

import re
import sys
from typing import Any, Dict, List, Optional, Sequence, Tuple

from formation_ros.core.settings.declarations import (ARRAYS, Bound, BY_NAME, did_you_mean, Exe,
                                                      is_known, Kind, Param, ParamError,
                                                      SHAPE_NAME, SHAPE_VERTICES,
                                                      shape_vertices_name, used_by)
from formation_ros.core.settings.params import FormationConfig, validate
from formation_ros.ros.topics import robot_namespace
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter

TYPES = {
    Kind.INT: Parameter.Type.INTEGER,
    Kind.DOUBLE: Parameter.Type.DOUBLE,
    Kind.STRING: Parameter.Type.STRING,
    Kind.BOOL: Parameter.Type.BOOL,
    Kind.DOUBLE_ARRAY: Parameter.Type.DOUBLE_ARRAY,
    Kind.STRING_ARRAY: Parameter.Type.STRING_ARRAY,
}
FLOAT_MAX = sys.float_info.max
INT_MAX = 2 ** 63 - 1
DEFAULT_ZERO_VECTORS = ('reference.origin', 'reference.velocity')


def _end(bound: Optional[Bound], fallback: float) -> float:
    return fallback if bound is None else bound.value


def descriptor_for(param: Param, name: Optional[str] = None,
                   read_only: bool = True) -> ParameterDescriptor:
    """
    Build the descriptor of a declaration: type, description with range, read-only or not.

    name: the parameter's own name where the declaration stands for many
    (``formations.<name>.vertices``).
    """
    text = param.description
    allowed = param.range_text()
    if allowed:
        text += f' Allowed: {allowed}.'
    descriptor = ParameterDescriptor(name=name or param.name, type=TYPES[param.kind].value,
                                     description=text, read_only=read_only,
                                     dynamic_typing=False)
    if param.low is None and param.high is None:
        return descriptor
    if param.kind is Kind.DOUBLE:
        descriptor.floating_point_range = [FloatingPointRange(
            from_value=float(_end(param.low, -FLOAT_MAX)),
            to_value=float(_end(param.high, FLOAT_MAX)), step=0.0)]
    elif param.kind is Kind.INT:
        descriptor.integer_range = [IntegerRange(
            from_value=int(_end(param.low, -INT_MAX)), to_value=int(_end(param.high, INT_MAX)),
            step=0)]
    return descriptor


def _probe(node: Node, param: Param, name: str, given: Dict[str, Any],
           problems: List[Tuple[str, str]]) -> None:
    """Read what is given for parameter ``name`` (of declaration ``param``) into ``given``."""
    try:
        probe = node.declare_parameter(name, TYPES[param.kind],
                                       ParameterDescriptor(dynamic_typing=False))
    except (InvalidParameterTypeException, InvalidParameterValueException) as exc:
        problems.append((name, str(exc).split(': ' + name)[0]))
        return
    node.undeclare_parameter(name)
    if probe.value is not None:
        value = probe.value
        given[name] = list(value) if param.kind in ARRAYS else value


def _given(node: Node, exe: Exe) -> Dict[str, Any]:
    """
    Return what the command line and parameters files give for ``exe``'s parameters.

    The vertices of named shapes are read for the names ``formations.names`` gives, as nav2
    reads its plugins' parameters.
    """
    given: Dict[str, Any] = {}
    problems: List[Tuple[str, str]] = []
    for param in used_by(exe):
        if param.name != SHAPE_VERTICES:
            _probe(node, param, param.name, given, problems)
    shapes = BY_NAME[SHAPE_VERTICES]
    if exe in shapes.users:
        for shape in given.get('formations.names') or ():
            if SHAPE_NAME.fullmatch(shape):
                _probe(node, shapes, shape_vertices_name(shape), given, problems)
    if problems:
        raise ParamError(problems)
    return given


def _warn_unknown(node: Node) -> None:
    overrides = getattr(node, '_parameter_overrides', {}) or {}
    for name in overrides:
        if not is_known(name):
            node.get_logger().warning(f"ignoring unknown parameter '{name}'{did_you_mean(name)}")


def robot_id_of_namespace(namespace: str) -> Optional[int]:
    """Return i for a namespace ``/robot_<i>`` (i >= 1), else None."""
    match = re.fullmatch(r'/robot_([1-9][0-9]*)', namespace)
    return int(match.group(1)) if match else None


def _robot_identity(namespace: str, given: Dict[str, Any]) -> None:
    """``robot_id`` must agree with the namespace ``/robot_<id>``, or is taken from it."""
    implied = robot_id_of_namespace(namespace)
    stated = given.get('robot_id')
    if stated is None and implied is not None:
        given['robot_id'] = implied
    elif stated is not None and implied is not None and stated != implied:
        raise ParamError([('robot_id', f'is {stated} but the node runs in namespace '
                                       f'{namespace}: robot {stated} belongs in '
                                       f'{robot_namespace(stated)} (or leave robot_id out)')])
    elif stated is not None and implied is None:
        raise ParamError([('robot_id', f'is {stated} but the node runs in namespace '
                                       f"'{namespace}': start it in "
                                       f'{robot_namespace(stated)} (-r __ns:='
                                       f'{robot_namespace(stated)}), where the plant talks '
                                       'to it')])


def declare_parameters(node: Node, exe: Exe,
                       runtime: Sequence[str] = ()) -> FormationConfig:
    """
    Declare and validate the parameters of ``exe`` on ``node``; return its configuration.

    runtime: the parameters this node lets change while it runs (declared writable; the node
    checks new values in its own set-parameters callback); every other one is read-only.
    Raises :class:`ParamError` naming every bad parameter (wrong type, out of range,
    inconsistent). A parameter given that no formation executable knows is logged as a
    warning with the closest known name (it may be meant for another tool).
    """
    _warn_unknown(node)
    given = _given(node, exe)
    if exe is Exe.ROBOT:
        _robot_identity(node.get_namespace(), given)
    config = validate(given, exe)
    effective = dict(config.values)
    for name in DEFAULT_ZERO_VECTORS:
        effective.setdefault(name, [0.0] * config.dim)
    for param in used_by(exe):
        names = ([param.name] if param.name != SHAPE_VERTICES
                 else [shape_vertices_name(shape) for shape in config.shapes])
        for name in names:
            value = effective.get(name)
            if value is not None:
                node.declare_parameter(name, value,
                                       descriptor_for(param, name, name not in runtime),
                                       ignore_override=True)
    return config
