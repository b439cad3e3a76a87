# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a sampled run did near obstacles: the closest approach, the contacts, the stuck robots.

Beyond the paper (docs/equations.md, "Obstacles"): the law keeps the ideal body off every
obstacle but may leave a robot stuck behind one. Inputs as in ``core.runs.metrics``: t (T,) in
s, q and q_desired (T, N, dim) in m; positions are the bodies' (a unicycle's axle centre).
"""

from dataclasses import dataclass
import math
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs.metrics import formation_errors, SETTLE_TOLERANCE
import numpy as np
from numpy.typing import ArrayLike, NDArray

STILL_TIME = 5.0
"""Seconds at the end of a run over which a stuck robot has not moved on."""
STILL_SPEED = 0.05
"""m/s: a robot that stayed within this times :data:`STILL_TIME` (0.25 m) of where it ended
and got no nearer its place has not moved on: a body held at an obstacle trembles on the spot
by up to tenths of a metre (measured on the physics world: 0.08 to 0.3 m)."""
BLOCK_DISTANCES = 2_000_000
"""Robot-obstacle distances measured at once by :func:`obstacle_metrics` (about 50 MB)."""
NEAR_MARGIN = 1e-9
"""The closest pair measured near is the closest of all when it is this much (relative)
nearer than how near :func:`obstacle_metrics` measures: rounding cannot have left out a
nearer one."""


def _blocks(steps: int, robots: int, count: int) -> Iterator[slice]:
    """Slices of samples holding at most :data:`BLOCK_DISTANCES` robot-obstacle distances."""
    size = max(1, BLOCK_DISTANCES // max(1, robots * count))
    for first in range(0, steps, size):
        yield slice(first, min(first + size, steps))


def obstacle_clearances(q: ArrayLike, obstacles: Obstacles,
                        body_radius: float = 0.0) -> NDArray[np.float64]:
    """
    Return each body's gap to each obstacle's surface, footprint subtracted: (T, N, M) in m.

    q: (T, N, dim) positions; body_radius: the footprint about each position, m (0 for points).
    A gap at or below zero is a contact.
    """
    q = np.asarray(q, dtype=float)
    steps, n, dim = q.shape
    distances = obstacles.distances(q.reshape(-1, dim))
    gaps: NDArray[np.float64] = distances.reshape(steps, n, obstacles.count) - body_radius
    return gaps


def obstacle_metrics(q: ArrayLike, obstacles: Optional[Obstacles],
                     body_radius: float = 0.0) -> Dict[str, Any]:
    """
    Return metrics.json's obstacle keys of a run.

    ``min_obstacle_clearance``: the smallest gap of any body to any obstacle's surface over the
    samples, m, footprint subtracted (None without obstacles); ``obstacle_contacts``: the
    contacts, each robot-obstacle pair counted once per stretch of samples in contact. Only
    the pairs that can be within max(b_o, 2 body_radius) are measured (``Obstacles.nearby``),
    a block of samples at a time (:data:`BLOCK_DISTANCES`): every contact is among them, and so
    is the closest approach unless no body came that near (then every pair is measured). The
    numbers are those of every pair's gap (:func:`obstacle_clearances`).
    """
    if obstacles is None or obstacles.count == 0:
        return {'min_obstacle_clearance': None, 'obstacle_contacts': 0}
    q = np.asarray(q, dtype=float)
    steps, robots, dim = q.shape
    pairs = robots * obstacles.count
    within = max(obstacles.clearance, 2.0 * body_radius)
    nearest, smallest = math.inf, math.inf
    touching = [np.zeros(0, dtype=np.int64)]
    for block in _blocks(steps, robots, obstacles.count):
        which, kinds, distances = obstacles.nearby(q[block].reshape(-1, dim), within)
        if not len(distances):
            continue
        gaps = distances - body_radius
        nearest = min(nearest, float(distances.min()))
        smallest = min(smallest, float(gaps.min()))
        contact = gaps <= 0.0
        sample = block.start + which[contact] // robots
        touching.append(sample * pairs + (which[contact] % robots) * obstacles.count
                        + kinds[contact])
    if not nearest < within * (1.0 - NEAR_MARGIN):
        smallest = min(float(obstacle_clearances(q[block], obstacles, body_radius).min())
                       for block in _blocks(steps, robots, obstacles.count))
    keys = np.concatenate(touching)
    starts = int(np.count_nonzero(~np.isin(keys - pairs, keys)))
    return {'min_obstacle_clearance': smallest, 'obstacle_contacts': starts}


@dataclass(frozen=True)
class Stuck:
    """
    A robot that ended far from its place, hardly moving.

    robot: its 0-based index; position: (dim,) where it ended (its body: a unicycle's axle
    centre), m; error: its control point's distance from its place there, m; nearest: the
    0-based index of the obstacle nearest to it (None without obstacles), obstacle: that
    obstacle's name (``Obstacles.labels``) and gap: the distance from its footprint to that
    obstacle's surface, m (inf without obstacles).
    """

    robot: int
    position: NDArray[np.float64]
    error: float
    nearest: Optional[int]
    gap: float
    obstacle: Optional[str] = None

    def line(self) -> str:
        """Say in one line which robot is stuck, where, and what is nearest."""
        record = self.record()
        if self.nearest is not None and self.obstacle is None:
            record['nearest_obstacle'] = f'obstacle {self.nearest + 1}'
        return stuck_line(record)

    def record(self) -> Dict[str, Any]:
        """Return the robot as metrics.json keeps it (robot numbered from 1)."""
        return {'robot': self.robot + 1, 'position': [float(x) for x in self.position],
                'error': self.error, 'nearest_obstacle': self.obstacle,
                'obstacle_gap': None if math.isinf(self.gap) else self.gap}


def stuck_line(record: Mapping[str, Any]) -> str:
    """Return :meth:`Stuck.line` of a robot as :meth:`Stuck.record` keeps it."""
    name, gap = record.get('nearest_obstacle'), record.get('obstacle_gap')
    where = ', '.join(f'{float(value):.3g}' for value in record['position'])
    text = (f"robot {record['robot']} stuck at ({where}), {float(record['error']):.3g} m from "
            'its place')
    if name is None:
        return text
    distance = 'at an unknown distance' if gap is None else f'{float(gap):.3g} m away'
    return f'{text}; nearest {name}, {distance}'


def stuck_robots(t: ArrayLike, q: ArrayLike, q_desired: ArrayLike,
                 obstacles: Optional[Obstacles] = None,
                 tolerance: float = SETTLE_TOLERANCE, still_time: float = STILL_TIME,
                 still_speed: float = STILL_SPEED, bodies: Optional[ArrayLike] = None,
                 body_radius: float = 0.0) -> List[Stuck]:
    """
    Return the robots stuck at the end of a run, in index order.

    A robot is stuck when its control point ``q`` ends farther than ``tolerance`` (m) from its
    place ``q_desired``, stayed within ``still_speed * still_time`` of where it ended over the
    last ``still_time`` seconds and got no nearer its place over them than ``tolerance`` (a
    robot pressed against an obstacle may tremble on the spot, which a path length would count
    as moving; one still closing in slowly is not stuck). A run shorter than ``still_time``
    has none. bodies: (T, N, dim) the bodies' positions when they are not the control points
    (unicycles' axle centres): whether a robot stays is told by its body (a base turning on the
    spot sweeps its hand point round it), and its footprint ``body_radius`` (m) is measured to
    the nearest obstacle.
    """
    times = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if len(times) < 2 or times[-1] - times[0] < still_time:
        return []
    window = times >= times[-1] - still_time
    where = q if bodies is None else np.asarray(bodies, dtype=float)
    wander = formation_errors(where[window], where[-1][None]).max(axis=0)
    desired = np.asarray(q_desired, dtype=float)
    errors = formation_errors(q[-1], desired[-1])
    first = int(np.argmax(window))
    closed = formation_errors(q[first], desired[first]) - errors
    found = np.nonzero((errors > tolerance) & (wander < still_speed * still_time)
                       & (closed < tolerance))[0]
    places = q[-1] if bodies is None else np.asarray(bodies, dtype=float)[-1]
    gaps = (obstacle_clearances(places[None], obstacles, body_radius)[0]
            if obstacles is not None and obstacles.count and len(found) else None)
    labels: Sequence[str] = obstacles.labels() if obstacles is not None else ()
    stuck = []
    for robot in found.tolist():
        nearest = None if gaps is None else int(np.argmin(gaps[robot]))
        gap = math.inf if gaps is None or nearest is None else float(gaps[robot, nearest])
        stuck.append(Stuck(robot, places[robot].copy(), float(errors[robot]), nearest, gap,
                           None if nearest is None else labels[nearest]))
    return stuck
