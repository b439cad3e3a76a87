# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Obstacles (maths/obstacles.py): surfaces against sampled boundaries, terms against the gradient.

The closest surface points are checked against a brute-force search over densely sampled
boundaries and an independent inside test; the repulsion terms against a central finite
difference of the obstacles' part of log(phi + 1), for every jump kind, in 2D and 3D.
"""

import math

from formation_ros.core.maths.jump import make_jump
from formation_ros.core.maths.law import log_potential, make_law, robot_command, team_command
from formation_ros.core.maths.obstacles import (log_obstacle_factor, MAX_OBSTACLE_REPULSION,
                                                obstacle_beta, obstacle_terms, Obstacles)
from formation_ros.core.maths.reference import Reference
import numpy as np
import pytest

CIRCLES = [0.0, 0.0, 1.0, 3.0, 2.0, 0.4]
WALLS = [-2.0, -3.0, 2.0, -3.0, 0.1, 4.0, -1.0, 4.0, -1.0, 0.3]
SPHERES = [0.0, 4.0, 1.0, 0.7]
JUMPS = [('poly', 1), ('poly', 2), ('poly', 4), ('smooth', 2)]


def segment_distance(points, a, b):
    """Distances (K,) of points (K, 2) to the segment from a to b (a point when a is b)."""
    if np.array_equal(a, b):
        return np.linalg.norm(points - a, axis=1)
    s = np.clip((points - a) @ (b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return np.linalg.norm(points - (a + s[:, None] * (b - a)), axis=1)


def boundary_2d(circles, walls, per=20000):
    """Points on the boundary of each 2D shape: a list of (K, 2) arrays, in obstacle order."""
    angles = np.linspace(0.0, 2.0 * math.pi, per, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    shapes = [np.array(c[:2]) + c[2] * ring for c in np.reshape(circles, (-1, 3))]
    for x1, y1, x2, y2, t in np.reshape(walls, (-1, 5)):
        a, b = np.array([x1, y1]), np.array([x2, y2])
        if np.array_equal(a, b):
            shapes.append(a + t * ring)
            continue
        normal = np.array([a[1] - b[1], b[0] - a[0]]) / np.linalg.norm(b - a)
        spine = a + np.linspace(0.0, 1.0, per)[:, None] * (b - a)
        caps = np.concatenate([a + t * ring, b + t * ring])
        caps = caps[segment_distance(caps, a, b) >= t * (1.0 - 1e-9)]
        shapes.append(np.concatenate([spine + t * normal, spine - t * normal, caps]))
    return shapes


def central_gradient(function, q, step=1e-6):
    """Return the gradient of a function of positions q (N, dim) by central differences."""
    slope = np.zeros_like(q)
    for index in np.ndindex(*q.shape):
        up, down = q.copy(), q.copy()
        up[index] += step
        down[index] -= step
        slope[index] = (function(up) - function(down)) / (2.0 * step)
    return slope


def inside_2d(p, circles, walls):
    """Whether p is strictly inside each 2D shape, from the definitions."""
    result = [math.dist(p, c[:2]) < c[2] for c in np.reshape(circles, (-1, 3))]
    for x1, y1, x2, y2, t in np.reshape(walls, (-1, 5)):
        gap = segment_distance(p[None, :], np.array([x1, y1]), np.array([x2, y2]))[0]
        result.append(gap < t)
    return result


def test_the_closest_surface_points_in_2d_are_those_of_a_dense_search():
    obstacles = Obstacles(CIRCLES, WALLS, [], 0.5, 2)
    rng = np.random.default_rng(3)
    q = rng.uniform(-4.0, 6.0, size=(60, 2))
    surface = obstacles.surface(q)
    shapes = boundary_2d(CIRCLES, WALLS)
    assert surface.points.shape == (60, 4, 2) and surface.distances.shape == (60, 4)
    for i, p in enumerate(q):
        inside = inside_2d(p, CIRCLES, WALLS)
        for o, shape in enumerate(shapes):
            gaps = np.linalg.norm(shape - p, axis=1)
            nearest = shape[np.argmin(gaps)]
            sign = -1.0 if inside[o] else 1.0
            assert surface.distances[i, o] == pytest.approx(sign * gaps.min(), abs=2e-3)
            assert np.linalg.norm(surface.points[i, o] - nearest) < 0.05
            assert abs(np.linalg.norm(surface.normals[i, o]) - 1.0) < 1e-12


def test_pillars_walls_and_spheres_in_3d_keep_the_robots_height():
    obstacles = Obstacles(CIRCLES, WALLS, SPHERES, 0.5, 3)
    q = np.array([[1.5, 0.0, 7.0], [0.0, 4.0, 2.0], [0.0, -2.5, -1.0]])
    surface = obstacles.surface(q)
    assert surface.points.shape == (3, 5, 3)
    assert np.allclose(surface.points[:, :4, 2], q[:, 2:3])
    assert np.allclose(surface.normals[:, :4, 2], 0.0)
    assert surface.distances[0, 0] == pytest.approx(0.5)
    assert surface.distances[1, 4] == pytest.approx(1.0 - 0.7)
    assert np.allclose(surface.points[1, 4], [0.0, 4.0, 1.7])
    assert surface.distances[2, 2] == pytest.approx(0.5 - 0.1)


@pytest.mark.parametrize('kind,order', JUMPS)
@pytest.mark.parametrize('dim', [2, 3])
def test_the_terms_are_the_gradient_of_the_obstacles_log_factor(kind, order, dim):
    jump = make_jump(kind, order)
    kappa, clearance = 0.7, 0.8
    obstacles = Obstacles(CIRCLES, WALLS, SPHERES if dim == 3 else [], clearance, dim)
    rng = np.random.default_rng(11 + dim + order)
    q = rng.uniform(-3.0, 5.0, size=(400, dim))
    d = obstacles.surface(q).distances
    q = q[np.all(d > 0.05, axis=1) & np.any(d < clearance - 0.05, axis=1)][:12]
    assert len(q) >= 6
    terms = obstacle_terms(q, obstacles.surface(q), jump, clearance, np.full(len(q), 10.0))
    slope = central_gradient(lambda x: log_obstacle_factor(x, obstacles, jump, kappa), q)
    assert np.allclose(-kappa * terms, slope, rtol=1e-5, atol=1e-6)


def test_only_obstacles_within_the_clearance_and_the_sensing_radius_count():
    jump = make_jump('poly', 2)
    obstacles = Obstacles([0.0, 0.0, 1.0], [], [], 0.5, 2)
    q = np.array([[1.3, 0.0], [1.6, 0.0], [1.3, 0.0]])
    before = q.copy()
    terms = obstacle_terms(q, obstacles.surface(q), jump, 0.5, [1.0, 1.0, 0.25])
    assert np.array_equal(q, before)
    assert terms[0, 0] > 0.0 and terms[0, 1] == 0.0
    assert np.all(terms[1:] == 0.0)
    assert obstacle_beta([0.6, 0.5, 0.2, 0.0, -0.1], jump, 0.5).tolist()[:2] == [1.0, 1.0]
    assert obstacle_beta([0.0, -0.1], jump, 0.5).tolist() == [0.0, 0.0]


def test_a_robot_on_or_inside_an_obstacle_is_pushed_out_at_the_cap():
    jump = make_jump('smooth', 2)
    obstacles = Obstacles([0.0, 0.0, 1.0], [], [0.0, 0.0, 5.0, 1.0], 0.5, 3)
    q = np.array([[0.0, 0.5, 0.0], [0.0, 1.0, 3.0], [0.0, 0.0, 5.5]])
    terms = obstacle_terms(q, obstacles.surface(q), jump, 0.5, np.full(3, 2.0))
    assert np.array_equal(terms[0], [0.0, MAX_OBSTACLE_REPULSION, 0.0])
    assert np.array_equal(terms[1], [0.0, MAX_OBSTACLE_REPULSION, 0.0])
    assert np.array_equal(terms[2], [MAX_OBSTACLE_REPULSION, 0.0, MAX_OBSTACLE_REPULSION])
    assert log_obstacle_factor(q[:1], obstacles, jump, 1.0) == math.inf


@pytest.mark.parametrize('kwargs,message', [
    ({'circles': [0.0, 0.0]}, 'circles takes 3 numbers'),
    ({'circles': [0.0, 0.0, -1.0]}, 'radius must be > 0'),
    ({'walls': [0.0, 0.0, 1.0, 1.0, 0.0]}, 'half-thickness must be > 0'),
    ({'spheres': [0.0, 0.0, 0.0, 1.0]}, 'spheres are 3D obstacles'),
    ({'circles': [math.nan, 0.0, 1.0]}, 'must be finite'),
    ({'clearance': 0.0}, 'clearance must be'),
])
def test_invalid_obstacles_are_refused_with_the_reason(kwargs, message):
    values = {'circles': [], 'walls': [], 'spheres': [], 'clearance': 0.5, 'dim': 2, **kwargs}
    with pytest.raises(ValueError, match=message):
        Obstacles(**values)


def test_the_obstacles_keep_their_own_copies():
    circles = np.array([0.0, 0.0, 1.0])
    obstacles = Obstacles(circles, [], [], 0.5, 2)
    circles[2] = 5.0
    assert obstacles.circles[0, 2] == 1.0 and obstacles.count == 1
    with pytest.raises(ValueError):
        obstacles.circles[0, 2] = 2.0


def law_and_team(dim, kind='poly', order=2):
    law = make_law(0.3, 0.05, 'arctan', kind, order, 0.6)
    rng = np.random.default_rng(5 + dim)
    obstacles = Obstacles(CIRCLES, WALLS, SPHERES if dim == 3 else [], 0.5, dim)
    q = rng.uniform(-3.0, 5.0, size=(300, dim))
    d = obstacles.surface(q).distances
    q = q[np.all(d > 0.1, axis=1)][:8]
    q = q[np.all(np.linalg.norm(q[:, None] - q[None], axis=2) + np.eye(len(q)) > 0.1, axis=1)]
    return law, obstacles, q, rng.uniform(-1.0, 1.0, size=q.shape)


@pytest.mark.parametrize('kind,order', JUMPS)
@pytest.mark.parametrize('dim', [2, 3])
def test_omega_with_obstacles_is_the_gradient_of_the_log_potential(kind, order, dim):
    law, obstacles, q, vertices = law_and_team(dim, kind, order)
    radii = np.full(len(q), 10.0)
    command = team_command(q, vertices, radii, law, obstacles=obstacles)
    slope = central_gradient(lambda x: log_potential(x, vertices, law, obstacles=obstacles), q)
    assert np.allclose(command.omega, slope, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize('dim', [2, 3])
def test_one_robot_and_the_team_agree_with_obstacles_in_a_moving_frame(dim):
    law, obstacles, q, vertices = law_and_team(dim)
    reference = Reference('circle' if dim == 2 else 'helix', dim, origin=[0.5] * dim,
                          radius=2.0, speed=0.4, pitch=1.0)
    frame = reference.sample(3.0)
    radii = np.linspace(0.6, 3.0, len(q))
    team = team_command(q, vertices, radii, law, frame, obstacles=obstacles)
    for i in range(len(q)):
        others = np.delete(q, i, axis=0)
        one = robot_command(q[i], vertices[i], others, radii[i], law, frame, obstacles)
        assert np.allclose(one.u, team.u[i], rtol=1e-12, atol=1e-12)
    bare = team_command(q, vertices, radii, law, frame)
    near = np.any(obstacles.surface(q).distances < obstacles.clearance, axis=1)
    assert np.any(near) and not np.allclose(team.omega[near], bare.omega[near])
    assert np.array_equal(team.omega[~near], bare.omega[~near])


def test_the_command_stays_bounded_on_and_inside_obstacles():
    law = make_law(0.3, 0.05, 'tanh', 'smooth', 2, 0.6)
    obstacles = Obstacles(CIRCLES, WALLS, [], 0.5, 2)
    q = np.array([[0.0, 1.0], [0.2, 0.1], [0.0, -2.9], [3.0, 2.4000001]])
    command = team_command(q, np.zeros_like(q), np.full(4, 2.0), law, obstacles=obstacles)
    assert np.all(np.isfinite(command.u))
    assert np.max(np.abs(command.u_hat)) <= law.u_bound
    assert command.u_hat[0, 1] == pytest.approx(law.u_bound)


def random_map(rng, dim, side, counts):
    """Return random circles, walls and (3D) spheres, ``counts`` of each, within +-side m."""
    circles = np.column_stack([rng.uniform(-side, side, (counts[0], 2)),
                               rng.uniform(0.1, 0.6, counts[0])])
    walls = np.column_stack([rng.uniform(-side, side, (counts[1], 4)),
                             rng.uniform(0.05, 0.2, counts[1])])
    spheres = (np.column_stack([rng.uniform(-side, side, (counts[2], 3)),
                                rng.uniform(0.2, 0.8, counts[2])]) if dim == 3 else [])
    return Obstacles(circles, walls, spheres, 0.9, dim)


@pytest.mark.parametrize('dim', [2, 3])
def test_the_terms_measured_near_only_are_the_terms_of_every_surface(dim):
    """Obstacles.terms skips far pairs: the same sums as obstacle_terms of the whole surface."""
    rng = np.random.default_rng(7 + dim)
    obstacles = random_map(rng, dim, 8.0, (30, 6, 5))
    q = rng.uniform(-9.0, 9.0, size=(400, dim))
    radii = rng.uniform(0.5, 2.0, size=len(q))
    jump = make_jump('poly', 2)
    every = obstacle_terms(q, obstacles.surface(q), jump, obstacles.clearance, radii)
    near = obstacles.terms(q, jump, radii)
    assert np.any(np.any(every != 0.0, axis=1)) and np.any(np.all(every == 0.0, axis=1))
    assert np.max(np.abs(near - every)) <= 1e-12 * max(1.0, float(np.max(np.abs(every))))


@pytest.mark.parametrize('dim', [2, 3])
def test_the_distances_alone_are_the_surfaces_distances(dim):
    rng = np.random.default_rng(11 + dim)
    obstacles = random_map(rng, dim, 5.0, (8, 3, 2))
    q = rng.uniform(-6.0, 6.0, size=(200, dim))
    assert np.allclose(obstacles.distances(q), obstacles.surface(q).distances, rtol=0.0,
                       atol=1e-12)
    assert obstacles.distances(q).shape == (200, obstacles.count)
    assert Obstacles([], [], [], 0.9, dim).distances(q).shape == (200, 0)


def mixed_map(rng, dim):
    """Return a random map: pillars, short and long walls, (3D) balls, b_o from 5 cm to 3 m."""
    side = float(rng.choice([3.0, 20.0]))
    count = rng.integers(1, 40)
    circles = np.column_stack([rng.uniform(-side, side, (count, 2)),
                               rng.uniform(0.05, 1.5, count)])
    ends = rng.uniform(-side, side, (rng.integers(0, 6), 2))
    walls = np.column_stack([ends, ends + rng.normal(0.0, rng.choice([0.3, side]), ends.shape),
                             rng.uniform(0.02, 0.3, len(ends))])
    balls = rng.integers(0, 8) if dim == 3 else 0
    spheres = np.column_stack([rng.uniform(-side, side, (balls, 3)),
                               rng.uniform(0.1, 1.0, balls)]) if dim == 3 else []
    return Obstacles(circles, walls, spheres, float(rng.choice([0.05, 0.5, 3.0])), dim), side


@pytest.mark.parametrize('dim', [2, 3])
def test_the_grid_gives_the_terms_of_every_surface_on_random_maps(dim):
    """The grid's pairs are those of the test over every pair, in the same order."""
    jump = make_jump('smooth', 2)
    acting = 0
    for seed in range(20):
        rng = np.random.default_rng(100 * dim + seed)
        obstacles, side = mixed_map(rng, dim)
        q = rng.uniform(-1.5 * side, 1.5 * side, size=(200, dim))
        radii = rng.uniform(0.5, 2.0, size=len(q)) * obstacles.clearance
        every = obstacle_terms(q, obstacles.surface(q), jump, obstacles.clearance, radii)
        near = obstacles.terms(q, jump, radii)
        acting += int(np.count_nonzero(np.any(every != 0.0, axis=1)))
        assert np.max(np.abs(near - every)) <= 1e-12 * max(1.0, float(np.max(np.abs(every))))
    assert acting > 200


