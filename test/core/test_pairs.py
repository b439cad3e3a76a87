# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The grid search of maths.pairs against a k-d tree and brute force, and the plant model's pairs.

The plant model keeps candidates within (1 + PAIR_SKIN) b and filters them each step; every
step's pairs must be those a fresh search finds, in the order the law sums them.
"""

import math

from formation_ros.core.maths.law import make_law, team_command
from formation_ros.core.maths.pairs import closest_pair, pairs_within, squared_norms
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, PlantModel
import numpy as np
import pytest
from scipy.spatial import cKDTree

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
MS = 10_000_000


def tree_pairs(q, radius):
    """Return the pairs a k-d tree finds, as sorted (i, j) tuples."""
    found = cKDTree(q).query_pairs(radius, output_type='ndarray').reshape(-1, 2)
    return sorted(map(tuple, found.tolist()))


@pytest.mark.parametrize('dim', [2, 3])
@pytest.mark.parametrize('seed', range(6))
def test_grid_pairs_are_the_k_d_trees_sorted_by_i_then_j(dim, seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 400))
    q = rng.uniform(-5.0, 5.0, (n, dim))
    q[1] = q[0]
    if seed % 2:
        q[-1] *= 1e7  # one point far away: many empty cells
    radius = float(rng.uniform(0.1, 3.0))
    found = pairs_within(q, radius)
    assert found.dtype == np.intp and found.shape[1] == 2
    assert list(map(tuple, found.tolist())) == tree_pairs(q, radius)


def test_grid_pairs_of_few_points_far_apart_and_of_bad_positions():
    assert pairs_within(np.zeros((1, 2)), 1.0).shape == (0, 2)
    assert pairs_within(np.array([[0.0, 0.0], [1e100, -1e100]]), 1e-3).shape == (0, 2)
    assert pairs_within(np.array([[0.0, 0.0], [0.0, 0.0]]), 0.0).tolist() == [[0, 1]]
    with pytest.raises(ValueError):
        pairs_within(np.array([[0.0, 0.0], [math.nan, 0.0]]), 1.0)


@pytest.mark.parametrize('seed', range(5))
def test_closest_pair_is_the_brute_force_one(seed):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(int(rng.integers(2, 300)), 2 + seed % 2)) * 10.0 ** seed
    distance = np.sqrt(((q[:, None] - q[None]) ** 2).sum(axis=-1))
    distance[np.diag_indices(len(q))] = np.inf
    found, i, j = closest_pair(q)
    assert i < j and found == pytest.approx(distance.min(), rel=1e-15)
    assert distance[i, j] == pytest.approx(distance.min(), rel=1e-15)
    assert closest_pair(np.zeros((3, 2))) == (0.0, 0, 1)
    assert closest_pair(np.zeros((1, 2)))[0] == math.inf


def test_squared_norms_are_einsums():
    v = np.random.default_rng(3).normal(size=(1000, 3))
    plane = np.ascontiguousarray(v[:, :2])
    assert np.array_equal(squared_norms(plane), np.einsum('kd,kd->k', plane, plane))
    assert np.allclose(squared_norms(v), np.einsum('kd,kd->k', v, v), rtol=1e-15, atol=0.0)


def test_the_plant_models_kept_pairs_are_a_fresh_search_at_every_step():
    rng = np.random.default_rng(5)
    n = 150
    start = rng.uniform(-2.0, 2.0, (n, 2))
    model = PlantModel(start, np.full(n, 1.0), MS, LAW, Reference('fixed', 2), 50 * MS, 1e-3,
                       pair_radius=LAW.repulsion_radius)
    commands = Commands.empty(n, 2)
    vertices = rng.uniform(-6.0, 6.0, (n, 2))
    searches = 0
    for _ in range(120):
        fresh = pairs_within(model.points, LAW.repulsion_radius)
        assert np.array_equal(model.pairs, fresh)
        tree = tree_pairs(model.points, LAW.repulsion_radius)
        assert list(map(tuple, model.pairs.tolist())) == tree
        kept = team_command(model.points, vertices, model.radii, LAW, None, None, model.pairs)
        searched = team_command(model.points, vertices, model.radii, LAW)
        assert np.array_equal(kept.u, searched.u)
        before = model._candidates
        commands.store_all(kept.u, model.t_ns)
        model.advance(commands)
        searches += model._candidates is not before
    assert 0 < searches <= 60  # searched again, at most every other step at full speed
