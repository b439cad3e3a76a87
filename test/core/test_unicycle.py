# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Unicycles and their hand points (core/maths/unicycle.py) against independent references."""

import math

from formation_ros.core.maths.unicycle import (command_bounds, hand_points, hand_velocity,
                                               headings_from_quaternions,
                                               quaternions_from_headings, unicycle_commands,
                                               unicycle_rates, zoh_step)
import numpy as np
import pytest
from scipy.integrate import solve_ivp

L = 0.08
RNG = np.random.default_rng(12)


def reference_step(q, th, v, w, dt):
    """Integrate x' = v cos th, y' = v sin th, th' = w with RK45 at tight tolerances."""
    def rhs(_t, y):
        return [v * math.cos(y[2]), v * math.sin(y[2]), w]
    sol = solve_ivp(rhs, (0.0, dt), [q[0], q[1], th], method='RK45', rtol=1e-12, atol=1e-13)
    return sol.y[:2, -1], sol.y[2, -1]


@pytest.mark.parametrize('w', [0.0, 1e-14, -1e-9, 1e-5, 0.3, -2.84, 40.0])
@pytest.mark.parametrize('dt', [0.01, 0.5])
def test_exact_step_matches_fine_reference_integration(w, dt):
    for _ in range(5):
        q = RNG.uniform(-3.0, 3.0, 2)
        th = RNG.uniform(-math.pi, math.pi)
        v = RNG.uniform(-0.3, 0.3)
        moved, turned = zoh_step(q, th, [v, w], dt)
        ref_q, ref_th = reference_step(q, th, v, w, dt)
        assert np.max(np.abs(moved - ref_q)) < 1e-10
        assert turned == pytest.approx(ref_th, abs=1e-12)


def test_tiny_turn_rates_agree_with_the_taylor_expansion_without_cancellation():
    q, th, v, dt = np.array([0.3, -0.2]), 0.7, 0.2, 0.01
    for w in (1e-6, 1e-9, 1e-12, 1e-300):
        moved, _ = zoh_step(q, th, [v, w], dt)
        a = w * dt
        series = q + v * dt * np.array([math.cos(th) - 0.5 * a * math.sin(th),
                                        math.sin(th) + 0.5 * a * math.cos(th)])
        assert np.max(np.abs(moved - series)) <= 1e-16 + 1e-14 * abs(v * dt * a)
    straight, _ = zoh_step(q, th, [v, 0.0], dt)
    assert np.array_equal(straight, q + v * dt * np.array([math.cos(th), math.sin(th)]))


def test_a_full_turn_returns_to_the_start():
    q = np.array([1.0, 2.0])
    moved, turned = zoh_step(q, 0.4, [0.5, 2.0 * math.pi], 1.0)
    assert np.max(np.abs(moved - q)) < 1e-15
    assert turned == pytest.approx(0.4 + 2.0 * math.pi)


def test_hand_point_velocity_matches_its_numerical_derivative():
    for _ in range(20):
        q = RNG.uniform(-2.0, 2.0, 2)
        th = RNG.uniform(-math.pi, math.pi)
        command = np.array([RNG.uniform(-0.2, 0.2), RNG.uniform(-3.0, 3.0)])
        h = 1e-5
        ahead = hand_points(*zoh_step(q, th, command, h), L)
        behind = hand_points(*zoh_step(q, th, command, -h), L)
        numeric = (ahead - behind) / (2.0 * h)
        assert np.max(np.abs(numeric - hand_velocity(command, th, L))) < 1e-9


def test_maps_invert_each_other():
    q = RNG.normal(size=(50, 2))
    th = RNG.uniform(-10.0, 10.0, 50)
    u = RNG.normal(size=(50, 2))
    axles = hand_points(q, th, L) - L * np.stack([np.cos(th), np.sin(th)], axis=-1)
    assert np.max(np.abs(axles - q)) < 1e-15
    assert np.max(np.abs(hand_velocity(unicycle_commands(u, th, L), th, L) - u)) < 1e-14
    command = unicycle_commands(u, th, L)
    assert np.max(np.abs(unicycle_commands(hand_velocity(command, th, L), th, L)
                         - command)) < 1e-12
    assert np.allclose(np.linalg.norm(hand_points(q, th, L) - q, axis=1), L, rtol=0, atol=1e-15)


