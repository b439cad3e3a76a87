# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Unicycle bodies in the plant model (core/model/bodies.py, core/model/plant.py)."""

import math

from formation_ros.core.maths.law import make_law, team_command
from formation_ros.core.maths.reference import Reference
from formation_ros.core.maths.unicycle import command_bounds, hand_points, unicycle_commands
from formation_ros.core.model.bodies import (make_bodies, PointBodies, random_headings,
                                             UnicycleBodies)
from formation_ros.core.model.plant import Commands, CommandStatus, PlantModel
from formation_ros.core.settings.params import validate
import numpy as np
import pytest
from scipy.integrate import solve_ivp

LAW = make_law(0.15, 1.0, 'tanh', 'poly', 2, 0.5)
FIXED = Reference('fixed', 2)
CIRCLE = Reference('circle', 2, np.zeros(2), np.zeros(2), 3.0, 0.1, 1.0)
MS = 10_000_000
L = 0.08


def unicycle_model(q, heading, reference=FIXED, radius=0.0, max_linear=None, max_angular=None,
                   collision=1e-3, radii=1.0, timeout_ns=50 * MS):
    q = np.asarray(q, dtype=float)
    bodies = UnicycleBodies(L, radius, max_linear, max_angular)
    return PlantModel(q, np.full(len(q), radii), MS, LAW, reference, timeout_ns, collision,
                      bodies=bodies, headings=heading)


def test_model_steps_unicycles_exactly_against_a_fine_reference():
    q = np.array([[0.0, 0.0], [2.0, 1.0], [-1.0, 3.0]])
    heading = np.array([0.3, -2.0, 3.0])
    plant = unicycle_model(q, heading)
    commands = Commands.empty(3, 2)
    command = np.array([[0.08, 1.2], [-0.1, 0.0], [0.1, -1.0]])
    for _ in range(50):
        commands.store_all(command, plant.t_ns)
        report = plant.advance(commands)
        assert report.admission.status.tolist() == [CommandStatus.APPLIED] * 3
    for i in range(3):
        v, w = command[i]
        solution = solve_ivp(lambda _t, y: [v * math.cos(y[2]), v * math.sin(y[2]), w],
                             (0.0, 0.5), [*q[i], heading[i]], rtol=1e-12, atol=1e-13)
        assert np.max(np.abs(plant.q[i] - solution.y[:2, -1])) < 1e-10
        assert plant.heading[i] == pytest.approx(solution.y[2, -1], abs=1e-11)
    assert np.array_equal(plant.points, hand_points(plant.q, plant.heading, L))
    assert np.array_equal(q, [[0.0, 0.0], [2.0, 1.0], [-1.0, 3.0]])


def test_admission_zeroes_what_does_not_count_and_saturates_beyond_the_law():
    plant = unicycle_model([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0], [3.0, 3.0], [6.0, 6.0]],
                           [0.0, 0.5, 1.0, -1.0, 2.0])
    for _ in range(3):
        plant.advance(Commands.empty(5, 2))
    commands = Commands.empty(5, 2)
    commands.store(0, [0.1, 1.0], plant.t_ns)
    commands.store(1, [0.1, 1.0], plant.t_ns - 60 * MS)
    commands.store(2, [math.inf, 0.0], plant.t_ns)
    commands.store(3, [1e9, -1e9], plant.t_ns - MS)
    admission = plant.admit(commands)
    assert admission.status.tolist() == [CommandStatus.APPLIED, CommandStatus.STALE,
                                         CommandStatus.NON_FINITE, CommandStatus.SATURATED,
                                         CommandStatus.MISSING]
    assert admission.u[0].tolist() == [0.1, 1.0]
    assert np.all(admission.u[1:3] == 0.0) and np.all(admission.u[4] == 0.0)
    v_bound, w_bound = command_bounds(LAW.u_bound, L)
    saturated = admission.u[3]
    assert abs(saturated[0]) <= v_bound and abs(saturated[1]) <= w_bound
    earlier_heading = -1.0
    hand_velocity = np.array([math.cos(earlier_heading) * saturated[0]
                              - math.sin(earlier_heading) * L * saturated[1],
                              math.sin(earlier_heading) * saturated[0]
                              + math.cos(earlier_heading) * L * saturated[1]])
    assert np.allclose(np.abs(hand_velocity), LAW.u_bound, rtol=1e-12)


