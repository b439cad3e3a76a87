# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Simulated time for robot nodes without a ``/clock`` subscription.

A robot node is made on the wall clock (:func:`wall_clock_overrides`, so rclpy's time source
makes no ``/clock`` subscription) and then put on the time asked for
(:func:`sim_time_without_clock`); on simulated time :class:`StateClock` sets its clock to the
time its states set (the rule: ``core.rules.robot_intake.StateIntake``), and :func:`keep_sim_time`
refuses a change of ``use_sim_time`` while it runs. Why: docs/ros_interface.md ("Time").
"""

import time
from typing import Any, List, Mapping, Optional, Sequence

from formation_ros.core.settings.declarations import ParamError
from formation_ros.ros.team import PublisherWatch
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
    """The simulated clocks of robot nodes, set to the time their states set."""

    def __init__(self, node: Node) -> None:
        """Drive the clock of ``node`` if it is on simulated time (else none)."""
        self.clocks: List[ROSClock] = []
        clock = node.get_clock()
        if _active_source(node) is not None and isinstance(clock, ROSClock):
            self.clocks.append(clock)
            node.add_on_set_parameters_callback(keep_sim_time)

    @property
    def follows_states(self) -> bool:
        """Whether the clocks are set here from the states (simulated time without /clock)."""
        return bool(self.clocks)

    def join(self, other: 'StateClock') -> None:
        """Drive the clocks of ``other`` too (the robots of one process's link)."""
        self.clocks.extend(other.clocks)

    def set_time(self, stamp_ns: int) -> None:
        """Set every clock to ``stamp_ns`` (ns)."""
        if not self.clocks:
            return
        moment = Time(nanoseconds=stamp_ns, clock_type=self.clocks[0].clock_type)
        for clock in self.clocks:
            clock.set_ros_time_override(moment)


def clock_advice(graph: PublisherWatch, expected: Mapping[str, Optional[str]],
                 nodes: str) -> Optional[str]:
    """
    Say what to do about stamps from another clock: the graph's answer, else use_sim_time.

    expected: the topics (/clock, the reference) that must have one publisher; two of one are
    two teams on one domain. ``nodes``: the nodes to start with ``use_sim_time:=true``. None
    while the graph has not yet named every publisher (``PublisherWatch.named_publishers``).
    """
    now = time.monotonic()
    found = {topic: graph.named_publishers(topic, now) for topic in expected}
    if any(names is None for names in found.values()):
        return None
    doubled = {topic: names for topic, names in found.items() if names}
    if doubled:
        return ('; '.join(f"{topic} has {len(names)} publishers ({', '.join(names or [])})"
                          for topic, names in doubled.items())
                + ': two teams on one domain? each needs a ROS_DOMAIN_ID of its own')
    return f'start {nodes} with use_sim_time:=true'
