# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Work that a callback asks for and a timer does: a one-shot timer that callbacks arm.

A subscription callback only stores what arrived and calls :meth:`Wake.arm`; the node's work (a
robot's answer to a new state, the lockstep plant's next step) then runs in the timer's callback,
once, as soon as the executor gets to it (or after a delay), however many callbacks armed it in
between. This keeps "callbacks store, timers act" without a timer polling for news: rclpy's
EventsExecutor has no guard conditions, but it runs a reset timer, and a cancelled timer costs
nothing. The answer then follows the message at once instead of at the next tick of a
free-running timer (half a control period later on average).
"""

from typing import Callable

from formation_ros.core.units import NS_PER_S
from rclpy.clock import Clock
from rclpy.node import Node


class Wake:
    """A cancelled timer of ``node`` that :meth:`arm` starts: ``action`` runs once per arming."""

    def __init__(self, node: Node, action: Callable[[], None], clock: Clock) -> None:
        """Create the timer on ``clock`` (the steady clock: it must run when /clock stops)."""
        self._action = action
        self._delay_ns = 0
        self._timer = node.create_timer(0.0, self._fire, clock=clock, autostart=False)

    def arm(self, delay_s: float = 0.0) -> None:
        """Run the action once, ``delay_s`` s from now (0: as soon as the executor can)."""
        delay_ns = max(0, int(delay_s * NS_PER_S))
        if delay_ns != self._delay_ns:
            self._timer.timer_period_ns = delay_ns
            self._delay_ns = delay_ns
        self._timer.reset()

    def _fire(self) -> None:
        self._timer.cancel()
        self._action()