def test_a_map_wider_than_the_doubles_is_searched_whole():
    """Pillars 2e308 m apart (no grid divides that) act as each would alone."""
    jump = make_jump('poly', 2)
    obstacles = Obstacles([1e308, 0.0, 1.0, -1e308, 0.0, 1.0, 0.0, 0.0, 1.0], [], [], 0.5, 2)
    q = np.array([[0.0, 1.3], [0.0, 1.6], [-1e308, 1.2]])
    with np.errstate(over='ignore', invalid='ignore'):
        terms = obstacles.terms(q, jump, [1.0, 1.0, 1.0])
    alone = [Obstacles([x, 0.0, 1.0], [], [], 0.5, 2).terms(q[k:k + 1], jump, [1.0])[0]
             for k, x in enumerate([0.0, 0.0, -1e308])]
    assert terms[0, 1] > 0.0 and terms[1, 1] == 0.0 and terms[2, 1] > 0.0
    assert np.array_equal(terms, alone)


@pytest.mark.parametrize('dim', [2, 3])
def test_the_pairs_nearby_hold_every_near_pair_with_its_distance(dim):
    for seed in range(20):
        rng = np.random.default_rng(300 * dim + seed)
        obstacles, side = mixed_map(rng, dim)
        q = rng.uniform(-1.5 * side, 1.5 * side, size=(200, dim))
        every = obstacles.distances(q)
        within = float(rng.choice([0.1, 1.0, 4.0]))
        robots, kinds, distances = obstacles.nearby(q, within)
        assert np.array_equal(distances, every[robots, kinds])
        listed = np.zeros(every.shape, dtype=bool)
        listed[robots, kinds] = True
        assert np.all(listed[every < within])
        assert len(robots) == np.count_nonzero(listed) < every.size
