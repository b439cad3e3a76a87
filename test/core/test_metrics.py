# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Run metrics (core/runs/metrics.py) against brute-force and hand-computed references."""

import itertools
import json
import math

from formation_ros.core.runs import metrics
from formation_ros.core.runs.metrics import (closest_pair_distance, compute_metrics, dis_all,
                                             dis_all_series, dis_min_series, formation_errors,
                                             settle_time)
import numpy as np
import pytest


def brute_pair_distances(points):
    """Every ||p_i - p_j||, i < j, by a double loop."""
    return [math.dist(points[i], points[j])
            for i, j in itertools.combinations(range(len(points)), 2)]


def brute_settle_time(t, errors, tolerance):
    """First t[k] from which on every error is <= tolerance, by trying every k; None if none."""
    for k in range(len(t)):
        if all(e <= tolerance for row in errors[k:] for e in row):
            return t[k]
    return None


def random_run(seed, samples=30, robots=5, dim=2):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 3.0, samples)
    q = rng.normal(size=(samples, robots, dim)) * 2.0
    q_desired = q + rng.normal(size=q.shape) * np.exp(-2.0 * t)[:, None, None]
    return t, q, q_desired


@pytest.mark.parametrize('dim', [2, 3])
def test_formation_errors_are_the_distances_to_the_desired_places(dim):
    t, q, q_desired = random_run(1, dim=dim)
    errors = formation_errors(q, q_desired)
    assert errors.shape == q.shape[:2]
    for k, i in itertools.product(range(len(t)), range(q.shape[1])):
        assert errors[k, i] == pytest.approx(math.dist(q[k, i], q_desired[k, i]), rel=1e-14)


def test_settle_time_hand_cases():
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    inside = np.full((5, 3), 0.01)
    assert settle_time(t, inside) == 0.0
    never = inside.copy()
    never[-1, 2] = 0.2
    assert settle_time(t, never) is None
    late = inside.copy()
    late[:3, 0] = 1.0
    late[1, 2] = 0.06
    assert settle_time(t, late) == 1.5
    excursion = inside.copy()
    excursion[0, :] = 1.0
    excursion[2, 1] = 0.051
    assert settle_time(t, excursion) == 1.5
    on_the_tolerance = inside.copy()
    on_the_tolerance[:4, 1] = 0.05
    assert settle_time(t, on_the_tolerance) == 0.0
    assert settle_time(t, late, tolerance=2.0) == 0.0
    assert settle_time(t, late, tolerance=0.005) is None


def test_settle_time_matches_brute_force_on_random_errors():
    rng = np.random.default_rng(3)
    for _ in range(200):
        samples = int(rng.integers(1, 12))
        t = np.cumsum(rng.uniform(0.1, 1.0, samples))
        errors = rng.uniform(0.0, 0.08, size=(samples, 3))
        assert settle_time(t, errors) == brute_settle_time(list(t), errors.tolist(), 0.05)


@pytest.mark.parametrize('dt', [0.5, 0.4, 0.25, 0.1, 0.03])
def test_settle_time_resolution_is_the_sample_spacing(dt):
    """An error exp(-t) first reaches 0.05 at ln 20 s; the samples see it up to dt later."""
    t = np.arange(0.0, 6.0, dt)
    errors = np.exp(-t)[:, None]
    settled = settle_time(t, errors)
    assert settled - dt < math.log(20.0) <= settled


def test_closest_pair_distance_matches_brute_force():
    rng = np.random.default_rng(5)
    for n, dim in [(2, 2), (3, 3), (17, 2), (60, 3)]:
        points = rng.uniform(-3.0, 3.0, size=(n, dim))
        before = points.copy()
        assert closest_pair_distance(points) == pytest.approx(
            min(brute_pair_distances(points)), rel=1e-14)
        assert np.array_equal(points, before)
    assert closest_pair_distance([[0.0, 0.0], [3.0, 4.0]]) == 5.0
    assert closest_pair_distance([[1.0, 2.0], [0.0, 0.0], [1.0, 2.0]]) == 0.0


def test_closest_pair_distance_of_fewer_than_two_points_is_infinite():
    assert closest_pair_distance(np.empty((0, 2))) == math.inf
    assert closest_pair_distance([[1.0, 2.0, 3.0]]) == math.inf


def test_dis_min_series_is_the_closest_pair_at_each_sample():
    _, q, _ = random_run(7, samples=12, robots=8, dim=3)
    series = dis_min_series(q)
    assert series.shape == (12,)
    for k in range(12):
        assert series[k] == pytest.approx(min(brute_pair_distances(q[k])), rel=1e-14)


def test_dis_all_hand_case_and_collision():
    # pair distances 1, 3 and 2: geometric mean 6**(1/3)
    assert dis_all([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]]) == pytest.approx(6.0 ** (1.0 / 3.0))
    assert dis_all([[0.0, 0.0], [3.0, 4.0]]) == pytest.approx(5.0)
    assert dis_all([[0.0, 0.0], [0.0, 0.0], [3.0, 4.0]]) == 0.0


@pytest.mark.parametrize('n,dim', [(2, 2), (4, 3), (10, 2), (25, 3)])
def test_dis_all_is_the_geometric_mean_of_all_pair_distances(n, dim):
    points = np.random.default_rng(n).uniform(0.0, 2.0, size=(n, dim))
    distances = brute_pair_distances(points)
    expected = math.prod(distances) ** (2.0 / (n * (n - 1)))
    value = dis_all(points)
    assert value == pytest.approx(expected, rel=1e-12)
    assert min(distances) <= value <= max(distances)
    assert dis_all(3.0 * points) == pytest.approx(3.0 * value, rel=1e-12)


