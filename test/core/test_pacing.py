# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The pace of a plant and a world: steps due at wall time x factor; a slow world lets time go."""

from formation_ros.core.rules.pacing import Pacer
import pytest

STEP_NS = 2_000_000
MS = 1_000_000


def test_steps_follow_wall_time_times_the_factor():
    pacer = Pacer(STEP_NS, 1.0, 200 * MS)
    pacer.start(10 * MS)
    steps = 0
    for wall in range(30 * MS, 1010 * MS + 1, 20 * MS):
        steps += pacer.due(wall, steps)
        assert steps == (wall - 10 * MS) // STEP_NS
    assert pacer.falls == 0 and pacer.dropped_steps == 0
    assert pacer.achieved(1010 * MS, steps) == pytest.approx(1.0)


def test_a_faster_factor_asks_for_more_steps_and_none_are_due_twice():
    pacer = Pacer(STEP_NS, 2.5, 10_000 * MS)
    pacer.start(0)
    assert pacer.due(100 * MS, 0) == 125
    assert pacer.due(100 * MS, 125) == 0
    assert pacer.due(101 * MS, 125) == 1
    assert pacer.due(100 * MS, 200) == 0


def test_a_world_behind_catches_up_at_most_its_share_and_counts_the_rest():
    pacer = Pacer(STEP_NS, 1.0, 100 * MS)
    pacer.start(0)
    assert pacer.due(1000 * MS, 0) == 50
    assert pacer.falls == 1 and pacer.dropped_steps == 450
    assert pacer.dropped_s == pytest.approx(0.9)
    assert pacer.due(1000 * MS, 50) == 0
    assert pacer.due(1020 * MS, 50) == 10
    assert pacer.achieved(1020 * MS, 60) == pytest.approx(60 * 0.002 / 1.02)


def test_pacing_needs_a_start():
    with pytest.raises(RuntimeError):
        Pacer(STEP_NS, 1.0, 100 * MS).due(0, 0)
    assert Pacer(STEP_NS, 1.0, 100 * MS).achieved(5, 0) == 0.0


def test_a_lockstep_run_ahead_of_the_wall_clock_waits_the_difference():
    pacer = Pacer(STEP_NS, 0.5, 100 * MS)
    pacer.start(10 * MS, 3)
    assert pacer.ahead_ns(10 * MS, 3) == 0.0
    assert pacer.ahead_ns(12 * MS, 4) == 2 * MS
    assert pacer.ahead_ns(15 * MS, 4) == -1 * MS
    assert pacer.wall_s(1010 * MS) == pytest.approx(1.0) and pacer.step_period_s == 0.004
    with pytest.raises(RuntimeError):
        Pacer(STEP_NS, 1.0, 100 * MS).ahead_ns(0, 0)
