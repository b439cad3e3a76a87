# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Work that a callback asks for and the executor does once: :class:`Wake`.

A subscription callback only stores what arrived and calls :meth:`Wake.arm`; the node's work (a
robot's answer to a new state, the lockstep plant's next step) then runs once, as soon as the
executor gets to it (or after a delay), however many callbacks armed it in between. This keeps
"callbacks store, timers act" without a timer polling for news, and the answer follows the
message at once instead of at the next tick of a free-running timer.

Work due now is a task of the node's executor (``create_task``: rclpy's EventsExecutor has no
guard conditions); work due later is a one-shot timer, reset only when it is not armed already
for an earlier moment. Why not a timer for both: rclpy's EventsExecutor (7.1) looks at every
timer of a clock each time one of them is reset and queues a call of each one that is due, even
when a call of it is queued already, and each such call, once run, makes it look again. A fleet
that reset a timer at every state it heard could, on a starved core, fill that queue faster
than it ran it, its diagnostics timer called back to back and its states no longer answered: a
lockstep run hung (docs/faults.md, "a robot process or fleet that stops answering"). A call of
the timer that comes before the moment armed (a queued copy, which rcl takes as a tick and so
moves the timer a period on) sets the timer back to that moment and does nothing else.
"""

from typing import Callable, Optional

from formation_ros.core.maths.units import NS_PER_S
from rclpy.clock import Clock
from rclpy.node import Node


class Wake:
    """Runs ``action`` of ``node`` once per arming: now as a task, later from a timer."""

    def __init__(self, node: Node, action: Callable[[], None], clock: Clock) -> None:
        """Create the timer on ``clock`` (the steady clock: it must run when /clock stops)."""
        self._node = node
        self._action = action
        self._clock = clock
        self._task_pending = False
        self._failure: Optional[Exception] = None
        self._delay_ns = 0
        self._due_ns: Optional[int] = None
        """When the timer's action is due (``clock``, ns); None while it is not armed."""
        self._timer = node.create_timer(0.0, self._fire, clock=clock, autostart=False)

    def arm(self, delay_s: float = 0.0) -> None:
        """Run the action once, ``delay_s`` s from now (0: as soon as the executor can)."""
        delay_ns = max(0, int(delay_s * NS_PER_S))
        executor = self._node.executor
        if delay_ns == 0 and executor is not None:
            if not self._task_pending:
                self._task_pending = True
                executor.create_task(self._run_task)
            return
        due_ns = self._clock.now().nanoseconds + delay_ns
        if self._due_ns is not None and self._due_ns <= due_ns:
            return
        self._due_ns = due_ns
        self._restart(delay_ns)

    def _run_task(self) -> None:
        """Run the action armed for now, and one armed for later that is due by now."""
        self._task_pending = False
        if self._due_ns is not None and self._due_ns <= self._clock.now().nanoseconds:
            self._disarm()
        try:
            self._action()
        except Exception as exc:
            # An exception leaving a task of rclpy's EventsExecutor crashes the process at
            # exit (a segmentation fault instead of the traceback): the timer raises it.
            self._failure = exc
            self._restart(0)

    def _fire(self) -> None:
        if self._failure is not None:
            raise self._failure
        if self._due_ns is None:
            return
        early_ns = self._due_ns - self._clock.now().nanoseconds
        if early_ns > 0:
            # the early call moved the timer a period on: count what is left from now
            self._restart(early_ns)
            return
        self._disarm()
        self._action()

    def _restart(self, delay_ns: int) -> None:
        if delay_ns != self._delay_ns:
            self._timer.timer_period_ns = delay_ns
            self._delay_ns = delay_ns
        self._timer.reset()

    def _disarm(self) -> None:
        if self._due_ns is not None:
            self._timer.cancel()
            self._due_ns = None
