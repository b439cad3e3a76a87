# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Obstacles offline (issue 36): formation_sim, metrics.json, the summary and formation_report."""

import json
import os

from formation_ros.core.runs.obstacle_metrics import obstacle_metrics
from formation_ros.core.settings.params import load_config, validate
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.simulation.simulate import (format_summary, Progress, run_fixed_step,
                                               run_metrics, simulate)
from formation_ros.tools import report, sim
import numpy as np
import pytest
import yaml

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'config')

BEHIND_A_WALL = {
    'num_robots': 2, 'dim': 2, 'sensing_radius': 2.0, 'repulsion_radius': 1.0,
    'controller.gain': 1.0, 'controller.kappa': 1.0, 'controller.psi': 'arctan',
    'jump.kind': 'poly', 'jump.order': 2,
    'formation.vertices': [3.0, 0.0, 0.0, 6.0],
    'start.positions': [-3.0, 0.0, 0.0, 4.0],
    'reference.kind': 'fixed', 'duration': 12.0,
    'obstacles.walls': [0.0, -5.0, 0.0, 2.0, 0.2], 'obstacles.clearance': 0.5,
}
"""Robot 1 heads straight at a wide wall (symmetric about its path): it stops in front."""


def write_params(path, flat):
    """Write flat parameters as a ROS 2 parameters file (/**: ros__parameters: nested)."""
    nested = {}
    for name, value in flat.items():
        *parents, leaf = name.split('.')
        place = nested
        for parent in parents:
            place = place.setdefault(parent, {})
        place[leaf] = value
    with open(path, 'w', encoding='utf-8') as stream:
        yaml.safe_dump({'/**': {'ros__parameters': nested}}, stream)
    return str(path)


def test_a_robot_behind_a_wall_is_named_with_where_and_the_wall(tmp_path, capsys):
    params = write_params(tmp_path / 'wall.yaml', BEHIND_A_WALL)
    assert sim.main([params, '--out', str(tmp_path / 'run'), '--dt', '0.01', '--quiet']) == 0
    printed = capsys.readouterr().out
    with open(tmp_path / 'run' / 'metrics.json', encoding='utf-8') as stream:
        metrics = json.load(stream)
    assert metrics['settle_time'] is None
    assert metrics['obstacle_contacts'] == 0
    assert 0.0 < metrics['min_obstacle_clearance'] < 0.5
    (stuck,) = metrics['stuck_robots']
    assert stuck['robot'] == 1 and stuck['nearest_obstacle'] == 'wall 1'
    assert -0.7 < stuck['position'][0] < -0.2 and abs(stuck['position'][1]) < 1e-6
    assert stuck['error'] > 3.0
    assert 'not settled by the end: 1 robot stuck (below)' in printed
    assert 'robot 1 stuck at (' in printed and 'nearest wall 1' in printed
    assert 'obstacles: 1, closest approach of a body' in printed and 'no contact' in printed
    assert report.main([str(tmp_path / 'run'), '--out', str(tmp_path / 'report'),
                        '--no-plots']) == 0
    reported = capsys.readouterr().out
    assert 'robot 1 stuck at (' in reported and 'nearest wall 1' in reported
    with open(tmp_path / 'report' / 'metrics.json', encoding='utf-8') as stream:
        again = json.load(stream)
    for key in ('min_obstacle_clearance', 'obstacle_contacts', 'stuck_robots'):
        assert again[key] == metrics[key]


def test_a_run_without_obstacles_has_the_keys_empty():
    config = validate({**{k: v for k, v in BEHIND_A_WALL.items()
                          if not k.startswith('obstacles.')}, 'duration': 10.0})
    metrics = run_metrics(simulate(config, dt=0.01), config, 'test')
    assert metrics['min_obstacle_clearance'] is None and metrics['obstacle_contacts'] == 0
    assert metrics['stuck_robots'] == [] and metrics['settle_time'] is not None


@pytest.mark.parametrize('dt', [None, 0.01])
def test_unicycles_keep_their_bodies_off_a_pillar(dt):
    flat = {**BEHIND_A_WALL, 'body.kind': 'unicycle', 'body.hand_distance': 0.1,
            'body.radius': 0.15, 'start.headings': [0.0, 0.0], 'duration': 8.0,
            'obstacles.circles': [0.0, 0.3, 0.4], 'obstacles.walls': []}
    del flat['obstacles.walls']
    config = validate(flat)
    metrics = run_metrics(simulate(config, dt=dt), config, 'test')
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0
    assert metrics['bound_violations'] == 0


@pytest.mark.parametrize('name', ['pillars.yaml', 'doorway.yaml', 'helix_spheres.yaml',
                                  'world_doorway.yaml'])
def test_the_obstacle_configs_run_without_contact(name):
    config = load_config(os.path.join(CONFIG, name))
    metrics = run_metrics(simulate(config, dt=0.02), config, 'test')
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0
    assert metrics['bound_violations'] == 0 and metrics['min_pair_distance'] > 0.0
    if name.endswith('doorway.yaml'):
        stuck = metrics['stuck_robots']
        assert stuck and all(robot['nearest_obstacle'].startswith('wall') for robot in stuck)
        assert 1 not in [robot['robot'] for robot in stuck]
    else:
        assert metrics['settle_time'] is not None and metrics['stuck_robots'] == []


