# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Contacts between robots from MuJoCo's collision detection, and the closest approach."""

import numpy as np
import pytest

pytest.importorskip('mujoco')

from formation_ros.physics.contacts import (closest_distance, ClosestApproach,  # noqa: E402, I100
                                            ContactLog)
from formation_ros.physics.engine import Engine  # noqa: E402, I100
from physics_helpers import bases, run, team  # noqa: E402, I100

LIVE = {'world.cmd_timeout': 10.0}


def test_two_bases_driven_into_each_other_make_one_contact_and_do_not_pass_through():
    engine = Engine(bases([[0.0, 0.0], [0.6, 0.0]], [0.0, np.pi], LIVE))
    engine.apply([[0.2, 0.0], [0.2, 0.0]])
    gaps = [pose.positions[1, 0] - pose.positions[0, 0] for pose in run(engine, 3.0, every=5)]
    assert engine.contacts.count == 1
    (event,) = engine.contacts.events
    assert (event.i, event.j) == (1, 2)
    footprints = 2.0 * engine.model.footprint
    assert 0.5 < event.t < 1.2
    assert event.t == pytest.approx((0.6 - footprints) / 0.4, abs=0.2)
    assert min(gaps) > footprints - 0.01
    stats = engine.stats(engine.wall)
    assert stats.contacts == 1
    assert stats.min_body_distance == pytest.approx(min(gaps), abs=0.01)
    assert -0.01 < stats.min_footprint_gap < 0.001
    assert stats.steps == 1500 and stats.simulated_time == pytest.approx(3.0)


def test_bases_that_part_and_meet_again_make_two_contacts():
    engine = Engine(bases([[0.0, 0.0], [0.4, 0.0]], [0.0, np.pi], LIVE))
    engine.apply([[0.2, 0.0], [0.2, 0.0]])
    run(engine, 1.0)
    engine.apply([[-0.2, 0.0], [-0.2, 0.0]])
    run(engine, 1.0)
    assert engine.contacts.count == 1 and not len(engine.contacts.touching)
    engine.apply([[0.2, 0.0], [0.2, 0.0]])
    run(engine, 2.0)
    assert engine.contacts.count == 2


def test_holonomic_bases_collide_and_a_third_far_away_is_never_counted():
    engine = Engine(team([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]], 2, None,
                         {'body.radius': 0.2, **LIVE}))
    engine.apply([[0.3, 0.0], [-0.3, 0.0], [0.0, 0.0]])
    run(engine, 3.0, every=10)
    assert [(e.i, e.j) for e in engine.contacts.events] == [(1, 2)]
    positions = engine.poses().positions
    assert positions[1, 0] - positions[0, 0] > 0.39


def test_the_contact_log_counts_a_pair_once_until_it_parts():
    log = ContactLog(4, release=0.5)
    near = np.array([[0.0, 0.0], [0.4, 0.0], [5.0, 0.0], [5.4, 0.0]])
    apart = np.array([[0.0, 0.0], [0.45, 0.0], [5.0, 0.0], [5.6, 0.0]])
    none = np.zeros(0, int)
    assert log.update(np.array([0, 1]), np.array([1, 0]), near, 10) == log.events
    log.update(none, none, near, 15)
    log.update(np.array([1]), np.array([0]), near, 20)
    log.update(np.array([2, 0]), np.array([3, 1]), near, 30)
    log.update(none, none, apart, 40)
    assert log.touching.tolist() == [1]
    log.update(np.array([3]), np.array([2]), near, 50)
    assert [(e.i, e.j, e.t_ns) for e in log.events] == [(1, 2, 10), (3, 4, 30), (3, 4, 50)]


@pytest.mark.parametrize('n', [5, 120])
def test_the_closest_approach_is_the_smallest_distance_of_every_step(n):
    rng = np.random.default_rng(n)
    points = rng.uniform(-3.0, 3.0, (n, 2))
    velocity = rng.normal(0.0, 0.3, (n, 2))
    closest = ClosestApproach(points, reach=0.2, skin=0.3)
    smallest = closest_distance(points)[0]
    for step in range(1, 400):
        points = points + 0.01 * velocity
        closest.update(points, step)
        smallest = min(smallest, closest_distance(points)[0])
    assert closest.distance == pytest.approx(smallest, rel=1e-12)
