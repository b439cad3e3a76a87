# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The plant's intake of commands, without ROS: a robot's cmd_vel or a team message, once read.

The node reads the bytes (``ros.cdr``); :class:`CommandIntake` checks the frame and the values
(``core.rules.admission.command_refusal``, the world's rule too) and stores what it admits in
``core.model.plant.Commands`` with
its stamp and arrival. What is refused is counted by the node's ``ros.once.RefusalLog`` under the
sources robot index (cmd_vel), :data:`TEAM` and 'shape' / 'status'. The faults:
docs/faults.md; the layouts: docs/ros_interface.md ("Transports").
"""

from typing import Dict, List, Optional, Sequence, Union

from formation_ros.core.model.plant import Commands
from formation_ros.core.rules.admission import command_refusal, Reason, Refusals
from formation_ros.core.rules.transport import command_of, commands_of
import numpy as np
from numpy.typing import ArrayLike, NDArray

TEAM = 'team'
"""The source of the team transport's command messages in the refusal counts."""
Source = Union[int, str]
"""A robot's index (0-based: its cmd_vel), :data:`TEAM`, or 'shape' / 'status' (a change)."""


class CommandIntake:
    """
    Every robot's latest admitted command and when it arrived.

    command_frames: (N,) the frame each robot's commands are in; world_frame: the team
    message's header frame; dim: the space's; unicycles: commands are (v, w); stamped:
    cmd_vel is a TwistStamped (else a Twist, which answers the latest state published).
    """

    def __init__(self, command_frames: Sequence[str], world_frame: str, dim: int,
                 unicycles: bool, stamped: bool) -> None:
        """Start with no command from anyone."""
        self.command_frames = list(command_frames)
        self.world_frame = world_frame
        self.dim = dim
        self.unicycles = unicycles
        self.stamped = stamped
        n = len(self.command_frames)
        self.commands = Commands.empty(n, 2 if unicycles else dim)
        self.arrived_ns: NDArray[np.int64] = np.zeros(n, dtype=np.int64)
        """(N,) when each robot's latest command arrived, ns (steady clock; 0: never)."""
        self.state_stamp_ns = 0
        """The stamp of the latest state published, ns: what a Twist answers."""

    def take(self, index: int, frame_id: str, linear: Sequence[float],
             angular: Sequence[float], stamp_ns: int, arrived_ns: int) -> Optional[Reason]:
        """
        Store robot ``index``'s command unless refused; return the reason of a refusal.

        linear, angular: (3,) m/s and rad/s; frame_id, stamp_ns: its header's (a Twist's are
        not looked at); arrived_ns: now, ns.
        """
        expected = self.command_frames[index]
        values = command_of(linear, angular, self.dim, self.unicycles)
        reason = command_refusal(frame_id if self.stamped else expected, expected, values)
        if reason is not None:
            return reason
        if not self.stamped:
            stamp_ns = self.state_stamp_ns
        self.commands.store(index, values, stamp_ns)
        self.arrived_ns[index] = arrived_ns
        return None

    def take_team(self, indices: ArrayLike, frame_id: str, linear: ArrayLike,
                  angular: ArrayLike, stamp_ns: int, arrived_ns: int) -> Optional[Reason]:
        """
        Store the commands of one team message unless refused; return the reason of a refusal.

        indices: (K,) the robots (0-based) it answers for; linear, angular: (K, 3) m/s and
        rad/s, in each robot's command frame; frame_id, stamp_ns: its header's, in world_frame
        and stamped with the state the commands answer; arrived_ns: now, ns.
        """
        values = commands_of(linear, angular, self.dim, self.unicycles)
        reason = command_refusal(frame_id, self.world_frame, values)
        if reason is not None:
            return reason
        rows = np.asarray(indices, dtype=np.intp)
        self.commands.u[rows] = values
        self.commands.stamp_ns[rows] = stamp_ns
        self.commands.present[rows] = True
        self.arrived_ns[rows] = arrived_ns
        return None

    def answered(self, stamp_ns: int) -> bool:
        """Whether every robot's latest command answers the state stamped ``stamp_ns``."""
        commands = self.commands
        return bool(np.all(commands.present & (commands.stamp_ns == stamp_ns)))

    def silent(self, stamp_ns: int) -> List[int]:
        """Return the robots (1-based) whose latest command does not answer ``stamp_ns``."""
        commands = self.commands
        return (np.flatnonzero(~(commands.present & (commands.stamp_ns == stamp_ns)))
                + 1).tolist()

    def missing(self) -> List[int]:
        """Return the robots (1-based) that have sent no command yet."""
        return (np.flatnonzero(~self.commands.present) + 1).tolist()

    def arrival_states(self, now_ns: int, lease_ns: int) -> List[str]:
        """
        Return each robot's 'alive', 'lost' or 'unknown', from when its latest command came.

        Alive while it came within ``lease_ns`` of ``now_ns`` (steady clock, ns), unknown before
        the first: a robot process or fleet answers every state, so a dead one shows as lost.
        """
        recent = now_ns - self.arrived_ns <= lease_ns
        return ['unknown' if not present else 'alive' if fresh else 'lost'
                for present, fresh in zip(self.commands.present.tolist(), recent.tolist())]

    def line(self, source: Source, reason: Reason, detail: str) -> str:
        """
        Return the log line of a refusal (``ros.once.RefusalLog``'s line).

        detail: a malformed message's error, the frame of one in another frame, the values of a
        non-finite one, or what is wrong with a change.
        """
        if reason is Reason.CHANGE:
            return f'ignoring a {source} with {detail} (logged once; counted in diagnostics)'
        if source == TEAM:
            if reason is Reason.NON_FINITE:
                return ('ignoring /formation/commands with a non-finite command (logged once, '
                        'counted in diagnostics)')
            if reason is Reason.MALFORMED:
                return ('ignoring /formation/commands bytes that are not a team command '
                        f'({detail}; logged once, counted in diagnostics)')
            return (f'ignoring /formation/commands in frame {detail!r}: its header is in '
                    f'{self.world_frame!r} (logged once, counted in diagnostics)')
        assert isinstance(source, int)
        if reason is Reason.MALFORMED:
            kind = 'TwistStamped' if self.stamped else 'Twist'
            return (f'robot {source + 1}: ignoring cmd_vel bytes that are not a {kind} '
                    f'({detail}; logged once, counted in diagnostics)')
        if reason is Reason.NON_FINITE:
            return (f'robot {source + 1}: ignoring a non-finite command on cmd_vel ({detail}; '
                    'its last one holds until it is stale; logged once, counted in diagnostics)')
        return (f'robot {source + 1}: ignoring cmd_vel in frame {detail!r}: its commands are '
                f'in {self.command_frames[source]!r} (logged once, counted in diagnostics)')


def refused_by_robot(refusals: 'Refusals[Source]', reason: Reason) -> Dict[int, int]:
    """Return {robot (1-based): cmd_vel messages refused for ``reason``}, robots in order."""
    return {int(source) + 1: count for (source, why), count in sorted(
        ((key, count) for key, count in refusals.items() if isinstance(key[0], int)),
        key=lambda item: item[0][0]) if why is reason}
