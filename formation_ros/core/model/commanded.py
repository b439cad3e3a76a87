# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a robot commanded: its published command read back at the orientation it answered.

A robot publishes u of eqs. (14), (25) in its command frame (``core.rules.control.Control``): (v,
w) of (U4) at the heading of its own pose for unicycles, u in its body frame with
``command.frame: body``, else u itself. Reading u back needs the orientation of the pose that
robot heard for the state it answered (a stamped command names it by its stamp), not the
body's true orientation at some later time: beside a world the relay passes the latest pose it
received, which is the world's truth at the relay's stamp or at the pose before it, as the
messages race (docs/physics.md, "What a world run's report says"). Nothing here imports ROS
and nothing modifies its arguments.
"""

from collections import OrderedDict
from typing import List, Optional

from formation_ros.core.maths.frames import from_body_frame
from formation_ros.core.maths.unicycle import hand_velocity, headings_from_quaternions
import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
UNKNOWN_ORIENTATION = (np.nan,) * 4
"""The orientation of a state nobody heard: the velocity of a non-zero command is then NaN."""


def needs_orientation(unicycle: bool, body_frame: bool) -> bool:
    """Whether a published command means nothing without the orientation it answered."""
    return unicycle or body_frame


def commanded_velocity(published: ArrayLike, orientations: ArrayLike, unicycle: bool,
                       hand_distance: float, body_frame: bool) -> Float:
    """
    Return the world velocity u each robot commanded: (K, dim) in m/s.

    published: (K, width) the commands as published ((v, w) in m/s and rad/s for unicycles,
    u in the body frame with ``body_frame``, else u), orientations: (K, 4) quaternions (x, y,
    z, w) of the poses they answered. The inverse of ``Control.commands``' last step: (U3) at
    the heading, or the body frame turned into the world. A row whose orientation is NaN
    (unknown) is NaN, unless its command is zero (zero at any orientation).
    """
    commands = np.asarray(published, dtype=float)
    quaternions = np.asarray(orientations, dtype=float)
    if unicycle:
        velocity = hand_velocity(commands, headings_from_quaternions(quaternions),
                                 hand_distance)
    elif body_frame:
        velocity = from_body_frame(commands, quaternions)
    else:
        return commands.copy()
    still = np.all(commands == 0.0, axis=-1)
    return np.where(still[:, None], 0.0, velocity)


class HeardPoses:
    """
    Each robot's pose, by stamp, as the robots heard them: the states their commands answer.

    Keeps the last ``kept`` stamps of each of ``robots`` robots (stamps in ns; positions (3,) m
    and quaternions (4,) x, y, z, w), enough to look up the state any held command answers.
    """

    def __init__(self, robots: int, kept: int) -> None:
        """Keep up to ``kept`` stamps per robot."""
        self.kept = kept
        self._heard: List['OrderedDict[int, Float]'] = [OrderedDict() for _ in range(robots)]

    def hear(self, index: int, stamp_ns: int, position: ArrayLike,
             orientation: ArrayLike) -> None:
        """Keep robot ``index``'s (0-based) pose stamped ``stamp_ns``."""
        heard = self._heard[index]
        heard[int(stamp_ns)] = np.concatenate([np.asarray(position, dtype=float)[:3],
                                               np.asarray(orientation, dtype=float)[:4]])
        while len(heard) > self.kept:
            heard.popitem(last=False)

    def at(self, index: int, stamp_ns: int) -> Optional[Float]:
        """Return robot ``index``'s orientation (4,) at ``stamp_ns``, None if not heard."""
        pose = self._heard[index].get(int(stamp_ns))
        return None if pose is None else pose[3:]

    def rows(self, stamps_ns: ArrayLike) -> Float:
        """Return every robot's orientation at its stamp, (N, 4); NaN rows where not heard."""
        return self._poses(stamps_ns)[:, 3:]

    def positions(self, stamps_ns: ArrayLike) -> Float:
        """Return every robot's position at its stamp, (N, 3) m; NaN rows where not heard."""
        return self._poses(stamps_ns)[:, :3]

    def _poses(self, stamps_ns: ArrayLike) -> Float:
        found = [self._heard[i].get(int(stamp))
                 for i, stamp in enumerate(np.asarray(stamps_ns).tolist())]
        unknown = np.full(7, np.nan)
        return np.array([unknown if row is None else row for row in found]).reshape(-1, 7)
