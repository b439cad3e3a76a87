# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Differential-drive robots in formation_sim: convergence, bounds, bodies, files, refusals."""

import json
import math
import os
import subprocess
import sys

from formation_ros.core.maths.law import log_potential, team_command
from formation_ros.core.maths.safety import guaranteed_min_distance
from formation_ros.core.maths.unicycle import command_bounds, hand_points
from formation_ros.core.runs.metrics import dis_min_series, formation_errors
from formation_ros.core.runs.trajectory import ARRAYS, BODY_ARRAYS, Trajectory
from formation_ros.core.settings.declarations import Exe
from formation_ros.core.settings.params import load_config, validate, validate_for_every_executable
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.figures.plots import FIGURES
from formation_ros.simulation.simulate import run_metrics, simulate
import numpy as np
import pytest
from scipy.spatial.distance import pdist

ROOT = os.path.join(os.path.dirname(__file__), '..')
CONFIG = os.path.join(ROOT, 'config')
HEXAGON = os.path.join(CONFIG, 'unicycle_2d.yaml')
CIRCLE = os.path.join(CONFIG, 'unicycle_circle_2d.yaml')
DT = 0.01


def raw_hexagon(**changes):
    raw = load_params_file(HEXAGON)
    for key, value in changes.items():
        if value is None:
            raw.pop(key, None)
        else:
            raw[key] = value
    return raw


def facing_away():
    """Return the hexagon file's random start with every robot facing away from its vertex."""
    config = load_config(HEXAGON)
    away = config.start - config.vertices
    headings = np.arctan2(away[:, 1], away[:, 0])
    return validate(raw_hexagon(**{'start.headings': [float(h) for h in headings]}))


def check_bodies(config, trajectory):
    """Every pair of bodies is at least its hand-point distance - 2 l apart; none touch."""
    l_value = config.body.hand_distance
    for q, q_body in zip(trajectory.q[::10], trajectory.q_body[::10]):
        assert np.all(pdist(q_body) >= pdist(q) - 2.0 * l_value - 1e-12)
    closest_body = float(np.min(dis_min_series(trajectory.q_body)))
    assert closest_body > 2.0 * config.body.radius
    return closest_body


def check_within_bounds_at_every_step(config, trajectory):
    v_bound, w_bound = command_bounds(config.law().u_bound, config.body.hand_distance)
    assert np.allclose(np.diff(trajectory.t), DT, rtol=0, atol=1e-9)
    command = trajectory.body_command
    assert np.all(np.abs(command[..., 0]) <= min(v_bound, config.body.max_linear))
    assert np.all(np.abs(command[..., 1]) <= min(w_bound, config.body.max_angular))
    return float(np.max(np.abs(command[..., 0]))), float(np.max(np.abs(command[..., 1])))


def test_rk45_hand_points_move_exactly_as_the_papers_points():
    config = load_config(HEXAGON)
    unicycles = simulate(config, duration=20.0, sample_dt=0.1)
    points = validate(raw_hexagon(**{
        'body.kind': None, 'body.hand_distance': None, 'body.max_linear': None,
        'body.max_angular': None, 'start.random_radius': None, 'start.min_separation': None,
        'start.positions': [float(v) for v in hand_points(
            config.start, config.start_headings, config.body.hand_distance).ravel()]}))
    papers = simulate(points, duration=20.0, sample_dt=0.1)
    assert papers.heading is None and unicycles.heading.shape == (201, 6)
    assert np.max(np.abs(unicycles.q - papers.q)) < 1e-6
    assert np.max(np.abs(hand_points(unicycles.q_body, unicycles.heading,
                                     config.body.hand_distance) - unicycles.q)) < 1e-15


def test_zero_order_hold_stays_close_to_the_continuous_system():
    config = load_config(HEXAGON)
    exact = simulate(config, duration=20.0, sample_dt=0.1)
    held = simulate(config, duration=20.0, dt=DT, sample_dt=0.1)
    assert np.allclose(held.t, exact.t, rtol=0, atol=1e-9)
    assert np.max(np.abs(held.q - exact.q)) < 5e-3
    assert np.max(np.abs(held.heading - exact.heading)) < 2e-2


def test_hexagon_converges_within_turtlebot_limits_from_random_headings():
    config = load_config(HEXAGON)
    headings = config.start_headings
    assert np.ptp(headings) > 3.0
    trajectory = simulate(config, dt=DT, sample_dt=DT)
    errors = formation_errors(trajectory.q, trajectory.q_desired)
    assert np.max(errors[-1]) < 1e-3
    max_v, max_w = check_within_bounds_at_every_step(config, trajectory)
    assert max_v > 0.9 * math.sqrt(2.0) * config.law().u_bound
    closest_body = check_bodies(config, trajectory)
    guaranteed = guaranteed_min_distance(trajectory.q[0], config.vertices, config.law())
    assert guaranteed - 2.0 * config.body.hand_distance > 2.0 * config.body.radius
    assert float(np.min(dis_min_series(trajectory.q))) >= guaranteed
    assert closest_body >= guaranteed - 2.0 * config.body.hand_distance
    metrics = run_metrics(trajectory, config, 'zoh')
    assert metrics['min_body_distance'] == pytest.approx(closest_body)
    assert metrics['guaranteed_min_hand_point_distance'] == pytest.approx(guaranteed)
    assert (metrics['max_abs_v'], metrics['max_abs_omega']) == (max_v, max_w)


