# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Obstacles offline (issue 36): formation_sim, metrics.json, the summary and formation_report."""

import json

from formation_ros.core.settings.params import validate
from formation_ros.simulation.simulate import run_metrics, simulate
from formation_ros.tools import report, sim
import pytest
import yaml

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
