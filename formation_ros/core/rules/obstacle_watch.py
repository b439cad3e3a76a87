# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The plant's watch on its bodies and the obstacles: the smallest gap, each contact, once.

Beyond the paper (docs/equations.md, "Obstacles"): the law keeps the ideal body off every
obstacle; the plant measures what its bodies did. :class:`ObstacleWatch` takes every step's
real body positions against the real obstacles (the map as given, not grown), the body's
radius subtracted (``obstacle_metrics``' gap), and counts a contact once per robot-obstacle pair
per stretch of steps in contact: ``plant_stats.json`` (``obstacle_contacts``,
``min_obstacle_gap``), ``/diagnostics`` and the final summary (docs/ros_interface.md).
"""

import math
from typing import Dict, List, Union

from formation_ros.core.maths.obstacles import Obstacles
import numpy as np
from numpy.typing import ArrayLike


class ObstacleWatch:
    """
    Contacts of N bodies with the obstacles of a map over a run.

    obstacles: the real map; body_radius: ``body.radius``, m (0 for points).
    """

    def __init__(self, obstacles: Obstacles, body_radius: float) -> None:
        """Start with no contact and no gap measured."""
        self.obstacles = obstacles
        self.body_radius = float(body_radius)
        self.labels = obstacles.labels()
        self.touching = np.zeros((0, obstacles.count), dtype=bool)
        self.contacts = 0
        """Contacts counted: robot-obstacle pairs that came into contact."""
        self.min_gap = math.inf
        """The smallest gap of any body to any obstacle's surface so far, m."""

    def step(self, q: ArrayLike, t: float) -> List[str]:
        """
        Take the bodies' positions q (N, dim) in m at time t (s); return the new contacts' lines.

        A line for each robot-obstacle pair that comes into contact (its gap <= 0): logged
        once, counted once until the pair is apart again.
        """
        gaps = self.obstacles.distances(q) - self.body_radius
        if gaps.size:
            self.min_gap = min(self.min_gap, float(gaps.min()))
        touching = gaps <= 0.0
        before = (self.touching if self.touching.shape == touching.shape
                  else np.zeros_like(touching))
        new = np.argwhere(touching & ~before)
        self.touching = touching
        self.contacts += len(new)
        return [f'robot {i + 1} touches {self.labels[o]} at t = {t:.3f} s (gap '
                f'{gaps[i, o]:.3g} m; body.radius {self.body_radius:g} m)'
                for i, o in new.tolist()]

    def record(self) -> Dict[str, Union[int, float, None]]:
        """Return the keys of ``plant_stats.json``: ``obstacle_contacts``, ``min_obstacle_gap``."""
        return {'obstacle_contacts': self.contacts,
                'min_obstacle_gap': None if math.isinf(self.min_gap) else self.min_gap}

    def values(self) -> Dict[str, Union[int, float, str]]:
        """Return the diagnostics values: contacts and the smallest gap."""
        return {'obstacle contacts': self.contacts,
                'min obstacle gap [m]': 'none' if math.isinf(self.min_gap) else self.min_gap}

    def summary(self) -> str:
        """Return the part of the plant's summary line about the obstacles."""
        gap = 'none' if math.isinf(self.min_gap) else f'{self.min_gap:.4g} m'
        return f'{self.contacts} obstacle contacts, min obstacle gap {gap}'
