# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a node admits of what it hears: the reasons for a refusal, the rule, the count.

One :class:`Reason` enum for every node that refuses input (robot, relay, plant, world), the
rule that a pose, a set of poses or a command breaks first (:func:`refusal`,
:func:`poses_refusal`, :func:`command_refusal`) and the counter of refusals
(:class:`Refusals`). What each node refuses and why:
docs/faults.md. Logging a refusal once while it lasts is the ROS adapter's
(``ros.once.RefusalLog``); nothing here decides by what was logged.
"""

import enum
import math
from typing import Dict, Generic, Hashable, List, Optional, Tuple, TypeVar

from formation_ros.core.maths.frames import valid_quaternions
import numpy as np
from numpy.typing import ArrayLike

Source = TypeVar('Source', bound=Hashable)


class Reason(enum.Enum):
    """Why a node refuses a message it heard (the value completes 'ignoring ... with')."""

    MALFORMED = 'bytes that are not a whole message of its type'
    FRAME = 'a frame other than world_frame'
    NON_FINITE = 'non-finite values'
    ORIENTATION = 'an orientation that is not a unit quaternion'
    CLOCK = 'stamps from another clock'
    NOT_NEWER = 'a stamp no later than the last one taken (a repeated or reordered measurement)'
    TOO_MANY = 'more neighbours than there are robots'
    TOO_MANY_POINTS = 'more obstacle points than a robot takes'
    NO_NORMAL = 'a normal (the x axis of an orientation) with no direction in the plane'
    SCAN_FRAME = 'a frame other than obstacles.scan_frame'
    SCAN_FIELDS = 'angle or range fields no scan can have'
    TOO_MANY_RAYS = 'more rays than a robot takes'
    UNPLACED = 'a stamp no pose of the robot was kept near (its returns cannot be placed)'
    TOO_FAST = 'a speed or turn rate its reference kind cannot have'
    OTHER_REFERENCE = ('a frame other than the one its reference parameters and the announced '
                       'changes give')
    CHANGE = 'a shape or team status that cannot hold'


def refusal(frame_id: str, world_frame: str, finite: bool,
            oriented: bool = True) -> Optional[Reason]:
    """
    Return the first rule a message breaks, in the order frame, finite values, orientation.

    frame_id: the message's frame; world_frame: the one it must be in; finite: whether the
    values used are finite; oriented: whether the orientations used are unit quaternions.
    None when it breaks none.
    """
    if frame_id != world_frame:
        return Reason.FRAME
    if not finite:
        return Reason.NON_FINITE
    if not oriented:
        return Reason.ORIENTATION
    return None


def poses_refusal(frame_id: str, world_frame: str, positions: ArrayLike,
                  orientations: ArrayLike, needs_orientation: bool) -> Optional[Reason]:
    """
    Return the first rule a set of poses breaks (:func:`refusal`), or None.

    positions: (..., dim) m; orientations: (..., 4) quaternions (x, y, z, w), looked at only
    when ``needs_orientation`` (a unicycle's heading, a body-frame command, a measurement).
    """
    finite = bool(np.all(np.isfinite(positions))
                  and (not needs_orientation or np.all(np.isfinite(orientations))))
    oriented = not needs_orientation or bool(np.all(valid_quaternions(orientations)))
    return refusal(frame_id, world_frame, finite, oriented)


def command_refusal(frame_id: str, command_frame: str, values: ArrayLike) -> Optional[Reason]:
    """
    Return the first rule a command heard on the wire breaks, or None: the one rule of both.

    The plant and the world admit a command (a robot's ``cmd_vel``, a team message's rows) only
    in its command frame and with finite values; a refused one is dropped and counted, and the
    robot's last admitted command holds until it ages out, as after a malformed message.
    frame_id: the message's (the command frame itself for a Twist, which has none);
    command_frame: the one it must be in; values: the components the body uses, (width,) or
    (K, width), m/s and rad/s. Nothing non-finite reaches a model or the engine.
    """
    finite = (all(map(math.isfinite, values)) if isinstance(values, tuple)
              else bool(np.all(np.isfinite(values))))
    return refusal(frame_id, command_frame, finite)


class Refusals(Generic[Source]):
    """The refused messages of one node, counted by (source, reason)."""

    def __init__(self) -> None:
        """Start with no refusal."""
        self._counts: Dict[Tuple[Source, Reason], int] = {}

    def add(self, source: Source, reason: Reason) -> int:
        """Count one message from ``source`` refused for ``reason``; return its count."""
        key = (source, reason)
        self._counts[key] = count = self._counts.get(key, 0) + 1
        return count

    def count(self, source: Optional[Source] = None, reason: Optional[Reason] = None) -> int:
        """Return how many were refused, of ``source`` and for ``reason`` where given."""
        return sum(count for (each, why), count in self._counts.items()
                   if (source is None or each == source) and (reason is None or why is reason))

    def items(self) -> List[Tuple[Tuple[Source, Reason], int]]:
        """Return ((source, reason), count) in the order they first happened."""
        return list(self._counts.items())

    def __contains__(self, key: object) -> bool:
        """Whether any message was refused for the (source, reason) ``key``."""
        return key in self._counts

    def get(self, key: Tuple[Source, Reason], default: int = 0) -> int:
        """Return the count of the (source, reason) ``key``, ``default`` if none."""
        return self._counts.get(key, default)

    def __getitem__(self, key: Tuple[Source, Reason]) -> int:
        """Return the count of the (source, reason) ``key`` (KeyError if none)."""
        return self._counts[key]
