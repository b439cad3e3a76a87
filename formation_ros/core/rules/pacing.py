# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
How many steps keep a run's simulated time at wall-clock time times a factor (no ROS).

The plant (``plant.realtime_factor``) and the world (``world.realtime_factor``) pace their runs
by one :class:`Pacer`, started when their clock starts. A world asks it at each tick of its
timer how many engine steps are due (:meth:`Pacer.due`): the steps it was given at the start
and the steps due since then make simulated time follow the factor x wall time. A world that
falls further behind than one call may catch up (the engine steps slower than asked: too many
robots for the machine) runs the steps it can catch up and lets the rest go, counted: it then
runs slower than asked, as Gazebo does, rather than in bursts that would make its clock jump. A
lockstep plant asks how far its run is ahead of the wall clock (:meth:`Pacer.ahead_ns`) and
steps once it is not. Times are integer ns; wall-clock times come from a monotonic clock.
"""

from typing import Optional

from formation_ros.core.maths.units import NS_PER_S


class Pacer:
    """
    The steps due to keep simulated time at wall time x ``factor``.

    step_ns: the engine's step, ns of simulated time (> 0); factor: simulated s per wall s
    (> 0); catch_up_ns: the most simulated time one call asks for, ns (at least one step).
    """

    def __init__(self, step_ns: int, factor: float, catch_up_ns: int) -> None:
        """Pace steps of ``step_ns`` at ``factor``; start with :meth:`start`."""
        self.step_ns = int(step_ns)
        self.factor = float(factor)
        self.catch_up_steps = max(1, int(catch_up_ns) // self.step_ns)
        self.started_ns: Optional[int] = None
        self.started_steps = 0
        self._anchor_ns = 0
        self._anchor_steps = 0
        self.falls = 0
        """Calls that found the world further behind than it may catch up at once."""
        self.dropped_steps = 0
        """Steps that were due but let go (simulated time the world lost on the wall clock)."""

    def start(self, wall_ns: int, steps: int = 0) -> None:
        """Start pacing at wall-clock ``wall_ns`` with the engine at ``steps``."""
        self.started_ns = self._anchor_ns = int(wall_ns)
        self.started_steps = self._anchor_steps = int(steps)

    def due(self, wall_ns: int, steps: int) -> int:
        """
        Return how many steps to run now (>= 0), at wall-clock ``wall_ns``, engine at ``steps``.

        At most the catch-up's worth; steps due beyond it are let go (:attr:`dropped_steps`).
        """
        if self.started_ns is None:
            raise RuntimeError('Pacer.due before Pacer.start')
        simulated_ns = (int(wall_ns) - self._anchor_ns) * self.factor
        target = self._anchor_steps + int(simulated_ns // self.step_ns)
        behind = target - int(steps)
        if behind > self.catch_up_steps:
            let_go = behind - self.catch_up_steps
            self.falls += 1
            self.dropped_steps += let_go
            self._anchor_steps -= let_go
            behind = self.catch_up_steps
        return max(0, behind)

    @property
    def step_period_s(self) -> float:
        """Return the wall-clock time of one step at the factor, s (a free plant's tick)."""
        return self.step_ns / NS_PER_S / self.factor

    def ahead_ns(self, wall_ns: int, steps: int) -> float:
        """
        Return how far the run at ``steps`` is ahead of wall-clock ``wall_ns`` x factor, ns.

        In wall-clock ns: > 0 is how long to wait before the next step keeps the pace, <= 0 a
        step is due. Steps that are let go (:meth:`due`) do not count here.
        """
        if self.started_ns is None:
            raise RuntimeError('Pacer.ahead_ns before Pacer.start')
        simulated_ns = (int(steps) - self.started_steps) * self.step_ns
        return simulated_ns / self.factor - (int(wall_ns) - self.started_ns)

    def wall_s(self, wall_ns: int) -> float:
        """Return the wall-clock time since :meth:`start` at ``wall_ns``, s (0.0 before)."""
        if self.started_ns is None:
            return 0.0
        return (int(wall_ns) - self.started_ns) / NS_PER_S

    def achieved(self, wall_ns: int, steps: int) -> float:
        """Return the simulated time per wall time since :meth:`start` (0.0 before any)."""
        if self.started_ns is None or wall_ns <= self.started_ns:
            return 0.0
        simulated = (int(steps) - self.started_steps) * self.step_ns
        return simulated / (int(wall_ns) - self.started_ns)

    @property
    def dropped_s(self) -> float:
        """Return the simulated time let go so far, s."""
        return self.dropped_steps * self.step_ns / NS_PER_S
