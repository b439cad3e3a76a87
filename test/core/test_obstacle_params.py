# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The obstacle parameters (``obstacles.*``) and the checks no single value shows."""

import os

from formation_ros.core.model.bodies import BodyKind, BodySettings
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.params import validate
from formation_ros.core.settings.params_file import load_params_file
import numpy as np
import pytest

CONFIG_DIR = os.path.join(os.path.dirname(__file__), '..', '..', 'config')
SQUARE = os.path.join(CONFIG_DIR, 'square_4.yaml')
UNICYCLES = os.path.join(CONFIG_DIR, 'unicycle_2d.yaml')
START = [-0.5, -0.5, 0.5, -0.5, 0.5, 0.5, -0.5, 0.5]


def square(**extra):
    """Return the square's values with a fixed start and ``extra`` on top."""
    raw = load_params_file(SQUARE)
    for name in ('start.random_radius', 'start.min_separation'):
        raw.pop(name, None)
    return {**raw, 'start.positions': START, **extra}


def problems_of(raw, executable='formation_sim'):
    """Return the parameter names of the problems validating ``raw`` raises."""
    with pytest.raises(ParamError) as caught:
        validate(raw, executable)
    return caught.value, [name for name, _ in caught.value.problems]


def test_no_obstacle_is_none_for_every_reader():
    for exe in ('formation_sim', 'plant', 'relay', 'world'):
        assert validate(square(), exe).obstacles is None


def test_the_map_is_read_as_given():
    config = validate(square(**{'obstacles.circles': [3.0, 0.0, 0.2, -3.0, 0.0, 0.3],
                                'obstacles.walls': [0.0, 3.0, 2.0, 3.0, 0.05],
                                'obstacles.clearance': 0.4}))
    assert config.obstacles.count == 3
    assert np.array_equal(config.obstacles.circles, [[3.0, 0.0, 0.2], [-3.0, 0.0, 0.3]])
    assert np.array_equal(config.obstacles.walls, [[0.0, 3.0, 2.0, 3.0, 0.05]])
    assert config.obstacles.clearance == config.obstacle_clearance == 0.4


def test_a_robot_reads_only_the_clearance():
    raw = square(**{'obstacles.circles': [3.0, 0.0, 0.2], 'obstacles.clearance': 0.4,
                    'robot_id': 2})
    config = validate(raw, 'robot')
    assert config.obstacles is None and config.obstacle_clearance == 0.4


def test_obstacles_need_a_clearance():
    error, names = problems_of(square(**{'obstacles.circles': [3.0, 0.0, 0.2]}))
    assert names == ['obstacles.clearance'] and 'required' in str(error)


def test_the_clearance_is_within_every_sensing_radius():
    error, names = problems_of(square(**{'obstacles.circles': [3.0, 0.0, 0.2],
                                         'obstacles.clearance': 2.5}))
    assert names == ['obstacles.clearance'] and 'smallest R_i = 2 m' in str(error)


@pytest.mark.parametrize('name, flat, words', [
    ('obstacles.circles', [3.0, 0.0], 'takes 3 numbers an obstacle, got 2'),
    ('obstacles.walls', [0.0, 3.0, 2.0, 3.0], 'takes 5 numbers an obstacle, got 4'),
    ('obstacles.circles', [3.0, 0.0, 0.0], 'radius r must be > 0'),
    ('obstacles.walls', [0.0, 3.0, 2.0, 3.0, -0.1], 'half-thickness t must be > 0'),
    ('obstacles.spheres', [3.0, 0.0, 0.0, 0.2], 'spheres are 3D obstacles'),
])
def test_malformed_lists_are_named(name, flat, words):
    error, names = problems_of(square(**{name: flat, 'obstacles.clearance': 0.4}))
    assert names == [name] and words in str(error)


def test_non_numbers_are_refused_by_type():
    error, names = problems_of(square(**{'obstacles.circles': ['a', 'b', 'c'],
                                         'obstacles.clearance': 0.4}))
    assert names == ['obstacles.circles']


def test_a_start_inside_an_obstacle_is_refused():
    error, names = problems_of(square(**{'obstacles.circles': [0.5, 0.5, 0.1],
                                         'obstacles.clearance': 0.4}))
    assert names == ['start.positions']
    assert 'robot 3 starts touching circle 1' in str(error)


