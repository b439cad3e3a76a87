# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A Wake (ros/wake.py) on the executors the nodes spin: once per arming, no timer reset for now.

Work due now goes as an executor task and leaves the timer alone: a timer reset makes rclpy's
EventsExecutor queue a call of every due timer again, which starved a fleet (the lockstep hang).
"""

from formation_ros.ros.wake import Wake
import pytest
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.executors import SingleThreadedExecutor
from rclpy.experimental import EventsExecutor

WITHIN = 10.0
"""Seconds a wait for the executor may take on a busy core (waited for, not timed)."""


@pytest.fixture(params=['events', 'single'])
def spinning(request):
    """Yield (node, executor, steady clock) on the nodes' executor or the single-threaded one."""
    context = rclpy.Context()
    rclpy.init(context=context)
    executor = (EventsExecutor(context=context) if request.param == 'events'
                else SingleThreadedExecutor(context=context))
    node = rclpy.create_node('wake_test', context=context)
    executor.add_node(node)
    try:
        yield node, executor, Clock(clock_type=ClockType.STEADY_TIME)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)


def spin_until(executor, clock, condition):
    """Spin until ``condition()`` holds (WITHIN s at most); return whether it does."""
    start = clock.now().nanoseconds
    while not condition() and clock.now().nanoseconds - start < WITHIN * 1e9:
        executor.spin_once(timeout_sec=0.05)
    return condition()


def timed_wake(node, clock):
    """Return a Wake whose action notes when it ran (steady ns), and that list."""
    runs = []
    return Wake(node, lambda: runs.append(clock.now().nanoseconds), clock), runs


def test_many_armings_before_the_executor_runs_it_give_one_action_and_no_reset(spinning):
    node, executor, clock = spinning
    runs, marks = [], []
    wake = Wake(node, lambda: runs.append(1), clock)
    mark = Wake(node, lambda: marks.append(1), clock)
    resets = []
    original = wake._timer.reset
    wake._timer.reset = lambda: resets.append(1) or original()

    def rounds(count):
        # each round's mark runs after whatever the executor had queued before it
        for _ in range(count):
            done = len(marks) + 1
            mark.arm()
            assert spin_until(executor, clock, lambda: len(marks) == done)

    for _ in range(1000):
        wake.arm()
    assert spin_until(executor, clock, lambda: runs)
    rounds(3)
    assert runs == [1] and resets == []
    for ran in range(2, 5):
        wake.arm()
        assert spin_until(executor, clock, lambda: len(runs) == ran)
    rounds(3)
    assert len(runs) == 4 and resets == []


def test_a_later_arming_keeps_the_earlier_moment_and_an_earlier_one_moves_it(spinning):
    node, executor, clock = spinning
    wake, runs = timed_wake(node, clock)
    armed = clock.now().nanoseconds
    wake.arm(0.05)
    wake.arm(5.0)
    assert spin_until(executor, clock, lambda: runs)
    assert 0.05e9 <= runs[0] - armed < 5.0e9
    armed = clock.now().nanoseconds
    wake.arm(5.0)
    wake.arm(0.05)
    assert spin_until(executor, clock, lambda: len(runs) == 2)
    assert 0.05e9 <= runs[1] - armed < 5.0e9


def test_an_action_that_raises_stops_the_spin_with_its_exception(spinning):
    node, executor, clock = spinning

    def fail():
        raise ValueError('the action failed')

    wake = Wake(node, fail, clock)
    wake.arm()
    raised = []

    def spin_until_raised():
        try:
            executor.spin_once(timeout_sec=0.05)
        except ValueError as exc:
            raised.append(str(exc))
        return raised

    start = clock.now().nanoseconds
    while not spin_until_raised() and clock.now().nanoseconds - start < WITHIN * 1e9:
        pass
    assert raised == ['the action failed']


def test_an_early_call_of_the_timer_leaves_the_moment_armed(spinning):
    # a queued copy calls the timer before it is due; rcl then counts a whole period from it
    node, executor, clock = spinning
    wake, runs = timed_wake(node, clock)
    armed = clock.now().nanoseconds
    wake.arm(0.5)
    with wake._timer.handle:
        wake._timer.handle.call_timer()
    wake._fire()
    assert runs == [] and wake._timer.time_until_next_call() <= 0.5e9
    assert spin_until(executor, clock, lambda: runs)
    assert 0.5e9 <= runs[0] - armed


def test_work_due_now_leaves_a_later_arming_standing(spinning):
    node, executor, clock = spinning
    wake, runs = timed_wake(node, clock)
    wake.arm()
    armed = clock.now().nanoseconds
    wake.arm(0.3)
    assert spin_until(executor, clock, lambda: len(runs) == 2)
    assert runs[1] - armed >= 0.3e9
