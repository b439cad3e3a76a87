# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Where a robot's commands go: its ``cmd_vel`` publisher and the output it answers through.

:class:`CmdVel` is a robot's ``cmd_vel`` publisher (made at once, or on demand for a team
robot: ``ros.on_demand``); :class:`Output` is what a robot node publishes its answers through,
:class:`CmdVelOutput` with ``transport: robot`` and ``nodes.robots_link.RobotsLink`` with
``transport: team``. Message types and QoS: docs/ros_interface.md ("Topics", "Transports").
"""

from typing import Optional, Protocol

from formation_ros.core.rules.control import Control
from formation_ros.core.rules.transport import command_vectors
from formation_ros.ros import qos, topics
from formation_ros.ros.cdr import encode_twist, encode_twist_stamped
from geometry_msgs.msg import Twist, TwistStamped
import numpy as np
from numpy.typing import NDArray
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.publisher import Publisher


class CmdVel:
    """A robot's ``cmd_vel`` publisher: made at once, or (``lazy``) once a subscriber shows."""

    def __init__(self, node: Node, stamped: bool, frame: str, team: bool, lazy: bool) -> None:
        """Publish TwistStamped in ``frame`` (else Twist); a team robot's offers no lease."""
        self.node, self.stamped, self.frame, self.team = node, stamped, frame, team
        self.pub: Optional[Publisher] = None if lazy else self.make()

    def make(self) -> Publisher:
        """Create the publisher."""
        self.pub = self.node.create_publisher(TwistStamped if self.stamped else Twist,
                                              topics.CMD_VEL,
                                              qos.TEAM_CMD_VEL if self.team else qos.COMMAND)
        return self.pub

    def listeners(self) -> int:
        """Return its matched subscribers (0 before it is made)."""
        return 0 if self.pub is None else self.pub.get_subscription_count()

    def encode(self, stamp_ns: int, linear: NDArray[np.float64],
               angular: NDArray[np.float64]) -> bytes:
        """Return the message of a twist (3,) m/s and (3,) rad/s answering ``stamp_ns``."""
        if self.stamped:
            return encode_twist_stamped(stamp_ns, self.frame, linear, angular)
        return encode_twist(linear, angular)

    def publish(self, data: bytes) -> None:
        """Publish a message's bytes (the publisher must be made)."""
        assert self.pub is not None
        self.pub.publish(data)


class Output(Protocol):
    """Where a robot's commands go: its cmd_vel, or its process's link (team transport)."""

    what: str

    def publish(self, u: Optional[NDArray[np.float64]], stamp_ns: int) -> None:
        """Publish commands u (K, width) (None: zero) answering the state ``stamp_ns``."""

    def resend(self) -> None:
        """Publish the commands sent last again."""

    def listeners(self) -> int:
        """Return the command subscribers every robot has."""

    def started(self) -> None:
        """Note that the robots start answering."""

    def flush(self, seconds: float) -> None:
        """Wait up to ``seconds`` for the subscribers to have the commands sent."""


class CmdVelOutput:
    """The output of a robot with ``transport: robot``: its command on its own cmd_vel."""

    what = 'cmd_vel'

    def __init__(self, cmd_vel: CmdVel, control: Control) -> None:
        """Publish on ``cmd_vel`` the commands ``control`` computes."""
        self.cmd_vel, self.control = cmd_vel, control
        self.last: Optional[bytes] = None

    def publish(self, u: Optional[NDArray[np.float64]], stamp_ns: int) -> None:
        """Publish u (1, width) (None: zero) answering the state ``stamp_ns``."""
        linear, angular = command_vectors(self.control.zero() if u is None else u,
                                          self.control.unicycle)
        self.last = self.cmd_vel.encode(stamp_ns, linear[0], angular[0])
        self.cmd_vel.publish(self.last)

    def resend(self) -> None:
        """Publish the command sent last again."""
        if self.last is not None:
            self.cmd_vel.publish(self.last)

    def listeners(self) -> int:
        """Return cmd_vel's subscribers."""
        return self.cmd_vel.listeners()

    def started(self) -> None:
        """Nothing to do: cmd_vel exists."""

    def flush(self, seconds: float) -> None:
        """Wait up to ``seconds`` for cmd_vel's subscribers to have the last command."""
        assert self.cmd_vel.pub is not None
        self.cmd_vel.pub.wait_for_all_acked(Duration(seconds=seconds))
