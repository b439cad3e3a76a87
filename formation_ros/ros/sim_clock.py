# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Simulated time for robot nodes without a ``/clock`` subscription.

With ``use_sim_time`` every rclpy node subscribes to ``/clock`` and runs a Python callback per
tick (the plant publishes one per published state). A robot needs none: every state the plant
sends it (its ``pose``, or ``/formation/states`` with the team transport) is stamped with the
plant's simulated time, which is the time the robot needs, so :class:`StateClock` detaches the
nodes' ``/clock`` subscriptions and sets their clocks to each accepted state's stamp: forward
only while the states come, whichever way it jumps once they had stopped (the robot decides:
a link cut for a while, a plant started again). ``use_sim_time`` still decides which clock a
robot is on: with it false the robot stays on the wall clock and refuses the plant's states as
stamped on another clock. It is fixed while the nodes run (:func:`keep_sim_time` refuses a
change). Nodes on wall time, and rclpy versions without the node's time source attribute, are
left as they are.
"""

from typing import List, Optional, Sequence

from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import ROSClock
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from rclpy.time_source import TimeSource


def _active_source(node: Node) -> Optional[TimeSource]:
    """Return the node's time source if it runs on simulated time, else None."""
    source = getattr(node, '_time_source', None)
    if source is None or not source.ros_time_is_active:
        return None
    return source


def keep_sim_time(parameters: List[Parameter]) -> SetParametersResult:
    """Refuse to change ``use_sim_time`` of a robot whose clock is driven for it."""
    if any(parameter.name == 'use_sim_time' for parameter in parameters):
        return SetParametersResult(successful=False, reason='use_sim_time of this robot is '
                                   'fixed at start (its clock is set from the stamps of the '
                                   'states it hears)')
    return SetParametersResult(successful=True)


class StateClock:
    """The simulated clocks of ``nodes``, set from the states' stamps instead of ``/clock``."""

    def __init__(self, nodes: Sequence[Node]) -> None:
        """Detach the ``/clock`` subscription of every node on simulated time."""
        self.clocks: List[ROSClock] = []
        self.now_ns = 0
        for node in nodes:
            source = _active_source(node)
            clock = node.get_clock()
            if source is None or not isinstance(clock, ROSClock):
                continue
            source.detach_node()
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
