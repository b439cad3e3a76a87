# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Non-ideal bodies (core/model/dynamics.py, D1-D4): lag, acceleration limit, noise, delay."""

from dataclasses import replace
import math
import os

from formation_ros.core.maths.law import make_law
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.dynamics import (IDEAL, Imperfections, lagged_velocity, point_step,
                                               unicycle_step)
from formation_ros.core.model.plant import Commands, CommandStatus, PlantModel
from formation_ros.core.settings.params import load_config, validate
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.simulation.simulate import simulate
import numpy as np
import pytest

CONFIG = os.path.join(os.path.dirname(__file__), '..', '..', 'config')
LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
FIXED = Reference('fixed', 2)
MS = 10_000_000
SETTINGS = ('plant.actuator_lag', 'plant.max_acceleration', 'plant.pose_noise',
            'plant.state_delay')


def chained(velocity, command, dt, steps, lag, accel):
    """Velocity and total displacement after ``steps`` steps of dt (one component each)."""
    v, moved = np.asarray(velocity, dtype=float), 0.0
    for _ in range(steps):
        v, step = lagged_velocity(v, command, dt, lag, accel)
        moved = moved + step
    return v, moved


def euler(velocity, command, t, lag, accel, steps=40_000):
    """Brute force: explicit Euler of v' = clip((u - v) / tau, -a, a) with tiny steps."""
    v = np.array(velocity, dtype=float)
    u = np.asarray(command, dtype=float)
    h, moved = t / steps, np.zeros_like(v)
    a = math.inf if accel == 0.0 else accel
    for _ in range(steps):
        rate = np.clip((u - v) / lag, -a, a) if lag > 0.0 else np.clip((u - v) / h, -a, a)
        moved += h * v + 0.5 * h * h * rate
        v = v + h * rate
    return v, moved


def test_a_step_through_a_first_order_lag_is_the_closed_form():
    tau, u = 0.3, np.array([1.5, -0.4])
    for t in (0.01, 0.17, 0.3, 2.0):
        v, moved = lagged_velocity(np.zeros(2), u, t, tau, 0.0)
        assert np.allclose(v, u * (1.0 - math.exp(-t / tau)), rtol=1e-13, atol=0.0)
        assert np.allclose(moved, u * (t - tau * (1.0 - math.exp(-t / tau))), rtol=1e-12)
    v, moved = chained(np.zeros(2), u, 0.01, 137, tau, 0.0)
    t = 1.37
    assert np.allclose(v, u * (1.0 - math.exp(-t / tau)), rtol=1e-12)
    assert np.allclose(moved, u * (t - tau * (1.0 - math.exp(-t / tau))), rtol=1e-11)


def test_a_ramp_at_the_acceleration_limit_then_the_command():
    a, u = 2.0, np.array([1.0, -0.5, 0.0])
    t_reach = np.abs(u) / a
    for t in (0.1, 0.25, 0.6, 1.0):
        v, moved = chained(np.zeros(3), u, 0.01, int(round(t / 0.01)), 0.0, a)
        ramp = np.minimum(t, t_reach)
        assert np.allclose(v, np.sign(u) * a * ramp, rtol=1e-12, atol=1e-15)
        expected = np.sign(u) * 0.5 * a * ramp ** 2 + u * (t - ramp)
        assert np.allclose(moved, expected, rtol=1e-12, atol=1e-15)
    v, moved = lagged_velocity(np.zeros(3), u, 0.37, 0.0, a)
    assert np.allclose(moved, [0.5 * a * 0.37 ** 2, -0.0625 - 0.5 * (0.37 - 0.25), 0.0],
                       rtol=1e-13)