def test_dis_all_of_many_wide_pairs_does_not_overflow():
    """A product of 4950 distances near 1e3 overflows a float; the geometric mean does not."""
    points = np.column_stack([np.arange(100) * 1e3, np.zeros(100)])
    log_mean = math.fsum(math.log(d) for d in brute_pair_distances(points)) / 4950
    assert dis_all(points) == pytest.approx(math.exp(log_mean), rel=1e-12)


def test_dis_all_series_keeps_short_runs_whole():
    t, q, _ = random_run(9, samples=40)
    times, values = dis_all_series(t, q)
    assert np.array_equal(times, t)
    assert np.allclose(values, [dis_all(sample) for sample in q], rtol=1e-14)


def test_dis_all_series_thins_long_runs_to_at_most_400_samples():
    samples = 1001
    t = np.linspace(0.0, 10.0, samples)
    q = np.zeros((samples, 3, 2))
    q[:, 1, 0] = 1.0 + t
    q[:, 2, 1] = 2.0
    times, values = dis_all_series(t, q)
    assert 300 <= len(times) <= 400
    assert times[0] == t[0] and times[-1] == t[-1]
    assert np.all(np.diff(times) > 0.0) and np.all(np.isin(times, t))
    assert np.max(np.diff(times)) <= 2.0 * (t[-1] - t[0]) / (len(times) - 1)
    # sides 1 + t, 2 and the hypotenuse
    expected = ((1.0 + times) * 2.0 * np.hypot(1.0 + times, 2.0)) ** (1.0 / 3.0)
    assert np.allclose(values, expected, rtol=1e-12)


def test_dis_all_series_is_empty_above_2000_robots():
    q = np.random.default_rng(0).normal(size=(2, 2001, 2))
    times, values = dis_all_series(np.array([0.0, 1.0]), q)
    assert times.shape == (0,) and values.shape == (0,)
    assert len(dis_all_series(np.array([0.0, 1.0]), q[:, :2000])[0]) == 2


def hand_run():
    """Three robots in 2D over four samples, with a few command components above c M1 = 2."""
    t = np.array([0.0, 1.0, 2.0, 3.0])
    q_desired = np.tile([[0.0, 0.0], [4.0, 0.0], [0.0, 3.0]], (4, 1, 1))
    q = q_desired.copy()
    q[0, 0] = [0.0, -1.0]
    q[1, 1] = [4.0, 0.5]
    q[3, 2] = [0.0, 3.03]
    q[3, 0] = [0.04, 0.0]
    u_hat = np.zeros((4, 3, 2))
    u_hat[0, 0] = [2.0, -2.0]
    u_hat[1, 2] = [-2.5, 2.0 * (1.0 + 1e-14)]
    u_hat[2, 1] = [2.1, -3.0]
    u = u_hat.copy()
    u[2, 0, 1] = -4.5
    return t, q, u, u_hat, q_desired


def test_compute_metrics_keys_and_values():
    t, q, u, u_hat, q_desired = hand_run()
    inputs = [a.copy() for a in (t, q, u, u_hat, q_desired)]
    result = compute_metrics(t, q, u, u_hat, q_desired, 2.0, extra={'integrator': 'RK45'})
    for before, after in zip(inputs, (t, q, u, u_hat, q_desired)):
        assert np.array_equal(before, after)
    assert set(result) == {
        'num_robots', 'dim', 'duration', 'num_samples', 'min_pair_distance', 'dis_all_final',
        'final_max_error', 'final_mean_error', 'settle_tolerance', 'settle_time',
        'max_abs_u_component', 'max_abs_u_hat_component', 'u_bound', 'bound_violations',
        'integrator'}
    assert json.loads(json.dumps(result)) == result
    assert (result['num_robots'], result['dim'], result['num_samples']) == (3, 2, 4)
    assert result['duration'] == 3.0
    # closest pair: robots 1 and 3 at their places, (0, 0) and (0, 3)
    assert result['min_pair_distance'] == pytest.approx(3.0)
    final = [[0.04, 0.0], [4.0, 0.0], [0.0, 3.03]]
    assert result['dis_all_final'] == pytest.approx(
        math.prod(brute_pair_distances(final)) ** (1.0 / 3.0))
    assert result['final_max_error'] == pytest.approx(0.04)
    assert result['final_mean_error'] == pytest.approx((0.04 + 0.03) / 3.0)
    assert result['settle_tolerance'] == 0.05
    assert result['settle_time'] == 2.0
    assert result['max_abs_u_component'] == 4.5
    assert result['max_abs_u_hat_component'] == 3.0
    assert result['u_bound'] == 2.0
    # above 2: -2.5, 2.1 and -3.0; 2.0 itself and 2 (1 + 1e-14) (rounding) are not
    assert result['bound_violations'] == 3
    assert result['integrator'] == 'RK45'


def test_compute_metrics_never_settled_and_bound_violations_scale():
    t, q, u, u_hat, q_desired = hand_run()
    q[3, 1] = [4.0, 0.2]
    result = compute_metrics(t, q, u, u_hat, q_desired, 2.0)
    assert result['settle_time'] is None and result['final_max_error'] == pytest.approx(0.2)
    assert compute_metrics(t, q, u, u_hat, q_desired, 0.5)['bound_violations'] == 6
    assert compute_metrics(t, q, u, u_hat, q_desired, 3.0)['bound_violations'] == 0


def test_compute_metrics_leaves_out_dis_all_for_huge_teams(monkeypatch):
    t, q, u, u_hat, q_desired = hand_run()
    monkeypatch.setattr(metrics, 'DIS_ALL_MAX_ROBOTS', 0)
    assert compute_metrics(t, q, u, u_hat, q_desired, 2.0)['dis_all_final'] is None
