# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Simulated time for robot nodes without a ``/clock`` subscription.

With ``use_sim_time`` every rclpy node subscribes to ``/clock`` and runs a Python callback per
tick (the plant publishes one per published state). A robot needs none: every state the plant
sends it (its ``pose``, or ``/formation/states`` with the team transport) is stamped with the
plant's simulated time, which is the time the robot needs. A robot node is made on the wall
clock (:func:`wall_clock_overrides`), so rclpy's time source makes no ``/clock`` subscription
(made and removed at once, it would still be announced to every participant), and then put on
simulated time without one (:func:`sim_time_without_clock`); :class:`StateClock` sets the
nodes' clocks to each accepted state's stamp: forward only while the states come, whichever
way it jumps once they had stopped (the robot decides: a link cut for a while, a plant started
again). ``use_sim_time`` still decides which clock a robot is on: with it false the robot stays
on the wall clock and refuses the plant's states as stamped on another clock. It is fixed while
the nodes run (:func:`keep_sim_time` refuses a change). Nodes on wall time are left as they
are; on an rclpy without the node's time source attribute a robot follows ``/clock`` as any
node does.
"""

from typing import Any, List, Optional, Sequence

from formation_ros.core.declarations import ParamError
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import ROSClock
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from rclpy.time_source import TimeSource, USE_SIM_TIME_NAME


def wall_clock_overrides(given: Sequence[Parameter]) -> List[Parameter]:
    """Return a node's parameter overrides ``given`` with ``use_sim_time`` false."""
    return [*given, Parameter(USE_SIM_TIME_NAME, value=False)]


def sim_time_without_clock(node: Node, given: Sequence[Parameter]) -> bool:
    """
    Put ``node``, made with :func:`wall_clock_overrides`, on the time it was asked for.

    The ``use_sim_time`` asked for is that of ``given`` (the overrides the node was made with),
    else of the command line and parameters files. If it is true the node's time source is
    detached first, so the clock runs on simulated time and no ``/clock`` subscription is made.
    Returns it; raises :class:`ParamError` if it is not a bool.
    """
    asked: Any = next((parameter.value for parameter in given
                       if parameter.name == USE_SIM_TIME_NAME), None)
    if asked is None:
        with node.handle:
            found = node.handle.get_parameters(Parameter).get(USE_SIM_TIME_NAME)
        asked = False if found is None else found.value
    if not isinstance(asked, bool):
        raise ParamError([(USE_SIM_TIME_NAME, f'must be true or false, got {asked!r}')])
    if asked:
        source = getattr(node, '_time_source', None)
        if source is not None:
            source.detach_node()
        node.set_parameters([Parameter(USE_SIM_TIME_NAME, value=True)])
    return asked


def _active_source(node: Node) -> Optional[TimeSource]:
    """Return the node's time source if it runs on simulated time, else None."""
    source = getattr(node, '_time_source', None)
    if source is None or not source.ros_time_is_active:
        return None
    return source


def keep_sim_time(parameters: List[Parameter]) -> SetParametersResult:
    """Refuse to change ``use_sim_time`` of a robot whose clock is driven for it."""
    if any(parameter.name == USE_SIM_TIME_NAME for parameter in parameters):
        return SetParametersResult(successful=False, reason='use_sim_time of this robot is '
                                   'fixed at start (its clock is set from the stamps of the '
                                   'states it hears)')
    return SetParametersResult(successful=True)


class StateClock:
    """The simulated clocks of ``nodes``, set from the states' stamps instead of ``/clock``."""

    def __init__(self, nodes: Sequence[Node]) -> None:
        """Drive the clocks of those ``nodes`` that are on simulated time."""
        self.clocks: List[ROSClock] = []
        self.now_ns = 0
        for node in nodes:
            clock = node.get_clock()
            if _active_source(node) is None or not isinstance(clock, ROSClock):
                continue
            self.clocks.append(clock)
            node.add_on_set_parameters_callback(keep_sim_time)

    def advance(self, stamp_ns: int, jump: bool = False) -> None:
        """Set every clock to ``stamp_ns`` (ns) if it is later than their time, or ``jump``."""
        if not self.clocks or stamp_ns == self.now_ns or (stamp_ns < self.now_ns and not jump):
            return
        self.now_ns = stamp_ns
        moment = Time(nanoseconds=stamp_ns, clock_type=self.clocks[0].clock_type)
        for clock in self.clocks:
            clock.set_ros_time_override(moment)
