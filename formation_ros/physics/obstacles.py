# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The static obstacles of a formation's world as MJCF geoms (``obstacles.*``; beyond the paper).

:func:`add_obstacles` builds the map of :class:`~formation_ros.core.maths.obstacles.Obstacles`
(the real obstacles, not the ones the law grows by the footprint) in the world body, where they
never move:

* a circle (x, y, r) is a vertical cylinder of radius r about (x, y);
* a wall (x1, y1, x2, y2, t), the points within t of the segment, is a box as long as the
  segment and 2 t thick, plus a cylinder of radius t at each end (the rounded ends, their
  tops :data:`END_INSET` below the box's); a wall whose ends coincide is that one cylinder;
* a sphere (x, y, z, r) is a sphere.

Circles and walls stand between the heights ``bottom`` and ``top`` (m; the scene chooses them:
on the floor up to ``world.obstacle_height`` in 2D, the whole flight volume in 3D). Every geom
is in :data:`OBSTACLE_GROUP`, which the bodies' footprints collide with (and nothing else:
wheels and casters roll on the floor only), and is named after the obstacle's label
(``Obstacles.labels``): ``circle_1``, ``wall_2``, ``wall_2_end_1``, ``wall_2_end_2``,
``sphere_1``; :func:`obstacle_of_geom` reads a geom's obstacle back from its name.
"""

import math
from typing import Optional
from xml.etree import ElementTree

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.physics.parts import add, FOOTPRINT_GROUP, number, numbers

OBSTACLE_GROUP = FOOTPRINT_GROUP
"""The collision bits of the obstacles' geoms: a footprint (contype FOOTPRINT_GROUP) touches
them; they touch nothing themselves (contype 0)."""
OBSTACLE_RGBA = '0.55 0.5 0.45 1'
"""The obstacles' colour: stone grey."""
PREFIX = 'obstacle_'
"""Every obstacle geom's name starts so."""
END_INSET = 0.001
"""A wall's rounded ends stop this far below its top, m, so that their tops and the box's are
not drawn in one plane (which flickers); the bodies never reach that high."""


def geom_name(label: str, part: str = '') -> str:
    """Return the geom name of an obstacle part: 'wall 2', '_end_1' -> 'obstacle_wall_2_end_1'."""
    return PREFIX + label.replace(' ', '_') + part


def obstacle_of_geom(name: Optional[str], obstacles: Obstacles) -> int:
    """Return the obstacle (0-based, ``Obstacles.labels`` order) a geom is part of; -1: none."""
    if not name or not name.startswith(PREFIX):
        return -1
    kind, _, rest = name[len(PREFIX):].partition('_')
    number_text = rest.split('_')[0]
    if not number_text.isdigit():
        return -1
    try:
        return obstacles.labels().index(f'{kind} {int(number_text)}')
    except ValueError:
        return -1


def _static(worldbody: ElementTree.Element, name: str, shape: str, size: str, pos: str,
            **extra: str) -> None:
    """Add a static obstacle geom: in :data:`OBSTACLE_GROUP`, touching nothing itself."""
    add(worldbody, 'geom', name=name, type=shape, size=size, pos=pos, contype='0',
        conaffinity=str(OBSTACLE_GROUP), rgba=OBSTACLE_RGBA, **extra)


def add_obstacles(worldbody: ElementTree.Element, obstacles: Obstacles, bottom: float,
                  top: float) -> None:
    """
    Add the geoms of ``obstacles`` to ``worldbody``; circles and walls span ``bottom``-``top`` m.

    Spheres are where they are. ValueError if ``top`` is not above ``bottom``.
    """
    if not top > bottom:
        raise ValueError(f'obstacles need top > bottom, got {top!r} and {bottom!r}')
    half = 0.5 * (top - bottom)
    middle = 0.5 * (top + bottom)
    labels = obstacles.labels()
    for label, (x, y, r) in zip(labels, obstacles.circles):
        _static(worldbody, geom_name(label), 'cylinder', numbers((r, half)),
                numbers((x, y, middle)))
    for label, (x1, y1, x2, y2, t) in zip(labels[len(obstacles.circles):], obstacles.walls):
        length = math.hypot(x2 - x1, y2 - y1)
        ends = [(x1, y1)] if length == 0.0 else [(x1, y1), (x2, y2)]
        if length > 0.0:
            _static(worldbody, geom_name(label), 'box', numbers((0.5 * length, t, half)),
                    numbers((0.5 * (x1 + x2), 0.5 * (y1 + y2), middle)),
                    euler=numbers((0.0, 0.0, math.atan2(y2 - y1, x2 - x1))))
        inset = min(END_INSET, half) if length > 0.0 else 0.0
        for end, (x, y) in enumerate(ends, start=1):
            _static(worldbody, geom_name(label, f'_end_{end}'), 'cylinder',
                    numbers((t, half - 0.5 * inset)), numbers((x, y, middle - 0.5 * inset)))
    first_sphere = len(obstacles.circles) + len(obstacles.walls)
    for label, (x, y, z, r) in zip(labels[first_sphere:], obstacles.spheres):
        _static(worldbody, geom_name(label), 'sphere', number(r), numbers((x, y, z)))


def footprint_note(obstacles: Obstacles, body_radius: float, footprint: float) -> Optional[str]:
    """
    Say in one line that the law keeps a smaller body off the obstacles than the world has.

    body_radius: ``body.radius``, m, the radius the law keeps off the obstacles about the body's
    centre; footprint: the radius of the world's bodies, m (a point without ``body.radius``
    gets a default one, a base one that holds its wheels). None when the law covers the
    bodies or there is no obstacle.
    """
    if obstacles.count == 0 or body_radius >= footprint:
        return None
    return (f'the bodies in the world are {footprint:g} m in radius but body.radius is '
            f'{body_radius:g} m, all the law keeps off the obstacles: a body may touch one '
            f'(body.radius: {footprint:g} would cover it)')
