# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A robot's status: its values from what it knows, and the first level that holds."""

from formation_ros.core.law import Command
from formation_ros.core.robot_status import status_level, status_values
import numpy as np


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
