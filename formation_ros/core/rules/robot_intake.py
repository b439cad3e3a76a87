# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a robot takes of its states (pose, neighbours, a team state): the rule and the clock.

:class:`StateIntake` admits a state by the frame / finite / orientation rule of
``core.rules.admission`` and by its stamp (how far it may be from the robot's time, and when that
time jumps), and keeps the robot's simulated time as the states set it. The rules are stated in
docs/ros_interface.md ("Time") and docs/faults.md ("a node on the wrong clock"); the ROS side
(setting rclpy's clocks, logging) is ``ros.sim_clock`` and the robot node.
"""

from dataclasses import dataclass
from typing import Optional, Set

from formation_ros.core.maths.frames import valid_quaternions
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason, refusal
import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class Refused:
    """
    A refusal: its reason and the detail of its log line.

    gap_s: for CLOCK, how far the stamp is from the robot's time (s); log: whether it is
    logged now (a first sample unlike the frame evaluated is only counted).
    """

    reason: Reason
    detail: str = ''
    gap_s: float = 0.0
    log: bool = True


class StateIntake:
    """
    A robot's admission of its states and its time as they set it.

    world_frame: the frame every state must be in; timeout_ns: ``input_timeout`` (ns), how far
    a stamp may be from the robot's time; sim_time: whether the robot runs on simulated time;
    follows_states: whether its clock is set from the states' stamps (``ros.sim_clock``);
    heading_of: what needs a state's orientations ('a unicycle', 'command.frame body').
    """

    def __init__(self, world_frame: str, timeout_ns: int, sim_time: bool, follows_states: bool,
                 heading_of: str) -> None:
        """Start at time 0, no state taken."""
        self.world_frame = world_frame
        self.timeout_ns = timeout_ns
        self.sim_time = sim_time
        self.follows_states = follows_states
        self.heading_of = heading_of
        self.now_ns = 0
        """The time the states set (ns), forward only while they come."""
        self.advised: Set[str] = set()
        """Inputs refused as stamped on another clock whose refusal was said (logged)."""

    def stopped(self, heard_ns: Optional[int], steady_ns: int) -> bool:
        """
        Whether the robot's time is set from its states and none came within input_timeout.

        heard_ns: steady time (ns) the latest state was taken (None: never); steady_ns: now.
        Then the next state sets the time whichever way it jumps (a link cut for a while, a
        plant started again); while states come, one stamped further than input_timeout from
        their time is from another clock.
        """
        return self.follows_states and (heard_ns is None
                                        or steady_ns - heard_ns > self.timeout_ns)

    def gap_ns(self, stamp_ns: int, clock_ns: int, stopped: bool) -> int:
        """
        Return how far ``stamp_ns`` is from the robot's clock ``clock_ns`` (ns).

        0 on simulated time before it starts (clock 0), and for a far stamp while the states
        have stopped (``stopped``): the next state's stamp is then the time.
        """
        gap = stamp_ns - clock_ns
        if self.sim_time and (clock_ns == 0 or (abs(gap) > self.timeout_ns and stopped)):
            return 0
        return gap

    def refusal(self, frame_id: str, stamp_ns: int, finite: bool, oriented: bool,
                clock_ns: int, stopped: bool) -> Optional[Refused]:
        """
        Return why a state is refused (frame, finite values, orientation, clock), or None.

        finite / oriented: whether its values are finite and its needed orientations unit
        quaternions (``core.rules.admission.poses_refusal`` reckons both for a set of poses).
        """
        reason = refusal(frame_id, self.world_frame, finite, oriented)
        if reason is Reason.FRAME:
            return Refused(reason, f' (got {frame_id!r}, expected {self.world_frame!r})')
        if reason is Reason.ORIENTATION:
            return Refused(reason, f' (its heading is needed: {self.heading_of})')
        if reason is not None:
            return Refused(reason)
        gap = self.gap_ns(stamp_ns, clock_ns, stopped)
        if abs(gap) > self.timeout_ns:
            return Refused(Reason.CLOCK, gap_s=gap / NS_PER_S)
        return None

    def poses_refusal(self, frame_id: str, stamp_ns: int, positions: ArrayLike,
                      orientations: ArrayLike, needs_orientation: bool, clock_ns: int,
                      stopped: bool, finite: Optional[bool] = None) -> Optional[Refused]:
        """
        Return why a state of poses is refused (:meth:`refusal`), or None.

        positions: (..., dim) m; orientations: (..., 4) quaternions, looked at only when
        ``needs_orientation``; finite: given (a pose's whole finiteness), else reckoned.
        """
        if finite is None:
            finite = bool(np.all(np.isfinite(positions))
                          and (not needs_orientation or np.all(np.isfinite(orientations))))
        oriented = not needs_orientation or bool(np.all(valid_quaternions(orientations)))
        return self.refusal(frame_id, stamp_ns, finite, oriented, clock_ns, stopped)

    def advance(self, stamp_ns: int, jump: bool) -> bool:
        """
        Let a state taken, stamped ``stamp_ns``, set the time; return whether it moved.

        Forward only, unless ``jump`` (the states had :meth:`stopped` before it came).
        """
        if (not self.follows_states or stamp_ns == self.now_ns
                or (stamp_ns < self.now_ns and not jump)):
            return False
        self.now_ns = stamp_ns
        return True
