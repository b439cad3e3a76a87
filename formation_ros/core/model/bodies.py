# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The kinds of robot body the plant model integrates: points (eq. 1) and unicycles.

:class:`~formation_ros.core.model.plant.PlantModel` keeps every robot's body position q (N, dim) in
m and heading (N,) in rad (zero and unused for points) and delegates to one body object what
depends on the kind:

* the **control point** the law acts on: q itself for a point, the hand point
  ``p = q + l (cos th, sin th)`` of a unicycle (core/maths/unicycle.py, U2);
* the **command** a robot sends: the world velocity u (N, dim) of a point, (v, w) (N, 2) of a
  unicycle; :meth:`world_velocity` turns a command into the velocity of the control point, which
  the model admits against the law's bound, and :meth:`body_command` turns such a velocity back
  (U3, U4);
* the **step** with the command held over dt: ``q += dt u`` for a point, the exact arc of
  :func:`formation_ros.core.maths.unicycle.zoh_step` for a unicycle; and, for bodies whose velocity
  lags the command or is limited in acceleration (``plant.actuator_lag``,
  ``plant.max_acceleration``: :mod:`formation_ros.core.model.dynamics`), the step that carries the
  body's velocity along (:meth:`lagged_step`: exact for points, substeps of exact arcs for
  unicycles);
* the **actuator caps** a command is clipped to (``plant.max_speed`` per command component
  for points, in the world frame or, with ``command.frame: body``, the body's;
  ``body.max_linear`` on |v| and ``body.max_angular`` on |w| for unicycles);
* the **contact distance** of two bodies (``2 body.radius``) and the **sensing margin**: a
  range sensor sees bodies, so a unicycle's sensor must reach ``R_i + 2 l`` to see every hand
  point within R_i of its own.
"""

from dataclasses import dataclass
from typing import Optional, Tuple, Union

from formation_ros.core.maths.choice import Choice
from formation_ros.core.maths.frames import from_body_frame, to_body_frame
from formation_ros.core.maths.unicycle import (hand_points, hand_velocity,
                                               quaternions_from_headings, unicycle_commands,
                                               zoh_step)
from formation_ros.core.model.dynamics import Imperfections, point_step, unicycle_step
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]
HEADING_SEED_OFFSET = 1
"""Random headings come from the generator seeded with (start.seed, this), so the random
positions of a seed stay those of a point team."""


class BodyKind(Choice):
    """The robots' bodies: ``body.kind``."""

    POINT = 'point'
    UNICYCLE = 'unicycle'


@dataclass(frozen=True)
class BodySettings:
    """
    The robots' bodies (``body.*``).

    kind: :class:`BodyKind`; hand_distance: l in m (unicycles); radius: body radius in m (0:
    none); max_linear (m/s), max_angular (rad/s): actuator limits of a unicycle, None if not
    given.
    """

    kind: BodyKind = BodyKind.POINT
    hand_distance: float = 0.0
    radius: float = 0.0
    max_linear: Optional[float] = None
    max_angular: Optional[float] = None

    @property
    def is_unicycle(self) -> bool:
        """Tell whether the robots are unicycles."""
        return self.kind is BodyKind.UNICYCLE

    @property
    def footprint(self) -> float:
        """
        Return the radius about the control point that holds the whole body, m.

        A point body: ``radius``. A unicycle's control point is its hand point, l ahead of the
        body's centre, so the disc of radius l + ``radius`` about it holds the body's disc
        whatever its heading: the law keeps that disc off obstacles (docs/equations.md,
        "Obstacles").
        """
        return self.radius + (self.hand_distance if self.is_unicycle else 0.0)


POINT_BODY = BodySettings()


class PointBodies:
    """
    Single integrators q' = u (eq. 1); the control point is the body position.

    With ``body_frame`` (``command.frame: body``: holonomic bases that take body-frame
    velocities) a command is the velocity in the body's frame, which is turned by the body's
    heading about +z (constant: nothing turns a point): u = R(th) command. Otherwise the
    command is u itself, in the world frame.
    """

    has_heading = False
    sensing_margin = 0.0

    def __init__(self, max_speed: float = 0.0, radius: float = 0.0, body_frame: bool = False):
        """Cap every command component at ``max_speed`` m/s (0: no cap); radius in m."""
        self.max_speed = float(max_speed)
        self.contact_distance = 2.0 * float(radius)
        self.body_frame = bool(body_frame)

    def command_width(self, dim: int) -> int:
        """Return the number of values in one robot's command: dim."""
        return dim

    def control_points(self, q: Float, heading: Float) -> Float:
        """Return the points the law acts on: q itself (N, dim), not copied."""
        return q

    def world_velocity(self, command: Float, heading: Float) -> Float:
        """Return the velocity of the control point: the command (not copied), or R(th) it."""
        if not self.body_frame:
            return command
        return from_body_frame(command, quaternions_from_headings(heading))

    def body_command(self, u: Float, heading: Float,
                     orientations: Optional[Float] = None) -> Float:
        """
        Return the command that gives the control point velocity u: u, or R^T u.

        R: the body's rotation, ``orientations`` (N, 4) quaternions (x, y, z, w) where given (a
        robot's measured pose), else R(th) about +z of the headings (N,) rad.
        """
        if not self.body_frame:
            return u
        return to_body_frame(u, quaternions_from_headings(heading) if orientations is None
                             else orientations)

    def step(self, q: Float, heading: Float, command: Float, dt: float) -> Tuple[Float, Float]:
        """Zero-order hold over dt: (q + dt u, heading), u the command's world velocity."""
        return q + dt * self.world_velocity(command, heading), heading

    def lagged_step(self, q: Float, heading: Float, velocity: Float, command: Float, dt: float,
                    imperfections: Imperfections) -> Tuple[Float, Float, Float]:
        """
        Exact step with the world velocity (N, dim) lagging the command's (D2): (q, heading, v).

        The lag and the acceleration limit act per world component, on the velocity the
        command stands for (:meth:`world_velocity`).
        """
        moved, v = point_step(q, velocity, self.world_velocity(command, heading), dt,
                              imperfections.actuator_lag, imperfections.max_acceleration)
        return moved, heading, v

    def cap(self, command: Float, rows: NDArray[np.bool_]) -> Tuple[Float, NDArray[np.bool_]]:
        """
        Return ``command`` (N, dim) with its ``rows`` clipped to max_speed, and which were.

        A new array where any row is clipped; ``command`` itself where none is.
        """
        if self.max_speed <= 0.0:
            return command, np.zeros(len(command), dtype=bool)
        return _clipped(command, rows, self.max_speed)


