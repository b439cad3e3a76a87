# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Contacts of robots with robots and with obstacles, from MuJoCo's collision detection.

:class:`ContactLog` is given, step after step, the robot pairs MuJoCo finds in contact (geoms
of two different robots at distance <= 0) and the robots' positions. A pair that touches when
it was apart is a contact event; it stays in contact until its positions are more than
``release`` m apart (two footprints' radii and :data:`RELEASE_GAP`): two bases pushing against
each other, whose contact MuJoCo finds at some steps and not at others, make one event; two
that touch, part and touch again make two. :class:`ClosestApproach` keeps the closest approach
of the robots' positions over a run.

Obstacles (``obstacles.*``, beyond the paper) are counted apart: :class:`ObstacleContactLog`
takes the robot-obstacle pairs MuJoCo finds in contact, one event per pair until the body's
gap to that obstacle's surface (``Obstacles.surface`` from its position, its footprint radius
subtracted) is more than :data:`RELEASE_GAP` again; :class:`ObstacleApproach` keeps the
smallest such gap over a run.
"""

from dataclasses import dataclass
from typing import List, Tuple

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.maths.pairs import closest_pair, pairs_within, squared_norms
from formation_ros.core.maths.units import NS_PER_S
import numpy as np
from numpy.typing import NDArray

BRUTE_FORCE_UP_TO = 64
"""Teams up to this size compare every pair for the closest approach (faster than a grid)."""
RELEASE_GAP = 0.01
"""Two robots in contact have parted once their footprints are this far apart, m."""


@dataclass(frozen=True)
class ContactEvent:
    """Robots i < j (1-based) came into contact at t_ns (ns of simulated time)."""

    i: int
    j: int
    t_ns: int

    @property
    def t(self) -> float:
        """Return the time of the contact, s."""
        return self.t_ns / NS_PER_S


class ContactLog:
    """The contact events between N robots and the pairs in contact now."""

    def __init__(self, num_robots: int, release: float):
        """Start with no contact; pairs in contact part beyond ``release`` m."""
        self.num_robots = int(num_robots)
        self.release = float(release)
        self.events: List[ContactEvent] = []
        self.touching: NDArray[np.int64] = np.zeros(0, dtype=np.int64)

    @property
    def count(self) -> int:
        """Return the number of contact events so far."""
        return len(self.events)

    def update(self, first: NDArray[np.intp], second: NDArray[np.intp],
               positions: NDArray[np.float64], t_ns: int) -> List[ContactEvent]:
        """
        Take the robots (0-based) in contact now, first[k] with second[k], and positions (N, dim).

        Pairs may repeat and come in either order. Returns the new events.
        """
        n = self.num_robots
        low, high = np.minimum(first, second), np.maximum(first, second)
        keys = np.unique(low.astype(np.int64) * n + high)
        fresh = np.setdiff1d(keys, self.touching, assume_unique=True)
        held = self.touching
        if len(held):
            gaps = squared_norms(positions[held // n] - positions[held % n])
            held = held[gaps <= self.release ** 2]
        self.touching = np.union1d(held, keys)
        new = [ContactEvent(int(key // n) + 1, int(key % n) + 1, int(t_ns)) for key in fresh]
        self.events.extend(new)
        return new


class ClosestApproach:
    """
    The smallest distance between two of N moving points over a run, m, and its pair and time.

    Every step compares only the candidate pairs: those within ``reach + 2 skin`` of each other
    when the list was made, remade (with an exact closest pair of the whole team) once some
    point has moved ``skin`` / 2 since. So the result is exact whenever the closest approach
    is below ``reach + skin`` (m); above that it is the smallest of the exact values at the
    remakes. reach: the distance that matters (two footprints' radii), m.
    """

    def __init__(self, points: NDArray[np.float64], reach: float, skin: float = 0.5):
        """Start with the distances of ``points`` (N, dim)."""
        self.radius = float(reach) + 2.0 * float(skin)
        self.skin = float(skin)
        self.distance = float('inf')
        self.pair = (-1, -1)
        self.t_ns = 0
        self._remake(np.asarray(points, dtype=float), 0)

    def _remake(self, points: NDArray[np.float64], t_ns: int) -> None:
        self.anchor = points.copy()
        self.candidates = pairs_within(points, self.radius)
        distance, i, j = closest_distance(points)
        self._keep(distance, i, j, t_ns)

    def _keep(self, distance: float, i: int, j: int, t_ns: int) -> None:
        if distance < self.distance:
            self.distance, self.pair, self.t_ns = distance, (i, j), int(t_ns)

    def update(self, points: NDArray[np.float64], t_ns: int) -> None:
        """Take the points (N, dim) at t_ns."""
        moved = squared_norms(points - self.anchor)
        if float(np.max(moved, initial=0.0)) > (0.5 * self.skin) ** 2:
            self._remake(points, t_ns)
            return
        if not len(self.candidates):
            return
        first, second = self.candidates[:, 0], self.candidates[:, 1]
        squared = squared_norms(points[first] - points[second])
        k = int(np.argmin(squared))
        self._keep(float(np.sqrt(squared[k])), int(first[k]), int(second[k]), t_ns)


def closest_distance(points: NDArray[np.float64]) -> Tuple[float, int, int]:
    """
    Return the smallest distance between two of ``points`` (N, dim), m, and the pair (0-based).

    inf and (-1, -1) for fewer than two points.
    """
    n = len(points)
    if n < 2:
        return float('inf'), -1, -1
    if n > BRUTE_FORCE_UP_TO:
        distance, i, j = closest_pair(points)
        return float(distance), int(i), int(j)
    gaps = points[:, None, :] - points[None, :, :]
    squared = np.einsum('ijk,ijk->ij', gaps, gaps)
    squared[np.diag_indices(n)] = np.inf
    flat = int(np.argmin(squared))
    i, j = divmod(flat, n)
    return float(np.sqrt(squared[i, j])), min(i, j), max(i, j)


@dataclass(frozen=True)
class ObstacleContactEvent:
    """Robot ``robot`` (1-based) touched obstacle ``obstacle`` (0-based) at t_ns (simulated)."""

    robot: int
    obstacle: int
    t_ns: int

    @property
    def t(self) -> float:
        """Return the time of the contact, s."""
        return self.t_ns / NS_PER_S


def obstacle_gaps(obstacles: Obstacles, positions: NDArray[np.float64],
                  footprint: float) -> NDArray[np.float64]:
    """Return each body's gap to each obstacle's surface (N, M), m: footprint radius subtracted."""
    gaps: NDArray[np.float64] = obstacles.distances(positions) - footprint
    return gaps


class ObstacleContactLog:
    """
    The contact events between N robots and the M obstacles, and the pairs in contact now.

    footprint: the bodies' footprint radius, m; a pair in contact has parted once the body's
    gap to the obstacle is more than :data:`RELEASE_GAP`.
    """

    def __init__(self, obstacles: Obstacles, footprint: float):
        """Start with no contact."""
        self.obstacles = obstacles
        self.footprint = float(footprint)
        self.events: List[ObstacleContactEvent] = []
        self.touching: NDArray[np.int64] = np.zeros(0, dtype=np.int64)

    @property
    def count(self) -> int:
        """Return the number of contact events so far."""
        return len(self.events)

    def update(self, robots: NDArray[np.intp], obstacles: NDArray[np.intp],
               positions: NDArray[np.float64], t_ns: int) -> List[ObstacleContactEvent]:
        """
        Take the pairs in contact now, robots[k] (0-based) with obstacles[k] (0-based).

        positions: (N, dim), m. Pairs may repeat. Returns the new events.
        """
        m = self.obstacles.count
        keys = np.unique(robots.astype(np.int64) * m + obstacles)
        fresh = np.setdiff1d(keys, self.touching, assume_unique=True)
        held = self.touching
        if len(held):
            gaps = obstacle_gaps(self.obstacles, positions[held // m], self.footprint)
            held = held[gaps[np.arange(len(held)), held % m] <= RELEASE_GAP]
        self.touching = np.union1d(held, keys)
        new = [ObstacleContactEvent(int(key // m) + 1, int(key % m), int(t_ns))
               for key in fresh]
        self.events.extend(new)
        return new


class ObstacleApproach:
    """
    The smallest gap of a body to an obstacle's surface over a run, m, its pair and time.

    The gap is :func:`obstacle_gaps`'s (footprint subtracted; < 0: the body overlapped the
    obstacle). Only the candidate pairs are looked at, those with a gap below ``skin`` when the
    list was made; the list is remade (every pair) once some body has moved ``skin`` / 2 since.
    A candidate's gap is computed again only when it could have fallen below the smallest so
    far: a gap changes by at most as much as the body moves (a distance to a convex set), so a
    pair whose last gap less the body's move since is still above the smallest cannot be
    below it. So the result is exact whenever the smallest gap is below ``skin`` / 2 (m);
    above that it is the smallest of the exact values at the remakes.
    """

    def __init__(self, obstacles: Obstacles, footprint: float,
                 points: NDArray[np.float64], skin: float = 0.5):
        """Start with the gaps of ``points`` (N, dim)."""
        self.obstacles = obstacles
        self.footprint = float(footprint)
        self.skin = float(skin)
        self.gap = float('inf')
        self.pair = (-1, -1)
        self.t_ns = 0
        self.candidates: NDArray[np.intp] = np.zeros((0, 2), dtype=np.intp)
        self.known: NDArray[np.float64] = np.zeros(0)
        """(K,) each candidate's gap when last computed, m."""
        self.seen: NDArray[np.float64] = np.zeros((0, np.shape(points)[1]))
        """(K, dim) where its body was then, m."""
        self._remake(np.asarray(points, dtype=float), 0)

    def _remake(self, points: NDArray[np.float64], t_ns: int) -> None:
        self.anchor = points.copy()
        if self.obstacles.count == 0:
            return
        gaps = obstacle_gaps(self.obstacles, points, self.footprint)
        self.candidates = np.argwhere(gaps < self.skin)
        self.known = gaps[self.candidates[:, 0], self.candidates[:, 1]]
        self.seen = points[self.candidates[:, 0]]
        robot, obstacle = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
        self._keep(float(gaps[robot, obstacle]), int(robot), int(obstacle), t_ns)

    def _keep(self, gap: float, robot: int, obstacle: int, t_ns: int) -> None:
        if gap < self.gap:
            self.gap, self.pair, self.t_ns = gap, (robot, obstacle), int(t_ns)

    def update(self, points: NDArray[np.float64], t_ns: int) -> None:
        """Take the points (N, dim) at t_ns."""
        moved = squared_norms(points - self.anchor)
        if float(np.max(moved, initial=0.0)) > (0.5 * self.skin) ** 2:
            self._remake(points, t_ns)
            return
        if not len(self.candidates):
            return
        here = points[self.candidates[:, 0]]
        due = np.flatnonzero(self.known - np.sqrt(squared_norms(here - self.seen)) < self.gap)
        if not len(due):
            return
        pairs = self.candidates[due]
        robots, rows = np.unique(pairs[:, 0], return_inverse=True)
        gaps = obstacle_gaps(self.obstacles, points[robots], self.footprint)
        pair_gaps = gaps[rows, pairs[:, 1]]
        self.known[due], self.seen[due] = pair_gaps, here[due]
        k = int(np.argmin(pair_gaps))
        self._keep(float(pair_gaps[k]), int(pairs[k, 0]), int(pairs[k, 1]), t_ns)
