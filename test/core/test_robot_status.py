# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A robot's status: its values from what it knows, and the first level that holds."""

import os

from formation_ros.core.maths.law import Command
from formation_ros.core.rules.robot_status import startup_line, status_level, status_values
from formation_ros.core.settings.params import load_params_file, validate
from formation_ros.core.settings.team import reference_values
import numpy as np

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')


def square(**changes):
    values = load_params_file(SQUARE)
    values.update({'robot_id': 2, **changes})
    return validate(values, 'robot')


def test_values_count_neighbours_in_range_and_size_the_command():
    points = np.array([[0.0, 0.0], [0.5, 0.0], [1.5, 0.0], [3.0, 0.0]])
    last = (Command(u=np.array([0.3, -0.4]), u_hat=np.array([0.1, -0.2]), omega=np.zeros(2)),
            np.array([0.5, -2.0]))
    values = status_values({'pose': 0.25, 'reference': None}, points, 2.0, 1.0, last, True)
    assert values['pose message age [s]'] == 0.25
    assert values['reference message age [s]'] == 'never'
    assert (values['neighbours heard'], values['neighbours within R_i'],
            values['neighbours within b']) == (3, 2, 1)
    assert values['max |u| component [m/s]'] == 0.4
    assert values['max |u_hat| component [m/s]'] == 0.2
    assert (values['|v| [m/s]'], values['|w| [rad/s]']) == (0.5, 2.0)
    body = status_values({}, None, 2.0, 1.0, last, False)
    assert body['max |u| component in the body frame [m/s]'] == 2.0
    assert 'neighbours heard' not in body and '|v| [m/s]' not in body


def test_the_level_is_the_first_that_holds():
    shared = {'/clock': '/plant, /probe'}
    assert status_level(shared, True, True, True, False)[0] == 'error'
    assert status_level({}, True, True, True, False) == ('warn', 'waiting for its first inputs')
    assert status_level({}, False, True, True, False) == ('warn', 'publishing zero: inputs stale')
    assert status_level({}, False, False, True, False)[1].startswith('flooding')
    assert status_level({}, False, False, False, True) == ('ok', 'lockstep')
    assert status_level({}, False, False, False, False) == ('ok', 'controlling')


def test_the_startup_line_names_the_robot_its_constants_and_modes():
    line = startup_line(square(**{'plant.lockstep': True}), 1, 'world', True)
    assert line.startswith('robot 2/4: vertex ') and 'R_i = 2 m' in line
    assert line.endswith("lockstep, simulated time from the states' stamps"), line
    assert 'Hz' in startup_line(square(), 1, 'world', False)
    assert 'obstacles' not in line


def test_the_startup_line_says_where_the_obstacles_come_from():
    told = startup_line(square(**{'obstacles.clearance': 0.4}), 1, 'world', False)
    assert told.endswith(', obstacles as told (b_o = 0.4 m)'), told
    seen = startup_line(square(**{'obstacles.clearance': 0.4, 'obstacles.source': 'scan'}), 1,
                        'world', True)
    assert (', obstacles from its scan in robot_2/base_scan (b_o = 0.4 m), simulated time '
            "from the states' stamps") in seen, seen


def test_robots_share_a_track_only_with_the_values_that_decide_it():
    first = reference_values(square().values)
    assert first == reference_values(square(**{'controller.gain': 3.0}).values)
    circle = square(**{'reference.kind': 'circle', 'reference.radius': 1.0})
    assert first != reference_values(circle.values)
