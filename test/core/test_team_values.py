# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What a team announces (core/settings/team.py): every must-agree parameter shows in it."""

import dataclasses
import os

from formation_ros.core.settings.params import validate
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.core.settings.team import FRAME_VALUES, LAW_VALUES, LINK_VALUES, team_values
import pytest

UNICYCLES = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'unicycle_2d.yaml')
CHANGED = {
    'world_frame': 'map', 'repulsion_radius': 0.7, 'controller.gain': 0.1,
    'controller.kappa': 9.0, 'controller.psi': 'arctan', 'jump.kind': 'smooth',
    'jump.order': 3, 'body.hand_distance': 0.09,
}
"""A value of each validated must-agree parameter that differs from the unicycles' file."""
NOT_BY_FILE = {'num_robots': 5, 'dim': 3}
"""Must-agree values a file cannot change alone (the vertices follow them): set on the config."""


def announced(raw):
    """Return what a robot of ``raw`` announces, in the shape in force."""
    config = validate({**raw, 'robot_id': 1}, 'robot')
    return team_values(config, config.vertices)


@pytest.mark.parametrize('name', sorted(CHANGED))
def test_a_changed_must_agree_value_is_announced(name):
    raw = load_params_file(UNICYCLES)
    assert raw.get(name) != CHANGED[name]
    assert announced({**raw, name: CHANGED[name]}) != announced(raw)


def test_a_point_team_differs_from_a_unicycle_team():
    raw = load_params_file(UNICYCLES)
    points = {key: value for key, value in raw.items() if not key.startswith('body.')}
    assert announced(points)['body'] != announced(raw)['body']


@pytest.mark.parametrize('name', sorted(NOT_BY_FILE))
def test_the_size_and_dimension_are_announced(name):
    config = validate({**load_params_file(UNICYCLES), 'robot_id': 1}, 'robot')
    other = dataclasses.replace(config, **{name: NOT_BY_FILE[name]})
    assert team_values(other, config.vertices) != team_values(config, config.vertices)


def test_every_announced_parameter_is_tried():
    tried = set(CHANGED) | set(NOT_BY_FILE) | {'body.kind'}
    assert set(FRAME_VALUES) | set(LAW_VALUES) == tried


def test_a_fleet_shares_every_announced_value_and_the_footprint():
    assert set(FRAME_VALUES) | set(LAW_VALUES) <= set(LINK_VALUES)
    assert {'body.radius', 'obstacles.clearance'} <= set(LINK_VALUES)
