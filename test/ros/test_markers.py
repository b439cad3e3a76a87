# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""RViz markers: what each namespace shows (obstacles too), a count that does not grow with N."""

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.ros.markers import (DISC_THICKNESS, formation_markers, HEADING_LENGTH,
                                       obstacle_markers, Paths, PILLAR_HEIGHT)
from geometry_msgs.msg import Point
import numpy as np
import pytest
from visualization_msgs.msg import Marker


def as_rows(points):
    return [(p.x, p.y, p.z) for p in points]


@pytest.mark.parametrize('n', [3, 40])
def test_markers_show_every_robot_zone_and_path_in_a_fixed_number_of_markers(n):
    rng = np.random.default_rng(n)
    radii = np.where(np.arange(n) % 2 == 0, 2.0, 3.0)
    paths = Paths(n, length=4)
    history = [rng.uniform(-5.0, 5.0, (n, 2)) for _ in range(6)]
    for q in history:
        paths.append(q)
    q = history[-1]
    array = formation_markers(q, radii, 1.0, q + 0.5, paths, 7)
    by_ns = {}
    for marker in array.markers:
        by_ns.setdefault(marker.ns, []).append(marker)
    assert len(array.markers) == 6
    padded = [(x, y, 0.0) for x, y in q.tolist()]
    assert as_rows(by_ns['robots'][0].points) == padded
    sensing = {m.scale.x / 2.0: m for m in by_ns['sensing']}
    assert sorted(sensing) == [2.0, 3.0]
    assert as_rows(sensing[2.0].points) == padded[0::2]
    assert as_rows(sensing[3.0].points) == padded[1::2]
    assert all(m.type == Marker.SPHERE_LIST and m.scale.z == DISC_THICKNESS
               for m in by_ns['sensing'] + by_ns['repulsion'])
    (repulsion,) = by_ns['repulsion']
    assert repulsion.scale.x == 2.0 and as_rows(repulsion.points) == padded
    assert len({(m.ns, m.id) for m in array.markers}) == len(array.markers)
    (lines,) = by_ns['paths']
    segments = as_rows(lines.points)
    assert lines.type == Marker.LINE_LIST and len(segments) == 2 * 3 * n
    kept = history[-4:]
    for i in range(n):
        mine = segments[6 * i:6 * i + 6]
        assert mine[0::2] == [(*k[i], 0.0) for k in kept[:-1]]
        assert mine[1::2] == [(*k[i], 0.0) for k in kept[1:]]


def test_a_single_moment_draws_no_path_and_3d_zones_are_balls():
    paths = Paths(2, length=10)
    q = np.array([[0.0, 0.0, 1.0], [1.0, 2.0, 3.0]])
    paths.append(q)
    array = formation_markers(q, np.array([1.5, 1.5]), 0.5, q, paths, 0)
    assert [m.ns for m in array.markers] == ['robots', 'sensing', 'repulsion', 'desired']
    sensing = array.markers[1]
    assert sensing.scale.x == sensing.scale.y == sensing.scale.z == 3.0
    assert isinstance(sensing.points[0], Point) and len(paths) == 1


def test_unicycle_headings_are_lines_ahead_and_every_marker_is_in_the_world_frame():
    paths = Paths(2, length=3)
    q = np.array([[0.0, 0.0], [1.0, 2.0]])
    paths.append(q)
    array = formation_markers(q, np.array([1.0, 1.0]), 0.5, q, paths, 0, 'map',
                              headings=np.array([0.0, np.pi / 2]))
    (ahead,) = [m for m in array.markers if m.ns == 'headings']
    assert ahead.type == Marker.LINE_LIST
    assert np.allclose(as_rows(ahead.points), [(0.0, 0.0, 0.0), (HEADING_LENGTH, 0.0, 0.0),
                                               (1.0, 2.0, 0.0), (1.0, 2.0 + HEADING_LENGTH, 0.0)])
    assert {m.header.frame_id for m in array.markers} == {'map'}


def test_obstacles_are_drawn_where_they_are_as_they_are():
    obstacles = Obstacles([1.0, 2.0, 0.5], [0.0, 0.0, 0.0, 2.0, 0.1], [], 0.3, 2)
    q = np.array([[0.0, -3.0]])
    array = formation_markers(q, np.array([1.0]), 0.5, q, Paths(1, 2), 0, 'map',
                              obstacles=obstacles)
    drawn = [m for m in array.markers if m.ns == 'obstacles']
    assert [m.type for m in drawn] == [Marker.CYLINDER, Marker.CUBE, Marker.CYLINDER,
                                       Marker.CYLINDER]
    assert len({m.id for m in drawn}) == 4 and all(m.header.frame_id == 'map' for m in drawn)
    pillar, wall, start, end = drawn
    assert (pillar.pose.position.x, pillar.pose.position.y) == (1.0, 2.0)
    assert pillar.scale.x == pillar.scale.y == 1.0 and pillar.scale.z == PILLAR_HEIGHT[2]
    assert (wall.pose.position.x, wall.pose.position.y) == (0.0, 1.0)
    assert (wall.scale.x, wall.scale.y) == (2.0, pytest.approx(0.2))
    yaw = 2.0 * np.arctan2(wall.pose.orientation.z, wall.pose.orientation.w)
    assert yaw == pytest.approx(np.pi / 2.0)
    assert (end.pose.position.x, end.pose.position.y) == (0.0, 2.0)
    assert end.scale.x == pytest.approx(0.2)
    balls = obstacle_markers(Obstacles([], [], [0.0, 1.0, 2.0, 0.7], 0.3, 3), 5)
    assert [m.type for m in balls] == [Marker.SPHERE]
    assert balls[0].pose.position.z == 2.0 and balls[0].scale.z == pytest.approx(1.4)
