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

Each model adds its body (:meth:`add_body`) and actuators (:meth:`add_actuators`) to an MJCF
tree and turns commands into actuator set points (:meth:`controls`). Lengths in m, masses in
kg, angles in rad, speeds in m/s and rad/s, forces in N, torques in N m.
"""

from dataclasses import dataclass
import enum
import math
from typing import Optional, Sequence, Union
from xml.etree import ElementTree

from formation_ros.core.bodies import BodySettings
from formation_ros.core.declarations import BodyKind, CommandFrame
from formation_ros.core.params import WorldSettings
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]
GRAVITY = 9.81
"""Standard gravity, m/s^2 (the scene's ``option gravity``)."""
SERVO_TIME_CONSTANT = 0.01
"""Every velocity servo's gain is the inertia it drives over this, s (:func:`servo_gain`): stiff
enough that a servo meets its force or torque limit on any sizeable speed change."""
DEFAULT_FOOTPRINT = 0.1
"""The footprint radius of a point body without ``body.radius``, m."""
WHEEL_HALF_WIDTH = 0.009
WHEEL_MASS_FRACTION = 0.05
"""Each wheel's share of the base's mass."""
WHEEL_ARMATURE = 5e-4
"""The inertia of a wheel's geared motor as the wheel feels it (the rotor's times the gear
ratio squared), kg m^2: about half a 1 kg base's mass at a 0.033 m wheel's rim. A bare wheel's
own inertia is so small that a servo would spin it up within a step and make it slip."""
CASTER_FRACTION = 0.5
"""The caster ball's radius as a fraction of the wheel radius."""
CHASSIS_HALF_HEIGHT = 0.04
"""Half the height of a differential-drive chassis, m; its underside clears the floor by half
a wheel radius."""
PLANAR_HALF_HEIGHT = 0.05
"""Half the height of a holonomic base, m."""
CARRIAGE_MASS_FRACTION = 0.99
"""A point body's mass is split between the carriage that slides (this share) and the body that
turns on it, which has the turning inertia of the whole (MuJoCo wants mass on every moving
body); the slides move the whole mass."""
CARRIAGE_INERTIA = 1e-6
"""The carriage's own moments, kg m^2: it never turns."""
FOOTPRINT_GROUP = 2
"""Collision bits of the footprints, which touch each other only."""
FLOOR_GROUP = 1
"""Collision bits of what rolls on the floor (wheels, caster)."""


class ModelKind(enum.Enum):
    """The body a robot has in the physics world."""

    DIFF_DRIVE = 'diff_drive'
    HOLONOMIC = 'holonomic'
    FLYER = 'flyer'


def servo_gain(inertia: float, time_constant: float = SERVO_TIME_CONSTANT) -> float:
    """Return a velocity servo's gain: inertia (kg or kg m^2) over time constant (s)."""
    return inertia / time_constant


def number(value: float) -> str:
    """Return a float as MJCF text that reads back as the same float."""
    return repr(float(value))


def numbers(values: Sequence[float]) -> str:
    """Return floats as an MJCF list: '0 0.1 0'."""
    return ' '.join(number(float(v)) for v in values)


def _add(parent: ElementTree.Element, tag: str, **attributes: str) -> ElementTree.Element:
    return ElementTree.SubElement(parent, tag, attributes)


def _footprint_geom(body: ElementTree.Element, name: str, shape: str, size: Sequence[float],
                    pos: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
    """Add the geom other robots collide with: massless, in :data:`FOOTPRINT_GROUP` alone."""
    _add(body, 'geom', name=name, type=shape, size=numbers(size), pos=numbers(pos),
         mass='0', contype=str(FOOTPRINT_GROUP), conaffinity=str(FOOTPRINT_GROUP),
         rgba='0.2 0.45 0.8 1')


def _inertial(body: ElementTree.Element, mass: float, inertia: Sequence[float],
              pos: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
    _add(body, 'inertial', pos=numbers(pos), mass=number(mass), diaginertia=numbers(inertia))


def _velocity_servo(actuators: ElementTree.Element, name: str, joint: str, gain: float,
                    limit: float) -> None:
    _add(actuators, 'velocity', name=name, joint=joint, kv=number(gain),
         forcerange=numbers((-limit, limit)))


@dataclass(frozen=True)
class DiffDrive:
    """
    A differential-drive base (TurtleBot3 Burger defaults: ``world.*``).

    wheel_radius, track (between the wheels), footprint (the chassis' radius): m; mass: kg;
    wheel_torque: each wheel servo's limit, N m; friction: wheels on the floor; max_linear
    (m/s), max_angular (rad/s): the controller's limits (inf: none). The base's frame is at the
    axle centre, at wheel height, x forward; the caster touches the floor at the rear of the
    footprint, and the centre of mass sits at axle height halfway from the axle to the caster.
    A base pitches over its wheels when it brakes harder than g d / h (d: how far the centre
    of mass is behind the axle, h: its height): 1.4 g with the Burger's figures, beyond what
    the floor's friction lets the wheels do. With the centre of mass over the axle (d = 0) a
    base pitches over at the first hard stop.
    """

    wheel_radius: float
    track: float
    footprint: float
    mass: float
    wheel_torque: float
    friction: float
    max_linear: float = math.inf
    max_angular: float = math.inf

    kind = ModelKind.DIFF_DRIVE
    command_width = 2
    actuators_per_robot = 2
    has_floor = True
    needs_yaw = False

    @property
    def caster_radius(self) -> float:
        """Radius of the caster ball, m."""
        return CASTER_FRACTION * self.wheel_radius

    @property
    def caster_position(self) -> Float:
        """The caster's centre in the base frame, m: at the rear edge, touching the floor."""
        return np.array([-(self.footprint - self.caster_radius), 0.0,
                         self.caster_radius - self.wheel_radius])

    @property
    def centre_of_mass(self) -> Float:
        """The chassis' centre of mass in the base frame, m: halfway to the caster."""
        return np.array([0.5 * self.caster_position[0], 0.0, 0.0])

    @property
    def wheel_mass(self) -> float:
        """Mass of one wheel, kg."""
        return WHEEL_MASS_FRACTION * self.mass

    @property
    def chassis_mass(self) -> float:
        """Mass of the chassis, kg: the rest."""
        return self.mass - 2.0 * self.wheel_mass

    @property
    def height(self) -> float:
        """Height of the base frame above the floor, m: the wheel radius."""
        return self.wheel_radius

    def wheel_speeds(self, command: Float) -> Float:
        """
        Return the wheel speeds (left, right) (N, 2), rad/s, of commands (v, w) (N, 2).

        v and w are first clipped to max_linear and max_angular;
        ``left = (v - w track / 2) / r``, ``right = (v + w track / 2) / r``.
        """
        v = np.clip(command[:, 0], -self.max_linear, self.max_linear)
        w = np.clip(command[:, 1], -self.max_angular, self.max_angular)
        half_turn = 0.5 * self.track * w
        return np.stack([v - half_turn, v + half_turn], axis=1) / self.wheel_radius

    def body_rates(self, wheel_speeds: Float) -> Float:
        """Return (v, w) (N, 2) of wheel speeds (left, right) (N, 2) rolling without slip."""
        left, right = wheel_speeds[:, 0], wheel_speeds[:, 1]
        return np.stack([0.5 * self.wheel_radius * (left + right),
                         self.wheel_radius * (right - left) / self.track], axis=1)

    def controls(self, command: Float, yaw: Float) -> Float:
        """Return the wheel servos' set points (N, 2), rad/s."""
        return self.wheel_speeds(command)

    def add_body(self, worldbody: ElementTree.Element, name: str, position: Float,
                 heading: float) -> str:
        """Add robot ``name`` at ``position`` (2,) with ``heading``; return its pose body."""
        r, half_width = self.wheel_radius, WHEEL_HALF_WIDTH
        base = _add(worldbody, 'body', name=name,
                    pos=numbers((position[0], position[1], self.height)),
                    euler=numbers((0.0, 0.0, heading)))
        _add(base, 'freejoint', name=f'{name}_root')
        chassis_z = CHASSIS_HALF_HEIGHT - 0.5 * r
        _inertial(base, self.chassis_mass, _cylinder_inertia(
            self.chassis_mass, self.footprint, CHASSIS_HALF_HEIGHT), self.centre_of_mass)
        _footprint_geom(base, f'{name}_footprint', 'cylinder',
                        (self.footprint, CHASSIS_HALF_HEIGHT), (0.0, 0.0, chassis_z))
        _add(base, 'geom', name=f'{name}_caster', type='sphere',
             size=number(self.caster_radius), pos=numbers(self.caster_position), mass='0',
             condim='1', priority='1', contype=str(FLOOR_GROUP), conaffinity='0',
             rgba='0.3 0.3 0.3 1')
        _heading_mark(base, name, self.footprint, chassis_z + CHASSIS_HALF_HEIGHT)
        for side, sign in (('left', 1.0), ('right', -1.0)):
            wheel = _add(base, 'body', name=f'{name}_{side}_wheel_link',
                         pos=numbers((0.0, sign * 0.5 * self.track, 0.0)))
            _add(wheel, 'joint', name=f'{name}_{side}_wheel', type='hinge', axis='0 1 0',
                 armature=number(WHEEL_ARMATURE))
            m = self.wheel_mass
            _inertial(wheel, m, (0.25 * m * r * r, 0.5 * m * r * r, 0.25 * m * r * r))
            _add(wheel, 'geom', name=f'{name}_{side}_tyre', type='sphere', size=number(r),
                 mass='0', friction=numbers((self.friction, 0.005, 0.0001)),
                 contype=str(FLOOR_GROUP), conaffinity='0', group='3')
            _add(wheel, 'geom', name=f'{name}_{side}_rim', type='cylinder',
                 size=numbers((r, half_width)), euler=numbers((0.5 * math.pi, 0.0, 0.0)),
                 mass='0', contype='0', conaffinity='0', rgba='0.1 0.1 0.1 1')
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """Add the two wheel servos of robot ``name``: left, right."""
        r = self.wheel_radius
        gain = servo_gain(0.5 * self.mass * r * r + WHEEL_ARMATURE)
        for side in ('left', 'right'):
            _velocity_servo(actuators, f'{name}_{side}_motor', f'{name}_{side}_wheel', gain,
                            self.wheel_torque)


@dataclass(frozen=True)
class Holonomic:
    """
    A holonomic planar base (mecanum or omni wheels): slides x, y and turns about z.

    footprint: radius, m; mass: kg; force: each axis servo's force limit, N (at most
    friction x weight); torque: the heading servo's limit, N m; body_frame: commands are in
    the base's frame (``command.frame: body``), else in the world's.
    """

    footprint: float
    mass: float
    force: float
    torque: float
    body_frame: bool = False

    kind = ModelKind.HOLONOMIC
    command_width = 2
    actuators_per_robot = 3
    has_floor = False

    @property
    def needs_yaw(self) -> bool:
        """Tell whether :meth:`controls` turns commands by the bodies' headings."""
        return self.body_frame

    @property
    def height(self) -> float:
        """Height of the base's centre above the floor, m."""
        return PLANAR_HALF_HEIGHT

    def controls(self, command: Float, yaw: Float) -> Float:
        """Return the servos' set points (N, 3): world x and y velocities (m/s), yaw rate 0."""
        world = _rotated(command, yaw) if self.body_frame else command
        return np.concatenate([world, np.zeros((len(command), 1))], axis=1)

    def add_body(self, worldbody: ElementTree.Element, name: str, position: Float,
                 heading: float) -> str:
        """Add robot ``name`` at ``position`` (2,) with ``heading``; return its pose body."""
        carriage = _carriage(worldbody, name, (position[0], position[1], self.height),
                             self.mass, 2)
        base = _add(carriage, 'body', name=name, euler=numbers((0.0, 0.0, heading)))
        _add(base, 'joint', name=f'{name}_yaw', type='hinge', axis='0 0 1')
        _inertial(base, (1.0 - CARRIAGE_MASS_FRACTION) * self.mass,
                  _cylinder_inertia(self.mass, self.footprint, PLANAR_HALF_HEIGHT))
        _footprint_geom(base, f'{name}_footprint', 'cylinder',
                        (self.footprint, PLANAR_HALF_HEIGHT))
        _heading_mark(base, name, self.footprint, PLANAR_HALF_HEIGHT)
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """Add robot ``name``'s servos: x, y (force-limited), yaw (torque-limited)."""
        for axis in ('x', 'y'):
            _velocity_servo(actuators, f'{name}_{axis}_motor', f'{name}_{axis}',
                            servo_gain(self.mass), self.force)
        yaw_inertia = 0.5 * self.mass * self.footprint ** 2
        _velocity_servo(actuators, f'{name}_yaw_motor', f'{name}_yaw', servo_gain(yaw_inertia),
                        self.torque)


@dataclass(frozen=True)
class Flyer:
    """
    A rigid flying body (the paper's 3D robots): slides x, y, z and turns about z.

    footprint: radius of its sphere, m; mass: kg; force: each axis servo's force limit, N, on
    top of the thrust that holds its weight (never below zero thrust); torque: the heading
    servo's limit, N m; body_frame: commands are in the body's frame (turned by its heading),
    else in the world's.
    """

    footprint: float
    mass: float
    force: float
    torque: float
    body_frame: bool = False

    kind = ModelKind.FLYER
    command_width = 3
    actuators_per_robot = 4
    has_floor = False
    height = 0.0

    @property
    def needs_yaw(self) -> bool:
        """Tell whether :meth:`controls` turns commands by the bodies' headings."""
        return self.body_frame

    @property
    def weight(self) -> float:
        """The thrust that holds the body up, N."""
        return self.mass * GRAVITY

    def controls(self, command: Float, yaw: Float) -> Float:
        """Return the servos' set points (N, 4): world x, y, z velocities (m/s), yaw rate 0."""
        world = command
        if self.body_frame:
            world = np.concatenate([_rotated(command[:, :2], yaw), command[:, 2:]], axis=1)
        return np.concatenate([world, np.zeros((len(command), 1))], axis=1)

    def add_body(self, worldbody: ElementTree.Element, name: str, position: Float,
                 heading: float) -> str:
        """Add robot ``name`` at ``position`` (3,) with ``heading``; return its pose body."""
        carriage = _carriage(worldbody, name, position, self.mass, 3)
        base = _add(carriage, 'body', name=name, euler=numbers((0.0, 0.0, heading)))
        _add(base, 'joint', name=f'{name}_yaw', type='hinge', axis='0 0 1')
        inertia = 0.4 * self.mass * self.footprint ** 2
        _inertial(base, (1.0 - CARRIAGE_MASS_FRACTION) * self.mass, (inertia, inertia, inertia))
        _footprint_geom(base, f'{name}_footprint', 'sphere', (self.footprint,))
        _heading_mark(base, name, self.footprint, 0.0)
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """
        Add robot ``name``'s servos: x, y, then z with the thrust, yaw.

        The z servo is a general actuator: force = weight + gain (set point - vz), within
        [max(0, weight - force), weight + force].
        """
        gain = servo_gain(self.mass)
        for axis in ('x', 'y'):
            _velocity_servo(actuators, f'{name}_{axis}_motor', f'{name}_{axis}', gain,
                            self.force)
        _add(actuators, 'general', name=f'{name}_z_motor', joint=f'{name}_z',
             gaintype='fixed', gainprm=number(gain), biastype='affine',
             biasprm=numbers((self.weight, 0.0, -gain)),
             forcerange=numbers((max(0.0, self.weight - self.force), self.weight + self.force)))
        inertia = 0.4 * self.mass * self.footprint ** 2
        _velocity_servo(actuators, f'{name}_yaw_motor', f'{name}_yaw', servo_gain(inertia),
                        self.torque)


Model = Union[DiffDrive, Holonomic, Flyer]


def _cylinder_inertia(mass: float, radius: float, half_height: float) -> Sequence[float]:
    """Principal moments (x, y, z) of a solid cylinder about its centre, kg m^2."""
    across = mass * (3.0 * radius * radius + 4.0 * half_height * half_height) / 12.0
    return (across, across, 0.5 * mass * radius * radius)


AXES = (('x', '1 0 0'), ('y', '0 1 0'), ('z', '0 0 1'))
"""The world axes a carriage slides along: (name, direction)."""


def _carriage(worldbody: ElementTree.Element, name: str, position: Sequence[float],
              mass: float, dim: int) -> ElementTree.Element:
    """Add the body of robot ``name`` that slides along the first ``dim`` world axes."""
    carriage = _add(worldbody, 'body', name=f'{name}_carriage', pos=numbers(position))
    for axis, direction in AXES[:dim]:
        _add(carriage, 'joint', name=f'{name}_{axis}', type='slide', axis=direction)
    _inertial(carriage, CARRIAGE_MASS_FRACTION * mass, (CARRIAGE_INERTIA,) * 3)
    return carriage


def _heading_mark(body: ElementTree.Element, name: str, footprint: float,
                  half_height: float) -> None:
    """Add a visual marker on the body's +x side (its heading), no mass, no contact."""
    _add(body, 'geom', name=f'{name}_front', type='box',
         size=numbers((0.25 * footprint, 0.1 * footprint, 0.005)),
         pos=numbers((0.7 * footprint, 0.0, half_height)), mass='0', contype='0',
         conaffinity='0', rgba='0.95 0.75 0.1 1')


def _rotated(vectors: Float, yaw: Float) -> Float:
    """Return planar vectors (N, 2) turned by yaw (N,) about +z: R(yaw) v."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * vectors[:, 0] - s * vectors[:, 1],
                     s * vectors[:, 0] + c * vectors[:, 1]], axis=1)


def footprint_radius(body: BodySettings, minimum: float = 0.0) -> float:
    """Return the footprint radius, m: ``body.radius``, or a default, at least ``minimum``."""
    return max(body.radius if body.radius > 0.0 else DEFAULT_FOOTPRINT, minimum)


def make_model(body: BodySettings, dim: int, world: WorldSettings,
               command_frame: Optional[CommandFrame] = None) -> Model:
    """Return the model of ``body.kind`` and ``dim`` with the world's settings."""
    body_frame = command_frame is CommandFrame.BODY
    if body.kind is BodyKind.UNICYCLE:
        return DiffDrive(
            wheel_radius=world.wheel_radius, track=world.wheel_track,
            footprint=footprint_radius(body, 0.5 * world.wheel_track + WHEEL_HALF_WIDTH),
            mass=world.mass, wheel_torque=world.wheel_torque, friction=world.floor_friction,
            max_linear=math.inf if body.max_linear is None else body.max_linear,
            max_angular=math.inf if body.max_angular is None else body.max_angular)
    if dim == 2:
        traction = world.floor_friction * world.mass * GRAVITY
        return Holonomic(footprint=footprint_radius(body), mass=world.mass,
                         force=min(world.force_limit, traction), torque=world.torque_limit,
                         body_frame=body_frame)
    return Flyer(footprint=footprint_radius(body), mass=world.mass, force=world.force_limit,
                 torque=world.torque_limit, body_frame=body_frame)
