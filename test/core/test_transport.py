# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The team transport's pure parts: layouts, a fleet's sensing and its commands in one call."""

from formation_ros.core.maths.frames import frame_from_pose, STATIONARY
from formation_ros.core.maths.law import make_law, robot_command, robot_commands
from formation_ros.core.maths.sensing import neighbour_lists, sensed_pairs, sensor_radii
from formation_ros.core.maths.unicycle import quaternions_from_headings
from formation_ros.core.rules.transport import (command_of, command_vectors, commands_of,
                                                robot_indices, state_rows)
from formation_ros.core.settings.names import robot_name
import numpy as np
import pytest
from scipy.spatial import cKDTree

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 1.0)


def team(n=40, seed=3, dim=2):
    """Return a crowded random team: positions (n, dim) in a 6 m square, radii (n,)."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-3.0, 3.0, (n, dim)), rng.uniform(1.0, 2.5, n)


def test_robot_names_give_indices_and_refuse_strangers():
    assert robot_name(7) == 'robot_7'
    assert robot_indices(['robot_3', 'robot_1', 'robot_10'], 10).tolist() == [2, 0, 9]
    for bad in (['robot_11'], ['robot_0'], ['robot_01'], ['robot_2', 'robot_2'], ['plant'],
                ['robot_1 ']):
        with pytest.raises(ValueError):
            robot_indices(bad, 10)


def test_state_rows_put_robot_i_at_entry_i_minus_1():
    q = np.array([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0]])
    turns = quaternions_from_headings(np.array([0.0, 0.5, -1.0]))
    rows = state_rows(q, turns)
    assert rows.shape == (3, 7)
    assert rows[1].tolist() == [3.0, 4.0, 0.0, *turns[1].tolist()]
    assert np.array_equal(state_rows(np.c_[q, q[:, :1]], turns)[:, 2], q[:, 0])


@pytest.mark.parametrize('unicycle', [False, True])
def test_command_twists_are_what_cmd_vel_carries(unicycle):
    u = np.array([[0.5, -0.25], [1.0, 2.0]])
    linear, angular = command_vectors(u, unicycle)
    if unicycle:
        assert linear.tolist() == [[0.5, 0.0, 0.0], [1.0, 0.0, 0.0]]
        assert angular.tolist() == [[0.0, 0.0, -0.25], [0.0, 0.0, 2.0]]
    else:
        assert linear.tolist() == [[0.5, -0.25, 0.0], [1.0, 2.0, 0.0]]
        assert not angular.any()
    assert np.array_equal(commands_of(linear, angular, 2, unicycle), u)
    for k in range(len(u)):
        assert command_of(linear[k], angular[k], 2, unicycle) == tuple(u[k])


def test_a_fleets_sensing_is_the_whole_teams_for_its_robots():
    q, radii = team()
    reach = sensor_radii(radii, 0.0)
    observer, seen = sensed_pairs(q, reach)
    members = np.array([4, 5, 6, 17, 30, 39])
    mine = np.isin(observer, members)
    only = np.zeros_like(reach)
    only[members] = reach[members]
    fleet_observer, fleet_seen = sensed_pairs(q, only, observers=members)
    assert np.array_equal(fleet_observer, observer[mine])
    assert np.array_equal(fleet_seen, seen[mine])
    searched = sensed_pairs(q, only, cKDTree(q), observers=members[::-1])
    assert np.array_equal(searched[0], fleet_observer)
    assert np.array_equal(searched[1], fleet_seen)
    assert len(fleet_seen) > 3 * len(members)
    empty = sensed_pairs(q, only, observers=np.zeros(0, dtype=np.intp))
    assert len(empty[0]) == len(empty[1]) == 0


@pytest.mark.parametrize('moving', [False, True])
def test_a_fleets_commands_in_one_call_are_each_robots(moving):
    q, radii = team()
    vertices = np.random.default_rng(5).uniform(-2.0, 2.0, q.shape)
    frame = (frame_from_pose(1.3, (1.0, -0.5, 0.0), (0.0, 0.0, np.sin(0.4), np.cos(0.4)),
                             (0.3, 0.2, 0.0), (0.0, 0.0, 0.25), 2) if moving else STATIONARY)
    members = np.array([0, 3, 8, 9, 21, 22, 35])
    reach = np.zeros(len(q))
    reach[members] = radii[members]
    observer, seen = sensed_pairs(q, reach, observers=members)
    local = np.full(len(q), -1)
    local[members] = np.arange(len(members))
    together = robot_commands(q[members], vertices[members], local[observer], q[seen],
                              radii[members], LAW, frame)
    lists = neighbour_lists(observer, seen, len(q))
    for k, i in enumerate(members):
        alone = robot_command(q[i], vertices[i], q[lists[i]], radii[i], LAW, frame)
        for name in ('u', 'u_hat', 'omega'):
            assert np.max(np.abs(getattr(together, name)[k] - getattr(alone, name))) < 1e-12
    assert np.max(np.abs(together.u)) > 0.1


def test_a_robot_that_senses_no_one_is_commanded_to_its_vertex():
    q = np.array([[0.0, 0.0], [10.0, 0.0]])
    command = robot_commands(q, np.array([[1.0, 0.0], [10.0, 1.0]]), np.zeros(0, dtype=int),
                             np.zeros((0, 2)), np.array([2.0, 2.0]), LAW)
    alone = robot_command(q[1], (10.0, 1.0), np.zeros((0, 2)), 2.0, LAW)
    assert np.array_equal(command.u[1], alone.u)
    assert command.u[0, 0] > 0.0 and command.u[1, 1] > 0.0