def test_saturation_uses_the_heading_of_the_state_the_command_answers():
    plant = unicycle_model([[0.0, 0.0], [3.0, 0.0]], [0.0, 0.0])
    commands = Commands.empty(2, 2)
    commands.store_all([[0.0, 3.0], [0.0, 3.0]], plant.t_ns)
    plant.advance(commands)
    answered = plant.t_ns - MS
    commands.store_all([[1.0, 0.0], [1.0, 0.0]], answered)
    admission = plant.admit(commands)
    assert admission.status.tolist() == [CommandStatus.SATURATED] * 2
    expected = unicycle_commands(np.clip(np.array([1.0, 0.0]), -LAW.u_bound, LAW.u_bound),
                                 0.0, L)
    assert np.allclose(admission.u, expected, atol=1e-15)
    assert np.allclose(admission.velocity, [[LAW.u_bound, 0.0]] * 2, rtol=0, atol=1e-15)


def test_actuator_caps_clip_v_and_w():
    plant = unicycle_model([[0.0, 0.0], [3.0, 0.0], [6.0, 0.0]], [0.0, 0.0, 0.0],
                           max_linear=0.1, max_angular=1.0)
    commands = Commands.empty(3, 2)
    commands.store_all([[0.12, 0.5], [0.05, -1.5], [0.05, 0.5]], plant.t_ns)
    admission = plant.admit(commands)
    assert admission.u.tolist() == [[0.1, 0.5], [0.05, -1.0], [0.05, 0.5]]
    assert np.allclose(admission.velocity, [[0.1, 0.5 * L], [0.05, -L], [0.05, 0.5 * L]],
                       rtol=0, atol=1e-15)
    assert admission.status.tolist() == [CommandStatus.SATURATED, CommandStatus.SATURATED,
                                         CommandStatus.APPLIED]


def test_law_commands_stay_within_their_bounds_and_are_never_touched():
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.0, 1.0, (12, 2))
    heading = rng.uniform(-math.pi, math.pi, 12)
    for reference in (FIXED, CIRCLE):
        plant = unicycle_model(q, heading, reference=reference)
        commands = Commands.empty(12, 2)
        for _ in range(30):
            frame = reference.sample(plant.t)
            u = team_command(plant.points, rng.normal(size=(12, 2)), np.full(12, 1.0), LAW,
                             frame, plant.tree).u
            sent = unicycle_commands(u, plant.heading, L)
            commands.store_all(sent, plant.t_ns)
            report = plant.advance(commands)
            assert np.array_equal(report.admission.u, sent)
            assert not report.violations
        if reference is FIXED:
            v_bound, w_bound = command_bounds(LAW.u_bound, L)
            assert np.all(np.abs(sent[:, 0]) <= v_bound)
            assert np.all(np.abs(sent[:, 1]) <= w_bound)
        assert plant.counts.steps_with(CommandStatus.SATURATED) == 0


def test_bodies_collide_at_twice_their_radius_and_hand_points_are_what_the_sensor_needs():
    plant = unicycle_model([[0.0, 0.0], [0.5, 0.0], [5.0, 0.0]], [0.0, math.pi, 0.0],
                           radius=0.2, radii=0.3)
    assert plant.closest_pair_distance() == pytest.approx(0.5 - 2 * L)
    assert plant.closest_body_distance() == pytest.approx(0.5)
    sensed = plant.neighbours()
    assert sensed[0].tolist() == [] and plant.sensor_radii.tolist() == [0.3 + 2 * L] * 3
    plant = unicycle_model([[0.0, 0.0], [0.4005, 0.0], [5.0, 0.0]], [0.0, math.pi, 0.0],
                           radius=0.2, radii=0.3)
    assert plant.neighbours()[0].tolist() == [1] and plant.neighbours()[1].tolist() == [0]
    commands = Commands.empty(3, 2)
    commands.store_all([[0.05, 0.0], [0.05, 0.0], [0.0, 0.0]], 0)
    reports = []
    for _ in range(3):
        commands.stamp_ns[:] = plant.t_ns
        reports.append(plant.advance(commands))
    assert [len(r.collisions) for r in reports] == [1, 0, 0]
    assert reports[0].collisions[0][:2] == (0, 1)
    assert reports[0].collisions[0][2] == pytest.approx(0.4005 - 0.001)


def test_point_bodies_are_the_default_and_unchanged():
    start = np.array([[0.0, 0.0], [3.0, 0.0]])
    plant = PlantModel(start, np.ones(2), MS, LAW, FIXED, 50 * MS, 1e-3)
    assert isinstance(plant.body, PointBodies) and plant.points is plant.q
    assert plant.body_tree is plant.tree
    commands = Commands.empty(2, 2)
    commands.store_all([[0.1, 0.0], [0.0, -0.1]], 0)
    report = plant.advance(commands)
    assert np.array_equal(plant.q, start + 0.01 * np.array([[0.1, 0.0], [0.0, -0.1]]))
    assert report.points is report.q and np.all(report.heading == 0.0)
    assert isinstance(make_bodies(validate(point_raw()).body), PointBodies)