def pillar_field(seed, count=12, radius=0.35, clearance=0.5):
    """Random pillars among the Section 5 team: none within b_o of a start or a resting place."""
    rng = np.random.default_rng(seed)
    raw = load_params_file(os.path.join(CONFIG, 'paper_section5.yaml'))
    raw.update({'obstacles.clearance': clearance, 'duration': 12.0})
    config = validate(raw)
    keep_off = np.vstack([config.start, config.vertices])
    pillars = []
    while len(pillars) < count:
        centre = rng.uniform(-9.0, 9.0, 2)
        if np.min(np.linalg.norm(keep_off - centre, axis=1)) > radius + clearance + 0.3:
            pillars += [*centre, radius]
    raw['obstacles.circles'] = pillars
    return raw


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_no_contact_among_random_pillars_when_stabilising(seed):
    config = validate(pillar_field(seed))
    trajectory = simulate(config, sample_dt=0.002)
    metrics = obstacle_metrics(trajectory.q, config.obstacles)
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0


@pytest.mark.parametrize('seed, speed', [(3, 1.5), (4, 4.0)])
def test_no_contact_among_random_pillars_when_tracking_a_line(seed, speed):
    """The team forms up while its place crosses the field, at 4 m/s faster than c M1."""
    raw = pillar_field(seed)
    raw.update({'reference.kind': 'line', 'reference.origin': [-6.0, 0.0],
                'reference.velocity': [speed, 0.0], 'duration': 12.0 / speed})
    config = validate(raw)
    trajectory = simulate(config, sample_dt=0.002)
    metrics = obstacle_metrics(trajectory.q, config.obstacles)
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0


def test_rk45_does_not_step_over_a_thin_wall():
    """Robots holding their places on a line move exactly linearly: RK45 would leap the wall."""
    config = validate({**BEHIND_A_WALL, 'formation.vertices': [0.0, 0.0, 0.0, 3.0],
                       'start.positions': [0.0, 0.0, 0.0, 3.0], 'reference.kind': 'line',
                       'reference.velocity': [1.0, 0.0], 'duration': 8.0,
                       'obstacles.walls': [5.0, -10.0, 5.0, 10.0, 0.05]})
    trajectory = simulate(config)
    metrics = obstacle_metrics(trajectory.q, config.obstacles)
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0
    assert np.all(trajectory.q[-1, :, 0] < 5.0)  # held on their side, behind their places


def test_the_plant_model_keeps_the_guarded_feed_forward_it_audits():
    """Dragged at 4 m/s (> c M1) into a wall, stepped as the plant steps: no contact, no excess."""
    config = validate({**BEHIND_A_WALL, 'formation.vertices': [0.0, 0.0, 0.0, 10.0],
                       'start.positions': [0.0, 0.0, 0.0, 10.0], 'reference.kind': 'line',
                       'reference.velocity': [4.0, 0.0], 'duration': 3.0,
                       'obstacles.walls': [5.0, -20.0, 5.0, 20.0, 0.2],
                       'obstacles.clearance': 1.0})
    run = run_fixed_step(config, 3.0, 1e-3, 0.01, Progress(3.0, quiet=True))
    metrics = obstacle_metrics(run.trajectory.q, config.obstacles)
    assert metrics['obstacle_contacts'] == 0 and metrics['min_obstacle_clearance'] > 0.0
    assert np.all(run.trajectory.q[-1, :, 0] < 5.0)
    assert run.largest_u_hat <= config.law().u_bound + 1e-9


def test_the_summary_judges_a_collision_by_the_bodies_size():
    config = validate({**{k: v for k, v in BEHIND_A_WALL.items()
                          if not k.startswith('obstacles.')}, 'duration': 3.0})
    metrics = run_metrics(simulate(config, dt=0.01), config, 'test')
    assert 'min pair distance: ' in format_summary(metrics)
    assert '(no collision)' in format_summary(metrics)
    apart = metrics['min_pair_distance']
    sized = {**metrics, 'body_radius': 0.6 * apart}
    assert f'(COLLISION; 2 x body.radius = {1.2 * apart:.4g} m)' in format_summary(sized)
    small = {**metrics, 'body_radius': 0.4 * apart}
    assert f'(no collision; 2 x body.radius = {0.8 * apart:.4g} m)' in format_summary(small)
    sized_config = validate({**config.values, 'body.radius': 0.2})
    assert run_metrics(simulate(sized_config, dt=0.01), sized_config, 'test')[
        'body_radius'] == 0.2


def test_formation_sim_says_it_gives_a_scanning_team_the_map(tmp_path, capsys):
    params = write_params(tmp_path / 'scan.yaml', {**BEHIND_A_WALL, 'duration': 2.0,
                                                   'obstacles.source': 'scan'})
    assert sim.main([params, '--out', str(tmp_path / 'run'), '--dt', '0.01', '--quiet',
                     '--no-plots']) == 0
    said = capsys.readouterr().err
    assert said.count('obstacles.source is scan, but the simulator has no scanner') == 1
    with open(tmp_path / 'run' / 'metrics.json', encoding='utf-8') as stream:
        assert json.load(stream)['obstacle_count'] == 1, 'the map, as told'
