# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The static obstacles in the figures and the animation (beyond the paper: docs/equations.md).

In a plan view (2D runs, and the x-y projection of 3D ones) every obstacle is a filled outline:
a circle's disc (a pillar's footprint in 3D), a wall's thick segment (the points within its
half-thickness, so its ends are round), a sphere's disc of its radius. On 3D axes the pillars
and walls are their footprints drawn at the bottom and the top of the run with vertical edges
between, and the spheres wireframes. Everything is in world_frame, m, as the parameters give it.
"""

from typing import List, Tuple

from formation_ros.core.maths.obstacles import Obstacles
import matplotlib
import numpy as np
from numpy.typing import NDArray

matplotlib.use('Agg')
from matplotlib.collections import PolyCollection  # noqa: E402, I100

OBSTACLE_COLOR = '0.45'
OBSTACLE_ALPHA = 0.55
OUTLINE_POINTS = 48
"""Points on a circle's outline (a wall's two round ends share as many)."""
VERTICAL_EDGES = 4
"""Vertical edges drawn on each pillar or wall in 3D."""
GID = 'obstacles'
"""The gid of every artist drawn here (tests find them by it)."""


def _circle(x: float, y: float, radius: float, points: int) -> NDArray[np.float64]:
    angles = np.linspace(0.0, 2.0 * np.pi, points, endpoint=False)
    return np.stack([x + radius * np.cos(angles), y + radius * np.sin(angles)], axis=1)


def _thick_segment(row: NDArray[np.float64], points: int) -> NDArray[np.float64]:
    """Return the outline of the points within t of the segment (x1, y1)-(x2, y2): (K, 2), m."""
    start, end, thickness = row[0:2], row[2:4], float(row[4])
    along = end - start
    length = float(np.hypot(*along))
    if length == 0.0:
        return _circle(float(start[0]), float(start[1]), thickness, points)
    heading = float(np.arctan2(along[1], along[0]))
    half = np.linspace(-0.5 * np.pi, 0.5 * np.pi, points // 2 + 1)
    around_end = end + thickness * np.stack([np.cos(heading + half), np.sin(heading + half)], 1)
    back = heading + np.pi + half
    around_start = start + thickness * np.stack([np.cos(back), np.sin(back)], 1)
    return np.concatenate([around_end, around_start])


def plan_outlines(obstacles: Obstacles, points: int = OUTLINE_POINTS
                  ) -> List[NDArray[np.float64]]:
    """
    Return the x-y outline of every obstacle, in ``Obstacles.labels`` order: (K, 2) arrays, m.

    Circles (and pillars), walls (thick segments with round ends) and spheres (their discs).
    """
    outlines = [_circle(x, y, r, points) for x, y, r in obstacles.circles]
    outlines += [_thick_segment(row, points) for row in obstacles.walls]
    outlines += [_circle(x, y, r, points) for x, y, _, r in obstacles.spheres]
    return outlines


def plan_extent(obstacles: Obstacles) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the lowest and highest x-y of every obstacle's outline, (2,) each, m."""
    points = np.concatenate(plan_outlines(obstacles, 8)) if obstacles.count else np.zeros((1, 2))
    return points.min(axis=0), points.max(axis=0)


def draw_plan(ax, obstacles: Obstacles, label: str = 'obstacles') -> PolyCollection:
    """Fill every obstacle's outline on plan axes ``ax`` (one collection, gid 'obstacles')."""
    collection = PolyCollection(plan_outlines(obstacles), facecolors=OBSTACLE_COLOR,
                                edgecolors='0.25', alpha=OBSTACLE_ALPHA, linewidths=0.6,
                                zorder=1, gid=GID, label=label)
    ax.add_collection(collection)
    return collection


def draw_3d(ax, obstacles: Obstacles, z_low: float, z_high: float) -> list:
    """
    Draw the obstacles on 3D axes ``ax`` between heights z_low and z_high (m); return artists.

    Pillars and walls (unbounded in z) as their footprints at both heights joined by
    :data:`VERTICAL_EDGES` vertical edges, spheres as wireframes; every artist has gid
    'obstacles' and the first one the legend's label.
    """
    artists: list = []
    upright = len(obstacles.circles) + len(obstacles.walls)
    for outline in plan_outlines(obstacles)[:upright]:
        ring = np.vstack([outline, outline[:1]])
        for z in (z_low, z_high):
            artists += ax.plot(ring[:, 0], ring[:, 1], np.full(len(ring), z),
                               color=OBSTACLE_COLOR, linewidth=0.9, gid=GID)
        for corner in outline[np.linspace(0, len(outline) - 1, VERTICAL_EDGES).astype(int)]:
            artists += ax.plot([corner[0]] * 2, [corner[1]] * 2, [z_low, z_high],
                               color=OBSTACLE_COLOR, linewidth=0.6, gid=GID)
    polar, azimuth = np.meshgrid(np.linspace(0.0, np.pi, 9), np.linspace(0.0, 2.0 * np.pi, 17))
    for x, y, z, r in obstacles.spheres:
        artists.append(ax.plot_wireframe(
            x + r * np.sin(polar) * np.cos(azimuth), y + r * np.sin(polar) * np.sin(azimuth),
            z + r * np.cos(polar), color=OBSTACLE_COLOR, linewidth=0.5, gid=GID))
    if artists:
        artists[0].set_label('obstacles')
    return artists
