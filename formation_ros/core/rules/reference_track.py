# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The reference as a robot follows it: the samples it admits and the frame at a state's stamp.

:class:`ReferenceTrack` admits the reference node's samples (frame, finite values, a speed and
turn rate the reference can have, the frame the robot evaluates) and gives the frame at a
state's stamp: evaluated from the reference's parameters and the announced changes
(``core.runs.timeline.ReferenceTimeline``), or the newest sample carried forward. The rules are
stated in docs/ros_interface.md ("Reference timing", "Time") and docs/faults.md.
"""

from collections import deque
import math
from typing import Callable, Deque, Optional, Protocol, Tuple

from formation_ros.core.maths.frames import advance, FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.robot_intake import Refused
from formation_ros.core.runs.timeline import ReferenceTimeline
import numpy as np

REFERENCE_BUFFER = 64
"""Samples kept to match the stamps of states (lockstep)."""
RATE_TOLERANCE = 1e-3
"""Relative and absolute slack (m/s, rad/s) of a sample's speed and turn rate over the limits."""
SAME_REFERENCE = 1e-6
"""How far (m, m/s, 1, 1/s) a sample may be from the frame a robot evaluates for its stamp."""
OTHER_IN_ROW = 2
"""Samples in a row unlike the frame a robot evaluates before the refusal is logged (one may
only be ahead of the change announced with it: the two topics' callbacks run in either order)."""


class Sample(Protocol):
    """A reference sample as read (``ros.cdr.OdometryData``): stamp ns, frame, twist, frame."""

    stamp_ns: int
    frame_id: str
    linear: Tuple[float, float, float]
    angular: Tuple[float, float, float]

    @property
    def finite(self) -> bool:
        """Whether every value is finite."""

    def frame(self, dim: int) -> FrameSample:
        """Return the formation frame the sample carries."""


class ReferenceTrack:
    """
    The reference samples a robot (or every robot of a process) admitted, and the frame rule.

    timeline: the reference in force at each time; world_frame: the samples' frame;
    limits: (speed m/s, turn rate rad/s) the configured reference reaches; evaluates: whether
    the robot evaluates the frame itself (simulated time, the team transport) and checks the
    samples against it; timeout_ns: ``input_timeout`` (ns) of the robot that hears them.
    """

    def __init__(self, timeline: ReferenceTimeline, dim: int, world_frame: str,
                 limits: Tuple[float, float], evaluates: bool, timeout_ns: int) -> None:
        """Start with no sample."""
        self.timeline = timeline
        self.dim = dim
        self.world_frame = world_frame
        self.speed_limit, self.turn_limit = limits
        self.evaluates = evaluates
        self.timeout_ns = timeout_ns
        self.samples: Deque[Sample] = deque(maxlen=REFERENCE_BUFFER)
        self.others_in_row = 0
        """Samples in a row unlike the frame evaluated (:data:`OTHER_IN_ROW`)."""

    def widen(self, limits: Tuple[float, float]) -> None:
        """Admit samples as fast as a reference in force may be: (speed m/s, turn rad/s)."""
        self.speed_limit = max(self.speed_limit, limits[0])
        self.turn_limit = max(self.turn_limit, limits[1])

    def plausible(self, sample: Sample) -> bool:
        """Whether a sample's speed and turn rate fit the references in force."""
        speed = math.hypot(*sample.linear)
        turn = math.hypot(*sample.angular)
        return (speed <= self.speed_limit * (1.0 + RATE_TOLERANCE) + RATE_TOLERANCE
                and turn <= self.turn_limit * (1.0 + RATE_TOLERANCE) + RATE_TOLERANCE)

    def same(self, sample: Sample) -> bool:
        """Whether a sample is, within SAME_REFERENCE, the frame evaluated for its stamp."""
        mine = self.timeline.frame_at(sample.stamp_ns)
        heard = sample.frame(self.dim)
        return all(bool(np.all(np.abs(a - b) <= SAME_REFERENCE))
                   for a, b in ((mine.q_od, heard.q_od), (mine.qdot_od, heard.qdot_od),
                                (mine.J, heard.J), (mine.Jdot, heard.Jdot)))

    def refusal(self, sample: Sample, time_ns: int,
                catch_up: Callable[[], bool]) -> Optional[Refused]:
        """
        Return why a sample is refused, or None and keep it.

        time_ns: the robot's time, the stamp of its latest state (its clock before any), ns;
        catch_up: takes the changes heard but not yet taken, True if any (a sample may be
        ahead of them). Where the frame is evaluated, a sample is compared with it only if it
        is stamped within input_timeout of the robot's time: one further is on another clock,
        refused where it is used (:meth:`frame_at`), not another reference.
        """
        if sample.frame_id != self.world_frame:
            return Refused(Reason.FRAME, f' (got {sample.frame_id!r}, expected '
                                         f'{self.world_frame!r})')
        if not sample.finite:
            return Refused(Reason.NON_FINITE)
        if not self.plausible(sample) and not (catch_up() and self.plausible(sample)):
            return Refused(Reason.TOO_FAST)
        if (self.evaluates and abs(sample.stamp_ns - time_ns) <= self.timeout_ns
                and not self.same(sample) and not (catch_up() and self.same(sample))):
            self.others_in_row += 1
            return Refused(Reason.OTHER_REFERENCE, ' (another parameters file or reference.* '
                                                   'on one of them?)',
                           log=self.others_in_row >= OTHER_IN_ROW)
        self.others_in_row = 0
        self.samples.append(sample)
        return None

    def frame_at(self, stamp_ns: int, exact: bool, evaluates: bool,
                 timeout_ns: int) -> Tuple[Optional[FrameSample], Optional[float]]:
        """
        Return (the frame at ``stamp_ns``, None), or (None, the newest sample's gap in s).

        The frame: where the robot ``evaluates`` it, from the timeline, once a sample of that
        stamp or a recent one shows the reference runs on the states' clock; else that sample
        or (not ``exact``: lockstep needs the sample of the stamp) the newest one carried
        forward at constant velocity. (None, None) while there is none; (None, gap) for a
        newest sample further than ``timeout_ns`` from the stamp (from another clock).
        """
        for sample in reversed(self.samples):
            if sample.stamp_ns == stamp_ns:
                return (self.timeline.frame_at(stamp_ns) if evaluates
                        else sample.frame(self.dim)), None
        if exact or not self.samples:
            return None, None
        newest = self.samples[-1]
        ahead_ns = stamp_ns - newest.stamp_ns
        if abs(ahead_ns) > timeout_ns:
            return None, -ahead_ns / NS_PER_S
        if evaluates:
            return self.timeline.frame_at(stamp_ns), None
        return advance(newest.frame(self.dim), ahead_ns / NS_PER_S), None
