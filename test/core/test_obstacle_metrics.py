# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Obstacle metrics (runs/obstacle_metrics.py): closest approach, contacts, stuck robots."""

import math

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.runs import obstacle_metrics as obstacle_metrics_module
from formation_ros.core.runs.obstacle_metrics import obstacle_metrics, stuck_robots
import numpy as np
import pytest

PILLAR = Obstacles([0.0, 0.0, 1.0], [], [], 0.5, 2)


def passing(xs, y):
    """One robot at height y passing along x, a second far away: (T, 2, 2)."""
    first = np.stack([xs, np.full_like(xs, y)], axis=1)
    second = np.tile([10.0, 10.0], (len(xs), 1))
    return np.stack([first, second], axis=1)


def test_the_closest_approach_subtracts_the_footprint():
    q = passing(np.linspace(-3.0, 3.0, 61), 1.3)
    metrics = obstacle_metrics(q, PILLAR)
    assert metrics['min_obstacle_clearance'] == pytest.approx(0.3)
    assert metrics['obstacle_contacts'] == 0
    footprint = obstacle_metrics(q, PILLAR, body_radius=0.1)
    assert footprint['min_obstacle_clearance'] == pytest.approx(0.2)


def test_each_stretch_in_contact_counts_once():
    xs = np.concatenate([np.linspace(-3.0, 3.0, 61), np.linspace(3.0, -3.0, 61)])
    q = passing(xs, 0.5)
    inside = np.abs(xs) <= math.sqrt(1.0 - 0.25)
    assert inside.any()
    metrics = obstacle_metrics(q, PILLAR)
    assert metrics['obstacle_contacts'] == 2
    assert metrics['min_obstacle_clearance'] == pytest.approx(0.5 - 1.0)
    assert obstacle_metrics(q[:1], PILLAR)['obstacle_contacts'] == 0
    assert obstacle_metrics(passing(np.zeros(3), 0.0), PILLAR)['obstacle_contacts'] == 1


def test_blocks_of_samples_give_the_numbers_of_the_whole(monkeypatch):
    xs = np.concatenate([np.linspace(-3.0, 3.0, 61), np.linspace(3.0, -3.0, 61)])
    q = passing(xs, 0.5)
    whole = obstacle_metrics(q, PILLAR)
    monkeypatch.setattr(obstacle_metrics_module, 'BLOCK_DISTANCES', 3)
    assert obstacle_metrics(q, PILLAR) == whole


def test_no_obstacles_no_clearance():
    none = Obstacles([], [], [], 0.5, 2)
    for nothing in (none, None):
        assert obstacle_metrics(passing(np.zeros(3), 0.0), nothing) == {
            'min_obstacle_clearance': None, 'obstacle_contacts': 0}


def test_a_robot_still_and_far_from_its_place_is_named_with_its_nearest_obstacle():
    t = np.linspace(0.0, 20.0, 201)
    xs = np.concatenate([np.linspace(-4.0, -1.2, 101), np.full(100, -1.2)])
    q = passing(xs, 0.0)
    q_desired = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    stuck = stuck_robots(t, q, q_desired, PILLAR)
    assert [s.robot for s in stuck] == [0]
    assert stuck[0].error == pytest.approx(3.2) and stuck[0].nearest == 0
    assert stuck[0].gap == pytest.approx(0.2)
    assert stuck[0].line() == ('robot 1 stuck at (-1.2, 0), 3.2 m from its place; nearest '
                               'circle 1, 0.2 m away')
    assert stuck[0].record() == {'robot': 1, 'position': [-1.2, 0.0],
                                 'error': pytest.approx(3.2), 'nearest_obstacle': 'circle 1',
                                 'obstacle_gap': pytest.approx(0.2)}
    body = stuck_robots(t, q, q_desired, PILLAR, bodies=q - [0.1, 0.0], body_radius=0.05)[0]
    assert body.position == pytest.approx([-1.3, 0.0]) and body.gap == pytest.approx(0.25)
    alone = stuck_robots(t, q, q_desired)[0]
    assert alone.line() == 'robot 1 stuck at (-1.2, 0), 3.2 m from its place'
    assert alone.record()['nearest_obstacle'] is None and alone.record()['obstacle_gap'] is None


