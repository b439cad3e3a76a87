# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Static obstacles and their repulsion: the collision function beta of eq. (11) against a surface.

Beyond the paper (docs/equations.md, "Obstacles"): a static obstacle o adds to robot i's
potential the factor ``beta_io = h(0, b_o**2 / 2, d_io**2 / 2)`` of the distance ``d_io`` from
its position to the obstacle's surface, as eq. (11) does for a pair of robots with ``b_ij``;
``Omega_i`` of eq. (13) gains ``-kappa * betabar'_io * (q_i - p_io)``, with ``p_io`` the
surface point closest to ``q_i`` (``||q_i - p_io|| = d_io`` outside the obstacle) and
``betabar' = h'/h``. That is the gradient of ``-kappa * log beta_io`` with respect to ``q_i``,
since the gradient of ``d_io`` is the unit normal ``(q_i - p_io) / d_io``.

Three shapes, all in the world frame (m):

* circles ``(x, y, r)``: discs in 2D; in 3D vertical pillars of radius r, unbounded in z;
* walls ``(x1, y1, x2, y2, t)``: the points within t of the segment; in 3D vertical walls,
  unbounded in z;
* spheres ``(x, y, z, r)``: 3D only.

Positions are rows ``(N, dim)``, ``dim`` 2 or 3. A distance is negative inside an obstacle and
zero on its surface; nothing here modifies its arguments.
"""

from dataclasses import dataclass
import math
from typing import Callable, NamedTuple, Optional, Protocol, Sequence, Tuple

from formation_ros.core.maths.jump import JumpFunction
import numpy as np
from numpy.typing import ArrayLike, NDArray

MAX_OBSTACLE_REPULSION = 1e200
"""The repulsion of a robot on or inside an obstacle's surface, along its outward normal (the
term has no value there; the command saturates at c M1 as for two robots at one point)."""
CIRCLE_COLUMNS = 3
WALL_COLUMNS = 5
SPHERE_COLUMNS = 4
MAX_TOLD = 256
"""The most obstacle points one robot's message may list (``obstacles`` topic): more is
refused unread (an arena's map gives a robot far fewer within its R_i)."""
NORMAL_FLOOR = 1e-6
"""A heard normal whose part in the team's space is shorter than this has no direction there."""
GRID_CELLS = 1 << 20
"""The most cells of an :class:`ObstacleGrid`, and the most (cell, obstacle) entries it files:
wider cells beyond (a grid is built once for a map and never takes more than about 16 MB)."""
GRID_MARGIN = 1e-9
"""How much wider than its reach plus b_o an obstacle is filed, relative to the map's largest
coordinate and reach, so that no rounding in a cell index loses a pair the exact test keeps."""


class Surface(NamedTuple):
    """
    Where the obstacles' surfaces are, seen from robots.

    points: (N, M, dim) the surface point p_io closest to robot i, m; distances: (N, M) d_io,
    m, negative inside; normals: (N, M, dim) the unit outward normals at those points.
    """

    points: NDArray[np.float64]
    distances: NDArray[np.float64]
    normals: NDArray[np.float64]


Pairs = Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""The surface seen across P (robot, obstacle) pairs: points (P, dim), distances (P,), normals
(P, dim)."""


def _rows(values: ArrayLike, columns: int, name: str) -> NDArray[np.float64]:
    """Return ``values`` as a read-only (K, columns) float array; ValueError if it is not one."""
    array = np.array(values, dtype=float).reshape(-1) if np.size(values) else np.zeros(0)
    if array.size % columns:
        raise ValueError(f'{name} takes {columns} numbers an obstacle, got {array.size}')
    if not np.all(np.isfinite(array)):
        raise ValueError(f'{name} must be finite numbers')
    rows = array.reshape(-1, columns)
    rows.setflags(write=False)
    return rows


@dataclass(frozen=True)
class Obstacles:
    """
    The static obstacles of an arena, in the world frame.

    circles: (C, 3) rows (x, y, r), r > 0; walls: (W, 5) rows (x1, y1, x2, y2, t), t > 0 (a
    wall whose ends coincide is a disc of radius t); spheres: (S, 4) rows (x, y, z, r), r > 0,
    only when ``dim`` is 3; clearance: b_o in m, the distance from a surface within which an
    obstacle repels (> 0); dim: 2 or 3. Flat lists are accepted (``obstacles.circles`` etc.).
    """

    circles: NDArray[np.float64]
    walls: NDArray[np.float64]
    spheres: NDArray[np.float64]
    clearance: float
    dim: int

    def __post_init__(self) -> None:
        """Check shapes and values once, so that the hot path need not."""
        object.__setattr__(self, 'circles', _rows(self.circles, CIRCLE_COLUMNS, 'circles'))
        object.__setattr__(self, 'walls', _rows(self.walls, WALL_COLUMNS, 'walls'))
        object.__setattr__(self, 'spheres', _rows(self.spheres, SPHERE_COLUMNS, 'spheres'))
        if self.dim not in (2, 3):
            raise ValueError(f'dim must be 2 or 3, got {self.dim!r}')
        if not (math.isfinite(self.clearance) and self.clearance > 0.0):
            raise ValueError(f'clearance must be a finite number > 0, got {self.clearance!r}')
        if np.any(self.circles[:, 2] <= 0.0) or np.any(self.spheres[:, 3] <= 0.0):
            raise ValueError('an obstacle radius must be > 0')
        if np.any(self.walls[:, 4] <= 0.0):
            raise ValueError('a wall half-thickness must be > 0')
        if len(self.spheres) and self.dim != 3:
            raise ValueError('spheres are 3D obstacles; this team is 2D')

    @property
    def count(self) -> int:
        """Return the number of obstacles M: circles, then walls, then spheres."""
        return len(self.circles) + len(self.walls) + len(self.spheres)

    def grown(self, margin: float) -> 'Obstacles':
        """
        Return these obstacles grown by ``margin`` m: every radius and half-thickness.

        A robot's footprint of radius ``margin`` about its control point touches an obstacle
        exactly when the point touches the grown one (the configuration space of a disc among
        convex obstacles; grown obstacles are still convex). Nothing else changes.
        """
        if margin < 0.0 or not math.isfinite(margin):
            raise ValueError(f'margin must be a finite number >= 0, got {margin!r}')
        circles, walls, spheres = (np.array(rows) for rows in (self.circles, self.walls,
                                                               self.spheres))
        circles[:, 2] += margin
        walls[:, 4] += margin
        spheres[:, 3] += margin
        return Obstacles(circles, walls, spheres, self.clearance, self.dim)

    def labels(self) -> Tuple[str, ...]:
        """Return a name for every obstacle, in :attr:`count` order: 'circle 1', 'wall 1' ..."""
        return tuple([f'circle {k + 1}' for k in range(len(self.circles))]
                     + [f'wall {k + 1}' for k in range(len(self.walls))]
                     + [f'sphere {k + 1}' for k in range(len(self.spheres))])

    def surface(self, q: ArrayLike) -> Surface:
        """
        Return the :class:`Surface` of every obstacle as every robot sees it.

        q: (N, dim) positions, m; obstacles in the order of :attr:`count`. Circles and walls
        act in the plane: in 3D their points keep the robot's z and their normals have no z.
        A position on an obstacle's axis or segment (no direction to the surface) takes +x.
        """
        q = np.asarray(q, dtype=float).reshape(-1, self.dim)
        parts = []
        for rows, pairs in self._kinds():
            robots = np.repeat(np.arange(len(q)), len(rows))
            points, distances, normals = pairs(q[robots], np.tile(rows, (len(q), 1)))
            shape = (len(q), len(rows))
            parts.append((points.reshape(*shape, self.dim), distances.reshape(shape),
                          normals.reshape(*shape, self.dim)))
        if not parts:
            none = np.zeros((len(q), 0, self.dim))
            return Surface(none, np.zeros((len(q), 0)), none)
        return Surface(*(np.concatenate([part[k] for part in parts], axis=1) for k in range(3)))

    def distances(self, q: ArrayLike) -> NDArray[np.float64]:
        """
        Return d_io of every robot and obstacle, (N, M) m, negative inside: ``surface(q)``'s.

        Without the points and normals: a disc's, pillar's or ball's distance is the distance to
        its centre (in the plane for discs and pillars) less its radius; walls are measured as
        :meth:`surface` does.
        """
        q = np.asarray(q, dtype=float).reshape(-1, self.dim)
        parts = [np.zeros((len(q), 0))]
        for rows, pairs in self._kinds():
            if pairs is _wall_pairs:
                robots = np.repeat(np.arange(len(q)), len(rows))
                measured = pairs(q[robots], np.tile(rows, (len(q), 1)))[1]
                parts.append(measured.reshape(len(q), len(rows)))
            else:
                centres, reach = _bounds(rows, pairs)
                parts.append(np.sqrt(_apart_sq(q, centres)) - reach)
        return np.concatenate(parts, axis=1)

    def terms(self, q: ArrayLike, jump: JumpFunction,
              sensing_radii: ArrayLike) -> NDArray[np.float64]:
        """
        Return :func:`obstacle_terms` of every robot, measuring only the obstacles that can act.

        q: (N, dim) positions, m; sensing_radii: (N,) R_i, m. An obstacle acts on robot i only
        where d_io < min(R_i, b_o); d_io is at least the distance to the obstacle's centre (a
        wall's middle) less its reach (radius; half-length plus t), so pairs farther than that
        are never measured; an :class:`ObstacleGrid` of the map offers each robot only the
        obstacles filed in its cell of the plane. The same sums as ``obstacle_terms(q,
        self.surface(q), ...)`` at a cost that grows with the pairs near each other, not with
        N x M. (N, dim), 1/m.
        """
        q = np.asarray(q, dtype=float).reshape(-1, self.dim)
        radii = np.broadcast_to(np.asarray(sensing_radii, dtype=float).reshape(-1), (len(q),))
        acts = np.minimum(radii, self.clearance)
        summed = np.zeros_like(q)
        for (rows, pairs), grid in zip(self._kinds(), self._grids(self.clearance)):
            robots, kinds, _ = grid.near(q, acts)
            if len(robots) == 0:
                continue
            points, distances, normals = pairs(q[robots], rows[kinds])
            near = Surface(points[:, None, :], distances[:, None], normals[:, None, :])
            np.add.at(summed, robots, obstacle_terms(q[robots], near, jump, self.clearance,
                                                     radii[robots]))
        return summed

    def nearby(self, q: ArrayLike, within: float
               ) -> Tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
        """
        Return the pairs that may be nearer than ``within`` m: robots (P,), obstacles (P,), d_io.

        q: (N, dim) positions, m; within > 0, m. Every pair (i, o) with d_io < within is
        among them (to rounding at ``within`` itself), none whose centre (a wall's middle) is
        farther than ``within`` plus the obstacle's reach; obstacles numbered in :attr:`count`
        order; d_io (P,) in m exactly as :meth:`distances` gives it, at a cost that grows with
        the pairs near each other, not with N x M.
        """
        q = np.asarray(q, dtype=float).reshape(-1, self.dim)
        found = [(np.zeros(0, dtype=np.intp),) * 2 + (np.zeros(0),)]
        first = 0
        for (rows, pairs), grid in zip(self._kinds(), self._grids(float(within))):
            robots, kinds, apart_sq = grid.near(q, np.full(len(q), float(within)))
            if pairs is _wall_pairs:
                measured = pairs(q[robots], rows[kinds])[1]
            else:
                measured = np.sqrt(apart_sq) - grid.reach[kinds]
            found.append((robots, kinds + first, measured))
            first += len(rows)
        robots, obstacles, distances = (np.concatenate(part) for part in zip(*found))
        return robots, obstacles, distances

    def _grids(self, within: float) -> Tuple['ObstacleGrid', ...]:
        """Return the :class:`ObstacleGrid` of each kind present for ``within`` m (built once)."""
        built = self.__dict__.setdefault('_built_grids', {})
        if within not in built:
            built[within] = tuple(ObstacleGrid(*_bounds(rows, pairs), within)
                                  for rows, pairs in self._kinds())
        grids: Tuple[ObstacleGrid, ...] = built[within]
        return grids

    def _kinds(self) -> Tuple[Tuple[NDArray[np.float64], Callable[..., Pairs]], ...]:
        """Return (rows, their pair function) of each kind present, in :attr:`count` order."""
        kinds = ((self.circles, _circle_pairs), (self.walls, _wall_pairs),
                 (self.spheres, _sphere_pairs))
        return tuple((rows, pairs) for rows, pairs in kinds if len(rows))


class ObstacleGrid:
    """
    The obstacles of one kind filed by the square cells of the plane where they can act.

    centres: (K, 2 or 3) and reach: (K,) of each obstacle (:func:`_bounds`), m; clearance:
    b_o, m. Obstacle k is filed in every cell that the square about its centre (in the plane)
    of half-side reach_k + b_o (and :data:`GRID_MARGIN` of the map's size) meets, so a robot
    nearer than reach_k + b_o to the centre (in the plane, hence also in space) lies in a cell
    that files k. Cells are about as wide as that half-side (the median over the kind), wider
    when the map would need more than :data:`GRID_CELLS` of them or entries; numpy only.
    """

    def __init__(self, centres: NDArray[np.float64], reach: NDArray[np.float64],
                 clearance: float):
        """File obstacles with centres (K, 2 or 3) and reach (K,), m, for b_o = clearance."""
        self.centres = centres
        self.reach = reach
        xy = centres[:, :2]
        spread = reach + clearance
        spread = (spread + GRID_MARGIN * (np.max(spread) + np.max(np.abs(xy))))[:, None]
        self.low = np.min(xy - spread, axis=0)
        high = np.max(xy + spread, axis=0)
        with np.errstate(over='ignore'):
            extent = high - self.low
        cell = float(np.median(spread))
        for _ in range(80) if np.all(np.isfinite(extent)) else ():
            first = np.floor((xy - spread - self.low) / cell)
            last = np.floor((xy + spread - self.low) / cell)
            shape = np.floor(extent / cell) + 1.0
            entries = np.prod(last - first + 1.0, axis=1)
            if (np.prod(shape) <= GRID_CELLS
                    and np.sum(entries) <= max(GRID_CELLS, len(centres))):
                break
            cell *= 2.0
        else:  # a map wider than the doubles can divide: one cell files every obstacle
            cell, shape = math.inf, np.ones(2)
            first = last = np.zeros_like(xy)
            entries = np.ones(len(xy))
        self.cell = cell
        self.top = shape + 1.0
        self.width = int(shape[1]) + 2
        cells = np.concatenate([np.zeros(0, dtype=np.intp)] + [
            (np.arange(a[0] + 1, b[0] + 2, dtype=np.intp)[:, None] * self.width
             + np.arange(a[1] + 1, b[1] + 2, dtype=np.intp)[None, :]).ravel()
            for a, b in zip(first.astype(np.intp), last.astype(np.intp))])
        owners = np.repeat(np.arange(len(centres), dtype=np.intp), entries.astype(np.intp))
        self.members = owners[np.argsort(cells, kind='stable')]
        self.filed = np.bincount(cells, minlength=int(self.top[0] + 1.0) * self.width)
        self.starts = np.concatenate([[0], np.cumsum(self.filed)]).astype(np.intp)

    def near(self, q: NDArray[np.float64], acts: NDArray[np.float64]
             ) -> Tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64]]:
        """
        Return the pairs (robots (P,), obstacles (P,)) whose centres are near, and their apart**2.

        q: (N, dim) positions, m; acts: (N,) how near each robot's obstacles act, m (at most
        the grid's b_o). The pairs with squared centre distance (P,) m**2 below
        (acts_i + reach_k)**2, sorted by robot, then obstacle: exactly those, in the order, of
        the test over every pair. The cells are numbered with a ring of empty ones round the
        grid, where a robot outside it (or not a number) falls.
        """
        if math.isinf(self.cell):
            cells = np.full(len(q), self.width + 1)
        else:
            with np.errstate(invalid='ignore', over='ignore'):
                scaled = (q[:, :2] - self.low) / self.cell + 1.0
            where = np.fmin(np.fmax(scaled, 0.0), self.top).astype(np.intp)
            cells = where[:, 0] * self.width + where[:, 1]
        robots = np.flatnonzero(self.filed[cells])
        cells = cells[robots]
        first = self.starts[cells]
        count = self.starts[cells + 1] - first
        robots = np.repeat(robots, count)
        slots = np.arange(len(robots)) + np.repeat(first - (np.cumsum(count) - count), count)
        kinds = self.members[slots]
        apart_sq = np.zeros(len(robots))
        for axis in range(self.centres.shape[1]):
            offset = q[robots, axis] - self.centres[kinds, axis]
            apart_sq += offset * offset
        within = acts[robots] + self.reach[kinds]
        keep = apart_sq < within * within
        return robots[keep], kinds[keep], apart_sq[keep]


def _toward(offset: NDArray[np.float64]) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return the unit directions of offsets (..., k) and their norms; +x for a zero offset."""
    norm = np.linalg.norm(offset, axis=-1)
    unit = np.zeros_like(offset)
    unit[..., 0] = 1.0
    away = norm > 0.0
    unit[away] = offset[away] / norm[away][:, None]
    return unit, norm


def _in_plane(q: NDArray[np.float64], axis_xy: NDArray[np.float64],
              radius: NDArray[np.float64]) -> Pairs:
    """Return the surface of plane shapes from pairs' positions q (P, dim), axis points (P, 2)."""
    unit, norm = _toward(q[:, :2] - axis_xy)
    points = np.array(q)
    points[:, :2] = axis_xy + radius[:, None] * unit
    normals = np.zeros_like(points)
    normals[:, :2] = unit
    return points, norm - radius, normals


def _circle_pairs(q: NDArray[np.float64], circles: NDArray[np.float64]) -> Pairs:
    """Discs (2D) or vertical pillars (3D), rows (P, 3): the closest point keeps the robot's z."""
    return _in_plane(q, circles[:, :2], circles[:, 2])


def _wall_pairs(q: NDArray[np.float64], walls: NDArray[np.float64]) -> Pairs:
    """Thick segments, rows (P, 5): the closest point of the segment, then t towards q."""
    start, end = walls[:, 0:2], walls[:, 2:4]
    along = end - start
    length_sq = np.einsum('pd,pd->p', along, along)
    reach = np.einsum('pd,pd->p', q[:, :2] - start, along)
    with np.errstate(invalid='ignore', divide='ignore'):
        fraction = np.where(length_sq > 0.0, reach / length_sq, 0.0)
    nearest = start + np.clip(fraction, 0.0, 1.0)[:, None] * along
    return _in_plane(q, nearest, walls[:, 4])


def _sphere_pairs(q: NDArray[np.float64], spheres: NDArray[np.float64]) -> Pairs:
    """Balls, rows (P, 4): the closest point along the line from the centre."""
    unit, norm = _toward(q - spheres[:, :3])
    radius = spheres[:, 3]
    return spheres[:, :3] + radius[:, None] * unit, norm - radius, unit


def _apart_sq(q: NDArray[np.float64], centres: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return the squared distances (N, K) from q (N, dim) to centres (K, 2 or 3), m^2."""
    apart_sq = np.zeros((len(q), len(centres)))
    for axis in range(centres.shape[1]):
        offset = q[:, axis, None] - centres[None, :, axis]
        apart_sq += offset * offset
    return apart_sq


def _bounds(rows: NDArray[np.float64], pairs: Callable[..., Pairs]
            ) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Return each obstacle's centre (K, 2 or 3) and reach (K,): no surface point lies farther."""
    if pairs is _wall_pairs:
        along = rows[:, 2:4] - rows[:, 0:2]
        middle = 0.5 * (rows[:, 0:2] + rows[:, 2:4])
        return middle, 0.5 * np.linalg.norm(along, axis=1) + rows[:, 4]
    if pairs is _circle_pairs:
        return rows[:, :2], rows[:, 2]
    return rows[:, :3], rows[:, 3]


def obstacle_beta(distance: ArrayLike, jump: JumpFunction, clearance: float
                  ) -> NDArray[np.float64]:
    """beta_io = h(0, b_o**2 / 2, d_io**2 / 2) of distances d_io (any shape, m); 0 at contact."""
    d = np.asarray(distance, dtype=float)
    return np.where(d > 0.0, jump.h(0.5 * d * d, 0.0, 0.5 * clearance * clearance), 0.0)


def obstacle_terms(q: ArrayLike, surface: Surface, jump: JumpFunction, clearance: float,
                   sensing_radii: ArrayLike) -> NDArray[np.float64]:
    """
    Return sum_o betabar'_io (q_i - p_io) for every robot: its obstacles' part of eq. (13).

    q: (N, dim) positions; surface: :meth:`Obstacles.surface` of q; sensing_radii: (N,) R_i,
    m. Only obstacles nearer than R_i and than b_o count (betabar' vanishes at and beyond b_o).
    Returns (N, dim) in 1/m, the world frame. On or inside an obstacle (d_io <= 0), or nearer
    than the doubles can tell, the term is :data:`MAX_OBSTACLE_REPULSION` along the normal.
    """
    d = surface.distances
    radii = np.asarray(sensing_radii, dtype=float).reshape(-1, 1)
    near = (d < clearance) & (d < radii)
    outside = near & (d > 0.0)
    weight = np.zeros_like(d)
    with np.errstate(over='ignore', invalid='ignore'):
        weight[outside] = jump.ratio(0.5 * d[outside] ** 2, 0.0, 0.5 * clearance * clearance)
        terms = weight[..., None] * (np.asarray(q, dtype=float)[:, None, :] - surface.points)
    huge = (near & (d <= 0.0)) | (outside & ~np.all(np.isfinite(terms), axis=-1))
    terms[huge] = MAX_OBSTACLE_REPULSION * surface.normals[huge]
    summed: NDArray[np.float64] = terms.sum(axis=1)
    return summed


def log_obstacle_factor(q: ArrayLike, obstacles: Obstacles, jump: JumpFunction,
                        kappa: float) -> float:
    """
    Return -kappa * sum_{i, o} log beta_io, the obstacles' part of log(phi + 1), a float.

    Its gradient with respect to q_i is kappa times minus the sum of :func:`obstacle_terms`
    (every obstacle counted, whatever R_i): the check of the terms. +inf at a contact.
    """
    distances = obstacles.distances(q)
    with np.errstate(divide='ignore'):
        logs = np.log(obstacle_beta(distances, jump, obstacles.clearance))
    return -kappa * float(np.sum(logs))


class ObstacleSurfaces(Protocol):
    """
    What the law takes of obstacles (``core.maths.law.obstacle_sum``).

    count: obstacles a robot may have; clearance: b_o, m; ``surface(q)``: the
    :class:`Surface` of every one seen from positions q (N, dim); ``terms(q, jump, radii)``:
    the obstacles' part of eq. (13) (:func:`obstacle_terms`), computed as each kind best can:
    :class:`Obstacles` (a map) and :class:`HeardObstacles` (points heard) are two.
    """

    @property
    def count(self) -> int:
        """Return the number of obstacles M of a robot (columns of the surface)."""

    @property
    def clearance(self) -> float:
        """Return b_o, m."""

    def surface(self, q: ArrayLike) -> Surface:
        """Return the :class:`Surface` of the obstacles seen from positions q (N, dim)."""

    def terms(self, q: ArrayLike, jump: JumpFunction,
              sensing_radii: ArrayLike) -> NDArray[np.float64]:
        """Return :func:`obstacle_terms` of the obstacles at q (N, dim): (N, dim), 1/m."""


class Told(NamedTuple):
    """
    What the plant or relay tells each of N robots of M obstacles (``obstacles`` topic).

    listed: (N, M) whether obstacle o is told to robot i: its surface within R_i of the body's
    position; points: (N, M, dim) the surface point closest to the robot's control point, m;
    normals: (N, M, dim) the unit outward normals there (the surface is real, not grown).
    """

    listed: NDArray[np.bool_]
    points: NDArray[np.float64]
    normals: NDArray[np.float64]


def told_obstacles(obstacles: Obstacles, positions: ArrayLike, control_points: ArrayLike,
                   sensing_radii: ArrayLike) -> Told:
    """
    Return what every robot is told of ``obstacles``: the one rule of the plant and the relay.

    positions: (N, dim) the bodies' positions (a unicycle's centre), m; control_points:
    (N, dim) the points the law acts on (a unicycle's hand point), m; sensing_radii: (N,) R_i,
    m. An obstacle is listed for robot i when its surface is nearer than R_i to the position
    (the sensor is on the body); the point told is the real surface's point closest to the
    control point, with the outward normal there (docs/ros_interface.md, "Obstacles").
    """
    radii = np.asarray(sensing_radii, dtype=float).reshape(-1, 1)
    listed = obstacles.distances(positions) < radii
    closest = obstacles.surface(control_points)
    return Told(listed, closest.points, closest.normals)


def normal_quaternions(normals: ArrayLike) -> NDArray[np.float64]:
    """
    Return unit quaternions (..., 4) (x, y, z, w) whose rotation takes +x onto ``normals``.

    normals: (..., 2 or 3) unit vectors (a 2D one lies in the plane). The shortest rotation;
    for -x, the half turn about +z. Inverse: :func:`quaternion_normals`.
    """
    n = np.asarray(normals, dtype=float)
    full = np.zeros(n.shape[:-1] + (3,))
    full[..., :n.shape[-1]] = n
    quat = np.stack([np.zeros(full.shape[:-1]), -full[..., 2], full[..., 1],
                     1.0 + full[..., 0]], axis=-1)
    norm = np.linalg.norm(quat, axis=-1)
    back = norm < 1e-12
    quat[back] = (0.0, 0.0, 1.0, 0.0)
    norm[back] = 1.0
    result: NDArray[np.float64] = quat / norm[..., None]
    return result


def quaternion_normals(quaternions: ArrayLike, dim: int) -> NDArray[np.float64]:
    """
    Return the x axes (..., dim) of unit quaternions (..., 4) (x, y, z, w): heard normals.

    In 2D the axis's part in the plane, made unit again; one shorter than
    :data:`NORMAL_FLOOR` there comes back as zeros (no direction: the caller refuses it).
    """
    x, y, z, w = np.moveaxis(np.asarray(quaternions, dtype=float), -1, 0)
    axis = np.stack([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z),
                     2.0 * (x * z - w * y)], axis=-1)[..., :dim]
    norm = np.linalg.norm(axis, axis=-1, keepdims=True)
    usable = norm >= NORMAL_FLOOR
    result: NDArray[np.float64] = np.where(usable, axis / np.where(usable, norm, 1.0), 0.0)
    return result


@dataclass(frozen=True)
class HeardObstacles:
    """
    The obstacles K robots heard: per robot, surface points and outward normals (world frame).

    points: (K, M, dim) m and normals: (K, M, dim) unit, robot k's first ``counts[k]`` rows
    (the rest padding); counts: (K,); footprint: f, m, the radius about the control point
    that holds the body (``BodySettings.footprint``); clearance: b_o, m. Each point with its
    normal bounds its obstacle by the tangent half-space (a convex obstacle lies behind the
    tangent plane at any point of its surface), grown by f: robot k at q is
    ``d = (q - p) . n - f`` from it, the grown half-space's closest point is ``q - d n``.
    For the point the plant tells (closest to q) that is exactly the obstacle grown by f:
    the law's terms equal the map's (docs/ros_interface.md, "Obstacles").
    """

    points: NDArray[np.float64]
    normals: NDArray[np.float64]
    counts: NDArray[np.intp]
    footprint: float
    clearance: float

    @classmethod
    def from_lists(cls, heard: Sequence[Optional[Tuple[ArrayLike, ArrayLike]]], dim: int,
                   footprint: float, clearance: float) -> 'HeardObstacles':
        """
        Gather K robots' (points (m_k, >= dim), normals (m_k, >= dim)) heard; None: none.

        Padded to the largest m_k; the arrays are copies.
        """
        counts = np.array([0 if pair is None else len(np.asarray(pair[0])) for pair in heard],
                          dtype=np.intp)
        width = int(counts.max()) if len(counts) else 0
        points = np.zeros((len(heard), width, dim))
        normals = np.zeros((len(heard), width, dim))
        normals[..., 0] = 1.0
        for k, pair in enumerate(heard):
            if pair is not None and counts[k]:
                points[k, :counts[k]] = np.asarray(pair[0], dtype=float)[:, :dim]
                normals[k, :counts[k]] = np.asarray(pair[1], dtype=float)[:, :dim]
        return cls(points, normals, counts, float(footprint), float(clearance))

    @property
    def count(self) -> int:
        """Return M: the most obstacles any of the robots heard."""
        return int(self.points.shape[1])

    def surface(self, q: ArrayLike) -> Surface:
        """
        Return the :class:`Surface` of the grown half-spaces seen from q (K, dim), m.

        A padded entry is at distance +inf (never near), its point q itself.
        """
        q = np.asarray(q, dtype=float).reshape(len(self.points), -1)
        listed = np.arange(self.count)[None, :] < self.counts[:, None]
        offset = q[:, None, :] - self.points
        depth = np.einsum('kmd,kmd->km', offset, self.normals) - self.footprint
        distances = np.where(listed, depth, np.inf)
        closest = q[:, None, :] - np.where(listed, depth, 0.0)[..., None] * self.normals
        return Surface(closest, distances, self.normals)

    def terms(self, q: ArrayLike, jump: JumpFunction,
              sensing_radii: ArrayLike) -> NDArray[np.float64]:
        """Return :func:`obstacle_terms` of the K robots from what they heard: (K, dim), 1/m."""
        return obstacle_terms(q, self.surface(q), jump, self.clearance, sensing_radii)
