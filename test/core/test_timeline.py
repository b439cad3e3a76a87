# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What holds when (core/runs/timeline.py): the change in force at a stamp, whatever the order."""

import itertools

from formation_ros.core.maths.reference import Reference
from formation_ros.core.runs.timeline import (MAX_CHANGES, Mode, ReferenceTimeline, Shape,
                                              TeamState, Timeline)
import numpy as np


def test_the_latest_change_at_or_before_a_stamp_holds():
    timeline = Timeline(Mode.RUNNING)
    timeline.add(100, Mode.STOPPED)
    timeline.add(300, Mode.RUNNING)
    expected = {-5: Mode.RUNNING, 0: Mode.RUNNING, 99: Mode.RUNNING, 100: Mode.STOPPED,
                299: Mode.STOPPED, 300: Mode.RUNNING, 10 ** 12: Mode.RUNNING}
    assert {stamp: timeline.at(stamp) for stamp in expected} == expected
    assert timeline.changes() == [(100, Mode.STOPPED), (300, Mode.RUNNING)]


def test_arrival_order_does_not_matter():
    changes = [(50, 'a'), (10, 'b'), (30, 'c'), (70, 'd')]
    answers = set()
    for order in itertools.permutations(changes):
        timeline = Timeline('start')
        for stamp, value in order:
            timeline.add(stamp, value)
        answers.add(tuple(timeline.at(t) for t in range(0, 80, 5)))
    assert len(answers) == 1
    brute = tuple(max([(s, v) for s, v in changes if s <= t], default=(0, 'start'))[1]
                  for t in range(0, 80, 5))
    assert answers == {brute}


def test_a_change_with_the_same_stamp_replaces_it_and_old_ones_are_dropped():
    timeline = Timeline(0)
    timeline.add(5, 1)
    timeline.add(5, 2)
    assert timeline.changes() == [(5, 2)] and timeline.latest == 2
    for k in range(MAX_CHANGES + 10):
        timeline.add(10 + k, k)
    assert len(timeline.changes()) == MAX_CHANGES - 1
    assert timeline.latest == MAX_CHANGES + 9
    first_kept = timeline.changes()[0][0]
    assert timeline.at(first_kept - 1) == timeline.at(first_kept) - 1 == first_kept - 11


def test_shapes_compare_by_vertices():
    square = Shape('square', np.array([[1.0, 1.0], [-1.0, 1.0]]))
    assert square.same_as(Shape('', square.vertices.copy()))
    assert not square.same_as(Shape('square', square.vertices + 1e-12))


def test_the_reference_timeline_gives_each_stamp_the_frame_of_the_state_in_force():
    base = Reference('circle', 2, origin=[1.0, -2.0], radius=1.5, speed=0.5)
    states = Timeline(TeamState.of(Mode.RUNNING, '', base))
    timeline = ReferenceTimeline(base, states)
    states.add(2_000_000_000, TeamState(Mode.RUNNING, '', (0.0, 0.0), 1.0, 0.25))
    epoch = 500_000_000
    for stamp in (0, 1_999_999_999, 2_000_000_000, 3_250_000_000):
        t = (stamp - epoch) / 1e9
        centre = (np.array([1.0, -2.0]) if stamp < 2_000_000_000 else np.zeros(2))
        frame = timeline.frame_at(stamp, epoch)
        assert frame.t == t
        expected = base.with_values(centre, 0.5 if stamp < 2_000_000_000 else 1.0,
                                    0.0 if stamp < 2_000_000_000 else 0.25).sample(t)
        assert np.array_equal(frame.q_od, expected.q_od)
        assert np.array_equal(frame.J, expected.J)
        assert abs(np.linalg.norm(frame.q_od - centre) - 1.5) < 1e-12
        assert abs(np.linalg.norm(frame.qdot_od) - (0.5 if stamp < 2e9 else 1.0)) < 1e-12
