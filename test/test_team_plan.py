# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A run's plan with the team transport: the plant's run takes it, a lab's refuses it."""

import os

from formation_ros.core.settings.declarations import Exe
from formation_ros.core.settings.params import load_config
from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.tools.system import PlanError, read_formation
import pytest

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'config')


def with_team_transport(tmp_path, name):
    """Return a copy of config ``name`` with ``transport: team``."""
    values = load_params_file(os.path.join(CONFIG, name))
    values['transport'] = 'team'
    path = str(tmp_path / name)
    write_params_file(path, values)
    return path


def test_a_plants_run_takes_the_team_transport(tmp_path):
    path = with_team_transport(tmp_path, 'square_4.yaml')
    assert read_formation(path).num_robots == 4
    assert load_config(path, Exe.PLANT).team_transport
    assert not load_config(os.path.join(CONFIG, 'square_4.yaml'), Exe.PLANT).team_transport


def test_a_lab_refuses_the_team_transport(tmp_path):
    with pytest.raises(PlanError, match='transport team needs the plant'):
        read_formation(with_team_transport(tmp_path, 'lab_turtlebot3.yaml'), plant=False)
