# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Moving references q_od(t) for formation tracking (Section 6) and their frames.

The path parameter s of the paper is time here (``ds/dt = 1``), so ``qdot_od = q_od'(t)``.
Kinds (the ``reference.*`` parameters):

* ``fixed``: ``q_od = origin``; J = I (stabilisation about ``origin``).
* ``line``: ``q_od = origin + velocity * t``.
* ``circle``: centred on ``origin``, radius r, starts at angle 0 (``origin + (r, 0)``) and runs
  counter-clockwise about +z at path speed ``speed``; in 3D it lies in the plane z = origin_z.
* ``figure_eight``: the lemniscate of Gerono ``origin + r (sin a, sin a cos a)``, a = omega t,
  starting at its crossing (an inflection point); omega is chosen so that one loop of length
  ``L_8`` takes ``L_8 / speed`` seconds (``speed`` is the mean path speed).
* ``helix`` (3D): the circle rising along +z by ``pitch`` per turn at constant path speed.

2D frames come from atan2 of the velocity; the helix uses the Frenet triad; the planar kinds in
3D use the planar frame of :mod:`formation_ros.core.maths.frames`.
"""

import math
from typing import Optional, Tuple, Union

from formation_ros.core.maths.choice import Choice
from formation_ros.core.maths.frames import (frame_2d, frame_frenet_3d, frame_planar_3d,
                                             FrameSample, stationary_frame)
import numpy as np
from numpy.typing import ArrayLike, NDArray


class ReferenceKind(Choice):
    """Desired formation trajectory: ``reference.kind``."""

    FIXED = 'fixed'
    LINE = 'line'
    CIRCLE = 'circle'
    FIGURE_EIGHT = 'figure_eight'
    HELIX = 'helix'


PERIODIC = (ReferenceKind.CIRCLE, ReferenceKind.FIGURE_EIGHT, ReferenceKind.HELIX)
"""The kinds that go round a closed path at a path speed (``reference.speed`` > 0)."""
Z_AXIS = np.array([0.0, 0.0, 1.0])
Derivatives = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
                    NDArray[np.float64]]
GERONO_SAMPLES = 4096
RATE_SAMPLES = 1024


def _gerono_loop_length() -> float:
    """
    Length of one loop of the unit lemniscate of Gerono, the integral of its speed over a period.

    The speed sqrt(cos(a)^2 + cos(2a)^2) is periodic, analytic and never zero, so the
    trapezoidal rule over one period converges geometrically: 4096 points give it to rounding.
    """
    a = np.linspace(0.0, 2.0 * math.pi, GERONO_SAMPLES, endpoint=False)
    speed = np.sqrt(np.cos(a) ** 2 + np.cos(2.0 * a) ** 2)
    return float(2.0 * math.pi * np.mean(speed))


GERONO_LOOP_LENGTH = _gerono_loop_length()


def dimension_problem(kind: ReferenceKind, dim: int) -> Optional[str]:
    """Return why a reference of ``kind`` cannot run in ``dim`` dimensions (None: it can)."""
    if kind is ReferenceKind.HELIX and dim != 3:
        return 'helix needs dim 3'
    return None


class Reference:
    """
    A moving desired formation centre q_od(t) with its frame J(t).

    dim: 2 or 3. ``sample(t)`` returns a :class:`FrameSample`; ``derivatives(t)`` returns
    (q, q', q'', q''') as (dim,) arrays (m, m/s, m/s**2, m/s**3).
    """

    def __init__(self, kind: Union[ReferenceKind, str], dim: int,
                 origin: Optional[ArrayLike] = None, velocity: Optional[ArrayLike] = None,
                 radius: float = 1.0, speed: float = 0.0, pitch: float = 0.0,
                 phase: float = 0.0) -> None:
        """
        Build a reference (values already validated by ``core.settings.params``).

        phase: angle a of the circle, figure eight and helix at t = 0, rad (0: their start
        above); a = rate t + phase.
        """
        try:
            self.kind = ReferenceKind(kind)
        except ValueError:
            raise ValueError(f'unknown reference kind {kind!r}; expected one of '
                             f'{[str(member) for member in ReferenceKind]}') from None
        if dim not in (2, 3):
            raise ValueError(f'dim must be 2 or 3, got {dim!r}')
        problem = dimension_problem(self.kind, dim)
        if problem:
            raise ValueError(f'a {problem}')
        self.dim = dim
        self.origin = np.zeros(dim) if origin is None else np.array(origin, dtype=float)
        self.velocity = np.zeros(dim) if velocity is None else np.array(velocity, dtype=float)
        self.radius = float(radius)
        self.speed = float(speed)
        self.pitch = float(pitch)
        self.phase = float(phase)
        self.rate = self._angular_rate()

    def _angular_rate(self) -> float:
        if self.kind is ReferenceKind.CIRCLE:
            return self.speed / self.radius
        if self.kind is ReferenceKind.FIGURE_EIGHT:
            return 2.0 * math.pi * self.speed / (self.radius * GERONO_LOOP_LENGTH)
        if self.kind is ReferenceKind.HELIX:
            rise = self.pitch / (2.0 * math.pi)
            return self.speed / math.hypot(self.radius, rise)
        return 0.0

    def with_speed(self, speed: float, t: float) -> 'Reference':
        """
        Return this reference run at path speed ``speed`` from time ``t`` on, without a jump.

        For the circle, figure eight and helix: the same path with the phase chosen so that
        ``q_od`` at ``t`` is where it is now (a = rate t + phase is kept at t); the speed, and so
        qdot_od and J's rate, change at once. Raises ValueError for the other kinds.
        """
        if self.kind not in PERIODIC:
            raise ValueError(f'a {self.kind} reference has no path speed')
        angle = self.rate * t + self.phase
        faster = Reference(self.kind, self.dim, self.origin, self.velocity, self.radius, speed,
                           self.pitch)
        return Reference(self.kind, self.dim, self.origin, self.velocity, self.radius, speed,
                         self.pitch, angle - faster.rate * t)

    def with_values(self, origin: ArrayLike, speed: float, phase: float) -> 'Reference':
        """Return this reference with another origin (dim,) m, path speed m/s and phase rad."""
        return Reference(self.kind, self.dim, origin, self.velocity, self.radius, speed,
                         self.pitch, phase)

    @property
    def is_stationary(self) -> bool:
        """Tell whether q_od never moves (fixed, or a line with zero velocity)."""
        return self.kind is ReferenceKind.FIXED or (self.kind is ReferenceKind.LINE
                                                    and not np.any(self.velocity))

    def rate_limits(self) -> Tuple[float, float]:
        """
        Return the largest speed |q_od'| (m/s) and turn rate |w| (rad/s) the reference reaches.

        Exact for the fixed, line, circle and helix kinds (constant rates); the figure eight's
        are the largest over RATE_SAMPLES points of one loop (relative error below 1e-4).
        """
        if self.kind not in PERIODIC:
            return float(np.linalg.norm(self.velocity)), 0.0
        if self.rate == 0.0:
            return 0.0, 0.0
        times = np.arange(RATE_SAMPLES) * (2.0 * math.pi / self.rate / RATE_SAMPLES) \
            - self.phase / self.rate
        speed = turn = 0.0
        for t in times:
            frame = self.sample(float(t))
            speed = max(speed, float(np.linalg.norm(frame.qdot_od)))
            turn = max(turn, float(np.linalg.norm(frame.Jdot)) / math.sqrt(2.0))
        return speed, turn

    def derivatives(self, t: float) -> Derivatives:
        """Return (q_od, q_od', q_od'', q_od''') at time t, each (dim,)."""
        dim = self.dim
        zero = np.zeros(dim)
        if self.kind is ReferenceKind.FIXED:
            return self.origin.copy(), zero, zero.copy(), zero.copy()
        if self.kind is ReferenceKind.LINE:
            return self.origin + self.velocity * t, self.velocity.copy(), zero, zero.copy()
        r, w = self.radius, self.rate
        a = w * t + self.phase
        ca, sa = math.cos(a), math.sin(a)
        if self.kind is ReferenceKind.FIGURE_EIGHT:
            c2, s2 = math.cos(2.0 * a), math.sin(2.0 * a)
            planar = (np.array([sa, 0.5 * s2]), np.array([w * ca, w * c2]),
                      np.array([-w * w * sa, -2.0 * w * w * s2]),
                      np.array([-w ** 3 * ca, -4.0 * w ** 3 * c2]))
            rise = (0.0, 0.0, 0.0, 0.0)
        else:
            planar = (np.array([ca, sa]), np.array([-w * sa, w * ca]),
                      np.array([-w * w * ca, -w * w * sa]),
                      np.array([w ** 3 * sa, -w ** 3 * ca]))
            c = self.pitch / (2.0 * math.pi) if self.kind is ReferenceKind.HELIX else 0.0
            rise = (c * a, c * w, 0.0, 0.0)
        out = []
        for order in range(4):
            vec = np.zeros(dim)
            vec[:2] = r * planar[order]
            if dim == 3:
                vec[2] = rise[order]
            out.append(vec)
        return out[0] + self.origin, out[1], out[2], out[3]

    def sample(self, t: float) -> FrameSample:
        """Return the :class:`FrameSample` (q_od, qdot_od, J, Jdot) at time t in s."""
        if self.kind is ReferenceKind.FIXED:
            return stationary_frame(self.dim, self.origin, t)
        q, q1, q2, q3 = self.derivatives(t)
        if self.dim == 2:
            jmat, jdot = frame_2d(q1, q2)
        elif self.kind is ReferenceKind.HELIX:
            jmat, jdot = frame_frenet_3d(q1, q2, q3)
        else:
            jmat, jdot = frame_planar_3d(q1, q2, self._plane_normal(q1))
        return FrameSample(float(t), q, q1, jmat, jdot)

    def _plane_normal(self, qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """Return the plane normal of the planar 3D frame: +z, or +y for a line along z."""
        if self.kind is ReferenceKind.LINE:
            speed = float(np.linalg.norm(qdot))
            if speed > 0.0 and np.linalg.norm(np.cross(Z_AXIS, qdot / speed)) < 1e-6:
                return np.array([0.0, 1.0, 0.0])
        return Z_AXIS
