# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Bodies that are not q' = u: actuator lag, acceleration limits, noisy and late sensing.

The paper's theorem assumes the ideal body of eq. (1): the velocity is the command, at once, and
every robot senses exact positions without delay. A real base lags its command, cannot
accelerate without limit, and its localisation is noisy and late. These settings (beyond the
paper: it proves nothing for them) describe such bodies for the one plant model
(``core.plant``), so that ``formation_sim --dt`` and the plant node both have them. Every value
0 is the ideal body, and then the model does exactly what it did without them.
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class Imperfections:
    """
    What separates the bodies from the ideal q' = u (``plant.*``; all 0: ideal).

    actuator_lag: time constant tau of the first-order lag v' = (u - v) / tau between the
    admitted command u and the body's velocity v, s; max_acceleration: limit on |v'| per
    world component for points, on v' and w' for unicycles, m/s^2 (rad/s^2 for w); pose_noise:
    standard deviation of Gaussian noise on every sensed position, m; state_delay: a state
    reaches the robots this much after it happened, s; seed: seed of the noise (start.seed).
    """

    actuator_lag: float = 0.0
    max_acceleration: float = 0.0
    pose_noise: float = 0.0
    state_delay: float = 0.0
    seed: int = 0

    @property
    def ideal_body(self) -> bool:
        """Tell whether the body's velocity is its command at once (no lag, no limit)."""
        return self.actuator_lag == 0.0 and self.max_acceleration == 0.0

    @property
    def ideal_sensing(self) -> bool:
        """Tell whether every robot senses exact positions at once."""
        return self.pose_noise == 0.0 and self.state_delay == 0.0

    @property
    def is_ideal(self) -> bool:
        """Tell whether this is the paper's body, q' = u sensed exactly and at once."""
        return self.ideal_body and self.ideal_sensing


IDEAL = Imperfections()
