# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""One path computes the commands of one robot and of K: each robot's as if it were alone."""

from formation_ros.core.maths.frames import to_body_frame
from formation_ros.core.maths.law import make_law, robot_command
from formation_ros.core.maths.reference import Reference
from formation_ros.core.maths.unicycle import (hand_points, headings_from_quaternions,
                                               quaternions_from_headings, unicycle_commands)
from formation_ros.core.rules.control import Control, Sensed
import numpy as np
import pytest

LAW = make_law(1.0, 1.0, 'arctan', 'poly', 2, 0.5)
RNG = np.random.default_rng(11)
N = 6
POSITIONS = RNG.uniform(-3.0, 3.0, (N, 2))
HEADINGS = RNG.uniform(-np.pi, np.pi, N)
ORIENTATIONS = quaternions_from_headings(HEADINGS)
VERTICES = RNG.uniform(-2.0, 2.0, (N, 2))
RADII = np.full(N, 2.5)
FRAME = Reference(kind='circle', dim=2, radius=1.0, speed=0.5).sample(1.0)


def sensed(points, k):
    """Every other robot's point as robot k hears it (those beyond R_i the law ignores)."""
    return np.delete(points, k, axis=0)


@pytest.mark.parametrize('unicycle, body_frame', [(False, False), (False, True), (True, False)])
def test_the_team_path_gives_each_robot_its_own_command(unicycle, body_frame):
    team = Control(LAW, RADII, 2, unicycle, 0.2, body_frame)
    points, headings = team.points(POSITIONS, ORIENTATIONS)
    observer = np.repeat(np.arange(N), N - 1)
    neighbours = np.concatenate([sensed(points, k) for k in range(N)])
    commands = team.commands(Sensed(np.arange(N), points, headings, ORIENTATIONS, observer,
                                    neighbours), VERTICES, FRAME)
    assert commands.published.shape == (N, team.width)
    for k in range(N):
        alone = Control(LAW, RADII[k:k + 1], 2, unicycle, 0.2, body_frame)
        one = alone.commands(Sensed(np.array([k]), points[k:k + 1], headings[k:k + 1],
                                    ORIENTATIONS[k:k + 1], np.zeros(N - 1, dtype=np.intp),
                                    sensed(points, k)), VERTICES[k:k + 1], FRAME)
        assert np.allclose(one.published[0], commands.published[k], rtol=0, atol=1e-12)
        law = robot_command(points[k], VERTICES[k], sensed(points, k), RADII[k], LAW, FRAME)
        assert np.allclose(law.u, commands.law.u[k], rtol=0, atol=1e-12)
        if unicycle:
            expected = unicycle_commands(law.u, HEADINGS[k], 0.2)
        elif body_frame:
            expected = to_body_frame(law.u[None, :], ORIENTATIONS[k:k + 1])[0]
        else:
            expected = law.u
        assert np.allclose(commands.published[k], expected, rtol=0, atol=1e-12)


def test_unicycles_act_on_their_hand_points_and_others_on_their_positions():
    points, headings = Control(LAW, RADII, 2, True, 0.2, False).points(POSITIONS, ORIENTATIONS)
    assert np.allclose(headings, headings_from_quaternions(ORIENTATIONS))
    assert np.allclose(points, hand_points(POSITIONS, HEADINGS, 0.2))
    same, _ = Control(LAW, RADII, 2, False, 0.2, False).points(POSITIONS, ORIENTATIONS)
    assert np.array_equal(same, POSITIONS)


def test_zero_has_a_row_per_robot_and_the_command_width():
    assert Control(LAW, RADII[:1], 2, True, 0.2, False).zero().shape == (1, 2)
    assert Control(LAW, RADII, 3, False, 0.2, False).zero().shape == (N, 3)


def test_inputs_are_not_changed():
    before = POSITIONS.copy(), ORIENTATIONS.copy()
    team = Control(LAW, RADII, 2, True, 0.2, False)
    points, headings = team.points(POSITIONS, ORIENTATIONS)
    team.commands(Sensed(np.arange(N), points, headings, ORIENTATIONS,
                         np.zeros(0, dtype=np.intp), np.zeros((0, 2))), VERTICES, FRAME)
    assert np.array_equal(before[0], POSITIONS) and np.array_equal(before[1], ORIENTATIONS)


def test_one_robot_alone_is_the_team_path_with_k_1():
    control = Control(LAW, RADII[:1], 2, True, 0.2, False)
    positions = np.hstack([POSITIONS, np.zeros((N, 1))])
    alone = control.alone(3, positions[0], ORIENTATIONS[0], positions[1:], ORIENTATIONS[1:])
    points, headings = control.points(POSITIONS, ORIENTATIONS)
    assert alone.indices.tolist() == [3] and np.array_equal(alone.points, points[:1])
    assert np.array_equal(alone.neighbours, points[1:]) and not alone.observer.any()
    commands = control.commands(alone, VERTICES[:1], FRAME)
    command, body = commands.row(0)
    assert np.array_equal(command.u, commands.law.u[0]) and np.array_equal(body, commands.body[0])
    assert body.shape == (2,) and headings.shape == (N,)
