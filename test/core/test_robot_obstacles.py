# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot's obstacles without ROS (core/rules/control.py, robot_core.py).

What it makes of an obstacle message (points, normals as quaternions), that a state waits for
its obstacles once some were heard, that they go stale as the pose does, and that a robot
that heard none answers as before.
"""

from formation_ros.core.maths.law import make_law, robot_commands
from formation_ros.core.maths.obstacles import normal_quaternions, Obstacles, told_obstacles
from formation_ros.core.maths.unicycle import hand_points, quaternions_from_headings
from formation_ros.core.rules.control import Control, Sensed
import numpy as np
import pytest

from test_robot_core import make_robot, PERIOD, START, STEADY, TIMEOUT

LAW = make_law(0.8, 0.3, 'arctan', 'poly', 2, 0.9)
PILLAR = Obstacles([1.0, 0.0, 0.4], [], [], 0.6, 2)


def message(told, i):
    """Return robot i's message content: (positions (m, 3), orientations (m, 4))."""
    points = told.points[i][told.listed[i]]
    rows = np.zeros((len(points), 3))
    rows[:, :points.shape[1]] = points
    return rows, normal_quaternions(told.normals[i][told.listed[i]])


@pytest.mark.parametrize('unicycle', [False, True])
def test_a_robot_commands_from_its_message_what_the_map_gives(unicycle):
    l, radius = (0.15, 0.05) if unicycle else (0.0, 0.05)
    footprint = radius + l
    control = Control(LAW, [2.0], 2, unicycle, l if unicycle else 1.0, False, footprint,
                      PILLAR.clearance)
    position, heading = np.array([0.1, 0.3]), 0.4
    orientation = quaternions_from_headings(np.array([heading]))[0]
    sensed = control.alone(0, np.append(position, 0.0), orientation, np.zeros((0, 3)),
                           np.zeros((0, 4)))
    point = hand_points(position[None], np.array([heading]), l)[0] if unicycle else position
    assert np.allclose(sensed.points[0], point)
    told = told_obstacles(PILLAR, position[None], point[None], [2.0])
    heard = control.heard_obstacles([message(told, 0)])
    assert heard is not None and heard.count == 1
    with_points = control.commands(_with(sensed, heard), [[2.0, 0.0]], None)
    by_map = Control(LAW, [2.0], 2, unicycle, l if unicycle else 1.0, False)
    expected = robot_commands(sensed.points, [[2.0, 0.0]], sensed.observer, sensed.neighbours,
                              [2.0], LAW, None, PILLAR.grown(footprint))
    assert np.max(np.abs(with_points.law.u - expected.u)) <= 1e-12
    without = by_map.commands(sensed, [[2.0, 0.0]], None)
    assert not np.allclose(with_points.law.u, without.law.u)  # the pillar is in the way
    assert np.all(np.abs(with_points.law.u_hat) <= LAW.u_bound)


def _with(sensed, heard):
    """Return ``sensed`` with the obstacles ``heard``."""
    return Sensed(sensed.indices, sensed.points, sensed.headings, sensed.orientations,
                  sensed.observer, sensed.neighbours, heard)


def test_without_b_o_or_without_a_message_nothing_is_heard():
    no_clearance = Control(LAW, [2.0], 2, False, 1.0, False, 0.1, None)
    pair = (np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 0.0, 1.0]]))
    assert no_clearance.heard_obstacles([pair]) is None
    control = Control(LAW, [2.0, 2.0], 2, False, 1.0, False, 0.1, 0.5)
    assert control.heard_obstacles([None, None]) is None
    heard = control.heard_obstacles([None, pair])
    assert heard is not None and heard.counts.tolist() == [0, 1]


def test_once_obstacles_were_heard_a_state_waits_for_its_own():
    robot = make_robot(lockstep=True)
    robot.sample(START)
    robot.core.reference_heard(STEADY)
    robot.core.state_heard(START, STEADY, True)
    assert robot.core.on_state(STEADY, START).publish, 'none heard yet: answered as before'
    robot.sample(START + PERIOD)
    robot.core.reference_heard(STEADY + PERIOD)
    robot.core.obstacles_heard(START, STEADY + PERIOD)  # late, of the state answered
    assert not robot.core.on_state(STEADY + PERIOD, START).publish, 'answered once'
    assert not robot.core.pose_heard(START + PERIOD, STEADY + PERIOD).now
    assert not robot.core.neighbours_heard(START + PERIOD, STEADY + PERIOD).now
    assert not robot.core.on_state(STEADY + PERIOD, START + PERIOD).publish
    assert robot.core.obstacles_heard(START + PERIOD, STEADY + PERIOD + 1).now
    answer = robot.core.on_state(STEADY + PERIOD + 1, START + PERIOD)
    assert answer.publish and answer.stamp_ns == START + PERIOD


def test_obstacles_heard_once_go_stale_as_the_pose_does():
    robot = make_robot(lockstep=False)
    robot.sample(START)
    robot.core.reference_heard(STEADY)
    robot.core.state_heard(START, STEADY, True, obstacles=True)
    assert robot.core.on_state(STEADY, START).publish
    late = STEADY + TIMEOUT + 1
    robot.sample(START + PERIOD)
    robot.core.reference_heard(late)
    robot.core.pose_heard(START + PERIOD, late)
    robot.core.neighbours_heard(START + PERIOD, late)
    answer = robot.core.on_watchdog(late, START + PERIOD)
    assert answer.publish and answer.commands is None
    assert [note.text for note in answer.notes if note.key == 'stale'] == [
        'no new obstacles for 0.5 s: publishing zero']
