# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A robot's obstacles from its own scans (core/rules/scan_obstacles.py), on synthetic scans."""

import math

from formation_ros.core.maths.jump import JumpKind
from formation_ros.core.maths.law import make_law, PsiKind
from formation_ros.core.maths.obstacles import HeardObstacles, Obstacles
from formation_ros.core.maths.unicycle import quaternions_from_headings
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.scan_obstacles import EDGE_NS, MAX_RAYS, Scan, ScanObstacles
from formation_ros.core.settings.params import ScanSettings
import numpy as np
import pytest

RAYS = 360
STEP = 2.0 * math.pi / RAYS
RANGE_MIN, RANGE_MAX = 0.12, 3.5
FRAME = 'robot_1/base_scan'
SECOND = 1_000_000_000


def ray_hit(origin, angle, centre, radius):
    """Distance along a ray to a circle (+inf if it misses), by the quadratic formula."""
    d = np.array([math.cos(angle), math.sin(angle)])
    f = np.asarray(origin, dtype=float) - np.asarray(centre, dtype=float)
    b, c = float(f @ d), float(f @ f) - radius ** 2
    if b * b - c < 0.0:
        return math.inf
    t = -b - math.sqrt(b * b - c)
    return t if t > 0.0 else math.inf


def synthetic(origin, heading, circles, stamp_ns=SECOND, frame=FRAME, mount=(0.0, 0.0, 0.0)):
    """Return a 360-ray scan from a scanner at ``mount`` on a base at ``origin``, ``heading``."""
    c, s = math.cos(heading), math.sin(heading)
    scanner = np.asarray(origin, dtype=float) + (c * mount[0] - s * mount[1],
                                                 s * mount[0] + c * mount[1])
    ranges = []
    for k in range(RAYS):
        angle = heading + mount[2] + k * STEP
        hit = min(ray_hit(scanner, angle, centre, r) for centre, r in circles)
        ranges.append(hit if RANGE_MIN <= hit <= RANGE_MAX else math.inf)
    return Scan(stamp_ns, frame, 0.0, STEP, RANGE_MIN, RANGE_MAX, np.array(ranges))


def quaternion(heading):
    return tuple(quaternions_from_headings(np.array([heading]))[0])


def rule(mount=(0.0, 0.0, 0.0), radius=2.0, sectors=72, margin=0.05, body=0.1, join=0.2):
    return ScanObstacles(ScanSettings(FRAME, mount[:2], mount[2], margin, join, sectors),
                         radius, body)


def held(rule_, origin, heading, stamp_ns=SECOND):
    rule_.pose_heard(stamp_ns, (origin[0], origin[1], 0.0), quaternion(heading))


@pytest.mark.parametrize('mount', [(0.0, 0.0, 0.0), (-0.032, 0.0, 0.0), (0.05, 0.02, 0.3)])
@pytest.mark.parametrize('heading', [0.0, 1.1, -2.8])
def test_returns_lie_on_the_pillar_seen(mount, heading):
    origin, centre, r = np.array([0.4, -0.2]), np.array([1.5, 0.3]), 0.2
    scans = rule(mount)
    held(scans, origin, heading)
    scans.scan_heard(synthetic(origin, heading, [(centre, r)], mount=mount))
    placed = scans.place(SECOND)
    assert placed is not None and len(placed.points) > 5
    assert np.allclose(np.linalg.norm(placed.points - centre, axis=1), r, atol=1e-6)


def test_neighbour_returns_left_to_the_pair_terms_and_the_rest_kept():
    origin, pillar, neighbour = np.zeros(2), (np.array([0.0, 1.0]), 0.15), np.array([1.0, 0.0])
    scans = rule(body=0.1, margin=0.05)
    held(scans, origin, 0.0)
    scans.scan_heard(synthetic(origin, 0.0, [pillar, (neighbour, 0.1)]))
    placed = scans.place(SECOND)
    points, normals = scans.obstacles(placed, origin, origin, neighbour[None, :])
    assert len(points) == 1, 'the pillar, by its nearest return'
    assert np.allclose(points[0], (0.0, 0.85), atol=1e-6)
    alone, _ = scans.obstacles(placed, origin, origin, np.zeros((0, 3)))
    assert len(alone) == 2 and np.any(np.linalg.norm(alone - neighbour, axis=1) < 0.15)
    assert np.allclose(normals, -points / np.linalg.norm(points, axis=1, keepdims=True))


