# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The distance the potential guarantees (core/maths/safety.py)."""

import math

from formation_ros.core.maths.law import beta, log_potential, make_law
from formation_ros.core.maths.safety import body_clearance, guaranteed_min_distance
import numpy as np
import pytest

LAW = make_law(1.0, 2.0, 'arctan', 'poly', 2, 1.0)
VERTICES = np.array([[0.0, 0.0], [3.0, 0.0]])


def test_the_distance_is_where_beta_reaches_its_floor():
    start = np.array([[0.0, 0.0], [0.5, 0.0]])
    d = guaranteed_min_distance(start, VERTICES, LAW)
    floor = math.exp(-log_potential(start, VERTICES, LAW) / LAW.kappa)
    assert float(beta(np.array(d * d), LAW)) == pytest.approx(floor, rel=1e-9)
    assert 0.0 < d < 0.5


def test_closed_form_for_p_2_and_no_pair_within_b():
    start = np.array([[0.0, 0.0], [2.0, 0.0]])
    gamma = 0.5 * 1.0
    y = np.linspace(0.0, 1.0, 200001)
    h = 10 * y ** 3 - 15 * y ** 4 + 6 * y ** 5
    expected = math.sqrt(np.interp(math.exp(-gamma / LAW.kappa), h, y))
    assert guaranteed_min_distance(start, VERTICES, LAW) == pytest.approx(expected, abs=1e-5)


def test_edges():
    assert guaranteed_min_distance(VERTICES, VERTICES, LAW) == LAW.repulsion_radius
    assert guaranteed_min_distance(np.zeros((2, 2)), VERTICES, LAW) == 0.0
    assert body_clearance(0.5, 0.08) == pytest.approx(0.34)


def test_more_kappa_guarantees_more():
    start = np.array([[0.0, 0.0], [0.6, 0.0], [5.0, 5.0]])
    vertices = np.array([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]])
    distances = [guaranteed_min_distance(start, vertices, make_law(1.0, kappa, 'arctan', 'poly',
                                                                   2, 1.0))
                 for kappa in (0.5, 1.0, 4.0, 16.0)]
    assert all(a < b for a, b in zip(distances, distances[1:]))
    assert distances[-1] < 0.6
