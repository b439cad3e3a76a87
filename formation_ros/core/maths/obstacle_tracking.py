# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Tracking a moving reference near obstacles: the feed-forward of eq. (25) kept out of them.

Beyond the paper (docs/equations.md, "Tracking near an obstacle"). Eq. (25) commands
``u_i = J^T u_hat_i + f_i`` with the feed-forward ``f_i = qdot_od - J^T Jdot (q_i - q_od)``
(``frames.from_frame_velocity`` of a zero u_hat): the velocity robot i would have if it held
its place in the moving formation frame. An obstacle is static in the world, so it moves in the
formation frame, and f_i can carry a robot into it whatever u_hat does: along the obstacles'
repulsion ``a_i = sum_o betabar'_io (q_i - p_io)`` (``obstacles.obstacle_terms``, world frame,
pointing away from them) the obstacles' factors of the potential change at
``-kappa a_i . q_i'``, and f_i adds ``-kappa a_i . f_i``, positive when f_i points into them.

The rule: where ``a_i . f_i < 0`` (robot i within b_o of its obstacles and its feed-forward
heading into them) the fraction ``w_i = ||a_i|| / (||a_i|| + A_0)`` of the component of f_i
along a_i is removed, ``f_i <- f_i - w_i (a_i . f_i) a_i / ||a_i||**2``, with ``A_0 = 1 / b_o``:
the feed-forward then raises the robot's obstacle factors of log(phi + 1) at most at
``kappa (1 - w_i) ||a_i|| ||f_i|| <= kappa A_0 ||f_i||``, a bounded rate, while the bounded
command's repulsion grows without bound near contact. u_hat is untouched: every component stays
within c M1 (eq. 14). Everywhere else (no obstacle within b_o, f_i along or away from the
repulsion, a fixed reference) the command is eq. (25)'s.
"""

from dataclasses import dataclass, replace
from typing import Optional

from formation_ros.core.maths.frames import FrameSample, from_frame_velocity
from formation_ros.core.maths.law import Command, LawParams, RADIUS_MAX
from formation_ros.core.maths.obstacles import Obstacles, ObstacleSurfaces
import numpy as np
from numpy.typing import ArrayLike, NDArray


def guarded_feed_forward(feed_forward: ArrayLike, away: ArrayLike,
                         softness: float) -> NDArray[np.float64]:
    """
    Return the feed-forward without (most of) its component into the obstacles: (N, dim), m/s.

    feed_forward: (N, dim) f_i, m/s; away: (N, dim) a_i, the obstacles' repulsion of each
    robot in the world frame, 1/m (zero rows: no obstacle near); softness: A_0 > 0, 1/m. A row
    with ``a_i . f_i < 0`` loses the fraction ``w_i = ||a_i|| / (||a_i|| + A_0)`` of its
    component along a_i: none at b_o (where a_i vanishes), all of it at contact (where a_i is
    unbounded), and continuously in between, so that an ODE solver meets no switch. The others
    are returned as they are.
    """
    f = np.array(feed_forward, dtype=float)
    a = np.asarray(away, dtype=float)
    scale = np.max(np.abs(a), axis=1)
    near = scale > 0.0
    unit = np.zeros_like(a)
    unit[near] = a[near] / scale[near, None]  # a_i is 1e200 at a contact: scaled first
    length = np.linalg.norm(unit[near], axis=1)
    unit[near] /= length[:, None]
    size = np.zeros(len(a))
    with np.errstate(over='ignore'):
        size[near] = scale[near] * length
    into = np.einsum('nd,nd->n', f, unit)
    heading_in = near & (into < 0.0)
    with np.errstate(invalid='ignore'):
        weight = np.where(np.isinf(size), 1.0, size / (size + softness))
    f[heading_in] -= (weight * into)[heading_in, None] * unit[heading_in]
    return f


def feed_forward_change(q: ArrayLike, frame: Optional[FrameSample], law: LawParams,
                        obstacles: Optional[ObstacleSurfaces], sensing_radii: ArrayLike
                        ) -> Optional[NDArray[np.float64]]:
    """
    Return what the rule changes in each robot's world command, (N, dim) m/s, or None.

    q: (N, dim) world positions the commands answer, m; obstacles: as the law sees them
    (``FormationConfig.law_obstacles``: grown by the footprint), each robot using those within
    its R_i (``sensing_radii``, (N,) m) and b_o; the softness is A_0 = 1 / b_o. The guarded
    feed-forward (:func:`guarded_feed_forward`) minus eq. (25)'s; None where nothing changes
    (no obstacle, a reference that does not move, no robot heading into its obstacles). Whoever
    audits a command against c M1 by inverting eq. (25) must subtract this first.
    """
    if obstacles is None or obstacles.count == 0 or frame is None or frame.still:
        return None  # a still frame's feed-forward is zero
    q = np.asarray(q, dtype=float)
    if not np.any(from_frame_velocity(np.zeros_like(q), q, frame)):
        return None
    radii = np.minimum(np.asarray(sensing_radii, dtype=float), RADIUS_MAX)
    away = obstacles.terms(q, law.jump, radii)
    return change_for(q, frame, away, obstacles.clearance)


def change_for(q: ArrayLike, frame: Optional[FrameSample], away: ArrayLike,
               clearance: float) -> Optional[NDArray[np.float64]]:
    """
    Return :func:`feed_forward_change` from the obstacles' repulsion already summed, or None.

    q: (N, dim) world positions, m; away: (N, dim) a_i, ``obstacles.obstacle_terms`` of the
    surface points each robot knows (a robot node: those it heard), 1/m; clearance: b_o, m.
    """
    if frame is None:
        return None
    q = np.asarray(q, dtype=float)
    feed_forward = from_frame_velocity(np.zeros_like(q), q, frame)
    if not np.any(feed_forward):
        return None
    change = guarded_feed_forward(feed_forward, away, 1.0 / clearance) - feed_forward
    return change if np.any(change) else None


def tracking_command(command: Command, q: ArrayLike, frame: Optional[FrameSample],
                     law: LawParams, obstacles: Optional[ObstacleSurfaces],
                     sensing_radii: ArrayLike) -> Command:
    """
    Return ``command`` (of ``law.team_command`` at q) with the feed-forward guarded.

    Arguments as :func:`feed_forward_change`. The world command u is eq. (25)'s with
    :func:`guarded_feed_forward` in place of the feed-forward; u_hat and omega are unchanged.
    The command itself where the rule changes nothing.
    """
    change = feed_forward_change(q, frame, law, obstacles, sensing_radii)
    return command if change is None else replace(command, u=command.u + change)


@dataclass(frozen=True)
class FeedForwardGuard:
    """
    The rule as whoever reads commands back needs it: the law, the obstacles, the radii.

    law: the constants of eq. (14); obstacles: as the law sees them (grown by the footprint);
    sensing_radii: (N,) R_i, m. A command of eq. (25) under the rule is ``u = J^T u_hat + f_i +
    change``: inverting eq. (25) for u_hat takes :meth:`change` off first.
    """

    law: LawParams
    obstacles: Obstacles
    sensing_radii: NDArray[np.float64]

    def change(self, q: ArrayLike, frame: Optional[FrameSample]
               ) -> Optional[NDArray[np.float64]]:
        """Return :func:`feed_forward_change` at q (N, dim) in ``frame``, or None."""
        return feed_forward_change(q, frame, self.law, self.obstacles, self.sensing_radii)

    def sent(self, u: ArrayLike, q: ArrayLike, frame: Optional[FrameSample]
             ) -> NDArray[np.float64]:
        """Return eq. (25)'s own part of commands u (N, dim) at q: u less :meth:`change`."""
        change = self.change(q, frame)
        own: NDArray[np.float64] = np.asarray(u, dtype=float)
        return own if change is None else own - change
