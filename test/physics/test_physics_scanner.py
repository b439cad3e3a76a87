# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world's laser scanner against geometry: pillars, walls, other bodies, its own, range."""

import math

from formation_ros.core.maths.scan import scan_points, scan_problem
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.params import validate
from formation_ros.physics.engine import Engine
from formation_ros.physics.scanner import height_note, scan_period, steps_per_scan
import numpy as np
from physics_helpers import bases, team
import pytest

BODY = 0.11
"""The bases' footprint radius (body.radius), m."""
PILLAR = (1.2, 0.9, 0.1)
"""A pillar 1.5 m from robot 1 at the origin, at 36.87 degrees: x, y, r (m)."""
WALL = (-1.0, -1.5, 1.0, -1.5, 0.05)
"""A wall below the team: x1, y1, x2, y2, t (m)."""
OBSTACLES = {'obstacles.circles': list(PILLAR), 'obstacles.walls': list(WALL),
             'obstacles.clearance': 0.2, 'sensing_radius': 3.0, 'repulsion_radius': 0.5}


def lab(headings=(0.0, 0.0), extra=None):
    """Return an engine of two bases (robot 2 1 m along +x of robot 1) with a pillar and a wall."""
    config = bases([[0.0, 0.0], [1.0, 0.0]], list(headings),
                   {'formation.vertices': [0.0, 0.0, 1.0, 0.0], **OBSTACLES, **(extra or {})})
    return Engine(config)


def test_the_ray_through_a_pillar_s_centre_reads_the_distance_to_its_surface():
    heading = math.radians(6.87)
    engine = lab((heading, 0.0))
    ranges = engine.scans()[0]
    assert ranges.shape == (360,)
    # The pillar is at 36.87 degrees in the world: 30 degrees (ray 30) from the base's +x.
    centre = math.hypot(PILLAR[0], PILLAR[1])
    assert ranges[30] == pytest.approx(centre - PILLAR[2], abs=1e-6)
    # Robot 2 along world +x: at -6.87 degrees in the base, between rays 353 and 354.
    assert ranges[353] == pytest.approx(1.0 - BODY, abs=2e-3)
    # The wall's face, 1.45 m below the robot, along world -y: about ray 263 (-96.87 degrees).
    ray = int(round((270.0 - 6.87) % 360))
    assert ranges[ray] == pytest.approx(1.45 / math.cos(math.radians(270.0 - 6.87 - ray)),
                                        abs=1e-6)


def test_every_return_read_back_lies_on_an_obstacle_or_another_body():
    engine = lab((0.4, 2.0), {'world.scan_range_min': 0.0})
    scans = engine.scans()
    shape = engine.scanner.shape
    positions, headings = engine.planar_state()
    for robot in range(2):
        assert scan_problem(scans[robot], shape) is None
        points = scan_points(scans[robot], shape, positions[robot], float(headings[robot]))
        assert len(points) > 20
        on_obstacle = np.abs(engine.obstacles.surface(points).distances).min(axis=1)
        other = positions[1 - robot]
        on_body = np.abs(np.linalg.norm(points - other, axis=1) - BODY)
        assert np.all((on_obstacle < 1e-6) | (on_body < 1e-3)), (robot, points)
        assert np.any(on_body < 1e-3) and np.any(on_obstacle < 1e-6)
        mine = np.linalg.norm(points - positions[robot], axis=1)
        assert np.all(mine > BODY + 0.05), 'its own body is never seen'


def test_a_robot_alone_sees_nothing_not_its_own_body_nor_its_wheels():
    for config in (bases([[0.0, 0.0], [9.0, 0.0]], [0.3, 0.0],
                         {'world.scan_range_min': 0.0, 'world.scan_range_max': 3.0}),
                   team([[0.0, 0.0], [9.0, 0.0]], extra={
                       'body.radius': 0.1, 'world.scan_range_min': 0.0,
                       'world.scan_range_max': 3.0})):
        engine = Engine(config)
        scans = engine.scans()
        assert np.all(np.isinf(scans)) and np.all(scans > 0), engine.model.kind
        engine.step(50)
        assert np.all(np.isinf(engine.scans()))