def point_raw():
    return {'num_robots': 2, 'sensing_radius': 1.0, 'repulsion_radius': 0.5,
            'formation.vertices': [0.0, 0.0, 1.0, 0.0], 'start.positions': [0.0, 0.0, 2.0, 0.0]}


def test_random_headings_are_uniform_and_seeded():
    headings = random_headings(20000, 7)
    assert np.array_equal(headings, random_headings(20000, 7))
    assert np.all((headings >= -math.pi) & (headings < math.pi))
    counts, _ = np.histogram(headings, bins=8, range=(-math.pi, math.pi))
    assert np.all(np.abs(counts - 2500) < 250)


def test_chunks_keep_the_body_arrays(tmp_path):
    from formation_ros.core.runs.trajectory import ChunkWriter, read_body_chunks, read_chunks
    writer = ChunkWriter(str(tmp_path / 'chunks'))
    for k in range(5):
        writer.append(0.1 * k, np.full((3, 2), k), np.ones((3, 2)), heading=np.full(3, 0.5 * k),
                      q_body=np.full((3, 2), -k), body_command=np.full((3, 2), 2.0 * k))
        if k == 2:
            writer.flush()
    writer.flush()
    t, q, u = read_chunks(writer.folder)
    body = read_body_chunks(writer.folder)
    assert t.tolist() == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4]) and q.shape == (5, 3, 2)
    assert body['heading'][:, 0].tolist() == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert body['q_body'].shape == (5, 3, 2) and body['body_command'][4, 0, 0] == 8.0
    points = ChunkWriter(str(tmp_path / 'points'))
    points.append(0.0, np.zeros((3, 2)), np.zeros((3, 2)))
    points.flush()
    assert read_body_chunks(points.folder) is None


def test_kept_pairs_are_the_hand_points_and_bodies_still_collide_on_their_own():
    q = [[0.0, 0.0], [0.4005, 0.0], [0.9, 0.0]]
    bodies = UnicycleBodies(L, 0.2)
    plant = PlantModel(np.array(q), np.full(3, 1.0), MS, LAW, FIXED, 50 * MS, 1e-3,
                       bodies=bodies, headings=[math.pi, 0.0, 0.0], pair_radius=0.5)
    hands = hand_points(np.array(q), np.array([math.pi, 0.0, 0.0]), L)
    assert sorted(map(tuple, plant.pairs.tolist())) == [
        (i, j) for i in range(3) for j in range(i + 1, 3)
        if np.linalg.norm(hands[i] - hands[j]) <= 0.5]
    commands = Commands.empty(3, 2)
    commands.store_all([[-0.05, 0.0], [-0.05, 0.0], [0.0, 0.0]], 0)
    report = plant.advance(commands)
    assert [c[:2] for c in report.collisions] == [(0, 1)]


@pytest.mark.parametrize('bodies', [
    PointBodies(0.3), UnicycleBodies(L, max_linear=0.2, max_angular=1.0)])
def test_caps_return_a_clipped_copy_and_leave_the_commands_alone(bodies):
    command = np.array([[0.1, 0.1], [0.5, -0.1], [-0.05, -3.0]])
    before = command.copy()
    rows = np.array([True, True, False])
    capped, which = bodies.cap(command, rows)
    assert np.array_equal(command, before)
    assert which.tolist() == [False, True, False]
    limits = np.array([0.3, 0.3]) if isinstance(bodies, PointBodies) else np.array([0.2, 1.0])
    assert np.array_equal(capped[1], np.clip(before[1], -limits, limits))
    assert np.array_equal(capped[[0, 2]], before[[0, 2]])
    untouched, none = bodies.cap(command, np.zeros(3, dtype=bool))
    assert untouched is command and not np.any(none)


def test_admission_leaves_the_stored_commands_alone():
    plant = unicycle_model([[0.0, 0.0], [3.0, 0.0]], [0.0, 0.5])
    plant.advance(Commands.empty(2, 2))
    commands = Commands.empty(2, 2)
    commands.store(0, [1e9, -1e9], plant.t_ns)
    commands.store(1, [0.01, 0.02], plant.t_ns)
    stored = commands.u.copy()
    admission = plant.admit(commands)
    assert np.array_equal(commands.u, stored)
    assert admission.status.tolist() == [CommandStatus.SATURATED, CommandStatus.APPLIED]
    assert admission.u[1].tolist() == [0.01, 0.02]