def test_a_robot_still_moving_or_at_its_place_or_a_short_run_is_not_stuck():
    t = np.linspace(0.0, 20.0, 201)
    creeping = passing(np.linspace(-4.0, -1.2, 201), 0.0)
    q_desired = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    assert stuck_robots(t, creeping, q_desired, PILLAR) == []
    arrived = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    assert stuck_robots(t, arrived, q_desired, PILLAR) == []
    assert stuck_robots(t[:10], arrived[:10] + 5.0, q_desired[:10], PILLAR) == []


@pytest.mark.parametrize('amplitude', [0.01, 0.1])
def test_a_robot_trembling_on_the_spot_is_stuck(amplitude):
    t = np.linspace(0.0, 20.0, 2001)
    xs = -1.2 + amplitude * np.where(np.arange(len(t)) % 2, 1.0, -1.0)  # back and forth
    q = passing(xs, 0.0)
    q_desired = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    assert [s.robot for s in stuck_robots(t, q, q_desired, PILLAR)] == [0]


def test_a_robot_closing_in_slowly_is_not_stuck():
    t = np.linspace(0.0, 20.0, 201)
    q = passing(np.linspace(-1.0, -0.6, len(t)), 0.0)  # 0.1 m in the last 5 s, nearer
    q_desired = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    assert stuck_robots(t, q, q_desired) == []
    away = np.tile([[-5.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))  # pushed away from its place
    assert [s.robot for s in stuck_robots(t, q, away)] == [0]


def test_a_base_turning_on_the_spot_is_stuck_though_its_hand_point_sweeps():
    t = np.linspace(0.0, 20.0, 2001)
    axle = passing(np.full(len(t), -1.3), 0.0)
    angle = 3.0 * t
    hand = axle.copy()
    hand[:, 0, 0] += 0.2 * np.cos(angle)
    hand[:, 0, 1] += 0.2 * np.sin(angle)
    q_desired = np.tile([[2.0, 0.0], [10.0, 10.0]], (len(t), 1, 1))
    assert stuck_robots(t, hand, q_desired, PILLAR) == []  # the hand point alone: moving
    stuck = stuck_robots(t, hand, q_desired, PILLAR, bodies=axle, body_radius=0.05)
    assert [s.robot for s in stuck] == [0] and stuck[0].position == pytest.approx([-1.3, 0.0])


def every_pair(q, obstacles, body_radius):
    """Return the closest gap and the contacts from every robot-obstacle gap of every sample."""
    gaps = obstacles.distances(q.reshape(-1, q.shape[2])).reshape(len(q), q.shape[1], -1)
    touching = gaps - body_radius <= 0.0
    starts = np.count_nonzero(touching[0]) + np.count_nonzero(touching[1:] & ~touching[:-1])
    return {'min_obstacle_clearance': float(gaps.min()) - body_radius,
            'obstacle_contacts': int(starts)}


@pytest.mark.parametrize('dim', [2, 3])
def test_the_pairs_measured_near_give_the_numbers_of_every_pair(dim, monkeypatch):
    """Random walks among random maps: contacts, near misses, and runs far from everything."""
    monkeypatch.setattr(obstacle_metrics_module, 'BLOCK_DISTANCES', 5000)
    touched = far = 0
    for seed in range(30):
        rng = np.random.default_rng(10 * dim + seed)
        count = rng.integers(1, 20)
        circles = np.column_stack([rng.uniform(-5.0, 5.0, (count, 2)),
                                   rng.uniform(0.05, 1.5, count)])
        walls = np.column_stack([rng.uniform(-5.0, 5.0, (3, 4)), rng.uniform(0.02, 0.3, 3)])
        spheres = ([] if dim == 2 else np.column_stack([rng.uniform(-5.0, 5.0, (2, 3)),
                                                        rng.uniform(0.1, 1.0, 2)]))
        obstacles = Obstacles(circles, walls, spheres, float(rng.choice([0.05, 0.5])), dim)
        start = rng.uniform(-6.0, 6.0, (1, 30, dim)) * rng.choice([1.0, 10.0])
        q = start + np.cumsum(rng.normal(0.0, 0.3, (40, 30, dim)), axis=0)
        radius = float(rng.choice([0.0, 0.1, 1.0]))
        measured = obstacle_metrics(q, obstacles, radius)
        assert measured == every_pair(q, obstacles, radius)
        touched += measured['obstacle_contacts'] > 0
        nearest = measured['min_obstacle_clearance'] + radius
        far += nearest >= max(obstacles.clearance, 2.0 * radius)
    assert touched >= 5 and far >= 3
