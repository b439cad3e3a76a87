# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's obstacle watch (core/rules/obstacle_watch.py): gaps, contacts once per stretch."""

import math

from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.rules.obstacle_watch import ObstacleWatch
import pytest


def test_a_contact_is_counted_and_said_once_per_stretch():
    watch = ObstacleWatch(Obstacles([0.0, 0.0, 1.0], [3.0, -2.0, 3.0, 2.0, 0.1], [], 0.5, 2),
                          0.1)
    assert watch.record() == {'obstacle_contacts': 0, 'min_obstacle_gap': None}
    assert watch.step([[2.0, 0.0], [0.0, 5.0]], 0.0) == []
    assert watch.min_gap == pytest.approx(0.8)  # the wall: 1 m off, less t and the radius
    lines = watch.step([[1.05, 0.0], [0.0, 5.0]], 0.1)
    assert lines == ['robot 1 touches circle 1 at t = 0.100 s (gap -0.05 m; body.radius '
                     '0.1 m)']
    assert watch.step([[1.02, 0.0], [0.0, 5.0]], 0.2) == []  # the same contact
    assert watch.step([[1.5, 0.0], [2.85, 0.0]], 0.3) == [
        'robot 2 touches wall 1 at t = 0.300 s (gap -0.05 m; body.radius 0.1 m)']
    assert len(watch.step([[1.05, 0.0], [2.85, 0.0]], 0.4)) == 1  # robot 1 again: a new one
    assert watch.record() == {'obstacle_contacts': 3, 'min_obstacle_gap': pytest.approx(-0.08)}
    assert watch.summary() == '3 obstacle contacts, min obstacle gap -0.08 m'


def test_points_touch_on_the_surface():
    watch = ObstacleWatch(Obstacles([0.0, 0.0, 1.0], [], [], 0.5, 2), 0.0)
    assert len(watch.step([[1.0, 0.0]], 0.0)) == 1
    assert watch.min_gap == 0.0 and not math.isinf(watch.min_gap)
