# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A planar laser scan as obstacle points: returns in the world frame, neighbours left out, thinned.

Beyond the paper (docs/equations.md, "Obstacles from a scan"). A robot that senses obstacles
with its own scanner (``obstacles.source: scan``) turns each return into a point in the world
frame with its pose at the scan's stamp; returns on a known neighbour's body are the pair
terms' business and are left out; of the rest, each run of returns that holds together (an
obstacle) gives its nearest within R_i (:func:`nearest_by_object`), and of those at most one per
sector of directions about the robot (the nearest) becomes a surface point p_io of
``core.maths.obstacles``, so that the law's cost stays bounded whatever the scanner's
resolution, each with the normal that faces the robot (:func:`facing_normals`): a return is a
point obstacle.
``core.rules.scan_obstacles`` keeps the scans and poses and applies these in order.

Angles in rad, counter-clockwise from the scanner's +x; ranges and positions in m. Nothing here
modifies its arguments.
"""

from dataclasses import dataclass
import math
from typing import List, Optional, Tuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

DEFAULT_SECTORS = 72
"""Sectors of directions about a robot that keep one scan point each (5 degrees wide)."""


@dataclass(frozen=True)
class ScanShape:
    """
    The fixed fields of a scan (``sensor_msgs/LaserScan``), and where the scanner sits.

    angle_min, angle_increment: the first ray's angle and the step between rays, rad (> 0 step);
    range_min, range_max: the valid returns, m (a return outside them is no return); mount: the
    scanner's (x, y) in the base's frame, m; mount_yaw: its rotation about +z there, rad.
    """

    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    mount: Tuple[float, float] = (0.0, 0.0)
    mount_yaw: float = 0.0


ANGLE_LIMIT = 4.0 * math.pi
"""The largest ``|angle_min|`` and ``|mount_yaw|`` a scan may give, rad."""


def scan_problem(ranges: ArrayLike, shape: ScanShape) -> Optional[str]:
    """
    Return why a scan cannot be read, or None.

    ranges: (K,) m, K >= 1. As REP 117 has them, +inf is no return within range_max, -inf an
    object nearer than range_min, NaN an erroneous measurement (that ray tells nothing); a scan
    whose rays are mostly NaN tells nothing and is refused. The shape's numbers must be finite,
    angles within :data:`ANGLE_LIMIT`, the angle step positive and the rays at most a full
    turn, and 0 <= range_min < range_max.
    """
    fields = (shape.angle_min, shape.angle_increment, shape.range_min, shape.range_max,
              shape.mount_yaw, *shape.mount)
    if not all(math.isfinite(value) for value in fields):
        return 'non-finite angle, range limit or mount'
    values = np.asarray(ranges, dtype=float).reshape(-1)
    if len(values) == 0:
        return 'no rays'
    if shape.angle_increment <= 0.0:
        return f'angle_increment must be > 0, got {shape.angle_increment:g}'
    if max(abs(shape.angle_min), abs(shape.mount_yaw)) > ANGLE_LIMIT:
        return f'an angle beyond +-{ANGLE_LIMIT:.4g} rad'
    if (len(values) - 1) * shape.angle_increment > 2.0 * math.pi:
        return f'{len(values)} rays {shape.angle_increment:g} rad apart: more than a full turn'
    if not 0.0 <= shape.range_min < shape.range_max:
        return (f'needs 0 <= range_min < range_max, got {shape.range_min:g} and '
                f'{shape.range_max:g}')
    if 2 * int(np.count_nonzero(np.isnan(values))) > len(values):
        return 'most ranges are NaN (erroneous measurements): the scan tells nothing'
    return None


def returning_rays(ranges: ArrayLike, shape: ScanShape) -> NDArray[np.intp]:
    """
    Return the indices of the rays with a return, in scan order: (K,).

    ranges: (R,) m; a return is finite and within [range_min, range_max], or -inf (an object
    nearer than range_min, REP 117: :func:`scan_points` puts it at range_min); +inf, NaN and
    a range outside the limits are none.
    """
    values = np.asarray(ranges, dtype=float).reshape(-1)
    with np.errstate(invalid='ignore'):
        valid = ((np.isfinite(values) & (values >= shape.range_min)
                  & (values <= shape.range_max)) | (values == -np.inf))
    rays: NDArray[np.intp] = np.flatnonzero(valid)
    return rays


def full_turn(shape: ScanShape, rays: int) -> bool:
    """Tell whether ``rays`` rays of ``shape`` go round (the last ray's neighbour is the first)."""
    return rays * shape.angle_increment >= 2.0 * math.pi - shape.angle_increment / 2.0


def scan_points(ranges: ArrayLike, shape: ScanShape, position: ArrayLike,
                heading: float) -> NDArray[np.float64]:
    """
    Return the returns of a scan as points in the world frame: (K, 2), m.

    ranges: (R,) m, ray k at ``angle_min + k * angle_increment`` in the scanner's frame;
    position: (2,) the base's position and heading its yaw, rad, at the scan's stamp. Rays
    without a return (+inf, or outside [range_min, range_max]) give no point: the points are
    those of :func:`returning_rays`, in that order. The scan must have passed
    :func:`scan_problem`.
    """
    values = np.asarray(ranges, dtype=float).reshape(-1)
    rays = returning_rays(values, shape)
    angles = shape.angle_min + rays * shape.angle_increment + shape.mount_yaw + heading
    c, s = math.cos(heading), math.sin(heading)
    mount_x, mount_y = shape.mount
    origin = np.asarray(position, dtype=float)[:2] + (c * mount_x - s * mount_y,
                                                      s * mount_x + c * mount_y)
    reach = np.where(values[rays] == -np.inf, shape.range_min, values[rays])
    points: NDArray[np.float64] = origin + reach[:, None] * np.column_stack(
        [np.cos(angles), np.sin(angles)])
    return points


def off_neighbours(points: ArrayLike, neighbours: ArrayLike, reach: float) -> NDArray[np.bool_]:
    """
    Tell which points are not on a known neighbour's body: (K,) bools.

    points: (K, 2); neighbours: (M, 2) the neighbours' positions, m; reach: a return within
    this distance of a neighbour's position is that neighbour (its footprint plus a margin for
    the pose's age and noise), m.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    others = np.asarray(neighbours, dtype=float).reshape(-1, 2)
    if len(others) == 0:
        return np.ones(len(p), dtype=bool)
    gaps = np.linalg.norm(p[:, None, :] - others[None, :, :], axis=2)
    kept: NDArray[np.bool_] = np.all(gaps > reach, axis=1)
    return kept


def nearest_by_object(points: ArrayLike, rays: ArrayLike, total: int, wraps: bool,
                      centre: ArrayLike, radius: float, join: float) -> NDArray[np.float64]:
    """
    Return the nearest returns of each obstacle a scan shows, within ``radius`` of ``centre``.

    points: (K, 2) returns in scan order and rays: (K,) their rays' indices (of ``total``
    rays; ``wraps``: the last ray's neighbour is the first, :func:`full_turn`); centre: (2,)
    and radius: R_i, m; join: returns of rays at most one ray apart (a dropout between) and
    nearer each other than this, m, belong to one run. A run's nearest return stands for it,
    as a mapped obstacle's closest point does (one term an obstacle), and so does each other
    nearest of a face of it: a return nearer than its neighbours whose distance rises by at
    least ``join`` on either side before anything nearer (:func:`held_minima`): the walls of
    a room or a corridor, each of its own. Returns (at most K, 2), in scan order.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    index = np.asarray(rays, dtype=np.intp).reshape(-1)
    if len(p) == 0:
        return np.zeros((0, 2))
    step = np.roll(index, -1) - index
    if wraps:
        step = step % total
    joined = ((step >= 1) & (step <= 2)
              & (np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1) < join))
    if not wraps or len(p) == 1:
        joined[-1] = False
    starts = ~np.roll(joined, 1)
    ring = not np.any(starts)
    shift = 0 if ring else int(np.argmax(starts))
    order = np.roll(np.arange(len(p)), -shift)
    distance = np.linalg.norm(p[order] - np.asarray(centre, dtype=float)[:2], axis=1)
    firsts = [0] if ring else np.flatnonzero(starts[order]).tolist()
    kept: List[int] = []
    for first, last in zip(firsts, firsts[1:] + [len(p)]):
        kept += [first + k for k in held_minima(distance[first:last], join, ring)]
    chosen = np.array(sorted(int(order[k]) for k in kept if distance[k] < radius),
                      dtype=np.intp)
    nearest: NDArray[np.float64] = p[chosen] if len(chosen) else np.zeros((0, 2))
    return nearest


