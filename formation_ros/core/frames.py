"""
The moving formation frame of Section 6: J, its time derivative, and eqs. (20), (21), (25).

J (dim x dim) rotates world vectors into the formation frame: ``qhat = J (q - q_od)`` (eq. 21).
Rows of J are the frame's axes written in world coordinates. With positions stored as rows
(N, dim), eq. (21) reads ``(q - q_od) @ J.T`` and ``J^{-1} v = J.T v`` reads ``v @ J``.

Frames:

* 2D (Section 6, ERRATA 6): ``J = [[cos th, sin th], [-sin th, cos th]]`` with
  ``th = atan2(y', x')``; ``Jdot = th' [[-sin, cos], [-cos, -sin]]`` with
  ``th' = (x' y'' - y' x'') / v**2``.
* 3D Frenet (helix): rows t, n, b; ``Jdot = -[w]x J`` with the Darboux vector
  ``w = v (tau, 0, k)`` (ERRATA 6).
* 3D planar (line, circle, figure eight; beyond the paper): ``b`` is the fixed plane normal,
  ``n = b x t``. This is the Frenet triad wherever the path turns counter-clockwise about the
  normal, and unlike the Frenet triad it stays defined and continuous where the curvature is zero
  (straight lines, the inflection points of a figure eight) and where the turning changes sense.
  Then ``w = v (0, 0, k_signed)``.

``STATIONARY`` (``None``) stands for stabilisation: ``q_od = 0``, ``J = I``, ``Jdot = 0``.
"""

from dataclasses import dataclass

import numpy as np

STATIONARY = None
SPEED_EPS = 1e-12


@dataclass(frozen=True)
class FrameSample:
    """
    The reference at one time.

    t: time in s; q_od: (dim,) centre of the formation, m; qdot_od: (dim,) its velocity, m/s;
    J: (dim, dim) rotation world -> formation frame; Jdot: (dim, dim) its time derivative, 1/s.
    """

    t: float
    q_od: np.ndarray
    qdot_od: np.ndarray
    J: np.ndarray
    Jdot: np.ndarray


def stationary_frame(dim, origin=None, t=0.0):
    """Frame of a fixed reference at ``origin`` (default 0): J = I, Jdot = 0."""
    q_od = np.zeros(dim) if origin is None else np.asarray(origin, dtype=float).copy()
    return FrameSample(float(t), q_od, np.zeros(dim), np.eye(dim), np.zeros((dim, dim)))


def to_frame(q, frame):
    """Eq. (21): positions (N, dim) in the world frame -> formation frame (N, dim)."""
    q = np.asarray(q, dtype=float)
    if frame is None:
        return q.copy()
    return (q - frame.q_od) @ frame.J.T


def to_frame_vectors(v, frame):
    """Rotate free vectors (N, dim), e.g. q_ij, into the formation frame (no translation)."""
    v = np.asarray(v, dtype=float)
    if frame is None:
        return v.copy()
    return v @ frame.J.T


def from_frame_velocity(u_hat, q, frame):
    """
    Eq. (25) with ERRATA 5: ``u = qdot_od + J^{-1} (u_hat - Jdot (q - q_od))``.

    u_hat: (N, dim) commands in the formation frame; q: (N, dim) world positions.
    Returns (N, dim) world velocities in m/s.
    """
    u_hat = np.asarray(u_hat, dtype=float)
    if frame is None:
        return u_hat.copy()
    offset = np.asarray(q, dtype=float) - frame.q_od
    return frame.qdot_od + (u_hat - offset @ frame.Jdot.T) @ frame.J


def desired_positions(vertices, frame):
    """Eq. (20) solved for q_id: ``q_id = q_od + J^{-1} qhat_id``; (N, dim) -> (N, dim)."""
    vertices = np.asarray(vertices, dtype=float)
    if frame is None:
        return vertices.copy()
    return frame.q_od + vertices @ frame.J


def skew(w):
    """Return the cross-product matrix [w]x of a 3-vector w (times v gives w x v)."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def frame_2d(qdot, qddot):
    """
    J and Jdot in 2D from the reference velocity and acceleration (ERRATA 6).

    Returns (J, Jdot), each (2, 2). A reference at rest has J = I, Jdot = 0.
    """
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


def frame_planar_3d(qdot, qddot, normal):
    """
    J and Jdot in 3D for a path in a plane with unit ``normal`` (module docstring).

    For a straight line ``normal`` only fixes the roll of the frame: any unit vector not parallel
    to the line. Returns (J, Jdot), each (3, 3); a reference at rest has J = I, Jdot = 0.
    """
    qdot = np.asarray(qdot, dtype=float)
    speed = float(np.linalg.norm(qdot))
    if speed <= SPEED_EPS:
        return np.eye(3), np.zeros((3, 3))
    tangent = qdot / speed
    n_raw = np.cross(normal, tangent)
    n_vec = n_raw / np.linalg.norm(n_raw)
    b_vec = np.cross(tangent, n_vec)
    jmat = np.vstack([tangent, n_vec, b_vec])
    k_signed = float(np.dot(np.cross(qdot, qddot), b_vec)) / speed ** 3
    jdot = -skew(speed * np.array([0.0, 0.0, k_signed])) @ jmat
    return jmat, jdot


def frame_frenet_3d(qdot, qddot, qdddot):
    """
    Frenet J and Jdot = -[w]x J, w = v (tau, 0, k) (Section 6, ERRATA 6).

    Needs a curvature bounded away from zero (the helix). Returns (J, Jdot), each (3, 3).
    """
    qdot = np.asarray(qdot, dtype=float)
    speed = float(np.linalg.norm(qdot))
    cross = np.cross(qdot, qddot)
    cross_norm = float(np.linalg.norm(cross))
    if speed <= SPEED_EPS or cross_norm <= SPEED_EPS:
        raise ValueError('the Frenet frame needs a moving reference with non-zero curvature')
    tangent = qdot / speed
    b_vec = cross / cross_norm
    n_vec = np.cross(b_vec, tangent)
    curvature = cross_norm / speed ** 3
    torsion = float(np.dot(cross, qdddot)) / cross_norm ** 2
    jmat = np.vstack([tangent, n_vec, b_vec])
    jdot = -skew(speed * np.array([torsion, 0.0, curvature])) @ jmat
    return jmat, jdot
