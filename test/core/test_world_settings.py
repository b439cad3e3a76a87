# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""world.*: declared like every parameter, validated into WorldSettings for formation_sim."""

from formation_ros.core.settings.declarations import BY_NAME, Exe, ParamError
from formation_ros.core.settings.params import load_config, validate, WORLD_FIELDS, WorldSettings
from formation_ros.core.settings.params_file import load_params_file
import pytest

SQUARE = 'config/square_4.yaml'


def test_the_defaults_are_a_turtlebot3_burger_at_two_millisecond_steps():
    world = load_config(SQUARE).world
    assert world == WorldSettings(seed=load_params_file(SQUARE)['start.seed'])
    assert (world.timestep, world.wheel_radius, world.wheel_track, world.mass) == (
        0.002, 0.033, 0.16, 1.0)
    assert world.timestep_ns == 2_000_000 and world.cmd_timeout_ns == 500_000_000
    assert world.steps_per_pose == 10


def test_every_world_parameter_is_described_with_a_range_and_read_by_the_simulator():
    names = [name for name in BY_NAME if name.startswith('world.')]
    assert set(names) == {f'world.{field}' for field in WORLD_FIELDS} and len(names) == 19
    for name in names:
        param = BY_NAME[name]
        assert param.description and Exe.SIM in param.users
        assert param.range_text() or param.name == 'world.output_dir'


def test_given_values_reach_the_settings_and_the_seed_is_the_start_s():
    raw = {**load_params_file(SQUARE), 'world.mass': 2.5, 'world.cmd_timeout': 0.25,
           'world.pose_noise': 0.01, 'start.seed': 7, 'world.output_dir': '/tmp/w'}
    world = validate(raw).world
    assert (world.mass, world.cmd_timeout, world.pose_noise, world.seed, world.output_dir) == (
        2.5, 0.25, 0.01, 7, '/tmp/w')


def test_the_nodes_do_not_read_them():
    assert validate(load_params_file(SQUARE), Exe.PLANT).world is None


@pytest.mark.parametrize('given, name, text', [
    ({'world.timestep': 1.5e-10 + 0.001}, 'world.timestep', 'whole number of nanoseconds'),
    ({'world.timestep': 0.01, 'world.pose_rate': 200.0}, 'world.pose_rate', 'faster'),
    ({'world.mass': 0.0}, 'world.mass', '> 0'),
    ({'world.floor_friction': 20.0}, 'world.floor_friction', '<= 10'),
    ({'world.cmd_timeout': 1}, 'world.cmd_timeout', 'double'),
])
def test_bad_world_values_are_refused_with_their_name(given, name, text):
    with pytest.raises(ParamError) as caught:
        validate({**load_params_file(SQUARE), **given})
    assert [problem[0] for problem in caught.value.problems] == [name]
    assert text in str(caught.value)
