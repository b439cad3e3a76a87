# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The moving formation frame of Section 6: J, its time derivative, and eqs. (20), (21), (25).

J (dim x dim) rotates world vectors into the formation frame: ``qhat = J (q - q_od)`` (eq. 21).
Rows of J are the frame's axes written in world coordinates. With positions stored as rows
(N, dim), eq. (21) reads ``(q - q_od) @ J.T`` and ``J^{-1} v = J.T v`` reads ``v @ J``.

Frames:

* 2D (Section 6; docs/equations.md, slip 6): ``J = [[cos th, sin th], [-sin th, cos th]]`` with
  ``th = atan2(y', x')``; ``Jdot = th' [[-sin, cos], [-cos, -sin]]`` with
  ``th' = (x' y'' - y' x'') / v**2``.
* 3D Frenet (helix): rows t, n, b; ``Jdot = -[w]x J`` with the Darboux vector
  ``w = v (tau, 0, k)`` (docs/equations.md, slip 6).
* 3D planar (line, circle, figure eight; beyond the paper): ``b`` is the fixed plane normal,
  ``n = b x t``. This is the Frenet triad wherever the path turns counter-clockwise about the
  normal, and unlike the Frenet triad it stays defined and continuous where the curvature is zero
  (straight lines, the inflection points of a figure eight) and where the turning changes sense.
  Then ``w = v (0, 0, k_signed)``.