def test_a_pillar_beyond_range_max_reads_inf_and_within_it_its_distance():
    far = {'obstacles.circles': [4.0, 0.0, 0.1], 'obstacles.clearance': 0.2,
           'sensing_radius': 3.0, 'formation.vertices': [0.0, 0.0, 0.0, -1.0]}
    positions = [[0.0, 0.0], [0.0, -1.0]]
    short = Engine(bases(positions, [0.0, 0.0], far)).scans()[0]
    assert np.isinf(short[0]) and short[0] > 0
    long = Engine(bases(positions, [0.0, 0.0], {**far, 'world.scan_range_max': 5.0})).scans()[0]
    assert long[0] == pytest.approx(3.9, abs=1e-6)
    near = Engine(bases(positions, [0.0, 0.0], {**far, 'world.scan_range_min': 3.95,
                                                'world.scan_range_max': 5.0})).scans()[0]
    assert np.isinf(near[0]), 'a return below range_min reads +inf'


def test_obstacles_lower_than_the_scan_plane_are_not_seen_and_said_so():
    low = lab(extra={'world.obstacle_height': 0.04})
    assert low.scanner.height == pytest.approx(0.0565)
    assert np.isinf(low.scans()[0][30]), 'the scan passes over the pillar'
    note = height_note(low.obstacles.count, 0.04, low.scanner.height)
    assert note is not None and 'pass over every obstacle' in note
    assert height_note(low.obstacles.count, 0.5, low.scanner.height) is None
    assert height_note(0, 0.04, low.scanner.height) is None


def test_the_noise_is_gaussian_and_seeded_by_start_seed():
    noisy = {'world.scan_noise': 0.01, 'start.seed': 7}
    first, again = lab(extra=noisy), lab(extra=noisy)
    scans = [first.scans() for _ in range(20)]
    assert np.array_equal(np.stack(scans), np.stack([again.scans() for _ in range(20)]))
    other = lab(extra={**noisy, 'start.seed': 8}).scans()
    hits = np.isfinite(scans[0]) & np.isfinite(other)
    assert not np.allclose(scans[0][hits], other[hits])
    exact = lab().scans()
    errors = np.concatenate([scan[both] - exact[both] for scan in scans
                             for both in [np.isfinite(scan) & np.isfinite(exact)]])
    assert len(errors) > 500
    assert abs(np.mean(errors)) < 0.002 and 0.008 < np.std(errors) < 0.012


def test_flyers_and_a_zero_rate_have_no_scanner():
    flyers = Engine(team([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]], dim=3))
    off = lab(extra={'world.scan_rate': 0.0})
    for engine in (flyers, off):
        assert engine.scanner is None
        with pytest.raises(ValueError, match='no scanner'):
            engine.scans()


def test_the_period_is_a_whole_number_of_steps():
    world = lab(extra={'world.scan_rate': 7.0}).world
    assert steps_per_scan(world) == 71 and scan_period(world) == pytest.approx(0.142)
    assert steps_per_scan(lab().world) == 100


@pytest.mark.parametrize('given, name, text', [
    ({'world.scan_rays': 0}, 'world.scan_rays', '>= 1'),
    ({'world.scan_rays': 2.5}, 'world.scan_rays', 'integer'),
    ({'world.scan_range_min': 3.5}, 'world.scan_range_min', 'not less than'),
    ({'world.scan_range_min': -0.1}, 'world.scan_range_min', '>= 0'),
    ({'world.scan_range_max': 0.0}, 'world.scan_range_max', '> 0'),
    ({'world.scan_noise': -0.01}, 'world.scan_noise', '>= 0'),
    ({'world.scan_rate': -1.0}, 'world.scan_rate', '>= 0'),
    ({'world.scan_rate': 1000.0}, 'world.scan_rate', 'faster than the engine steps'),
])
def test_bad_scanner_values_are_refused_with_their_name(given, name, text):
    params = {'num_robots': 2, 'dim': 2, 'sensing_radius': 2.0, 'repulsion_radius': 0.5,
              'formation.vertices': [0.0, 0.0, 1.0, 0.0],
              'start.positions': [0.0, 0.0, 1.0, 0.0], **given}
    with pytest.raises(ParamError) as caught:
        validate(params)
    assert [problem[0] for problem in caught.value.problems] == [name]
    assert text in str(caught.value)
