# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a world takes of the commands it hears, before the engine applies them (no ROS).

A world node reads each robot's ``cmd_vel`` bytes (``ros.cdr``) and hands the message's frame,
velocities and stamp to :meth:`CommandInbox.take`, which refuses it by the plant's rule
(``core.rules.admission.command_refusal``: the robot's command frame, then finite values: those
the body uses) or as
stamped on another clock (more than ``world.cmd_timeout`` after the world's time: a wall-clock
stamp, or a sender on another ``/clock``), and otherwise keeps it as the robot's latest until
the node's step timer drains the inbox into :meth:`formation_ros.physics.engine.Engine.apply`.
A stamped command's stamp is the simulated time it was computed for (a stamp ahead of the
world within the timeout is taken as now); an unstamped one (``command.type: twist``) is
taken at the world's time when it arrives. A command beyond the motors is not refused: the
engine's motors limit it. What is refused is counted by the node (``ros.once.RefusalLog``).
"""

from typing import Optional, Sequence, Tuple

from formation_ros.core.rules.admission import command_refusal, Reason
from formation_ros.core.rules.transport import command_of
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]


class CommandInbox:
    """
    Every robot's latest admitted command not yet applied, with its stamp.

    command_frames: (N,) the frame each robot's commands are in (``world_frame``, or
    ``robot_<i>/base_link`` for unicycles and ``command.frame: body``); dim: 2 or 3;
    unicycles: commands are (v, w) (linear.x m/s, angular.z rad/s), else the linear velocity's
    first ``dim`` components, m/s; stamped: TwistStamped (else Twist, no frame, no stamp);
    ahead_ns: a stamp more than this after the world's time is from another clock, ns.
    """

    def __init__(self, command_frames: Sequence[str], dim: int, unicycles: bool,
                 stamped: bool, ahead_ns: int):
        """Start with no command."""
        self.command_frames = list(command_frames)
        self.dim = int(dim)
        self.unicycles = bool(unicycles)
        self.stamped = bool(stamped)
        self.ahead_ns = int(ahead_ns)
        n = len(self.command_frames)
        self.width = 2 if self.unicycles else self.dim
        self.command: Float = np.zeros((n, self.width))
        self.stamp_ns: NDArray[np.int64] = np.zeros(n, dtype=np.int64)
        self.pending: NDArray[np.bool_] = np.zeros(n, dtype=bool)

    def take(self, index: int, frame_id: str, linear: Sequence[float],
             angular: Sequence[float], stamp_ns: int, now_ns: int) -> Optional[Reason]:
        """
        Keep robot ``index``'s (0-based) command unless refused; return the reason of a refusal.

        linear, angular: (3,) m/s and rad/s; frame_id, stamp_ns: its header's (a Twist's are
        not looked at); now_ns: the world's simulated time, ns.
        """
        values = command_of(linear, angular, self.dim, self.unicycles)
        expected = self.command_frames[index]
        reason = command_refusal(frame_id if self.stamped else expected, expected, values)
        if reason is not None:
            return reason
        if self.stamped and stamp_ns > now_ns + self.ahead_ns:
            return Reason.CLOCK
        self.command[index] = values
        self.stamp_ns[index] = min(stamp_ns, now_ns) if self.stamped else now_ns
        self.pending[index] = True
        return None

    def drain(self) -> Tuple[NDArray[np.intp], Float, NDArray[np.int64]]:
        """
        Return the robots with a command kept since the last call, their commands and stamps.

        (K,) 0-based robot indices, (K, width) commands, (K,) stamps in ns; then forget them.
        """
        rows = np.flatnonzero(self.pending)
        self.pending[rows] = False
        return rows, self.command[rows].copy(), self.stamp_ns[rows].copy()