def test_lag_and_acceleration_limit_together():
    tau, a, u = 0.2, 3.0, 1.2
    t1 = (u - a * tau) / a  # the ramp lasts until the gap is a tau
    for t in (0.1, t1, 0.35, 1.0):
        v, moved = lagged_velocity(0.0, u, t, tau, a)
        if t <= t1:
            v_ref, x_ref = a * t, 0.5 * a * t * t
        else:
            decay = math.exp(-(t - t1) / tau)
            v_ref = u - a * tau * decay
            x_ref = 0.5 * a * t1 * t1 + u * (t - t1) - a * tau * tau * (1.0 - decay)
        assert v == pytest.approx(v_ref, rel=1e-12) and moved == pytest.approx(x_ref, rel=1e-12)
    v, moved = chained(0.0, u, 0.01, 70, tau, a)
    assert v == pytest.approx(u - a * tau * math.exp(-(0.7 - t1) / tau), rel=1e-12)


@pytest.mark.parametrize('lag, accel', [(0.25, 0.0), (0.0, 1.5), (0.1, 4.0), (0.5, 0.3)])
def test_every_case_agrees_with_a_brute_force_integration(lag, accel):
    rng = np.random.default_rng(3)
    v0, u = rng.uniform(-1.0, 1.0, 6), rng.uniform(-1.0, 1.0, 6)
    v, moved = lagged_velocity(v0, u, 0.4, lag, accel)
    v_ref, moved_ref = euler(v0, u, 0.4, lag, accel)
    assert np.max(np.abs(v - v_ref)) < 1e-4 and np.max(np.abs(moved - moved_ref)) < 1e-5
    assert np.all(np.minimum(v0, u) - 1e-15 <= v) and np.all(v <= np.maximum(v0, u) + 1e-15)
    q, v_points = point_step(np.ones((3, 2)), v0.reshape(3, 2), u.reshape(3, 2), 0.4, lag, accel)
    assert np.array_equal(q, 1.0 + moved.reshape(3, 2)) and np.array_equal(v_points.ravel(), v)


def unicycle_reference(q, heading, velocity, command, t, lag, accel, steps=20_000):
    """RK4 with tiny steps of (x, y, th, v, w) under U1 and D1 (with a smooth-enough clip)."""
    u = np.asarray(command, dtype=float)
    a = math.inf if accel == 0.0 else accel

    def rates(state):
        rate = np.clip((u - state[..., 3:]) / lag, -a, a)
        th, v, w = state[..., 2], state[..., 3], state[..., 4]
        return np.concatenate([np.stack([v * np.cos(th), v * np.sin(th), w], axis=-1), rate],
                              axis=-1)

    state = np.concatenate([q, heading[:, None], velocity], axis=1)
    h = t / steps
    for _ in range(steps):
        k1 = rates(state)
        k2 = rates(state + 0.5 * h * k1)
        k3 = rates(state + 0.5 * h * k2)
        k4 = rates(state + h * k3)
        state = state + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return state[:, :2], state[:, 2], state[:, 3:]


def test_unicycles_follow_their_lagged_speeds_to_second_order():
    rng = np.random.default_rng(7)
    q, heading = rng.uniform(-1.0, 1.0, (4, 2)), rng.uniform(-np.pi, np.pi, 4)
    velocity = np.column_stack([rng.uniform(-0.2, 0.2, 4), rng.uniform(-2.0, 2.0, 4)])
    command = np.column_stack([rng.uniform(-0.2, 0.2, 4), rng.uniform(-2.5, 2.5, 4)])
    dt, lag, accel = 0.05, 0.1, 8.0
    ref_q, ref_th, ref_v = unicycle_reference(q, heading, velocity, command, dt, lag, accel)
    errors = []
    for substeps in (2, 4, 8):
        moved, th, v = unicycle_step(q, heading, velocity, command, dt, lag, accel, substeps)
        _, turned = lagged_velocity(velocity[:, 1], command[:, 1], dt, lag, accel)
        assert np.allclose(th, heading + turned, rtol=0.0, atol=1e-14)
        assert np.max(np.abs(th - ref_th)) < 1e-9 and np.max(np.abs(v - ref_v)) < 1e-9
        errors.append(np.max(np.abs(moved - ref_q)))
    assert errors[-1] < 1e-6
    assert errors[0] / errors[1] > 3.0 and errors[1] / errors[2] > 3.0  # O(h^2): 4x per halving