class UnicycleBodies:
    """
    Differential-drive robots (``maths.unicycle``): commands (v, w), control point the hand point.

    hand_distance: l in m; radius: body radius in m; max_linear (m/s), max_angular (rad/s):
    caps on |v| and |w| (None: none beyond the law's bound).
    """

    has_heading = True

    def __init__(self, hand_distance: float, radius: float = 0.0,
                 max_linear: Optional[float] = None, max_angular: Optional[float] = None):
        """Keep the constants (checked by core/settings/params.py)."""
        if not hand_distance > 0.0:
            raise ValueError(f'hand_distance must be > 0, got {hand_distance!r}')
        self.hand_distance = float(hand_distance)
        self.contact_distance = 2.0 * float(radius)
        self.sensing_margin = 2.0 * self.hand_distance
        self.limits = np.array([np.inf if max_linear is None else float(max_linear),
                                np.inf if max_angular is None else float(max_angular)])

    def command_width(self, dim: int) -> int:
        """Return the number of values in one robot's command: 2, (v, w)."""
        return 2

    def control_points(self, q: Float, heading: Float) -> Float:
        """Return the hand points (N, 2), m."""
        return hand_points(q, heading, self.hand_distance)

    def world_velocity(self, command: Float, heading: Float) -> Float:
        """Return the hand points' velocities R(th) (v, l w) (N, 2), m/s."""
        return hand_velocity(command, heading, self.hand_distance)

    def body_command(self, u: Float, heading: Float,
                     orientations: Optional[Float] = None) -> Float:
        """Return (v, w) (N, 2) that move the hand points with velocities u (headings (N,))."""
        return unicycle_commands(u, heading, self.hand_distance)

    def step(self, q: Float, heading: Float, command: Float, dt: float) -> Tuple[Float, Float]:
        """Exact zero-order-hold step of the unicycles over dt: (q, heading) after it."""
        return zoh_step(q, heading, command, dt)

    def lagged_step(self, q: Float, heading: Float, velocity: Float, command: Float, dt: float,
                    imperfections: Imperfections) -> Tuple[Float, Float, Float]:
        """Step with (v, w) (N, 2) lagging the command (D3): (q, heading, (v, w)) after it."""
        return unicycle_step(q, heading, velocity, command, dt, imperfections.actuator_lag,
                             imperfections.max_acceleration)

    def cap(self, command: Float, rows: NDArray[np.bool_]) -> Tuple[Float, NDArray[np.bool_]]:
        """
        Return ``command`` (N, 2) with |v| and |w| of its ``rows`` clipped to the caps, and which.

        A new array where any row is clipped; ``command`` itself where none is.
        """
        return _clipped(command, rows, self.limits)


def _clipped(command: Float, rows: NDArray[np.bool_],
             limits: Union[float, Float]) -> Tuple[Float, NDArray[np.bool_]]:
    """Return ``command`` with the ``rows`` beyond +-``limits`` clipped, and which were."""
    capped: NDArray[np.bool_] = rows & np.any(np.abs(command) > limits, axis=1)
    if np.any(capped):
        command = np.array(command)
        command[capped] = np.clip(command[capped], -limits, limits)
    return command, capped


Bodies = Union[PointBodies, UnicycleBodies]


def make_bodies(settings: BodySettings, max_speed: float = 0.0,
                body_frame: bool = False) -> Bodies:
    """
    Build the body object of ``settings``.

    max_speed: plant.max_speed; body_frame: points take body-frame commands (``command.frame:
    body``); both for points only.
    """
    if settings.is_unicycle:
        return UnicycleBodies(settings.hand_distance, settings.radius, settings.max_linear,
                              settings.max_angular)
    return PointBodies(max_speed, settings.radius, body_frame)


def random_headings(n: int, seed: int) -> Float:
    """Return n headings uniform in [-pi, pi), rad, from the generator of (seed, 1): (n,)."""
    rng = np.random.default_rng([seed, HEADING_SEED_OFFSET])
    return np.asarray(rng.uniform(-np.pi, np.pi, n), dtype=float)
