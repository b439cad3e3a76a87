# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The commands of K >= 1 robots of one process: their points, the law, their command frames.

:class:`Control` is the one path from what the robots sensed to what they publish: the points
the law acts on (positions, or hand points for unicycles: docs/equations.md U1-U5), u of eqs.
(14), (25) from ``core.maths.law.robot_commands``, then (v, w) for unicycles or u turned into the
body frame (``command.frame: body``); the body mapping is the plant's and the offline tools'
(``core.model.bodies``). A robot process is K = 1, a process's link to its
robots (``nodes.robots_link``) K.
"""

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.law import Command, LawParams, robot_commands
from formation_ros.core.maths.obstacle_tracking import tracking_command
from formation_ros.core.maths.obstacles import HeardObstacles, quaternion_normals
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.model.bodies import BodyKind, BodySettings, make_bodies
import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]


@dataclass(frozen=True)
class Sensed:
    """
    What K robots know at a state, as the law takes it.

    indices: (K,) the robots' 0-based ids; points: (K, dim) the points the law acts on, m
    (:meth:`Control.points`); headings: (K,) rad; orientations: (K, 4) quaternions (x, y, z,
    w); (observer, neighbours): (P,) indices into the K robots and (P, dim) the points each
    sensed, in order (``core.maths.law.robot_commands``); obstacles: the obstacles they
    heard with this state (:meth:`Control.heard_obstacles`) or saw in their scans
    (:meth:`Control.scanned_obstacles`), None: none, as without any; unseen: why the robots
    cannot tell their obstacles now (they then hold still), None: they can.
    """

    indices: NDArray[np.intp]
    points: Float
    headings: Float
    orientations: Float
    observer: NDArray[np.intp]
    neighbours: Float
    obstacles: Optional[HeardObstacles] = None
    unseen: Optional[str] = None


@dataclass(frozen=True)
class Commands:
    """
    The commands of K robots: ``law`` (u, u_hat, omega: (K, dim) m/s) and what is published.

    body: (K, 2) (v, w) in m/s and rad/s for unicycles, (K, dim) u in the body frame with
    ``command.frame: body``, None when u is published in the world frame.
    """

    law: Command
    body: Optional[Float]

    @property
    def published(self) -> Float:
        """Return the commands as published: (K, width), in their command frames."""
        return self.law.u if self.body is None else self.body

    def row(self, k: int) -> Tuple[Command, Optional[Float]]:
        """Return robot k's command ((dim,) arrays) and its published form, if not u."""
        law = self.law
        return (Command(u=law.u[k], u_hat=law.u_hat[k], omega=law.omega[k]),
                None if self.body is None else self.body[k])


