# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Differential-drive (unicycle) robots driven by the bounded law through their hand points.

Beyond the paper (its conclusion names nonholonomic robots as future work; docs/equations.md,
"Differential-drive robots"). A unicycle has its axle centre q = (x, y) in m, its heading th in
rad and two inputs, the forward speed v (m/s) and the turn rate w (rad/s)::

    x' = v cos th,   y' = v sin th,   th' = w                                    (U1)

Its hand point, a distance l > 0 (m) ahead of the axle, is::

    p = q + l (cos th, sin th)                                                    (U2)

and moves with ``p' = R(th) (v, l w)``, R(th) the rotation by th (U3). R(th) and l > 0 are
invertible, so a world velocity u wanted for the hand point (the law's command, eq. 14 or 25)
is produced exactly by::

    v = cos th u_x + sin th u_y,   w = (-sin th u_x + cos th u_y) / l             (U4)

With ``|u^k| <= c M1`` for both components, ``|v| <= ||u|| <= sqrt(2) c M1`` and
``|w| <= sqrt(2) c M1 / l`` (U5).

Shapes: positions (..., 2) in m, headings (...) in rad, commands (..., 2) holding (v, w) in m/s
and rad/s, hand-point velocities (..., 2) in m/s, with the same leading shape: one robot is
``(2,)`` and a scalar heading, a team ``(N, 2)`` and ``(N,)``. Nothing here imports ROS and no
function modifies its arguments.
"""

import math
from typing import Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]


def heading_vectors(heading: ArrayLike) -> Float:
    """Return the unit vectors (cos th, sin th) of the headings: (..., 2)."""
    th = np.asarray(heading, dtype=float)
    return np.stack((np.cos(th), np.sin(th)), axis=-1)


def hand_points(q: ArrayLike, heading: ArrayLike, hand_distance: float) -> Float:
    """Hand points p = q + l (cos th, sin th) (U2) of axle positions q: (..., 2) in m."""
    return np.asarray(q, dtype=float) + hand_distance * heading_vectors(heading)


def unicycle_commands(u: ArrayLike, heading: ArrayLike, hand_distance: float) -> Float:
    """
    Return (v, w) that move the hand point with world velocity u (U4): (..., 2).

    u: (..., 2) m/s; heading: (...) rad; hand_distance: l in m (> 0). Column 0 is v in m/s
    (the component of u along the heading), column 1 is w in rad/s (the component across it,
    divided by l).
    """
    u = np.asarray(u, dtype=float)
    c, s = np.cos(heading), np.sin(heading)
    along = c * u[..., 0] + s * u[..., 1]
    across = -s * u[..., 0] + c * u[..., 1]
    return np.stack((along, across / hand_distance), axis=-1)


def hand_velocity(command: ArrayLike, heading: ArrayLike, hand_distance: float) -> Float:
    """
    Velocity p' = R(th) (v, l w) of the hand point under the command (v, w) (U3): (..., 2).

    The inverse of :func:`unicycle_commands`; command (..., 2) holds (v, w).
    """
    command = np.asarray(command, dtype=float)
    c, s = np.cos(heading), np.sin(heading)
    v, lw = command[..., 0], hand_distance * command[..., 1]
    return np.stack((c * v - s * lw, s * v + c * lw), axis=-1)


def unicycle_rates(heading: ArrayLike, command: ArrayLike) -> Tuple[Float, Float]:
    """Right-hand side of (U1): (q' (..., 2) in m/s, th' (...) in rad/s)."""
    command = np.asarray(command, dtype=float)
    return command[..., :1] * heading_vectors(heading), np.array(command[..., 1], dtype=float)


def zoh_step(q: ArrayLike, heading: ArrayLike, command: ArrayLike,
             dt: float) -> Tuple[Float, Float]:
    """
    Exact solution of (U1) over dt with (v, w) held (zero-order hold): (q(t + dt), th(t + dt)).

    For w != 0 the axle moves on a circular arc::

        x += v / w (sin(th + w dt) - sin th),   y += -v / w (cos(th + w dt) - cos th)

    and th += w dt. Written with ``sin(a) - sin(b) = 2 cos((a + b) / 2) sin((a - b) / 2)`` this
    is ``q += v dt sinc(w dt / 2) (cos, sin)(th + w dt / 2)`` with ``sinc(x) = sin(x) / x``,
    which has no cancellation as w dt -> 0 and gives the straight line ``q += v dt (cos th,
    sin th)`` at w = 0 exactly. q: (..., 2) m; heading: (...) rad; command: (..., 2) (v, w).
    """
    command = np.asarray(command, dtype=float)
    th = np.asarray(heading, dtype=float)
    v, w = command[..., 0], command[..., 1]
    half = 0.5 * dt * w
    chord = dt * v * np.sinc(half / math.pi)
    moved = np.asarray(q, dtype=float) + chord[..., None] * heading_vectors(th + half)
    return moved, th + dt * w


def command_bounds(u_bound: float, hand_distance: float) -> Tuple[float, float]:
    """Bounds (U5) of |v| (m/s) and |w| (rad/s) for commands with every |u^k| <= u_bound."""
    v_bound = math.sqrt(2.0) * u_bound
    return v_bound, v_bound / hand_distance


def quaternions_from_headings(heading: ArrayLike) -> Float:
    """Return unit quaternions (x, y, z, w) of rotations by th about +z: (..., 4)."""
    half = 0.5 * np.asarray(heading, dtype=float)
    zeros = np.zeros_like(half)
    return np.stack((zeros, zeros, np.sin(half), np.cos(half)), axis=-1)


def headings_from_quaternions(quaternion: ArrayLike) -> Float:
    """
    Yaw th in (-pi, pi] of orientations given as quaternions (x, y, z, w): (...).

    ``th = atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))``, the rotation about +z of the body's x
    axis projected onto the plane; the quaternion need not be normalised (it is scaled out).
    """
    x, y, z, w = np.moveaxis(np.asarray(quaternion, dtype=float), -1, 0)
    norm = x * x + y * y + z * z + w * w
    return np.asarray(np.arctan2(2.0 * (w * z + x * y), norm - 2.0 * (y * y + z * z)),
                      dtype=float)
