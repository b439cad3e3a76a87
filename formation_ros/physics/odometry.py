# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Wheel-encoder odometry of differential-drive bases, as a base's controller integrates it.

Every odometry period (:data:`ODOMETRY_PERIOD`, a whole number of engine steps) the wheels'
encoder angles (left, right, rad) are read; their increments since the last reading, over the
time between, are the wheels' mean speeds, which the model's rolling-without-slip relation
(:meth:`DiffDrive.body_rates`) turns into (v, w), integrated exactly along the arc
(:func:`formation_ros.core.maths.unicycle.zoh_step`), as ``diff_drive_controller`` does from its
wheels' positions. The estimate starts at the true start pose and drifts from the truth
wherever a wheel slips or the base is pushed: what real odometry does.
"""

from typing import Tuple

from formation_ros.core.maths.unicycle import zoh_step
from formation_ros.physics.diff_drive import DiffDrive
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]
ODOMETRY_PERIOD = 0.01
"""Time between two odometry updates, s (a base controller's 100 Hz)."""


class WheelOdometry:
    """The odometry of N bases: positions (N, 2) in m, headings (N,) in rad, (v, w) (N, 2)."""

    def __init__(self, model: DiffDrive, positions: Float, headings: Float, angles: Float):
        """Start at the given poses, at rest, with the wheels' angles (N, 2), rad."""
        self.model = model
        self.positions = np.array(positions, dtype=float)
        self.headings = np.array(headings, dtype=float)
        self.angles = np.array(angles, dtype=float)
        self.rates = np.zeros((len(self.positions), 2))

    def advance(self, angles: Float, dt: float) -> None:
        """Take the wheels' angles (N, 2) (left, right; rad) dt s after the last reading."""
        self.rates = self.model.body_rates((angles - self.angles) / dt)
        self.angles = np.array(angles, dtype=float)
        self.positions, self.headings = zoh_step(self.positions, self.headings, self.rates, dt)

    def pose(self) -> Tuple[Float, Float]:
        """Return copies of the estimated positions (N, 2) and headings (N,)."""
        return self.positions.copy(), self.headings.copy()