def test_a_body_touching_an_obstacle_is_refused_by_its_radius():
    near = {'obstacles.circles': [0.2, 0.5, 0.25], 'obstacles.clearance': 0.4}
    assert validate(square(**near)).obstacles.count == 1
    error, names = problems_of(square(**near, **{'body.radius': 0.06}))
    assert names == ['start.positions'] and 'footprint, 0.06 m' in str(error)


def test_a_vertex_within_the_clearance_is_refused():
    error, names = problems_of(square(**{'obstacles.circles': [1.0, 1.3, 0.1],
                                         'obstacles.clearance': 0.4}))
    assert names == ['obstacles.clearance']
    assert "robot 1's place in the formation comes within b_o = 0.4 m of circle 1" in str(error)


def test_a_moving_formation_is_checked_where_it_ends():
    moving = {'reference.kind': 'line', 'reference.velocity': [1.0, 0.0], 'duration': 10.0}
    on_the_way = square(**moving, **{'obstacles.circles': [5.0, 1.0, 0.1],
                                     'obstacles.clearance': 0.4})
    assert validate(on_the_way).obstacles.count == 1
    error, names = problems_of(square(**moving, **{'obstacles.circles': [11.0, 1.0, 0.1],
                                                   'obstacles.clearance': 0.4}))
    assert names == ['obstacles.clearance']


def test_the_footprint_of_a_unicycle_holds_its_body():
    body = BodySettings(kind=BodyKind.UNICYCLE, hand_distance=0.1, radius=0.05)
    assert body.footprint == pytest.approx(0.15)
    assert BodySettings(radius=0.05).footprint == 0.05
    config = validate(load_params_file(UNICYCLES))
    assert config.law_obstacles() is None


def test_the_law_sees_the_obstacles_grown_by_the_footprint():
    config = validate(square(**{'obstacles.circles': [3.0, 0.0, 0.2],
                                'obstacles.walls': [0.0, 3.0, 2.0, 3.0, 0.05],
                                'obstacles.clearance': 0.4, 'body.radius': 0.1}))
    grown = config.law_obstacles()
    assert np.allclose(grown.circles, [[3.0, 0.0, 0.3]])
    assert np.allclose(grown.walls, [[0.0, 3.0, 2.0, 3.0, 0.15]])
    assert np.allclose(config.obstacles.circles, [[3.0, 0.0, 0.2]])


def test_a_robot_on_its_scanner_reads_the_scan_settings():
    raw = square(**{'obstacles.clearance': 0.4, 'obstacles.source': 'scan', 'robot_id': 3})
    scan = validate(raw, 'robot').robot.scan
    assert scan.frame == 'robot_3/base_scan' and scan.mount == (0.0, 0.0)
    assert scan.mount_yaw == 0.0 and scan.sectors == 72 and scan.margin == 0.05
    lab = validate({**raw, 'obstacles.scan_frame': 'base_scan',
                    'obstacles.scan_mount': [-0.032, 0.0, 0.1]}, 'robot').robot.scan
    assert lab.frame == 'base_scan' and lab.mount == (-0.032, 0.0) and lab.mount_yaw == 0.1
    assert validate({**raw, 'obstacles.source': 'map'}, 'robot').robot.scan is None


@pytest.mark.parametrize('extra, name, words', [
    ({}, 'obstacles.source', 'needs obstacles.clearance'),
    ({'obstacles.clearance': 0.4, 'obstacles.scan_mount': [0.1, 0.0]}, 'obstacles.scan_mount',
     'takes [x, y, yaw]'),
    ({'obstacles.clearance': 0.4, 'obstacles.scan_frame': '/base scan'},
     'obstacles.scan_frame', 'not a frame id'),
    ({'obstacles.clearance': 0.4, 'obstacles.source': 'lidar'}, 'obstacles.source', 'map, scan'),
])
def test_a_scanning_robot_with_what_cannot_hold_is_refused(extra, name, words):
    raw = square(**{'obstacles.source': 'scan', 'robot_id': 1, **extra})
    error, names = problems_of(raw, 'robot')
    assert names == [name] and words in str(error)


def test_a_scanning_robot_in_3d_is_refused():
    raw = load_params_file(os.path.join(CONFIG_DIR, 'helix_3d.yaml'))
    error, names = problems_of({**raw, 'obstacles.clearance': 0.2, 'obstacles.source': 'scan',
                                'robot_id': 1}, 'robot')
    assert names == ['obstacles.source'] and 'dim must be 2' in str(error)
