# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Point bodies in the physics world: a holonomic planar base (2D) and a flying body (3D).

Both slide along world axes on a carriage and turn about z on it; their commands are world
velocities or, with ``command.frame: body``, velocities in the body's frame turned by its
heading.
"""

from dataclasses import dataclass
from xml.etree import ElementTree

from formation_ros.physics.parts import (add, carriage, CARRIAGE_MASS_FRACTION,
                                         cylinder_inertia, footprint_geom, GRAVITY,
                                         heading_mark, inertial, ModelKind, number, numbers,
                                         rotated, servo_gain, velocity_servo)
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]
PLANAR_HALF_HEIGHT = 0.05
"""Half the height of a holonomic base, m."""


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
        world = rotated(command, yaw) if self.body_frame else command
        return np.concatenate([world, np.zeros((len(command), 1))], axis=1)

    def add_body(self, worldbody: ElementTree.Element, name: str, position: Float,
                 heading: float) -> str:
        """Add robot ``name`` at ``position`` (2,) with ``heading``; return its pose body."""
        slider = carriage(worldbody, name, (position[0], position[1], self.height),
                          self.mass, 2)
        base = add(slider, 'body', name=name, euler=numbers((0.0, 0.0, heading)))
        add(base, 'joint', name=f'{name}_yaw', type='hinge', axis='0 0 1')
        inertial(base, (1.0 - CARRIAGE_MASS_FRACTION) * self.mass,
                 cylinder_inertia(self.mass, self.footprint, PLANAR_HALF_HEIGHT))
        footprint_geom(base, f'{name}_footprint', 'cylinder',
                       (self.footprint, PLANAR_HALF_HEIGHT))
        heading_mark(base, name, self.footprint, PLANAR_HALF_HEIGHT)
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """Add robot ``name``'s servos: x, y (force-limited), yaw (torque-limited)."""
        for axis in ('x', 'y'):
            velocity_servo(actuators, f'{name}_{axis}_motor', f'{name}_{axis}',
                           servo_gain(self.mass), self.force)
        yaw_inertia = 0.5 * self.mass * self.footprint ** 2
        velocity_servo(actuators, f'{name}_yaw_motor', f'{name}_yaw', servo_gain(yaw_inertia),
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
        """Return the thrust that holds the body up, N."""
        return self.mass * GRAVITY

    def controls(self, command: Float, yaw: Float) -> Float:
        """Return the servos' set points (N, 4): world x, y, z velocities (m/s), yaw rate 0."""
        world = command
        if self.body_frame:
            world = np.concatenate([rotated(command[:, :2], yaw), command[:, 2:]], axis=1)
        return np.concatenate([world, np.zeros((len(command), 1))], axis=1)

    def add_body(self, worldbody: ElementTree.Element, name: str, position: Float,
                 heading: float) -> str:
        """Add robot ``name`` at ``position`` (3,) with ``heading``; return its pose body."""
        slider = carriage(worldbody, name, position, self.mass, 3)
        base = add(slider, 'body', name=name, euler=numbers((0.0, 0.0, heading)))
        add(base, 'joint', name=f'{name}_yaw', type='hinge', axis='0 0 1')
        inertia = 0.4 * self.mass * self.footprint ** 2
        inertial(base, (1.0 - CARRIAGE_MASS_FRACTION) * self.mass, (inertia, inertia, inertia))
        footprint_geom(base, f'{name}_footprint', 'sphere', (self.footprint,))
        heading_mark(base, name, self.footprint, 0.0)
        return name

    def add_actuators(self, actuators: ElementTree.Element, name: str) -> None:
        """
        Add robot ``name``'s servos: x, y, then z with the thrust, yaw.

        The z servo is a general actuator: force = weight + gain (set point - vz), within
        [max(0, weight - force), weight + force].
        """
        gain = servo_gain(self.mass)
        for axis in ('x', 'y'):
            velocity_servo(actuators, f'{name}_{axis}_motor', f'{name}_{axis}', gain,
                           self.force)
        add(actuators, 'general', name=f'{name}_z_motor', joint=f'{name}_z',
            gaintype='fixed', gainprm=number(gain), biastype='affine',
            biasprm=numbers((self.weight, 0.0, -gain)),
            forcerange=numbers((max(0.0, self.weight - self.force), self.weight + self.force)))
        inertia = 0.4 * self.mass * self.footprint ** 2
        velocity_servo(actuators, f'{name}_yaw_motor', f'{name}_yaw', servo_gain(inertia),
                       self.torque)
