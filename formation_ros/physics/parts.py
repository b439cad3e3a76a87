# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The parts every body model of the physics world is made of: MJCF elements, servos, kinds.

Numbers are written so that they read back as the same floats; lengths in m, masses in kg,
inertias in kg m^2, forces in N.
"""

import enum
from typing import Tuple
from xml.etree import ElementTree

import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
GRAVITY = 9.81
"""Standard gravity, m/s^2 (the scene's ``option gravity``)."""
SERVO_TIME_CONSTANT = 0.01
"""Every velocity servo's gain is the inertia it drives over this, s (:func:`servo_gain`): stiff
enough that a servo meets its force or torque limit on any sizeable speed change."""
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
DRAWN_GROUP = 1
"""The visual group of the geoms only drawn (heading marks, wheels' rims, casters): the viewer
shows it (as group 0), the laser scanner does not see it (``physics.scanner``)."""
AXES = (('x', '1 0 0'), ('y', '0 1 0'), ('z', '0 0 1'))
"""The world axes a carriage slides along: (name, direction)."""


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


def numbers(values: ArrayLike) -> str:
    """Return floats as an MJCF list: '0 0.1 0'."""
    return ' '.join(number(float(v)) for v in np.asarray(values, dtype=float).ravel())


def add(parent: ElementTree.Element, tag: str, **attributes: str) -> ElementTree.Element:
    """Add an MJCF element ``tag`` with ``attributes`` (text) under ``parent``; return it."""
    return ElementTree.SubElement(parent, tag, attributes)


def footprint_geom(body: ElementTree.Element, name: str, shape: str, size: ArrayLike,
                   pos: ArrayLike = (0.0, 0.0, 0.0)) -> None:
    """Add the geom other robots collide with: massless, in :data:`FOOTPRINT_GROUP` alone."""
    add(body, 'geom', name=name, type=shape, size=numbers(size), pos=numbers(pos),
        mass='0', contype=str(FOOTPRINT_GROUP), conaffinity=str(FOOTPRINT_GROUP),
        rgba='0.2 0.45 0.8 1')


def inertial(body: ElementTree.Element, mass: float, inertia: ArrayLike,
             pos: ArrayLike = (0.0, 0.0, 0.0)) -> None:
    """Give ``body`` its mass (kg), principal moments (kg m^2) and centre of mass (m)."""
    add(body, 'inertial', pos=numbers(pos), mass=number(mass), diaginertia=numbers(inertia))


def velocity_servo(actuators: ElementTree.Element, name: str, joint: str, gain: float,
                   limit: float) -> None:
    """Add a velocity servo on ``joint``: gain (N s/m or N m s/rad), force or torque limit."""
    add(actuators, 'velocity', name=name, joint=joint, kv=number(gain),
        forcerange=numbers((-limit, limit)))


def cylinder_inertia(mass: float, radius: float, half_height: float) -> Tuple[float, float, float]:
    """Return the principal moments (x, y, z) of a solid cylinder about its centre, kg m^2."""
    across = mass * (3.0 * radius * radius + 4.0 * half_height * half_height) / 12.0
    return (across, across, 0.5 * mass * radius * radius)


def carriage(worldbody: ElementTree.Element, name: str, position: ArrayLike,
             mass: float, dim: int) -> ElementTree.Element:
    """Add the body of robot ``name`` that slides along the first ``dim`` world axes."""
    carriage = add(worldbody, 'body', name=f'{name}_carriage', pos=numbers(position))
    for axis, direction in AXES[:dim]:
        add(carriage, 'joint', name=f'{name}_{axis}', type='slide', axis=direction)
    inertial(carriage, CARRIAGE_MASS_FRACTION * mass, (CARRIAGE_INERTIA,) * 3)
    return carriage


def heading_mark(body: ElementTree.Element, name: str, footprint: float,
                 half_height: float) -> None:
    """Add a visual marker on the body's +x side (its heading), no mass, no contact."""
    add(body, 'geom', name=f'{name}_front', type='box',
        size=numbers((0.25 * footprint, 0.1 * footprint, 0.005)),
        pos=numbers((0.7 * footprint, 0.0, half_height)), mass='0', contype='0',
        conaffinity='0', group=str(DRAWN_GROUP), rgba='0.95 0.75 0.1 1')


def rotated(vectors: Float, yaw: Float) -> Float:
    """Return planar vectors (N, 2) turned by yaw (N,) about +z: R(yaw) v."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * vectors[:, 0] - s * vectors[:, 1],
                     s * vectors[:, 0] + c * vectors[:, 1]], axis=1)
