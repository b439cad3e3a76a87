# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The lab's parameters: world_frame, command.*, relay.*, the non-ideal plant (params.py)."""

import os

from formation_ros.core.settings.declarations import (CommandFrame, CommandType, Exe, ParamError,
                                                      SourceType)
from formation_ros.core.settings.params import validate, validate_for_every_executable
from formation_ros.core.settings.params_file import load_params_file
import numpy as np
import pytest

CONFIG_DIR = os.path.join(os.path.dirname(__file__), '..', '..', 'config')


def section5(**changes):
    values = load_params_file(os.path.join(CONFIG_DIR, 'paper_section5.yaml'))
    values.update(changes)
    return values


def unicycles(**changes):
    values = load_params_file(os.path.join(CONFIG_DIR, 'unicycle_2d.yaml'))
    values.update(changes)
    return values


def problem(raw, exe):
    with pytest.raises(ParamError) as info:
        validate(raw, exe)
    return str(info.value)


def test_defaults_are_todays_system():
    for exe in (Exe.PLANT, Exe.ROBOT, Exe.SIM, Exe.RECORD):
        config = validate({**section5(), 'robot_id': 1, 'record.path': '/tmp/bag'}, exe)
        assert config.world_frame == 'world'
        assert config.command.message is CommandType.TWIST_STAMPED and config.command.stamped
        assert config.command.frame is CommandFrame.WORLD
        assert config.imperfections.is_ideal
    assert validate(unicycles(), Exe.PLANT).command.frame is CommandFrame.BODY


@pytest.mark.parametrize('frame', ['map', 'vicon_world', 'mocap', 'odom/child'])
def test_world_frame_is_any_frame_id(frame):
    assert validate(section5(world_frame=frame), Exe.PLANT).world_frame == frame


@pytest.mark.parametrize('frame', ['', '/world', 'my frame', 'a\tb'])
def test_world_frame_that_no_tf_takes_is_refused(frame):
    assert "parameter 'world_frame'" in problem(section5(world_frame=frame), Exe.PLANT)


def test_unicycles_command_in_their_body_frame_only():
    text = problem(unicycles(**{'command.frame': 'world'}), Exe.PLANT)
    assert "parameter 'command.frame'" in text and 'body frame' in text
    config = validate(unicycles(**{'command.frame': 'body', 'command.type': 'twist'}), Exe.PLANT)
    assert config.command.frame is CommandFrame.BODY and not config.command.stamped


def test_a_twist_cannot_answer_a_state_in_lockstep():
    text = problem(section5(**{'command.type': 'twist', 'plant.lockstep': True}), Exe.PLANT)
    assert "parameter 'command.type'" in text and 'no stamp' in text
    assert not validate(section5(**{'command.type': 'twist'}), Exe.PLANT).command.stamped


def test_body_frame_points_have_headings():
    headings = [0.1 * k for k in range(10)]
    config = validate(section5(**{'command.frame': 'body', 'start.headings': headings}),
                      Exe.PLANT)
    assert np.array_equal(config.start_headings, headings)
    assert validate(section5(**{'command.frame': 'body'}), Exe.PLANT).start_headings is not None
    assert validate(section5(), Exe.PLANT).start_headings is None
    text = problem(section5(**{'start.headings': headings}), Exe.PLANT)
    assert 'command.frame body' in text


def test_state_delay_must_leave_commands_fresh():
    text = problem(section5(**{'plant.state_delay': 0.5, 'plant.input_timeout': 0.5}),
                   Exe.PLANT)
    assert "parameter 'plant.state_delay'" in text and 'stale' in text
    config = validate(section5(**{'plant.state_delay': 0.1, 'plant.actuator_lag': 0.05,
                                  'plant.max_acceleration': 2.0, 'plant.pose_noise': 0.01}),
                      Exe.PLANT)
    imperfections = config.imperfections
    assert (imperfections.state_delay, imperfections.actuator_lag,
            imperfections.max_acceleration, imperfections.pose_noise) == (0.1, 0.05, 2.0, 0.01)
    assert not imperfections.is_ideal and imperfections.seed == config.values['start.seed']


def test_robots_and_reference_step_no_bodies():
    raw = section5(**{'plant.actuator_lag': 0.05, 'robot_id': 2})
    assert validate(raw, Exe.ROBOT).imperfections.is_ideal


def test_relay_sources_by_id_and_by_name():
    relay = validate(section5(), Exe.RELAY).relay
    assert relay.source(3) == '/robot_3/measured_pose' and relay.source_type is SourceType.POSE
    names = [f'tb{k}' for k in range(1, 11)]
    relay = validate(section5(**{'relay.source_topic': '/vrpn_mocap/{name}/pose',
                                 'relay.source_names': names,
                                 'relay.source_type': 'odometry'}), Exe.RELAY).relay
    assert relay.source(7) == '/vrpn_mocap/tb7/pose'
    assert relay.source_type is SourceType.ODOMETRY


@pytest.mark.parametrize('changes, words', [
    ({'relay.source_topic': '/vrpn_mocap/{name}/pose'}, ['relay.source_names', 'is required']),
    ({'relay.source_names': ['a', 'b']}, ['relay.source_names', '10 names, got 2']),
    ({'relay.source_names': ['a'] * 10, 'relay.source_topic': '/{name}/pose'},
     ['must differ']),
    ({'relay.source_topic': '/robot_{id}/pose'}, ['relay.source_topic', '{id}']),
    ({'relay.source_topic': '/robot_{i/pose'}, ['relay.source_topic', 'not a topic template']),
    ({'relay.source_topic': '/mocap/pose'}, ['names no robot']),
    ({'relay.source_names': [1.0] * 10}, ['list of strings']),
])
def test_relay_templates_that_cannot_work_are_refused(changes, words):
    text = problem(section5(**changes), Exe.RELAY)
    assert all(word in text for word in words), text


def test_a_lab_file_is_valid_for_every_executable():
    raw = section5(**{'world_frame': 'map', 'command.type': 'twist', 'command.frame': 'body',
                      'relay.source_topic': '/{name}/pose',
                      'relay.source_names': [f'body_{k}' for k in range(10)]})
    checked = validate_for_every_executable(raw)
    assert set(checked) == {Exe.SIM, Exe.PLANT, Exe.REFERENCE, Exe.ROBOT, Exe.RELAY}
    assert all(config.world_frame == 'map' for config in checked.values())


def test_a_delay_the_robots_would_refuse_is_refused_for_them():
    raw = section5(**{'plant.state_delay': 0.4, 'input_timeout': 0.3, 'robot_id': 1})
    text = problem(raw, Exe.ROBOT)
    assert "parameter 'plant.state_delay'" in text and 'input_timeout = 0.3 s' in text
    assert validate({**raw, 'input_timeout': 0.5}, Exe.ROBOT).robot is not None
