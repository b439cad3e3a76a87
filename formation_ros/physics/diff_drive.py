# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A differential-drive base in the physics world (``body.kind: unicycle``; TurtleBot3 Burger).

:class:`DiffDrive` adds the base to an MJCF tree and turns commands (v, w) into its wheels'
set points as ``diff_drive_controller`` does; :meth:`DiffDrive.body_rates` is the inverse, which
wheel odometry integrates.
"""

from dataclasses import dataclass
import math
from xml.etree import ElementTree

from formation_ros.physics.parts import (add, cylinder_inertia, DRAWN_GROUP, FLOOR_GROUP,
                                         footprint_geom, heading_mark, inertial, ModelKind,
                                         number, numbers, servo_gain, velocity_servo)
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]
WHEEL_HALF_WIDTH = 0.009
"""Half a wheel's width, m (drawn only: the tyre touching the floor is a ball)."""
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
        """Return the caster's centre in the base frame, m: at the rear edge, on the floor."""
        return np.array([-(self.footprint - self.caster_radius), 0.0,
                         self.caster_radius - self.wheel_radius])

    @property
    def centre_of_mass(self) -> Float:
        """Return the chassis' centre of mass in the base frame, m: halfway to the caster."""
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
        base = add(worldbody, 'body', name=name,
                   pos=numbers((position[0], position[1], self.height)),
                   euler=numbers((0.0, 0.0, heading)))
        add(base, 'freejoint', name=f'{name}_root')
        chassis_z = CHASSIS_HALF_HEIGHT - 0.5 * r
        inertial(base, self.chassis_mass, cylinder_inertia(
            self.chassis_mass, self.footprint, CHASSIS_HALF_HEIGHT), self.centre_of_mass)
        footprint_geom(base, f'{name}_footprint', 'cylinder',
                       (self.footprint, CHASSIS_HALF_HEIGHT), (0.0, 0.0, chassis_z))
        add(base, 'geom', name=f'{name}_caster', type='sphere',
            size=number(self.caster_radius), pos=numbers(self.caster_position), mass='0',
            condim='1', priority='1', contype=str(FLOOR_GROUP), conaffinity='0',
            group=str(DRAWN_GROUP), rgba='0.3 0.3 0.3 1')
        heading_mark(base, name, self.footprint, chassis_z + CHASSIS_HALF_HEIGHT)
        for side, sign in (('left', 1.0), ('right', -1.0)):
            wheel = add(base, 'body', name=f'{name}_{side}_wheel_link',
                        pos=numbers((0.0, sign * 0.5 * self.track, 0.0)))
            add(wheel, 'joint', name=f'{name}_{side}_wheel', type='hinge', axis='0 1 0',
                armature=number(WHEEL_ARMATURE))
            m = self.wheel_mass
            inertial(wheel, m, (0.25 * m * r * r, 0.5 * m * r * r, 0.25 * m * r * r))
            add(wheel, 'geom', name=f'{name}_{side}_tyre', type='sphere', size=number(r),
                mass='0', friction=numbers((self.friction, 0.005, 0.0001)),
                contype=str(FLOOR_GROUP), conaffinity='0', group='3')
            add(wheel, 'geom', name=f'{name}_{side}_rim', type='cylinder',
                size=numbers((r, half_width)), euler=numbers((0.5 * math.pi, 0.0, 0.0)),
                mass='0', contype='0', conaffinity='0', group=str(DRAWN_GROUP),
                rgba='0.1 0.1 0.1 1')
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """Add the two wheel servos of robot ``name``: left, right."""
        r = self.wheel_radius
        gain = servo_gain(0.5 * self.mass * r * r + WHEEL_ARMATURE)
        for side in ('left', 'right'):
            velocity_servo(actuators, f'{name}_{side}_motor', f'{name}_{side}_wheel', gain,
                           self.wheel_torque)