``STATIONARY`` (``None``) stands for stabilisation: ``q_od = 0``, ``J = I``, ``Jdot = 0``.
"""

from dataclasses import dataclass
import math
from typing import Any, Optional, overload, Tuple

from formation_ros.core.maths.unicycle import headings_from_quaternions
import numpy as np
from numpy.typing import ArrayLike, NDArray

STATIONARY = None
SPEED_EPS = 1e-12

JAndJdot = tuple[NDArray[np.float64], NDArray[np.float64]]
Pose = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


@dataclass(frozen=True)
class FrameSample:
    """
    The reference at one time.

    t: time in s; q_od: (dim,) centre of the formation, m; qdot_od: (dim,) its velocity, m/s;
    J: (dim, dim) rotation world -> formation frame; Jdot: (dim, dim) its time derivative, 1/s;
    still: True when J = I, Jdot = 0 and qdot_od = 0 (:func:`stationary_frame`), so that eqs.
    (21) and (25) are a translation and the identity, computed as such.
    """

    t: float
    q_od: NDArray[np.float64]
    qdot_od: NDArray[np.float64]
    J: NDArray[np.float64]
    Jdot: NDArray[np.float64]
    still: bool = False


def stationary_frame(dim: int, origin: Optional[ArrayLike] = None, t: float = 0.0) -> FrameSample:
    """Frame of a fixed reference at ``origin`` (default 0): J = I, Jdot = 0."""
    q_od = np.zeros(dim) if origin is None else np.asarray(origin, dtype=float).copy()
    return FrameSample(float(t), q_od, np.zeros(dim), np.eye(dim), np.zeros((dim, dim)), True)


def to_frame(q: ArrayLike, frame: Optional[FrameSample]) -> NDArray[np.float64]:
    """Eq. (21): positions (N, dim) in the world frame -> formation frame (N, dim)."""
    q = np.asarray(q, dtype=float)
    if frame is None:
        return q.copy()
    if frame.still:
        return q - frame.q_od
    return (q - frame.q_od) @ frame.J.T


def to_frame_vectors(v: ArrayLike, frame: Optional[FrameSample]) -> NDArray[np.float64]:
    """Rotate free vectors (N, dim), e.g. q_ij, into the formation frame (no translation)."""
    v = np.asarray(v, dtype=float)
    if frame is None:
        return v.copy()
    return v @ frame.J.T


def from_frame_velocity(u_hat: ArrayLike, q: ArrayLike,
                        frame: Optional[FrameSample]) -> NDArray[np.float64]:
    """
    World velocities from formation-frame commands: eq. (25), docs/equations.md, slip 5.

    ``u = qdot_od + J^{-1} (u_hat - Jdot (q - q_od))``. u_hat: (N, dim) commands in the formation
    frame; q: (N, dim) world positions. Returns (N, dim) world velocities in m/s.
    """
    u_hat = np.asarray(u_hat, dtype=float)
    if frame is None:
        return u_hat.copy()
    if frame.still:
        return u_hat + frame.qdot_od
    offset = np.asarray(q, dtype=float) - frame.q_od
    return frame.qdot_od + (u_hat - offset @ frame.Jdot.T) @ frame.J


def to_frame_velocity(u: ArrayLike, q: ArrayLike,
                      frame: Optional[FrameSample]) -> NDArray[np.float64]:
    """
    Invert eq. (25): ``u_hat = J (u - qdot_od) + Jdot (q - q_od)``.

    u: (N, dim) world velocities, q: (N, dim) world positions. Returns (N, dim), the bounded
    command of eq. (14) that produced ``u``.
    """
    u = np.asarray(u, dtype=float)
    if frame is None:
        return u.copy()
    offset = np.asarray(q, dtype=float) - frame.q_od
    return (u - frame.qdot_od) @ frame.J.T + offset @ frame.Jdot.T


def desired_positions(vertices: ArrayLike,
                      frame: Optional[FrameSample]) -> NDArray[np.float64]:
    """Eq. (20) solved for q_id: ``q_id = q_od + J^{-1} qhat_id``; (N, dim) -> (N, dim)."""
    vertices = np.asarray(vertices, dtype=float)
    if frame is None:
        return vertices.copy()
    return frame.q_od + vertices @ frame.J


def skew(w: ArrayLike) -> NDArray[np.float64]:
    """Return the cross-product matrix [w]x of a 3-vector w (times v gives w x v)."""
    w = np.asarray(w, dtype=float)
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def frame_2d(qdot: ArrayLike, qddot: ArrayLike) -> JAndJdot:
    """
    J and Jdot in 2D from the reference velocity and acceleration (docs/equations.md, slip 6).

    Returns (J, Jdot), each (2, 2). A reference at rest has J = I, Jdot = 0.
    """
    qdot, qddot = np.asarray(qdot, dtype=float), np.asarray(qddot, dtype=float)
    vx, vy = float(qdot[0]), float(qdot[1])
    v2 = vx * vx + vy * vy
    if v2 <= SPEED_EPS ** 2:
        return np.eye(2), np.zeros((2, 2))
    th = np.arctan2(vy, vx)
    th_dot = (vx * float(qddot[1]) - vy * float(qddot[0])) / v2
    c, s = np.cos(th), np.sin(th)
    jmat = np.array([[c, s], [-s, c]])
    jdot = th_dot * np.array([[-s, c], [-c, -s]])
    return jmat, jdot


def frame_planar_3d(qdot: ArrayLike, qddot: ArrayLike, normal: ArrayLike) -> JAndJdot:
    """
    J and Jdot in 3D for a path in a plane with unit ``normal`` (module docstring).

    For a straight line ``normal`` only fixes the roll of the frame: any unit vector not parallel
    to the line. Returns (J, Jdot), each (3, 3); a reference at rest has J = I, Jdot = 0.
    """
    qdot, qddot = np.asarray(qdot, dtype=float), np.asarray(qddot, dtype=float)
    speed = float(np.linalg.norm(qdot))
    if speed <= SPEED_EPS:
        return np.eye(3), np.zeros((3, 3))
    tangent = qdot / speed
    n_raw = np.cross(np.asarray(normal, dtype=float), tangent)
    n_vec = n_raw / np.linalg.norm(n_raw)
    b_vec = np.cross(tangent, n_vec)
    jmat = np.vstack([tangent, n_vec, b_vec])
    k_signed = float(np.dot(np.cross(qdot, qddot), b_vec)) / speed ** 3
    jdot = -skew(speed * np.array([0.0, 0.0, k_signed])) @ jmat
    return jmat, jdot


def frame_frenet_3d(qdot: ArrayLike, qddot: ArrayLike, qdddot: ArrayLike) -> JAndJdot:
    """
    Frenet J and Jdot = -[w]x J, w = v (tau, 0, k) (Section 6; docs/equations.md, slip 6).

    Needs a curvature bounded away from zero (the helix). Returns (J, Jdot), each (3, 3).
    """
    qdot, qddot = np.asarray(qdot, dtype=float), np.asarray(qddot, dtype=float)
    speed = float(np.linalg.norm(qdot))
    cross = np.cross(qdot, qddot)
    cross_norm = float(np.linalg.norm(cross))
    if speed <= SPEED_EPS or cross_norm <= SPEED_EPS:
        raise ValueError('the Frenet frame needs a moving reference with non-zero curvature')
    tangent = qdot / speed
    b_vec = cross / cross_norm
    n_vec = np.cross(b_vec, tangent)
    curvature = cross_norm / speed ** 3
    torsion = float(np.dot(cross, np.asarray(qdddot, dtype=float))) / cross_norm ** 2
    jmat = np.vstack([tangent, n_vec, b_vec])
    jdot = -skew(speed * np.array([torsion, 0.0, curvature])) @ jmat
    return jmat, jdot


def _vee(skew_matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([skew_matrix[2, 1], skew_matrix[0, 2], skew_matrix[1, 0]])


def _rotation_and_angular_velocity(
        frame: FrameSample) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """
    J as a 3x3 rotation and the frame's world angular velocity w, with ``Jdot = -J [w]x``.

    A 2D frame is a rotation about z: J goes in the upper left block of the identity, and w has
    only a z component.
    """
    dim = frame.J.shape[0]
    jmat, jdot = np.eye(3), np.zeros((3, 3))
    jmat[:dim, :dim] = frame.J
    jdot[:dim, :dim] = frame.Jdot
    return jmat, _vee(-jmat.T @ jdot)


def quaternion_from_matrix(rotation: ArrayLike) -> NDArray[np.float64]:
    """
    Return the unit quaternion (x, y, z, w), w >= 0, of a 3x3 rotation matrix.

    Computed from the largest of 1 + trace and the three 1 + 2 R_kk - trace (Shepperd's choice),
    so no division is by a small number; the result is normalised.
    """
    r = np.asarray(rotation, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    candidates = (1.0 + trace, 1.0 + 2.0 * r[0, 0] - trace, 1.0 + 2.0 * r[1, 1] - trace,
                  1.0 + 2.0 * r[2, 2] - trace)
    k = int(np.argmax(candidates))
    root = 2.0 * np.sqrt(candidates[k])
    if k == 0:
        quat = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1], 0.0]) / root
        quat[3] = 0.25 * root
    else:
        i, j, m = k - 1, k % 3, (k + 1) % 3
        quat = np.empty(4)
        quat[i] = 0.25 * root
        quat[j] = (r[j, i] + r[i, j]) / root
        quat[m] = (r[m, i] + r[i, m]) / root
        quat[3] = (r[m, j] - r[j, m]) / root
    unit: NDArray[np.float64] = quat / np.linalg.norm(quat)
    return unit if unit[3] >= 0.0 else -unit


def matrix_from_quaternion(quat: ArrayLike) -> NDArray[np.float64]:
    """
    Return the rotation matrix (3, 3) of a quaternion (x, y, z, w) != 0, normalised first.

    The same operations as :func:`_rotations` on floats: the same bits, a quarter of the time
    for one quaternion (a team process turns each reference sample into a frame).
    """
    x, y, z, w = (float(v) for v in np.asarray(quat, dtype=float).reshape(4))
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    return np.array(_rotation_rows(x / norm, y / norm, z / norm, w / norm))


def _rotation_rows(x: Any, y: Any, z: Any, w: Any) -> Tuple[Tuple[Any, Any, Any], ...]:
    """Return the rows of the rotation matrix of unit quaternions: floats or arrays alike."""
    return ((1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)),
            (2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)),
            (2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)))


QUATERNION_TOLERANCE = 1e-3
"""An orientation is valid when its quaternion is finite and its norm within this of 1."""


def valid_quaternions(quaternion: ArrayLike) -> NDArray[np.bool_]:
    """Tell which quaternions (x, y, z, w) (..., 4) are orientations: finite, norm ~ 1: (...)."""
    quat = np.asarray(quaternion, dtype=float)
    with np.errstate(invalid='ignore', over='ignore'):
        norm = np.sqrt(np.sum(quat * quat, axis=-1))
        valid: NDArray[np.bool_] = np.all(np.isfinite(quat), axis=-1) & (
            np.abs(norm - 1.0) <= QUATERNION_TOLERANCE)
    return valid


def _rotations(quaternion: ArrayLike) -> NDArray[np.float64]:
    """Return the rotation matrices (N, 3, 3) of valid quaternions (N, 4), normalised first."""
    quat = np.asarray(quaternion, dtype=float).reshape(-1, 4)
    x, y, z, w = (quat / np.linalg.norm(quat, axis=1, keepdims=True)).T
    return np.stack([np.stack(row, -1) for row in _rotation_rows(x, y, z, w)], axis=1)


def _planar_rotations(quaternion: ArrayLike) -> NDArray[np.float64]:
    """Return the yaw rotations (N, 2, 2) of quaternions (N, 4): the plane's part of them."""
    yaw = headings_from_quaternions(np.asarray(quaternion, dtype=float).reshape(-1, 4))
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], axis=1)