def test_ideal_imperfections_keep_no_extra_state():
    plant = PlantModel(np.zeros((2, 2)) + [[0.0], [1.0]], np.ones(2), MS, LAW, FIXED, MS,
                       1e-3, imperfections=IDEAL)
    assert plant.velocity is None and plant._positions is None and plant._noise is None
    sensed = plant.sensed()
    assert sensed.q is plant.q and sensed.points is plant.points and sensed.stamp_ns == 0
    assert sensed.tree is plant.tree and sensed.pairs is plant.pairs
    explicit = Imperfections(0.0, 0.0, 0.0, 0.0, seed=9)
    assert explicit.is_ideal and not Imperfections(actuator_lag=0.1).ideal_body
    assert not Imperfections(state_delay=0.1).ideal_sensing


def with_settings(name, values):
    raw = load_params_file(os.path.join(CONFIG, name))
    return validate({**raw, **values})


@pytest.mark.parametrize('name', ['paper_section5.yaml', 'unicycle_2d.yaml'])
def test_all_zero_is_the_old_zero_order_hold_bit_for_bit(name):
    default = load_config(os.path.join(CONFIG, name))
    explicit = with_settings(name, dict.fromkeys(SETTINGS, 0.0))
    assert explicit.imperfections == default.imperfections and default.imperfections.is_ideal
    dt = 0.01
    first = simulate(default, duration=2.0, dt=dt, sample_dt=dt)
    second = simulate(explicit, duration=2.0, dt=dt, sample_dt=dt)
    for array in ('t', 'q', 'u', 'u_hat', 'q_desired', 'q_body', 'heading', 'body_command'):
        old, new = getattr(first, array), getattr(second, array)
        assert (old is None and new is None) or np.array_equal(old, new), array
    if first.q_body is None:
        assert np.array_equal(first.q[1:], first.q[:-1] + dt * first.u[:-1])
        return
    q, th, (v, w) = first.q_body[:-1], first.heading[:-1], np.moveaxis(first.body_command[:-1],
                                                                       -1, 0)
    arc = np.stack([np.where(w == 0.0, v * dt * np.cos(th),
                             v / w * (np.sin(th + w * dt) - np.sin(th))),
                    np.where(w == 0.0, v * dt * np.sin(th),
                             -v / w * (np.cos(th + w * dt) - np.cos(th)))], axis=-1)
    assert np.max(np.abs(first.q_body[1:] - (q + arc))) < 1e-12
    assert np.max(np.abs(first.heading[1:] - (th + w * dt))) < 1e-12


def still_model(n=40, **settings):
    q = np.column_stack([np.arange(n) * 3.0, np.zeros(n)])
    return PlantModel(q, np.full(n, 1.0), MS, LAW, FIXED, 50 * MS, 1e-3,
                      imperfections=Imperfections(**settings))


def test_pose_noise_has_its_deviation_one_draw_per_state_and_a_seed():
    sigma, steps = 0.02, 400
    plant = still_model(pose_noise=sigma, seed=4)
    start = plant.q.copy()
    draws = []
    for _ in range(steps):
        first, again = plant.sensed(), plant.sensed()
        assert np.array_equal(first.q, again.q)  # one draw per state, the same for everyone
        draws.append(first.q - plant.q)
        plant.advance(Commands.empty(40, 2))
    noise = np.array(draws)
    assert np.array_equal(plant.q, start)  # the bodies themselves stay exact
    count = noise.size
    assert abs(np.std(noise) - sigma) < 4.0 * sigma / math.sqrt(2.0 * count)
    assert abs(np.mean(noise)) < 4.0 * sigma / math.sqrt(count)
    assert abs(np.corrcoef(noise[:-1].ravel(), noise[1:].ravel())[0, 1]) < 4.0 / math.sqrt(count)
    same, other = still_model(pose_noise=sigma, seed=4), still_model(pose_noise=sigma, seed=5)
    assert np.array_equal(same.sensed().q - same.q, noise[0])
    assert not np.array_equal(other.sensed().q - other.q, noise[0])