def held_minima(distance: ArrayLike, depth: float, ring: bool = False) -> List[int]:
    """
    Return the indices of a run's nearest return and of its other held minima, ascending.

    distance: (m,) m, along the run; depth: m. A held minimum is a return no farther than the
    one before it and nearer than the one after, from which the distance rises by at least
    ``depth`` on both sides before anything nearer (or the run's end on that side: an end
    itself counts as no rise); ring: the run goes round (its last return's neighbour is its
    first).
    """
    d = np.asarray(distance, dtype=float).reshape(-1)
    m = len(d)
    if m == 0:
        return []
    if ring:
        top = int(np.argmax(d))
        turned = held_minima(np.roll(d, -top), depth)
        return sorted((k + top) % m for k in turned)
    best = int(np.argmin(d))
    before = np.r_[np.inf, d[:-1]]
    after = np.r_[d[1:], np.inf]
    held = {best}
    for k in np.flatnonzero((d <= before) & (d < after)).tolist():
        if k != best and min(_rise(d[k::-1]), _rise(d[k:])) >= depth:
            held.add(k)
    return sorted(held)


def _rise(side: NDArray[np.float64]) -> float:
    """Return how far ``side`` (from a minimum outward) rises before it falls below its start."""
    lower = np.flatnonzero(side[1:] < side[0])
    walk = side[1:] if len(lower) == 0 else side[1:lower[0] + 1]
    return float(np.max(walk) - side[0]) if len(walk) else 0.0