def to_body_frame(u: ArrayLike, quaternion: ArrayLike) -> NDArray[np.float64]:
    """
    Express world vectors in the bodies' frames: ``R^T u`` for each row.

    u: (N, dim) world-frame vectors (m/s); quaternion: (N, 4) orientations (x, y, z, w) of the
    bodies in the world (valid: :func:`valid_quaternions`). In 2D the rotation is the yaw
    about +z (the plane's part of the orientation); in 3D the whole rotation. Returns (N, dim).
    """
    vectors = np.asarray(u, dtype=float)
    rotation = _rotations(quaternion) if vectors.shape[-1] == 3 else _planar_rotations(
        quaternion)
    return np.asarray(np.einsum('nji,nj->ni', rotation, vectors.reshape(len(rotation), -1)),
                      dtype=float)


def from_body_frame(v: ArrayLike, quaternion: ArrayLike) -> NDArray[np.float64]:
    """Inverse of :func:`to_body_frame`: body-frame vectors (N, dim) into the world, ``R v``."""
    vectors = np.asarray(v, dtype=float)
    rotation = _rotations(quaternion) if vectors.shape[-1] == 3 else _planar_rotations(
        quaternion)
    return np.asarray(np.einsum('nij,nj->ni', rotation, vectors.reshape(len(rotation), -1)),
                      dtype=float)


