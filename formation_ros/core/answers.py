# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
How many states a robot answers: at most about one per state period, whatever arrives.

A robot answers each new state (pose and neighbours) with a command. Whoever can publish on
its ``pose`` could make it answer as often as they publish, and the robot would pass the flood
on to ``cmd_vel``. :class:`AnswerBudget` is a token bucket on the robot's own clock (simulated
time with ``use_sim_time``, where the plant sets the pace even when it lags or steps in
lockstep; wall-clock time with the relay): it gains ``1 + RATE_MARGIN`` answers per expected
state period, holds at most :data:`BURST`, and each answer spends one. Over any stretch of T s
a robot then answers at most ``(1 + RATE_MARGIN) T / period + BURST`` states.
"""

from dataclasses import dataclass
from typing import Optional

RATE_MARGIN = 0.1
"""Answers per period beyond one: a relay on another host whose clock runs a little fast, or a
relay cycle late and the next on time, is not a flood."""
BURST = 3.0
"""Answers that may follow each other at once: a pose that arrives before the /clock tick of
its state, or states bunched by the network."""


@dataclass
class AnswerBudget:
    """
    Token bucket of answers: ``period_ns`` the expected time between states (robot's clock).

    tokens: answers that may be sent now; last_ns: the clock when they were counted.
    """

    period_ns: int
    tokens: float = BURST
    last_ns: Optional[int] = None

    def refill(self, now_ns: int) -> None:
        """Add what the time since the last count earns; a clock that went back restarts it."""
        if self.last_ns is not None and now_ns > self.last_ns:
            earned = (now_ns - self.last_ns) * (1.0 + RATE_MARGIN) / self.period_ns
            self.tokens = min(BURST, self.tokens + earned)
        self.last_ns = now_ns

    def take(self, now_ns: int) -> bool:
        """Spend one answer at clock ``now_ns`` (ns) if there is one; False if none is left."""
        self.refill(now_ns)
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True