def test_noise_is_sensed_but_the_recorded_run_and_collisions_are_true():
    config = with_settings('paper_section5.yaml', {'plant.pose_noise': 0.05})
    dt = 0.01
    noisy = simulate(config, duration=1.0, dt=dt, sample_dt=dt)
    ideal = simulate(load_config(os.path.join(CONFIG, 'paper_section5.yaml')), duration=1.0,
                     dt=dt, sample_dt=dt)
    assert np.array_equal(noisy.q[1:], noisy.q[:-1] + dt * noisy.u[:-1])  # the true bodies
    assert 1e-4 < np.max(np.abs(noisy.u - ideal.u))  # the law saw noisy positions
    plant = still_model(n=2, pose_noise=0.5)
    plant.q = np.array([[0.0, 0.0], [0.0005, 0.0]])
    plant._moved()
    assert plant.closest_body_distance() == pytest.approx(0.0005)


def test_a_delayed_state_is_the_true_state_whole_steps_earlier_stamped_then():
    plant = still_model(n=3, state_delay=0.054)  # rounds to 5 steps of 10 ms
    assert plant.delay_steps == 5 and still_model(state_delay=0.056).delay_steps == 6
    rng = np.random.default_rng(1)
    history = [plant.q]
    for k in range(1, 30):
        commands = Commands.empty(3, 2)
        sensed = plant.sensed()
        assert sensed.stamp_ns == max(k - 1 - 5, 0) * MS
        assert np.array_equal(sensed.q, history[max(k - 1 - 5, 0)])
        commands.store_all(rng.uniform(-1.0, 1.0, (3, 2)), sensed.stamp_ns)
        report = plant.advance(commands)
        assert np.all(report.admission.status == CommandStatus.APPLIED)
        history.append(plant.q)
    assert plant.counts.oldest_counted_ns == 5 * MS


def test_the_plant_keeps_the_states_a_delay_needs_beyond_its_cap():
    n = 2
    q = np.array([[0.0, 0.0], [5.0, 0.0]])
    plant = PlantModel(q, np.ones(n), 1_000_000, LAW, FIXED, 900_000_000, 1e-3,
                       imperfections=Imperfections(state_delay=0.7))  # 700 steps of 1 ms
    assert plant.delay_steps == 700 and plant._states_kept >= 702
    commands = Commands.empty(n, 2)
    commands.store_all(np.array([[0.1, 0.0], [0.0, 0.0]]), 0)
    for _ in range(705):
        commands.store_all(commands.u, plant.sensed().stamp_ns)
        plant.advance(commands)
    assert plant.sensed().stamp_ns == 5 * 1_000_000
    assert plant.sensed().q[0, 0] == pytest.approx(0.1 * 0.005, rel=1e-9)


def test_lagged_points_start_at_rest_and_follow_the_closed_form_in_the_model():
    plant = still_model(n=2, actuator_lag=0.05)
    u = np.array([[1.0, 0.0], [0.0, -2.0]])
    commands = Commands.empty(2, 2)
    start = plant.q.copy()
    for _ in range(10):
        commands.store_all(u, plant.t_ns)
        report = plant.advance(commands)
    t = 0.1
    assert np.allclose(report.velocity, u * (1.0 - math.exp(-t / 0.05)), rtol=1e-12)
    assert np.allclose(plant.q - start, u * (t - 0.05 * (1.0 - math.exp(-t / 0.05))),
                       rtol=1e-11, atol=1e-15)
    assert np.array_equal(report.admission.u, u)  # admitted as sent


def test_a_delayed_and_lagged_run_still_converges_and_records_its_settings(tmp_path):
    config = with_settings('paper_section5.yaml', {'plant.state_delay': 0.05,
                                                   'plant.actuator_lag': 0.1})
    trajectory = simulate(config, duration=20.0, dt=0.01, sample_dt=0.1)
    errors = np.linalg.norm(trajectory.q[-1] - trajectory.q_desired[-1], axis=1)
    assert np.max(errors) < 0.05
    assert replace(config.imperfections, seed=0).as_dict() == {
        'plant.actuator_lag': 0.1, 'plant.max_acceleration': 0.0, 'plant.pose_noise': 0.0,
        'plant.state_delay': 0.05}
