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
from typing import Any, Dict, List, Optional

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs.metrics import formation_errors, SETTLE_TOLERANCE
import numpy as np
from numpy.typing import ArrayLike, NDArray

STILL_TIME = 5.0
"""Seconds at the end of a run over which a stuck robot has hardly moved."""
STILL_SPEED = 0.01
"""m/s: a robot whose mean speed over :data:`STILL_TIME` is below this has hardly moved."""


def obstacle_clearances(q: ArrayLike, obstacles: Obstacles,
                        body_radius: float = 0.0) -> NDArray[np.float64]:
    """
    Return each body's gap to each obstacle's surface, footprint subtracted: (T, N, M) in m.

    q: (T, N, dim) positions; body_radius: the footprint about each position, m (0 for points).
    A gap at or below zero is a contact.
    """
    q = np.asarray(q, dtype=float)
    steps, n, dim = q.shape
    distances = obstacles.surface(q.reshape(-1, dim)).distances
    gaps: NDArray[np.float64] = distances.reshape(steps, n, obstacles.count) - body_radius
    return gaps


def obstacle_metrics(q: ArrayLike, obstacles: Obstacles,
                     body_radius: float = 0.0) -> Dict[str, Any]:
    """
    Return metrics.json's obstacle keys of a run.

    ``min_obstacle_clearance``: the smallest gap of any body to any obstacle's surface over the
    samples, m, footprint subtracted (None without obstacles); ``obstacle_contacts``: the
    contacts, each robot-obstacle pair counted once per stretch of samples in contact.
    """
    if obstacles.count == 0:
        return {'min_obstacle_clearance': None, 'obstacle_contacts': 0}
    gaps = obstacle_clearances(q, obstacles, body_radius)
    touching = gaps <= 0.0
    starts = touching[0].sum() + np.count_nonzero(touching[1:] & ~touching[:-1])
    return {'min_obstacle_clearance': float(gaps.min()), 'obstacle_contacts': int(starts)}


@dataclass(frozen=True)
class Stuck:
    """
    A robot that ended far from its place, hardly moving.

    robot: its 0-based index; position: (dim,) where it ended, m; error: its distance from its
    place there, m; nearest: the 0-based index of the obstacle nearest to it (None without
    obstacles) and gap: the distance to that obstacle's surface, m.
    """

    robot: int
    position: NDArray[np.float64]
    error: float
    nearest: Optional[int]
    gap: float

    def line(self) -> str:
        """Say in one line which robot is stuck, where, and what is nearest."""
        where = ', '.join(f'{value:.3g}' for value in self.position)
        text = f'robot {self.robot + 1} stuck at ({where}), {self.error:.3g} m from its place'
        if self.nearest is None:
            return text
        return f'{text}; nearest obstacle {self.nearest + 1}, {self.gap:.3g} m away'


def stuck_robots(t: ArrayLike, q: ArrayLike, q_desired: ArrayLike,
                 obstacles: Optional[Obstacles] = None,
                 tolerance: float = SETTLE_TOLERANCE, still_time: float = STILL_TIME,
                 still_speed: float = STILL_SPEED) -> List[Stuck]:
    """
    Return the robots stuck at the end of a run, in index order.

    A robot is stuck when it ends farther than ``tolerance`` (m) from its place and its path
    over the last ``still_time`` seconds is shorter than ``still_speed * still_time``. A run
    shorter than ``still_time`` has none.
    """
    times = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if len(times) < 2 or times[-1] - times[0] < still_time:
        return []
    window = times >= times[-1] - still_time
    steps = np.diff(q[window], axis=0)
    paths = np.sqrt(np.einsum('tnd,tnd->tn', steps, steps)).sum(axis=0)
    errors = formation_errors(q[-1], np.asarray(q_desired, dtype=float)[-1])
    found = np.nonzero((errors > tolerance) & (paths < still_speed * still_time))[0]
    gaps = (obstacle_clearances(q[-1:], obstacles)[0] if obstacles and obstacles.count
            else None)
    stuck = []
    for robot in found.tolist():
        nearest = None if gaps is None else int(np.argmin(gaps[robot]))
        gap = math.inf if gaps is None or nearest is None else float(gaps[robot, nearest])
        stuck.append(Stuck(robot, q[-1, robot].copy(), float(errors[robot]), nearest, gap))
    return stuck
