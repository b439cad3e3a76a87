# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Tracking near obstacles (maths/obstacle_tracking.py): the feed-forward kept out of them."""

from dataclasses import replace

from formation_ros.core.maths.frames import stationary_frame
from formation_ros.core.maths.law import make_law, team_command
from formation_ros.core.maths.obstacle_tracking import (change_for, feed_forward_change,
                                                        FeedForwardGuard, guarded_feed_forward,
                                                        tracking_command)
from formation_ros.core.maths.obstacles import (MAX_OBSTACLE_REPULSION, obstacle_terms,
                                                Obstacles)
from formation_ros.core.maths.reference import Reference
from formation_ros.core.runs.trajectory import frame_velocities
import numpy as np
import pytest

LAW = make_law(1.0, 1.0, 'arctan', 'poly', 2, 1.0)
WALL = Obstacles([], [5.0, -20.0, 5.0, 20.0, 0.2], [], 1.0, 2)
"""A wide wall across the path of a reference moving along +x."""


def test_only_a_feed_forward_into_the_obstacles_loses_part_of_its_component_along_them():
    feed_forward = np.array([[2.0, 1.0], [-2.0, 1.0], [2.0, 1.0], [2.0, 1.0]])
    away = np.array([[-3.0, 0.0], [-3.0, 0.0], [0.0, 0.0], [-MAX_OBSTACLE_REPULSION, 0.0]])
    guarded = guarded_feed_forward(feed_forward, away, 1.0)
    assert guarded[0] == pytest.approx([2.0 - 0.75 * 2.0, 1.0])  # w = 3 / (3 + 1)
    assert guarded[1:3] == pytest.approx(feed_forward[1:3])
    assert guarded[3] == pytest.approx([0.0, 1.0])  # at contact all of it
    assert feed_forward[0] == pytest.approx([2.0, 1.0])  # not modified
    slanted = guarded_feed_forward([[1.0, -1.0]], [[0.0, 2.0]], 2.0)
    assert slanted[0] == pytest.approx([1.0, -0.5])


def test_the_rule_changes_nothing_for_a_fixed_reference_or_far_from_obstacles():
    q = np.array([[0.0, 0.0], [3.5, 0.0]])
    vertices = np.zeros((2, 2))
    still = team_command(q, vertices, [2.0, 2.0], LAW, stationary_frame(2), obstacles=WALL)
    assert tracking_command(still, q, stationary_frame(2), LAW, WALL, [2.0, 2.0]) is still
    frame = Reference('line', 2, [0.0, 0.0], [4.0, 0.0]).sample(0.0)
    far = q[:1]
    command = team_command(far, vertices[:1], [2.0], LAW, frame, obstacles=WALL)
    assert tracking_command(command, far, frame, LAW, WALL, [2.0]) is command
    assert feed_forward_change(far, frame, LAW, None, [2.0]) is None


def test_near_the_wall_u_hat_is_kept_and_only_u_changes():
    frame = Reference('line', 2, [0.0, 0.0], [4.0, 0.0]).sample(0.0)
    q = np.array([[4.4, 0.3]])
    command = team_command(q, [[0.0, 0.0]], [2.0], LAW, frame, obstacles=WALL)
    guarded = tracking_command(command, q, frame, LAW, WALL, [2.0])
    assert guarded.u_hat is command.u_hat and np.all(np.abs(guarded.u_hat) <= LAW.u_bound)
    assert guarded.u[0, 0] < command.u[0, 0] and guarded.u[0, 1] == pytest.approx(command.u[0, 1])
    change = feed_forward_change(q, frame, LAW, WALL, [2.0])
    assert guarded.u == pytest.approx(command.u + change)
    away = obstacle_terms(q, WALL.surface(q), LAW.jump, WALL.clearance, [2.0])
    assert change_for(q, frame, away, WALL.clearance) == pytest.approx(change)
    assert change_for(q, stationary_frame(2), away, WALL.clearance) is None


def run_into_the_wall(guard, speed=4.0, dt=1e-3, duration=4.0):
    """One robot whose place moves along +x at ``speed`` (> c M1) into a wide wall: its path."""
    reference = Reference('line', 2, [0.0, 0.0], [speed, 0.0])
    q = np.zeros((1, 2))
    path = [q]
    for k in range(int(round(duration / dt))):
        frame = reference.sample(k * dt)
        command = team_command(q, [[0.0, 0.0]], [2.0], LAW, frame, obstacles=WALL)
        if guard:
            command = tracking_command(command, q, frame, LAW, WALL, [2.0])
        q = q + dt * command.u
        path.append(q)
    return np.array(path)


def test_a_robot_dragged_into_a_wall_faster_than_c_m1_stops_short_of_it_with_the_rule():
    guarded = WALL.surface(run_into_the_wall(True)[:, 0]).distances[:, 0]
    assert guarded.min() > 0.05
    assert guarded[-1] < 1.0  # pressed against the wall, within b_o, as its place moves on
    plain = WALL.surface(run_into_the_wall(False)[:, 0]).distances[:, 0]
    assert plain.min() < 0.0  # eq. (25)'s feed-forward alone carries it into the wall


def test_a_copy_of_the_command_is_returned_not_the_input_changed():
    frame = Reference('line', 2, [0.0, 0.0], [4.0, 0.0]).sample(0.0)
    q = np.array([[4.4, 0.0]])
    command = team_command(q, [[0.0, 0.0]], [2.0], LAW, frame, obstacles=WALL)
    kept = replace(command)
    tracking_command(command, q, frame, LAW, WALL, [2.0])
    assert np.array_equal(command.u, kept.u)


def test_a_command_is_read_back_at_the_state_it_answered_not_where_the_body_went():
    frame = Reference('line', 2, [0.0, 0.0], [4.0, 0.0]).sample(0.0)
    state = np.array([[4.4, 0.3]])
    command = tracking_command(team_command(state, [[0.0, 0.0]], [2.0], LAW, frame,
                                            obstacles=WALL),
                               state, frame, LAW, WALL, [2.0])
    guard = FeedForwardGuard(LAW, WALL, np.array([2.0]))
    moved = state + [[0.15, 0.0]]  # where the body is at the sample, a state later
    at_sample = frame_velocities(command.u[None], moved[None], [frame], guard)[0]
    answered = frame_velocities(command.u[None], moved[None], [frame], guard, state[None])[0]
    assert answered == pytest.approx(command.u_hat, abs=1e-12)
    assert np.max(np.abs(at_sample - command.u_hat)) > 0.1, 'read at the sample: not what it was'
    unknown = frame_velocities(command.u[None], moved[None], [frame], guard,
                               np.full((1, 1, 2), np.nan))[0]
    assert unknown == pytest.approx(at_sample)