def test_blind_zone_and_no_return_give_no_point():
    origin = np.zeros(2)
    scans = rule()
    held(scans, origin, 0.0)
    raw = np.full(RAYS, np.inf)
    raw[[0, 1, 2, 90]] = [0.05, 0.0, RANGE_MIN - 1e-6, 1.0]
    scans.scan_heard(Scan(SECOND, FRAME, 0.0, STEP, RANGE_MIN, RANGE_MAX, raw))
    near = scans.place(SECOND)
    assert near is not None and np.allclose(near.points, [[0.0, 1.0]])
    scans.scan_heard(Scan(2 * SECOND, FRAME, 0.0, STEP, RANGE_MIN, RANGE_MAX,
                          np.full(RAYS, np.inf)))
    held(scans, origin, 0.0, 2 * SECOND)
    empty = scans.place(SECOND)
    assert empty is not None and len(empty.points) == 0
    points, normals = scans.obstacles(empty, origin, origin, np.zeros((0, 3)))
    assert points.shape == (0, 2) and normals.shape == (0, 2)


def test_beyond_r_i_dropped_and_one_point_a_sector():
    origin = np.zeros(2)
    scans = rule(radius=1.0, sectors=8, join=0.0)
    held(scans, origin, 0.0)
    scans.scan_heard(synthetic(origin, 0.0, [(np.array([0.6, 0.0]), 0.2),
                                             (np.array([-2.0, 0.0]), 0.3)]))
    points, _ = scans.obstacles(scans.place(SECOND), origin, origin, np.zeros((0, 3)))
    distances = np.linalg.norm(points, axis=1)
    assert np.all(distances < 1.0)
    sectors = np.floor((np.arctan2(points[:, 1], points[:, 0]) + math.pi) / (2 * math.pi) * 8)
    assert len(np.unique(sectors)) == len(points) > 1
    assert math.isclose(distances.min(), 0.4, abs_tol=1e-6)


def wall_and_pillars(origin, heading):
    """Return a scan of a long wall (as a row of touching discs) and two pillars."""
    wall = [(np.array([x, -1.0]), 0.05) for x in np.arange(-1.5, 1.51, 0.05)]
    return synthetic(origin, heading, wall + [(np.array([0.8, 0.6]), 0.1),
                                              (np.array([-0.8, 0.6]), 0.1)])


@pytest.mark.parametrize('heading', [0.0, math.pi / 2, -math.pi / 2, 3.0])
def test_each_obstacle_repels_by_its_nearest_return_wherever_the_scan_starts(heading):
    origin = np.zeros(2)
    scans = rule(radius=2.0)
    held(scans, origin, heading)
    scans.scan_heard(wall_and_pillars(origin, heading))
    points, _ = scans.obstacles(scans.place(SECOND), origin, origin, np.zeros((0, 3)))
    assert len(points) == 3, points
    nearest = sorted(np.linalg.norm(points, axis=1))
    assert nearest == pytest.approx([0.9, 0.9, 0.95], abs=2e-3), 'pillars, then the wall'


def test_two_runs_of_returns_apart_are_two_obstacles_and_a_half_turn_scan_does_not_wrap():
    origin = np.zeros(2)
    scans = rule(radius=3.0, join=0.2)
    held(scans, origin, 0.0)
    pillars = [(np.array([1.0, 0.0]), 0.1), (np.array([1.0, 0.35]), 0.1)]
    scans.scan_heard(synthetic(origin, 0.0, pillars))
    points, _ = scans.obstacles(scans.place(SECOND), origin, origin, np.zeros((0, 3)))
    assert len(points) == 2, 'a gap of 0.15 m between them: two obstacles'

    def ends_of(turn, stamp_ns):
        """Return the obstacles of a scan of ``turn`` rays with returns at both ends only."""
        held(scans, origin, 0.0, stamp_ns)
        scans.scan_heard(Scan(stamp_ns, FRAME, -math.pi / 2, STEP, RANGE_MIN, RANGE_MAX,
                              np.r_[np.full(5, 1.0), np.full(turn - 10, np.inf),
                                    np.full(5, 1.0)]))
        return scans.obstacles(scans.place(SECOND), origin, origin, np.zeros((0, 3)))[0]

    assert len(ends_of(180, 2 * SECOND)) == 2, 'a half turn: its end rays are not neighbours'
    points = ends_of(RAYS, 3 * SECOND)
    assert len(points) == 1, 'a full turn wraps: one obstacle across its first ray'