def nearest_by_sector(points: ArrayLike, centre: ArrayLike, radius: float,
                      sectors: int = DEFAULT_SECTORS) -> NDArray[np.float64]:
    """
    Return the nearest point of each sector of directions about ``centre`` within ``radius``.

    points: (K, 2); centre: (2,) m; radius: R_i, m (a point at or beyond it is dropped);
    sectors: how many equal sectors the circle is cut into. Returns (at most ``sectors``, 2),
    ordered by sector from -pi: the points a robot's law uses (one surface point per direction).
    """
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    offset = p - np.asarray(centre, dtype=float)[:2]
    distance = np.linalg.norm(offset, axis=1)
    near = distance < radius
    p, offset, distance = p[near], offset[near], distance[near]
    if len(p) == 0:
        return np.zeros((0, 2))
    angle = np.arctan2(offset[:, 1], offset[:, 0])
    sector = np.minimum((angle + math.pi) / (2.0 * math.pi) * sectors, sectors - 1).astype(int)
    order = np.lexsort((distance, sector))
    first = np.ones(len(order), dtype=bool)
    first[1:] = sector[order][1:] != sector[order][:-1]
    nearest: NDArray[np.float64] = p[order[first]]
    return nearest


def facing_normals(points: ArrayLike, control_point: ArrayLike) -> NDArray[np.float64]:
    """
    Return the unit normals (K, 2) of point obstacles ``points`` (K, 2) facing ``control_point``.

    control_point: (2,) the point the law acts on, m. The normal of return p is
    ``(q - p) / |q - p|``: ``core.maths.obstacles.HeardObstacles`` then puts the robot at
    ``|q - p| - f`` from it, the distance from its footprint to the point itself. A return at q
    itself (no direction) gets +x.
    """
    q = np.asarray(control_point, dtype=float)[:2]
    offset = q - np.asarray(points, dtype=float).reshape(-1, 2)
    norm = np.linalg.norm(offset, axis=1, keepdims=True)
    normals: NDArray[np.float64] = np.where(norm > 0.0, offset / np.where(norm > 0.0, norm, 1.0),
                                            (1.0, 0.0))
    return normals
