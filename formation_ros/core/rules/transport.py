# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The layouts of the team transport (``transport: team``): what each entry of a team message is.

Two standard messages carry a whole team's state and a robot process's or fleet's commands
(``ros.topics.STATES``, ``ros.topics.TEAM_COMMANDS``; bytes in ``ros.cdr``):

* ``/formation/states``, a geometry_msgs/PoseArray: ``header.stamp`` is the state's time,
  ``header.frame_id`` the ``world_frame``; ``poses[i - 1]`` is robot i's body: position (x, y,
  z; z = 0 in 2D) and orientation (x, y, z, w), the heading of a unicycle or of a point with
  ``command.frame: body``, else the identity. Exactly ``num_robots`` poses:
  :func:`state_rows`.
* ``/formation/commands``, a trajectory_msgs/MultiDOFJointTrajectory: ``header.stamp`` is the
  stamp of the state the commands answer, ``header.frame_id`` the ``world_frame``;
  ``joint_names`` the robots' names ``robot_<i>`` (``core.settings.names``), in any order, each at
  most once; one point whose ``velocities[k]`` is the command of robot ``joint_names[k]``, the
  twist its ``cmd_vel`` would carry, in its command frame (``world_frame``, or its
  ``robot_<i>/base_link`` for unicycles and ``command.frame: body``): linear = u for points,
  linear.x = v and angular.z = w for unicycles (:func:`command_vectors`,
  :func:`commands_of`). The point's ``transforms`` and ``accelerations`` are empty and its
  ``time_from_start`` is zero.

Shapes: q (N, dim) m; orientations (N, 4); commands (K, dim) m/s for points, (K, 2) (v, w) in
m/s and rad/s for unicycles; linear and angular (K, 3).
"""

import re
from typing import Sequence, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

POSE_WIDTH = 7
"""Numbers per pose: position (3) and quaternion (4)."""
NAME = re.compile(r'robot_([1-9][0-9]{0,8})')


def robot_indices(names: Sequence[str], num_robots: int) -> NDArray[np.intp]:
    """
    Return the 0-based index of each named robot: (K,) ints.

    ValueError for a name that is not ``robot_<i>`` with 1 <= i <= ``num_robots``, or a robot
    named twice.
    """
    indices = np.empty(len(names), dtype=np.intp)
    for k, name in enumerate(names):
        match = NAME.fullmatch(name)
        if match is None or int(match.group(1)) > num_robots:
            raise ValueError(f'{name[:40]!r} is not robot_<i> with i in 1..{num_robots}')
        indices[k] = int(match.group(1)) - 1
    if len(np.unique(indices)) != len(indices):
        raise ValueError('a robot is named twice')
    return indices


def state_rows(q: ArrayLike, orientations: ArrayLike) -> NDArray[np.float64]:
    """Return the poses of a team state: (N, 7) rows (x, y, z, qx, qy, qz, qw), robot i at i-1."""
    q = np.asarray(q, dtype=float)
    rows = np.zeros((q.shape[0], POSE_WIDTH))
    rows[:, :q.shape[1]] = q
    rows[:, 3:] = orientations
    return rows


def command_vectors(u: ArrayLike,
                    unicycle: bool) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return (linear, angular) (K, 3) twists of commands u: (K, dim) points, (K, 2) (v, w)."""
    u = np.asarray(u, dtype=float)
    linear = np.zeros((u.shape[0], 3))
    angular = np.zeros((u.shape[0], 3))
    if unicycle:
        linear[:, 0] = u[:, 0]
        angular[:, 2] = u[:, 1]
    else:
        linear[:, :u.shape[1]] = u
    return linear, angular


def command_of(linear: Sequence[float], angular: Sequence[float], dim: int,
               unicycle: bool) -> Tuple[float, ...]:
    """Return a twist's command: linear[:dim], or (v, w) = (linear.x, angular.z) if unicycle."""
    return (linear[0], angular[2]) if unicycle else tuple(linear[:dim])


def commands_of(linear: ArrayLike, angular: ArrayLike, dim: int,
                unicycle: bool) -> NDArray[np.float64]:
    """Return the commands (K, dim), or (K, 2) (v, w) for unicycles, of (K, 3) twists."""
    linear = np.asarray(linear, dtype=float)
    if unicycle:
        return np.stack([linear[:, 0], np.asarray(angular, dtype=float)[:, 2]], axis=1)
    return linear[:, :dim].copy()
