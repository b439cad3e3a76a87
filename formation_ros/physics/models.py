# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The robots' bodies in the physics world: what each is made of and how a command drives it.

The model follows ``body.kind`` and ``dim`` (:func:`make_model`):

* :class:`DiffDrive` (unicycles, 2D): a differential-drive base on a free joint: a chassis
  whose centre of mass sits between the axle and the caster, two wheels on hinge joints rolling
  on the floor with friction, a frictionless ball caster at the rear; each wheel turned by a
  velocity servo with a torque limit. A command (v, w) is clipped to ``body.max_linear`` and
  ``body.max_angular`` and turned into wheel speeds, as ``diff_drive_controller`` does.
* :class:`Holonomic` (points, 2D): a planar base on slide joints x, y and a hinge about z,
  pushed by force-limited velocity servos along x and y (the force at most what the floor's
  friction lets wheels push) and held at its heading by a torque-limited servo.
* :class:`Flyer` (points, 3D): a rigid body on slide joints x, y, z and a hinge about z; a
  thrust holds its weight, force-limited velocity servos move it along x, y and z.

Each model (``diff_drive``, ``points``; their MJCF parts in ``parts``) adds its body
(``add_body``) and actuators (``add_actuators``) to an MJCF tree and turns commands into
actuator set points (``controls``). Lengths in m, masses in kg, angles in rad, speeds in m/s
and rad/s, forces in N, torques in N m.
"""

import math
from typing import Optional, Union

from formation_ros.core.model.bodies import BodyKind, BodySettings
from formation_ros.core.settings.declarations import CommandFrame
from formation_ros.core.settings.params import WorldSettings
from formation_ros.physics.diff_drive import DiffDrive, WHEEL_HALF_WIDTH
from formation_ros.physics.parts import GRAVITY
from formation_ros.physics.points import Flyer, Holonomic

DEFAULT_FOOTPRINT = 0.1
"""The footprint radius of a point body without ``body.radius``, m (at most
:data:`START_GAP_SHARE` of the closest start distance)."""
START_GAP_SHARE = 0.4
"""Points without ``body.radius`` get footprints this share of the closest two starts apart, so
that none overlap at the start."""
Model = Union[DiffDrive, Holonomic, Flyer]


def footprint_radius(body: BodySettings, closest_start: float = math.inf) -> float:
    """
    Return the footprint radius, m: ``body.radius``; without one a point's default.

    closest_start: the distance of the two closest starts, m (the default is at most
    :data:`START_GAP_SHARE` of it).
    """
    if body.radius > 0.0:
        return body.radius
    return min(DEFAULT_FOOTPRINT, START_GAP_SHARE * closest_start)


def make_model(body: BodySettings, dim: int, world: WorldSettings,
               command_frame: Optional[CommandFrame] = None,
               closest_start: float = math.inf) -> Model:
    """
    Return the model of ``body.kind`` and ``dim`` with the world's settings.

    A unicycle's footprint holds its wheels; closest_start: see :func:`footprint_radius`.
    """
    body_frame = command_frame is CommandFrame.BODY
    if body.kind is BodyKind.UNICYCLE:
        return DiffDrive(
            wheel_radius=world.wheel_radius, track=world.wheel_track,
            footprint=max(body.radius, 0.5 * world.wheel_track + WHEEL_HALF_WIDTH),
            mass=world.mass, wheel_torque=world.wheel_torque, friction=world.floor_friction,
            max_linear=math.inf if body.max_linear is None else body.max_linear,
            max_angular=math.inf if body.max_angular is None else body.max_angular)
    if dim == 2:
        traction = world.floor_friction * world.mass * GRAVITY
        return Holonomic(footprint=footprint_radius(body, closest_start), mass=world.mass,
                         force=min(world.force_limit, traction), torque=world.torque_limit,
                         body_frame=body_frame)
    return Flyer(footprint=footprint_radius(body, closest_start), mass=world.mass,
                 force=world.force_limit, torque=world.torque_limit, body_frame=body_frame)
