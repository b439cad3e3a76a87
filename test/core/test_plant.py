# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant model (plant.py): zero-order hold, admission, bound audit, collisions, sensor."""

import math
import os

from formation_ros.core.maths.law import make_law, neighbour_pairs, team_command
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import (Commands, CommandStatus, PlantModel, random_start,
                                            start_positions, StartSpec)
from formation_ros.core.settings.params import load_config
from formation_ros.simulation.simulate import simulate
import numpy as np
import pytest

CONFIG = os.path.join(os.path.dirname(__file__), '..', '..', 'config')
LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
FIXED = Reference('fixed', 2)
MS = 10_000_000


def model(q, radii=1.0, timeout_ns=50 * MS, collision=1e-3, reference=FIXED):
    q = np.asarray(q, dtype=float)
    return PlantModel(q, np.full(len(q), radii), MS, LAW, reference, timeout_ns, collision)


def test_zero_order_hold_step_and_time_in_nanoseconds():
    start = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    plant = model(start)
    commands = Commands.empty(3, 2)
    u = np.array([[1.0, -2.0], [0.5, 0.0], [0.0, 0.25]])
    commands.store_all(u, 0)
    report = plant.advance(commands)
    assert report.t_ns == 0 and np.array_equal(report.q, start)
    assert plant.t_ns == MS and plant.t == pytest.approx(0.01)
    assert np.array_equal(plant.q, start + 0.01 * u)
    assert np.array_equal(start, [[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    assert np.array_equal(u, [[1.0, -2.0], [0.5, 0.0], [0.0, 0.25]])


def test_admission_names_why_a_command_does_not_count():
    plant = model([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0], [3.0, 3.0]], timeout_ns=20 * MS)
    for _ in range(5):
        plant.advance(Commands.empty(4, 2))
    commands = Commands.empty(4, 2)
    commands.store(0, [0.1, 0.2], plant.t_ns - 20 * MS)
    commands.store(1, [0.1, 0.2], plant.t_ns - 20 * MS - 1)
    commands.store(2, [math.nan, 0.2], plant.t_ns)
    admission = plant.admit(commands)
    assert admission.status.tolist() == [CommandStatus.APPLIED, CommandStatus.STALE,
                                         CommandStatus.NON_FINITE, CommandStatus.MISSING]
    assert admission.u.tolist() == [[0.1, 0.2], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
    plant.advance(commands)
    totals = plant.counts.totals()
    assert totals['stale_command_steps'] == 1 and totals['bad_command_steps'] == 1
    assert totals['missing_command_steps'] == 5 * 4 + 1 and totals['steps'] == 6


def test_steps_are_counted_by_the_age_of_their_oldest_command():
    plant = model([[0.0, 0.0], [3.0, 0.0]], timeout_ns=3 * MS)
    plant.advance(Commands.empty(2, 2))
    for lag_1, lag_2 in [(0, 0), (1, 0), (2, 1), (0, 3), (0, 4)]:
        commands = Commands.empty(2, 2)
        commands.store(0, [0.0, 0.0], plant.t_ns - lag_1 * MS)
        commands.store(1, [0.0, 0.0], plant.t_ns - lag_2 * MS)
        plant.advance(commands)
    counts = plant.counts
    expected = np.zeros_like(counts.age_steps)
    for age in (0, 1, 2, 3):
        expected[age] = 1
    expected[-1] = 2
    assert counts.age_steps.tolist() == expected.tolist() and counts.steps == 6
    assert counts.fresh_fraction(0) == pytest.approx(1 / 6)
    assert counts.fresh_fraction(2) == pytest.approx(3 / 6)
    assert counts.fresh_fraction(3) == pytest.approx(4 / 6)
    assert counts.fresh_fraction(10 ** 6) == pytest.approx(4 / 6)
    assert counts.age_steps.sum() == counts.steps


def test_a_collision_is_counted_once_per_approach():
    plant = model([[0.0, 0.0], [0.01, 0.0], [5.0, 5.0]], collision=0.005)
    commands = Commands.empty(3, 2)
    commands.store_all([[0.2, 0.0], [-0.2, 0.0], [0.0, 0.0]], 0)
    reports = []
    for _ in range(4):
        commands.stamp_ns[:] = plant.t_ns
        reports.append(plant.advance(commands))
    assert [len(r.collisions) for r in reports] == [0, 1, 0, 0]
    (i, j, distance), = reports[1].collisions
    assert (i, j) == (0, 1) and distance == pytest.approx(0.002)
    assert plant.counts.collisions == 1


def test_bound_audit_counts_each_new_command_once():
    plant = model([[0.0, 0.0], [3.0, 0.0]])
    commands = Commands.empty(2, 2)
    commands.store_all([[LAW.u_bound + 0.1, 0.0], [0.0, -LAW.u_bound]], 0)
    first = plant.advance(commands)
    again = plant.advance(commands)
    assert [robot for robot, _ in first.violations] == [0]
    assert first.violations[0][1] == pytest.approx(LAW.u_bound + 0.1)
    assert again.violations == [] and plant.counts.bound_violations == 1


def test_bound_audit_of_a_moving_reference_uses_the_formation_frame():
    circle = Reference('circle', 2, radius=2.0, speed=1.0)
    q = np.array([[2.0, 0.3], [-1.0, -1.0]])
    plant = model(q, reference=circle, timeout_ns=10 * MS)
    config_vertices = np.array([[0.3, 0.0], [-0.3, 0.0]])
    frame = circle.sample(0.0)
    command = team_command(q, config_vertices, np.full(2, 1.0), LAW, frame)
    assert np.max(np.abs(command.u)) > LAW.u_bound or np.max(np.abs(command.u_hat)) < LAW.u_bound
    commands = Commands.empty(2, 2)
    commands.store_all(command.u, 0)
    assert plant.advance(commands).violations == []
    commands.store_all(command.u + [[0.0, 0.0], [10.0, 0.0]], plant.t_ns)
    assert [robot for robot, _ in plant.advance(commands).violations] == [1]


def test_range_sensor_sees_the_others_strictly_within_each_radius():
    rng = np.random.default_rng(4)
    q = rng.uniform(-3.0, 3.0, size=(60, 2))
    radii = rng.uniform(0.3, 1.5, size=60)
    q[0], q[1] = [0.0, 0.0], [radii[0], 0.0]
    plant = PlantModel(q, radii, MS, LAW, FIXED, MS, 1e-3)
    seen = plant.neighbours()
    assert len(seen) == 60
    for i in range(60):
        expected = [j for j in range(60)
                    if j != i and np.sum((q[j] - q[i]) ** 2) < radii[i] ** 2]
        assert seen[i].tolist() == expected, i
    assert 1 not in seen[0].tolist()


def test_closest_pair_distance():
    plant = model([[0.0, 0.0], [3.0, 4.0], [0.0, 2.0]])
    assert plant.closest_pair_distance() == pytest.approx(2.0)


def test_start_positions_random_and_explicit():
    points = random_start(30, 3, 2.0, 0.3, seed=5)
    assert points.shape == (30, 3) and np.all(np.linalg.norm(points, axis=1) <= 2.0)
    gaps = np.linalg.norm(points[:, None] - points[None], axis=2)
    assert np.min(gaps[np.triu_indices(30, 1)]) >= 0.3
    assert np.array_equal(points, start_positions(StartSpec(30, 3, None, 2.0, 0.3, 5)))
    assert random_start(50, 2, 0.1, 0.1, seed=0) is None
    given = np.arange(6.0).reshape(3, 2)
    assert np.array_equal(start_positions(StartSpec(3, 2, given)), given)


@pytest.mark.parametrize('name', ['square_4.yaml', 'circle_2d.yaml'])
def test_formation_sim_fixed_step_is_the_plant_model_answered_every_step(name):
    """formation_sim --dt: the law answers each state of the model, stamped with its time."""
    config = load_config(os.path.join(CONFIG, name))
    law, reference = config.law(), config.reference()
    trajectory = simulate(config, duration=0.5, dt=0.01, sample_dt=0.01)
    plant = PlantModel(config.start, config.sensing_radii, MS, law, reference, MS, 1e-3)
    commands = Commands.empty(config.num_robots, config.dim)
    for k in range(50):
        assert np.array_equal(plant.q, trajectory.q[k])
        commands.store_all(team_command(plant.q, config.vertices, config.sensing_radii, law,
                                        reference.sample(plant.t)).u, plant.t_ns)
        assert np.array_equal(trajectory.u[k], commands.u)
        report = plant.advance(commands)
        assert (report.admission.status == CommandStatus.APPLIED).all()
    assert np.array_equal(plant.q, trajectory.q[50])


def brute_force_start(n, dim, radius, separation, seed):
    """Draw the random start the same way, comparing each candidate with every point placed."""
    rng = np.random.default_rng(seed)
    placed = []
    while len(placed) < n:
        direction = rng.normal(size=dim)
        direction /= np.linalg.norm(direction)
        candidate = direction * radius * rng.random() ** (1.0 / dim)
        if all(np.sum((p - candidate) ** 2) >= separation ** 2 for p in placed):
            placed.append(candidate)
    return np.array(placed)


@pytest.mark.parametrize('n, dim, radius, separation, seed', [
    (40, 2, 1.0, 0.1, 0), (200, 2, 2.5, 0.2, 7), (60, 3, 1.0, 0.15, 3), (25, 2, 3.0, 0.0, 1)])
def test_random_start_with_its_grid_equals_comparing_with_every_point(n, dim, radius,
                                                                      separation, seed):
    assert np.array_equal(random_start(n, dim, radius, separation, seed),
                          brute_force_start(n, dim, radius, separation, seed))


def test_pairs_kept_for_the_law_are_its_pairs_and_give_the_same_collisions():
    rng = np.random.default_rng(4)
    start = rng.uniform(-1.0, 1.0, (60, 2))
    start[1] = start[0] + [0.0205, 0.0]
    plain, keeping = (PlantModel(start, np.full(60, 1.0), MS, LAW, FIXED, 50 * MS, 1e-3,
                                 pair_radius=radius) for radius in (0.0, LAW.repulsion_radius))
    assert plain.pairs is None
    commands = Commands.empty(60, 2)
    for _ in range(20):
        assert np.array_equal(keeping.pairs, neighbour_pairs(keeping.q, LAW.repulsion_radius))
        u = rng.uniform(-0.2, 0.2, (60, 2))
        u[0], u[1] = [0.5, 0.0], [-0.5, 0.0]
        commands.store_all(u, plain.t_ns)
        reports = plain.advance(commands), keeping.advance(commands)
        assert reports[0].collisions == reports[1].collisions
        assert np.array_equal(plain.q, keeping.q)
    assert plain.counts.collisions == keeping.counts.collisions > 0
