# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A laser scan as obstacle points (core/maths/scan.py), against geometry done by hand."""

import math

from formation_ros.core.maths.scan import (full_turn, nearest_by_sector, off_neighbours,
                                           returning_rays, scan_points, scan_problem,
                                           ScanShape)
import numpy as np
import pytest

LDS = ScanShape(angle_min=0.0, angle_increment=2.0 * math.pi / 360, range_min=0.12,
                range_max=3.5)


def ray_hits_circle(origin, angle, centre, radius):
    """Return the distance along a ray to a circle's surface (+inf if it misses), by algebra."""
    d = np.array([math.cos(angle), math.sin(angle)])
    f = np.asarray(origin, dtype=float) - centre
    b = float(f @ d)
    c = float(f @ f) - radius ** 2
    disc = b * b - c
    if disc < 0.0:
        return math.inf
    t = -b - math.sqrt(disc)
    return t if t > 0.0 else math.inf


def lds_scan(origin, heading, centre, radius, shape=LDS):
    """Return the LDS's ranges from ``origin`` facing ``heading`` with one pillar about."""
    ranges = []
    for k in range(360):
        hit = ray_hits_circle(origin, heading + shape.angle_min + k * shape.angle_increment,
                              np.asarray(centre, dtype=float), radius)
        ranges.append(hit if shape.range_min <= hit <= shape.range_max else math.inf)
    return np.array(ranges)


@pytest.mark.parametrize('heading', [0.0, 0.7, -2.5])
def test_every_return_lies_on_the_pillar(heading):
    origin, centre, radius = np.array([1.0, -0.5]), np.array([2.2, 0.4]), 0.3
    points = scan_points(lds_scan(origin, heading, centre, radius), LDS, origin, heading)
    assert len(points) > 10
    assert np.allclose(np.linalg.norm(points - centre, axis=1), radius, atol=1e-9)


def test_the_ray_through_the_centre_reads_the_distance_to_the_surface():
    origin, heading = np.array([0.0, 0.0]), 0.3
    centre = np.array([2.0 * math.cos(heading + math.radians(40)),
                       2.0 * math.sin(heading + math.radians(40))])
    ranges = lds_scan(origin, heading, centre, 0.25)
    assert ranges[40] == pytest.approx(2.0 - 0.25, abs=1e-12)
    points = scan_points(ranges, LDS, origin, heading)
    nearest = points[np.argmin(np.linalg.norm(points - origin, axis=1))]
    assert np.allclose(nearest, centre * (1.75 / 2.0), atol=1e-12)


def test_a_mounted_scanner_sees_from_where_it_sits():
    mount = ScanShape(0.0, LDS.angle_increment, 0.0, 3.5, mount=(-0.05, 0.02), mount_yaw=0.0)
    position, heading = np.array([0.5, 0.5]), math.pi / 2
    scanner = position + np.array([-0.02, -0.05])
    centre, radius = np.array([0.0, 2.0]), 0.4
    points = scan_points(lds_scan(scanner, heading, centre, radius, mount), mount, position,
                         heading)
    assert len(points) and np.allclose(np.linalg.norm(points - centre, axis=1), radius)


def test_rays_without_a_return_give_no_point():
    ranges = np.full(360, np.inf)
    ranges[[0, 90, 180]] = [1.0, 0.05, 3.6]
    points = scan_points(ranges, LDS, [0.0, 0.0], 0.0)
    assert np.allclose(points, [[1.0, 0.0]])


@pytest.mark.parametrize('ranges, shape, words', [
    ([1.0, math.nan, math.nan], LDS, 'most ranges are NaN'),
    ([], LDS, 'no rays'),
    (np.ones(400), LDS, 'more than a full turn'),
    ([1.0], ScanShape(1e300, 0.1, 0.1, 3.5), 'an angle beyond'),
    ([1.0], ScanShape(0.0, 0.1, 0.1, 3.5, mount_yaw=20.0), 'an angle beyond'),
    ([1.0], ScanShape(0.0, 0.0, 0.1, 3.5), 'angle_increment must be > 0'),
    ([1.0], ScanShape(0.0, 0.1, 3.5, 3.5), 'range_min < range_max'),
    ([1.0], ScanShape(math.nan, 0.1, 0.1, 3.5), 'non-finite'),
])
def test_unreadable_scans_are_named(ranges, shape, words):
    assert words in scan_problem(ranges, shape)


def test_a_scan_of_infinities_is_readable():
    assert scan_problem(np.full(360, np.inf), LDS) is None


def test_rep_117_a_nan_ray_tells_nothing_and_minus_inf_is_an_object_nearer_than_range_min():
    ranges = np.full(360, np.inf)
    ranges[[0, 90, 180]] = [math.nan, -math.inf, 1.0]
    assert scan_problem(ranges, LDS) is None
    points = scan_points(ranges, LDS, [0.0, 0.0], 0.0)
    assert np.allclose(points, [[0.0, LDS.range_min], [-1.0, 0.0]])
    assert np.array_equal(returning_rays(ranges, LDS), [90, 180])


def test_a_full_turn_of_rays_rounded_by_a_driver_still_goes_round():
    nearly = ScanShape(0.0, 2.0 * math.pi / 360 * (1.0 - 1e-4), 0.12, 3.5)
    assert full_turn(nearly, 360) and not full_turn(nearly, 180)


def test_returns_on_a_neighbour_are_left_out():
    points = np.array([[1.0, 0.0], [1.1, 0.05], [3.0, 3.0]])
    kept = off_neighbours(points, [[1.05, 0.0]], 0.2)
    assert kept.tolist() == [False, False, True]
    assert off_neighbours(points, np.zeros((0, 2)), 0.2).all()


def test_one_nearest_point_per_sector_within_the_radius():
    rng = np.random.default_rng(3)
    centre = np.array([0.2, -0.1])
    points = centre + rng.uniform(-3.0, 3.0, size=(500, 2))
    kept = nearest_by_sector(points, centre, 2.0, sectors=36)
    expected = []
    for k in range(36):
        low = -math.pi + k * 2.0 * math.pi / 36
        inside = [p for p in points
                  if np.linalg.norm(p - centre) < 2.0
                  and low <= math.atan2(p[1] - centre[1], p[0] - centre[0])
                  < low + 2.0 * math.pi / 36]
        if inside:
            expected.append(min(inside, key=lambda p: np.linalg.norm(p - centre)))
    assert np.allclose(kept, expected)


def test_nothing_near_is_no_point():
    assert nearest_by_sector([[5.0, 5.0]], [0.0, 0.0], 1.0).shape == (0, 2)