class Control:
    """
    The law of K robots and the map of its commands to their command frames.

    law: the law's constants; radii: (K,) R_i of the robots, m; dim: 2 or 3; unicycle, with
    hand_distance (m): the law acts on hand points and commands are (v, w); body_frame: u is
    published in each robot's body frame; footprint: the radius about the control point that
    holds the body, m (``BodySettings.footprint``); obstacle_clearance: b_o, m
    (``obstacles.clearance``; None: obstacles heard are not used).
    """

    def __init__(self, law: LawParams, radii: ArrayLike, dim: int, unicycle: bool,
                 hand_distance: float, body_frame: bool, footprint: float = 0.0,
                 obstacle_clearance: Optional[float] = None) -> None:
        """Keep the constants; ``radii`` is copied."""
        self.law = law
        self.footprint = float(footprint)
        self.obstacle_clearance = obstacle_clearance
        self.radii = np.array(radii, dtype=float)
        self.dim = dim
        self.unicycle = unicycle
        self.hand_distance = hand_distance
        self.body_frame = body_frame
        self.bodies = make_bodies(BodySettings(BodyKind.UNICYCLE if unicycle else BodyKind.POINT,
                                               hand_distance), body_frame=body_frame)
        self.width = self.bodies.command_width(dim)

    def points(self, positions: ArrayLike, orientations: ArrayLike) -> Tuple[Float, Float]:
        """
        Return (points, headings) of M robots' poses: the points the law acts on.

        positions: (M, >= dim) m; orientations: (M, 4) quaternions (x, y, z, w). points:
        (M, dim), the positions or (unicycles) the hand points; headings: (M,) rad (zeros
        but for unicycles).
        """
        q = np.asarray(positions, dtype=float)[:, :self.dim]
        headings = (np.asarray(headings_from_quaternions(orientations), dtype=float)
                    if self.bodies.has_heading else np.zeros(len(q)))
        return self.bodies.control_points(q, headings), headings

    def alone(self, index: int, position: ArrayLike, orientation: ArrayLike,
              positions: ArrayLike, orientations: ArrayLike) -> Sensed:
        """
        Return what one robot (0-based id ``index``) knows, as the law takes it (K = 1).

        position: (>= dim,) m and orientation (4,) of its pose; positions: (P, >= dim) m and
        orientations: (P, 4) of the neighbours it sensed.
        """
        own = np.asarray(orientation, dtype=float)[None, :]
        points, headings = self.points(np.vstack([np.asarray(position, dtype=float)[None, :],
                                                  positions]),
                                       np.vstack([own, orientations]))
        return Sensed(np.array([index], dtype=np.intp), points[:1], headings[:1], own,
                      np.zeros(len(points) - 1, dtype=np.intp), points[1:])

    def heard_obstacles(self, heard: Sequence[Optional[Tuple[ArrayLike, ArrayLike]]]
                        ) -> Optional[HeardObstacles]:
        """
        Return the obstacles K robots heard, as the law takes them; None without any.

        heard: per robot, (positions (m, >= dim) m, orientations (m, 4) unit quaternions) of
        its ``obstacles`` message, the surface points and their outward normals as x axes
        (docs/ros_interface.md, "Obstacles"), or None: no message. None when no robot heard
        one or this robot has no b_o (``obstacles.clearance``).
        """
        if self.obstacle_clearance is None or all(pair is None for pair in heard):
            return None
        lists = [None if pair is None else
                 (pair[0], quaternion_normals(np.asarray(pair[1], dtype=float).reshape(-1, 4),
                                              self.dim))
                 for pair in heard]
        return HeardObstacles.from_lists(lists, self.dim, self.footprint,
                                         self.obstacle_clearance)

    def scanned_obstacles(self, seen: Sequence[Tuple[ArrayLike, ArrayLike]]) -> HeardObstacles:
        """
        Return K robots' obstacles from their scans, as the law takes them.

        seen: per robot, (points (M, 2) returns kept, normals (M, 2) unit, facing the robot:
        ``core.rules.scan_obstacles``); needs ``obstacles.clearance`` (b_o).
        """
        assert self.obstacle_clearance is not None
        return HeardObstacles.from_lists(list(seen), self.dim, self.footprint,
                                         self.obstacle_clearance)

    def zero(self) -> Float:
        """Return the K robots' zero commands: (K, width)."""
        return np.zeros((len(self.radii), self.width))

    def commands(self, sensed: Sensed, vertices: ArrayLike,
                 frame: Optional[FrameSample]) -> Commands:
        """
        Return the K robots' commands: u of eqs. (14), (25), then in their command frames.

        sensed: what they know (:class:`Sensed`); vertices: (K, dim) their places in the
        formation frame; frame: the reference's frame at the state.
        """
        law = tracking_command(
            robot_commands(sensed.points, vertices, sensed.observer, sensed.neighbours,
                           self.radii, self.law, frame, sensed.obstacles),
            sensed.points, frame, self.law, sensed.obstacles, self.radii)
        body: Optional[Float] = None
        if self.unicycle or self.body_frame:
            body = self.bodies.body_command(law.u, sensed.headings, sensed.orientations)
        return Commands(law, body)
