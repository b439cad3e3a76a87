# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The shipped lab parameters files: valid for every executable, the relay's sources, limits."""

import os

from formation_ros.core.maths.unicycle import command_bounds
from formation_ros.core.settings.declarations import CommandFrame, CommandType, Exe, SourceType
from formation_ros.core.settings.params import validate_for_every_executable
from formation_ros.core.settings.params_file import load_params_file
import pytest

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), 'config')


def checked(name):
    return validate_for_every_executable(load_params_file(os.path.join(CONFIG, name)))


def test_turtlebot3_lab_reads_vrpn_mocap_and_keeps_within_a_burgers_limits():
    configs = checked('lab_turtlebot3.yaml')
    relay = configs[Exe.RELAY].relay
    assert [relay.source(i) for i in range(1, 5)] == [f'/vrpn_mocap/tb{i}/pose'
                                                      for i in range(1, 5)]
    assert relay.source_type is SourceType.POSE
    robot = configs[Exe.ROBOT]
    assert robot.body.is_unicycle and robot.world_frame == 'world'
    assert robot.command.frame is CommandFrame.BODY
    assert robot.command.message is CommandType.TWIST_STAMPED
    v_bound, w_bound = command_bounds(robot.law().u_bound, robot.body.hand_distance)
    body = configs[Exe.SIM].body
    assert (body.max_linear, body.max_angular) == (0.22, 2.84)
    assert v_bound <= body.max_linear and w_bound <= body.max_angular


def test_holonomic_lab_reads_natnet_and_commands_plain_twists_in_the_body_frame():
    configs = checked('lab_holonomic.yaml')
    relay = configs[Exe.RELAY].relay
    assert [relay.source(i) for i in range(1, 5)] == [f'/base{i}/pose' for i in range(1, 5)]
    robot = configs[Exe.ROBOT]
    assert not robot.body.is_unicycle
    assert robot.command.message is CommandType.TWIST
    assert robot.command.frame is CommandFrame.BODY


@pytest.mark.parametrize('name', ['lab_turtlebot3.yaml', 'lab_holonomic.yaml'])
def test_every_executable_reads_one_world_frame(name):
    frames = {exe: config.world_frame for exe, config in checked(name).items()}
    assert set(frames) == {Exe.SIM, Exe.PLANT, Exe.REFERENCE, Exe.ROBOT, Exe.RELAY}
    assert set(frames.values()) == {'world'}