def rotation_of_vector(rotvec: ArrayLike) -> NDArray[np.float64]:
    """
    Return the rotation matrix (3, 3) of a rotation vector (axis times angle in rad; Rodrigues).

    Near zero angle the coefficients sin(a)/a and (1 - cos(a))/a**2 are taken from their series.
    """
    v = np.asarray(rotvec, dtype=float)
    angle = float(np.linalg.norm(v))
    k = skew(v)
    if angle < 1e-4:
        a2 = angle * angle
        first, second = 1.0 - a2 / 6.0 + a2 * a2 / 120.0, 0.5 - a2 / 24.0 + a2 * a2 / 720.0
    else:
        first, second = np.sin(angle) / angle, (1.0 - np.cos(angle)) / (angle * angle)
    return np.eye(3) + first * k + second * (k @ k)


def frame_to_pose(frame: Optional[FrameSample], dim: int) -> Pose:
    """
    Express a frame as an odometry-like pose.

    Returns (position (3,), quaternion (x, y, z, w), linear velocity (3,), angular velocity
    (3,)), all in the world frame: the quaternion is the rotation J^T from formation axes to
    world axes, the angular velocity w satisfies ``Jdot = -J [w]x``. ``None`` stands for the
    stationary frame at the origin. 2D frames are rotations about z, with z components zero.
    """
    frame = stationary_frame(dim) if frame is None else frame
    jmat, angular = _rotation_and_angular_velocity(frame)
    position, linear = np.zeros(3), np.zeros(3)
    position[:dim] = frame.q_od
    linear[:dim] = frame.qdot_od
    return position, quaternion_from_matrix(jmat.T), linear, angular


def frame_from_pose(t: float, position: ArrayLike, quaternion: ArrayLike, linear: ArrayLike,
                    angular: ArrayLike, dim: int) -> FrameSample:
    """
    Inverse of :func:`frame_to_pose`: a :class:`FrameSample` of dimension ``dim``.

    position, linear, angular: 3 values each (m, m/s, rad/s); quaternion: (x, y, z, w), not zero.
    """
    jmat = matrix_from_quaternion(quaternion).T
    jdot = -jmat @ skew(angular)
    return FrameSample(float(t), np.array(np.asarray(position, dtype=float)[:dim]),
                       np.array(np.asarray(linear, dtype=float)[:dim]), jmat[:dim, :dim].copy(),
                       jdot[:dim, :dim].copy())


@overload
def advance(frame: FrameSample, dt: float) -> FrameSample: ...


@overload
def advance(frame: None, dt: float) -> None: ...


def advance(frame: Optional[FrameSample], dt: float) -> Optional[FrameSample]:
    """
    Carry a frame forward by dt seconds at constant velocity and angular velocity.

    Used to bring the latest reference sample to the time of a robot's state; exact for a line
    and a fixed reference, and for J of a circle or helix (constant angular velocity); q_od is
    first order in dt otherwise. Returns a new :class:`FrameSample` (``frame`` itself for
    ``dt == 0`` or ``None``).
    """
    if frame is None or dt == 0.0:
        return frame
    dim = frame.q_od.shape[0]
    jmat, omega = _rotation_and_angular_velocity(frame)
    moved = jmat @ rotation_of_vector(-omega * dt)
    moved_dot = -moved @ skew(omega)
    return FrameSample(frame.t + dt, frame.q_od + frame.qdot_od * dt, frame.qdot_od.copy(),
                       moved[:dim, :dim].copy(), moved_dot[:dim, :dim].copy())