def test_commands_are_the_components_along_and_across_the_heading():
    v_w = unicycle_commands([[1.0, 0.0], [0.0, 1.0], [0.0, -2.0]], [0.0, 0.0, math.pi / 2], 0.5)
    assert np.allclose(v_w, [[1.0, 0.0], [0.0, 2.0], [-2.0, 0.0]], atol=1e-15)


def test_per_robot_and_vectorised_forms_agree():
    n = 30
    q = RNG.normal(size=(n, 2))
    th = RNG.uniform(-math.pi, math.pi, n)
    u = RNG.normal(size=(n, 2))
    command = unicycle_commands(u, th, L)
    moved, turned = zoh_step(q, th, command, 0.05)
    rates_q, rates_th = unicycle_rates(th, command)
    for i in range(n):
        assert np.array_equal(hand_points(q[i], th[i], L), hand_points(q, th, L)[i])
        assert np.array_equal(unicycle_commands(u[i], th[i], L), command[i])
        assert np.array_equal(hand_velocity(command[i], th[i], L),
                              hand_velocity(command, th, L)[i])
        one_q, one_th = zoh_step(q[i], th[i], command[i], 0.05)
        assert np.array_equal(one_q, moved[i]) and one_th == turned[i]
        one_rate_q, one_rate_th = unicycle_rates(th[i], command[i])
        assert np.array_equal(one_rate_q, rates_q[i]) and one_rate_th == rates_th[i]


def test_bounds_hold_for_every_bounded_command_and_are_reached():
    u_bound = 0.15
    v_bound, w_bound = command_bounds(u_bound, L)
    assert (v_bound, w_bound) == (math.sqrt(2.0) * 0.15, math.sqrt(2.0) * 0.15 / L)
    u = RNG.uniform(-u_bound, u_bound, (20000, 2))
    u[:4] = [[u_bound, u_bound], [-u_bound, u_bound], [u_bound, -u_bound], [-u_bound, -u_bound]]
    th = RNG.uniform(-math.pi, math.pi, 20000)
    th[:4] = [math.pi / 4, math.pi / 4, -math.pi / 4, -3 * math.pi / 4]
    command = unicycle_commands(u, th, L)
    assert np.max(np.abs(command[:, 0])) <= v_bound * (1.0 + 1e-15)
    assert np.max(np.abs(command[:, 1])) <= w_bound * (1.0 + 1e-15)
    assert np.abs(command[0, 0]) == pytest.approx(v_bound, rel=1e-15)
    assert np.abs(command[1, 1]) == pytest.approx(w_bound, rel=1e-15)


def test_inputs_are_not_modified():
    q = RNG.normal(size=(5, 2))
    th = RNG.normal(size=5)
    command = RNG.normal(size=(5, 2))
    copies = [a.copy() for a in (q, th, command)]
    hand_points(q, th, L)
    unicycle_commands(command, th, L)
    hand_velocity(command, th, L)
    unicycle_rates(th, command)
    zoh_step(q, th, command, 0.1)
    for before, after in zip(copies, (q, th, command)):
        assert np.array_equal(before, after)


def test_quaternions_and_headings_round_trip_and_match_scipy():
    from scipy.spatial.transform import Rotation
    th = RNG.uniform(-math.pi, math.pi, 100)
    quaternions = quaternions_from_headings(th)
    assert np.allclose(Rotation.from_quat(quaternions).as_euler('ZYX')[:, 0], th, atol=1e-14)
    assert np.allclose(headings_from_quaternions(quaternions), th, atol=1e-14)
    assert np.allclose(headings_from_quaternions(3.0 * quaternions), th, atol=1e-14)
    tilted = Rotation.from_euler('ZYX', np.column_stack([th, 0.1 * th, -0.05 * th]))
    assert np.allclose(headings_from_quaternions(tilted.as_quat()), th, atol=1e-12)
    assert headings_from_quaternions([0.0, 0.0, 0.0, 1.0]) == 0.0
    one = quaternions_from_headings(th[0])
    assert np.array_equal(one, quaternions[0]) and headings_from_quaternions(one) == \
        headings_from_quaternions(quaternions)[0]
