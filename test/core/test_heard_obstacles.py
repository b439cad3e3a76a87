# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Obstacles a robot hears (maths/obstacles.py): the points told, and the law from them.

What the plant and the relay tell (``told_obstacles``) and what a robot makes of it
(``HeardObstacles``) give the command the map gives, grown by the footprint, to rounding; a
robot that hears none is the robot without obstacles; an old point still bounds its obstacle.
"""

from formation_ros.core.maths.law import make_law, robot_commands, team_command
from formation_ros.core.maths.obstacle_tracking import tracking_command
from formation_ros.core.maths.obstacles import (HeardObstacles, MAX_OBSTACLE_REPULSION,
                                                normal_quaternions, Obstacles,
                                                quaternion_normals, told_obstacles)
from formation_ros.core.maths.reference import Reference
from formation_ros.core.maths.unicycle import hand_points
from formation_ros.core.rules.control import Control, Sensed
import numpy as np
import pytest

LAW = make_law(0.8, 0.3, 'arctan', 'poly', 2, 0.9)


def heard_from(told, dim, footprint, clearance):
    """Return the HeardObstacles of what ``told`` lists (as a robot's messages carry it)."""
    lists = [(told.points[i][told.listed[i]], told.normals[i][told.listed[i]])
             for i in range(len(told.listed))]
    return HeardObstacles.from_lists(lists, dim, footprint, clearance)


def map_2d():
    return Obstacles([0.0, 0.0, 1.0, 3.0, 2.0, 0.4], [-2.0, -3.0, 2.0, -3.0, 0.1], [], 1.2, 2)


def map_3d():
    return Obstacles([0.0, 0.0, 1.0], [4.0, -1.0, 4.0, 2.0, 0.2], [0.0, 4.0, 1.0, 0.7], 1.2, 3)


@pytest.mark.parametrize('make_map, dim', [(map_2d, 2), (map_3d, 3)])
@pytest.mark.parametrize('footprint', [0.0, 0.15])
def test_points_heard_give_the_command_of_the_grown_map(make_map, dim, footprint):
    obstacles = make_map()
    rng = np.random.default_rng(36)
    q = rng.uniform(-4.0, 5.0, size=(40, dim))
    radii = np.full(len(q), 2.5)
    told = told_obstacles(obstacles, q, q, radii)
    heard = heard_from(told, dim, footprint, obstacles.clearance)
    vertices = rng.uniform(-1.0, 1.0, size=q.shape)
    observer = np.zeros(0, dtype=np.intp)
    none = np.zeros((0, dim))
    from_points = robot_commands(q, vertices, observer, none, radii, LAW, obstacles=heard)
    from_map = robot_commands(q, vertices, observer, none, radii, LAW,
                              obstacles=obstacles.grown(footprint))
    assert np.max(np.abs(from_points.omega - from_map.omega)) <= 1e-12
    assert np.max(np.abs(from_points.u - from_map.u)) <= 1e-12
    near = np.any(obstacles.grown(footprint).surface(q).distances < obstacles.clearance, axis=1)
    assert np.any(near) and np.any(~near)  # the draw has robots near obstacles and far
    assert np.all(np.abs(from_points.u) <= LAW.u_bound)


def test_a_unicycle_hears_the_points_closest_to_its_hand_point():
    obstacles = map_2d()
    l, radius = 0.2, 0.1
    centres = np.array([[1.8, 0.3], [2.0, 2.5], [-1.0, -2.2], [6.0, 6.0]])
    heading = np.array([2.5, -1.0, -1.6, 0.0])
    points = hand_points(centres, heading, l)
    radii = np.full(4, 1.5)
    told = told_obstacles(obstacles, centres, points, radii)
    assert told.listed[3].sum() == 0 and told.listed[:3].any(axis=1).all()
    heard = heard_from(told, 2, l + radius, obstacles.clearance)
    grown = obstacles.grown(l + radius)
    surface = heard.surface(points)
    truth = grown.surface(points)
    listed = np.arange(heard.count)[None, :] < heard.counts[:, None]
    rows = [truth.distances[i][told.listed[i]] for i in range(4)]
    for i in range(4):
        assert np.allclose(surface.distances[i][listed[i]], rows[i], atol=1e-12)
    vertices = np.zeros((4, 2))
    observer = np.zeros(0, dtype=np.intp)
    a = robot_commands(points, vertices, observer, np.zeros((0, 2)), radii, LAW, obstacles=heard)
    # the map's robots use every obstacle within R_i of the hand point; the listed ones are
    # those within R_i of the body: the same here (checked), so the commands agree
    within = grown.surface(points).distances < radii[:, None]
    assert np.array_equal(within & (truth.distances < obstacles.clearance),
                          told.listed & (truth.distances < obstacles.clearance))
    b = robot_commands(points, vertices, observer, np.zeros((0, 2)), radii, LAW,
                       obstacles=grown)
    assert np.max(np.abs(a.u - b.u)) <= 1e-12


def test_a_robot_that_heard_none_is_the_robot_without_obstacles():
    q = np.array([[0.0, 0.0], [1.0, 0.5], [3.0, 3.0]])
    vertices = np.array([[0.5, 0.0], [0.0, 1.0], [2.0, 2.0]])
    radii = np.full(3, 2.0)
    heard = HeardObstacles.from_lists([None, (np.zeros((0, 3)), np.zeros((0, 3))), None], 2,
                                      0.1, 0.5)
    assert heard.count == 0
    with_none = team_command(q, vertices, radii, LAW, obstacles=heard)
    without = team_command(q, vertices, radii, LAW)
    assert np.array_equal(with_none.u, without.u)


def test_robots_with_different_counts_are_padded_without_effect():
    obstacles = map_2d()
    q = np.array([[1.6, 0.2], [5.0, 5.0], [2.3, 2.0]])
    radii = np.full(3, 2.0)
    told = told_obstacles(obstacles, q, q, radii)
    counts = told.listed.sum(axis=1)
    assert counts.tolist() == [2, 0, 1]
    heard = heard_from(told, 2, 0.0, obstacles.clearance)
    one_by_one = [robot_commands(q[i:i + 1], np.zeros((1, 2)), np.zeros(0, dtype=np.intp),
                                 np.zeros((0, 2)), radii[i:i + 1], LAW,
                                 obstacles=heard_from(told._replace(
                                     listed=told.listed[i:i + 1], points=told.points[i:i + 1],
                                     normals=told.normals[i:i + 1]), 2, 0.0,
                                     obstacles.clearance)).u[0] for i in range(3)]
    together = robot_commands(q, np.zeros((3, 2)), np.zeros(0, dtype=np.intp),
                              np.zeros((0, 2)), radii, LAW, obstacles=heard).u
    assert np.all(np.isfinite(together))
    assert np.array_equal(np.array(one_by_one), together)


def test_the_listing_rule_is_the_distance_of_the_surface_from_the_body():
    obstacles = Obstacles([0.0, 0.0, 1.0], [], [], 0.5, 2)
    q = np.array([[2.49, 0.0], [2.51, 0.0], [0.0, -3.0]])
    told = told_obstacles(obstacles, q, q, [1.5, 1.5, 2.5])
    assert told.listed[:, 0].tolist() == [True, False, True]
    assert np.allclose(told.points[0, 0], [1.0, 0.0])
    assert np.allclose(told.normals[0, 0], [1.0, 0.0])
    assert np.allclose(told.points[2, 0], [0.0, -1.0])


def test_inside_the_grown_obstacle_the_term_pushes_out_along_the_normal():
    heard = HeardObstacles.from_lists([([[1.0, 0.0]], [[1.0, 0.0]])], 2, 0.3, 0.5)
    surface = heard.surface([[1.1, 0.0]])
    assert surface.distances[0, 0] == pytest.approx(-0.2)
    u = robot_commands([[1.1, 0.0]], [[-5.0, 0.0]], np.zeros(0, dtype=np.intp),
                       np.zeros((0, 2)), [2.0], LAW, obstacles=heard).u[0]
    assert u[0] == pytest.approx(LAW.u_bound)  # saturated outward, whatever the vertex
    assert MAX_OBSTACLE_REPULSION > 1e100


def test_an_old_point_still_bounds_its_obstacle():
    obstacles = map_2d()
    rng = np.random.default_rng(7)
    before = rng.uniform(-4.0, 5.0, size=(200, 2))
    after = before + rng.normal(scale=0.5, size=before.shape)
    told = told_obstacles(obstacles, before, before, np.full(200, 1e3))
    heard = heard_from(told, 2, 0.0, obstacles.clearance)
    truth = obstacles.surface(after).distances
    outside = obstacles.surface(before).distances > 0.0
    assert np.all((heard.surface(after).distances <= truth + 1e-12) | ~outside)


@pytest.mark.parametrize('dim', [2, 3])
def test_normals_go_through_quaternions_and_back(dim):
    rng = np.random.default_rng(3)
    normals = rng.normal(size=(50, dim))
    normals = np.concatenate([normals, -np.eye(dim), np.eye(dim)])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    quats = normal_quaternions(normals)
    assert np.allclose(np.linalg.norm(quats, axis=1), 1.0)
    assert np.allclose(quaternion_normals(quats, dim), normals, atol=1e-12)


def test_a_normal_out_of_the_plane_has_no_direction_in_2d():
    up = normal_quaternions(np.array([[0.0, 0.0, 1.0]]))
    assert np.array_equal(quaternion_normals(up, 2), np.zeros((1, 2)))


def test_a_robot_guards_the_feed_forward_as_formation_sim_does():
    """Dragged at 4 m/s towards a wall it heard: the robots' command is the offline one."""
    wall = Obstacles([], [5.0, -20.0, 5.0, 20.0, 0.2], [], 1.0, 2)
    q = np.array([[4.2, 0.0], [4.5, 3.0], [0.0, 8.0]])
    radii = np.full(3, 2.0)
    frame = Reference('line', 2, [0.0, 0.0], [4.0, 0.0]).sample(1.0)
    vertices = np.array([[0.0, 0.0], [0.0, 3.0], [-4.0, 8.0]])
    control = Control(LAW, radii, 2, False, 0.0, False, 0.1, wall.clearance)
    told = told_obstacles(wall, q, q, radii)
    heard = heard_from(told, 2, 0.1, wall.clearance)
    orientations = np.tile([0.0, 0.0, 0.0, 1.0], (3, 1))
    sensed = Sensed(np.arange(3), q, np.zeros(3), orientations, np.zeros(0, dtype=np.intp),
                    np.zeros((0, 2)), heard)
    robots = control.commands(sensed, vertices, frame).law
    grown = wall.grown(0.1)
    offline = tracking_command(team_command(q, vertices, radii, LAW, frame, obstacles=grown),
                               q, frame, LAW, grown, radii)
    assert np.max(np.abs(robots.u - offline.u)) <= 1e-12
    plain = team_command(q, vertices, radii, LAW, frame, obstacles=grown)
    assert robots.u[0, 0] < plain.u[0, 0] - 0.1  # the rule took feed-forward off robot 1
    assert np.array_equal(robots.u[2], plain.u[2])  # robot 3 is far from the wall