def test_the_scan_is_placed_with_the_pose_at_its_stamp():
    scans = rule()
    scans.pose_heard(0, (0.0, 0.0, 0.0), quaternion(3.0))
    scans.pose_heard(SECOND, (1.0, 2.0, 0.0), quaternion(-3.0))
    position, heading = scans.pose_at(SECOND // 4, 0)
    assert np.allclose(position, (0.25, 0.5))
    turn = 2.0 * math.pi - 6.0
    assert math.isclose(math.remainder(heading - (3.0 + turn / 4), 2 * math.pi), 0.0,
                        abs_tol=1e-9)
    assert scans.pose_at(SECOND + 100, 50) is None
    assert np.allclose(scans.pose_at(SECOND + 40, 50)[0], (1.0, 2.0))
    assert scans.pose_at(-100, 50) is None
    assert np.allclose(scans.pose_at(-40, 50)[0], (0.0, 0.0))


def test_a_pose_from_another_time_starts_the_poses_anew():
    scans = rule()
    held(scans, (0.0, 0.0), 0.0, 5 * SECOND)
    held(scans, (1.0, 0.0), 0.0, SECOND)
    assert len(scans.poses) == 1
    held(scans, (2.0, 0.0), 0.0, SECOND)
    assert len(scans.poses) == 1 and scans.poses[0][1][0] == 1.0


def test_a_scan_from_long_before_any_pose_kept_is_not_placed():
    scans = rule()
    held(scans, (0.0, 0.0), 0.0, 10 * SECOND)
    scans.scan_heard(synthetic((0.0, 0.0), 0.0, [(np.array([1.0, 0.0]), 0.2)], stamp_ns=SECOND))
    assert scans.place(SECOND) is None


@pytest.mark.parametrize('change, reason', [
    ({'frame_id': 'base_scan'}, Reason.SCAN_FRAME),
    ({'ranges': np.r_[np.full(RAYS // 2 + 1, np.nan), np.full(RAYS // 2 - 1, 1.0)]},
     Reason.NON_FINITE),
    ({'angle_min': math.nan}, Reason.NON_FINITE),
    ({'ranges': np.zeros(0)}, Reason.SCAN_FIELDS),
    ({'angle_increment': 1e307}, Reason.SCAN_FIELDS),
    ({'angle_increment': 0.0}, Reason.SCAN_FIELDS),
    ({'range_min': 4.0}, Reason.SCAN_FIELDS),
    ({'ranges': np.ones(MAX_RAYS + 1)}, Reason.TOO_MANY_RAYS),
])
def test_a_scan_that_cannot_be_read_is_refused(change, reason):
    fields = {'stamp_ns': SECOND, 'frame_id': FRAME, 'angle_min': 0.0, 'angle_increment': STEP,
              'range_min': RANGE_MIN, 'range_max': RANGE_MAX, 'ranges': np.full(RAYS, np.inf)}
    assert rule().refusal(Scan(**fields)) is None
    refused = rule().refusal(Scan(**{**fields, **change}))
    assert refused is not None and refused.reason is reason


def test_the_law_keeps_a_robot_off_a_pillar_it_only_sees():
    """The scan's points give the law about the map's terms: off by at most the ray spacing."""
    law = make_law(1.0, 1.0, PsiKind.TANH, JumpKind.POLY, 2, 0.4)
    centre, r, clearance = np.array([1.0, 0.2]), 0.3, 0.6
    mapped = Obstacles(np.array([*centre, r]), np.zeros(0), np.zeros(0), clearance=clearance,
                       dim=2)
    origin = np.array([0.3, 0.1])
    scans = rule(radius=2.0)
    held(scans, origin, 0.4)
    scans.scan_heard(synthetic(origin, 0.4, [(centre, r)]))
    points, normals = scans.obstacles(scans.place(SECOND), origin, origin, np.zeros((0, 3)))
    seen = HeardObstacles.from_lists([(points, normals)], 2, 0.0, clearance)
    q = origin[None, :]
    nearest = float(np.min(seen.surface(q).distances))
    true = float(np.linalg.norm(origin - centre) - r)
    assert true <= nearest <= true + (true + r) * STEP
    heard = seen.terms(q, law.jump, [2.0])
    told = mapped.terms(q, law.jump, np.array([2.0]))
    assert len(points) == 1, 'the pillar, by its nearest return'
    cosine = float(heard[0] @ told[0]) / float(np.linalg.norm(heard) * np.linalg.norm(told))
    assert cosine > math.cos(STEP / 2)
    assert np.linalg.norm(heard) == pytest.approx(np.linalg.norm(told), rel=0.05)


def test_a_robot_cannot_tell_its_obstacles_without_a_recent_scan_by_the_stamps():
    scans = rule()
    assert scans.unseen(SECOND, SECOND // 2) == 'no scan heard yet'
    held(scans, (0.0, 0.0), 0.0)
    scans.scan_heard(synthetic((0.0, 0.0), 0.0, [(np.array([1.0, 0.0]), 0.2)]))
    assert scans.unseen(SECOND + SECOND // 2, SECOND // 2) is None
    assert scans.unseen(SECOND + SECOND // 2 + 1, SECOND // 2) == (
        'its latest scan is more than 0.5 s older than the state')


def test_a_pose_without_numbers_is_not_kept_and_nothing_is_placed_with_it():
    scans = rule()
    scans.pose_heard(SECOND, (0.0, 0.0, 0.0), (math.nan,) * 4)
    scans.pose_heard(SECOND, (math.nan, 0.0, 0.0), quaternion(0.0))
    assert len(scans.poses) == 0
    scans.scan_heard(synthetic((0.0, 0.0), 0.0, [(np.array([1.0, 0.0]), 0.2)]))
    assert scans.place(SECOND) is None


def test_a_scan_is_placed_at_most_an_edge_beyond_the_poses_and_kept_only_between_two():
    scans = rule()
    for k in range(1001):  # 10 s of poses at 100 Hz, moving along +x at 0.2 m/s
        scans.pose_heard(k * SECOND // 100, (0.002 * k, 0.0, 0.0), quaternion(0.0))
    assert scans.pose_at(10 * SECOND + EDGE_NS + 1, 5 * SECOND) is None
    assert scans.pose_at(-EDGE_NS - 1, 5 * SECOND) is None
    assert np.allclose(scans.pose_at(6 * SECOND, 5 * SECOND)[0], (1.2, 0.0))
    scans.scan_heard(synthetic((2.0, 0.0), 0.0, [(np.array([3.0, 0.0]), 0.2)],
                               stamp_ns=10 * SECOND + SECOND // 200))
    ahead = scans.place(SECOND // 2)
    assert ahead is not None and scans.placed is None, 'after the newest: placed again later'
    scans.pose_heard(10 * SECOND + SECOND // 100, (2.002, 0.0, 0.0), quaternion(0.0))
    between = scans.place(SECOND // 2)
    assert scans.placed is between
    assert np.min(np.linalg.norm(between.points - (3.0, 0.0), axis=1)) == pytest.approx(
        0.2, abs=2e-3)


def walls(origin, segments):
    """Return a scan of thin straight segments, each a row of touching discs 0.01 m wide."""
    discs = []
    for x1, y1, x2, y2 in segments:
        for t in np.linspace(0.0, 1.0, int(math.hypot(x2 - x1, y2 - y1) / 0.02) + 1):
            discs.append((np.array([x1 + t * (x2 - x1), y1 + t * (y2 - y1)]), 0.01))
    return synthetic(origin, 0.0, discs)


def test_each_wall_of_a_room_or_a_corridor_repels_as_a_mapped_wall_would():
    scans = rule(radius=1.5)
    held(scans, (0.0, 0.0), 0.0)
    scans.scan_heard(walls((0.0, 0.0), [(-1, -1, 1, -1), (1, -1, 1, 1), (1, 1, -1, 1),
                                        (-1, 1, -1, -1)]))
    points, _ = scans.obstacles(scans.place(SECOND), np.zeros(2), np.zeros(2), np.zeros((0, 3)))
    assert sorted(map(tuple, np.round(points, 2))) == [(-0.99, 0.0), (0.0, -0.99), (0.0, 0.99),
                                                       (0.99, 0.0)], 'one term a wall'
    corridor = rule(radius=1.5)
    origin = np.array([0.0, 0.05])
    held(corridor, origin, 0.0)
    corridor.scan_heard(walls(origin, [(-1, -0.5, 2, -0.5), (2, -0.5, 2, 0.5),
                                       (2, 0.5, -1, 0.5)]))
    points, _ = corridor.obstacles(corridor.place(SECOND), origin, origin, np.zeros((0, 3)))
    assert np.allclose(points, [[0.0, -0.49], [0.0, 0.49]], atol=1e-3), 'both sides, the end far'


def test_a_ray_dropping_out_does_not_split_an_obstacle_and_noise_makes_no_faces():
    ranges = np.full(RAYS, np.inf)
    ranges[:21] = 1.0 / np.cos(np.radians(np.arange(-10, 11)))  # a flat wall ahead
    ranges[5] = np.inf
    scans = rule(radius=2.0)
    held(scans, (0.0, 0.0), 0.0)
    scans.scan_heard(Scan(SECOND, FRAME, -math.radians(10), STEP, RANGE_MIN, RANGE_MAX, ranges))
    points, _ = scans.obstacles(scans.place(SECOND), np.zeros(2), np.zeros(2), np.zeros((0, 3)))
    assert np.allclose(points, [[1.0, 0.0]])
    noisy = ranges + np.random.default_rng(3).normal(0.0, 0.01, RAYS)
    held(scans, (0.0, 0.0), 0.0, 2 * SECOND)
    scans.scan_heard(Scan(2 * SECOND, FRAME, -math.radians(10), STEP, RANGE_MIN, RANGE_MAX,
                          noisy))
    points, _ = scans.obstacles(scans.place(SECOND), np.zeros(2), np.zeros(2), np.zeros((0, 3)))
    assert len(points) == 1