def test_robots_facing_away_from_their_targets_turn_around_and_converge():
    config = facing_away()
    trajectory = simulate(config, duration=80.0, dt=DT, sample_dt=DT)
    q0, targets = trajectory.q_body[0], config.vertices
    facing = np.stack([np.cos(config.start_headings), np.sin(config.start_headings)], axis=1)
    assert np.all(np.einsum('nd,nd->n', facing, targets - q0) < 0.0)
    assert np.max(formation_errors(trajectory.q, trajectory.q_desired)[-1]) < 1e-3
    assert np.any(trajectory.body_command[:100, :, 0] < 0.0)
    check_within_bounds_at_every_step(config, trajectory)
    closest_body = check_bodies(config, trajectory)
    guaranteed = guaranteed_min_distance(trajectory.q[0], config.vertices, config.law())
    assert float(np.min(dis_min_series(trajectory.q))) >= guaranteed
    assert closest_body >= guaranteed - 2.0 * config.body.hand_distance


def test_the_potential_only_falls_along_a_zero_order_hold_run():
    config = facing_away()
    trajectory = simulate(config, duration=30.0, dt=DT, sample_dt=0.1)
    law = config.law()
    values = np.array([log_potential(q, config.vertices, law) for q in trajectory.q])
    assert np.all(np.diff(values) <= 1e-6 * np.maximum(1.0, np.abs(values[1:])))


def test_circle_tracking_converges_and_never_needs_the_actuator_caps():
    config = load_config(CIRCLE)
    trajectory = simulate(config, dt=DT, sample_dt=DT)
    assert np.max(formation_errors(trajectory.q, trajectory.q_desired)[-1]) < 1e-3
    command = trajectory.body_command
    assert np.max(np.abs(command[..., 0])) <= config.body.max_linear
    assert np.max(np.abs(command[..., 1])) <= config.body.max_angular
    reference, law = config.reference(), config.law()
    for k in range(0, len(trajectory.t), 97):
        wanted = team_command(trajectory.q[k], config.vertices, config.sensing_radii, law,
                              reference.sample(float(trajectory.t[k]))).u
        assert np.max(np.abs(wanted - trajectory.u[k])) < 1e-12
    check_bodies(config, trajectory)


def run_sim(*args):
    return subprocess.run([sys.executable, '-m', 'formation_ros.tools.sim', *args],
                          capture_output=True, text=True, timeout=600)


def test_cli_writes_headings_beside_the_usual_arrays(tmp_path):
    out = tmp_path / 'run'
    done = run_sim(HEXAGON, '--out', str(out), '--dt', '0.01', '--duration', '2', '--quiet')
    assert done.returncode == 0, done.stderr
    assert 'closest body approach' in done.stdout and 'max |w|' in done.stdout
    with np.load(out / 'trajectory.npz') as data:
        assert set(data.files) == set(ARRAYS + BODY_ARRAYS)
        assert data['heading'].shape == data['q'].shape[:2]
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.q_body.shape == trajectory.q.shape
    metrics = json.loads((out / 'metrics.json').read_text())
    for key in ('min_body_distance', 'max_abs_v', 'max_abs_omega', 'v_bound', 'omega_bound',
                'guaranteed_min_hand_point_distance'):
        assert key in metrics
    assert metrics['body_kind'] == 'unicycle' and metrics['max_linear'] == 0.22
    for name in FIGURES:
        assert (out / name).stat().st_size > 10000, name


def test_cli_refuses_a_file_beyond_turtlebot_limits_with_what_would_fit(tmp_path):
    path = tmp_path / 'fast.yaml'
    path.write_text(open(HEXAGON).read().replace('gain: 0.15', 'gain: 0.3'))
    done = run_sim(str(path), '--out', str(tmp_path / 'out'))
    assert done.returncode == 2 and not (tmp_path / 'out').exists()
    lines = done.stderr.strip().splitlines()
    assert lines[1:] == [
        "parameter 'body.max_linear': the law bound sqrt(2) c M1 = 0.4243 m/s exceeds "
        'body.max_linear = 0.22 m/s: controller.gain <= 0.1555 would fit',
        "parameter 'body.max_angular': the law bound sqrt(2) c M1 / l = 5.303 rad/s exceeds "
        'body.max_angular = 2.84 rad/s: controller.gain <= 0.1606 or body.hand_distance >= '
        '0.1494 m would fit']


def test_cli_refuses_unicycles_in_3d(tmp_path):
    path = tmp_path / 'three.yaml'
    text = open(os.path.join(CONFIG, 'helix_3d.yaml')).read().replace(
        '    duration:',
        '    body:\n      kind: unicycle\n      hand_distance: 0.1\n    duration:')
    path.write_text(text)
    done = run_sim(str(path), '--check')
    assert done.returncode == 2
    assert "parameter 'body.kind': unicycle needs dim 2" in done.stderr


@pytest.mark.parametrize('path', [HEXAGON, CIRCLE])
def test_shipped_unicycle_files_are_valid_for_every_node(path):
    checked = validate_for_every_executable(load_params_file(path))
    assert all(config.body.is_unicycle for config in checked.values())
    assert checked[Exe.ROBOT].body.hand_distance == 0.08
    assert checked[Exe.PLANT].start_headings is not None
