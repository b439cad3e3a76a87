# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Wheel-encoder odometry of differential-drive bases, as a base's controller integrates it.

Each engine step the wheels' measured speeds (left, right, rad/s) become (v, w) by the model's
own rolling-without-slip relation (:meth:`DiffDrive.body_rates`), held over the step and
integrated exactly along the arc (:func:`formation_ros.core.unicycle.zoh_step`). The estimate
starts at the true start pose and drifts from the truth wherever a wheel slips or the base is
pushed: what real odometry does.
"""

from typing import Tuple

from formation_ros.core.unicycle import zoh_step
from formation_ros.physics.diff_drive import DiffDrive
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]


class WheelOdometry:
    """The odometry of N bases: positions (N, 2) in m, headings (N,) in rad, (v, w) (N, 2)."""

    def __init__(self, model: DiffDrive, positions: Float, headings: Float):
        """Start at the given poses, at rest."""
        self.model = model
        self.positions = np.array(positions, dtype=float)
        self.headings = np.array(headings, dtype=float)
        self.rates = np.zeros((len(self.positions), 2))

    def advance(self, wheel_speeds: Float, dt: float) -> None:
        """Integrate wheel speeds (N, 2) (left, right; rad/s) held over dt s."""
        self.rates = self.model.body_rates(wheel_speeds)
        self.positions, self.headings = zoh_step(self.positions, self.headings, self.rates, dt)

    def pose(self) -> Tuple[Float, Float]:
        """Return copies of the estimated positions (N, 2) and headings (N,)."""
        return self.positions.copy(), self.headings.copy()
