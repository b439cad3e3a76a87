# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The MJCF scene: robots at their starts with their headings, world.xml loadable as it is."""

import math

import numpy as np
import pytest

mujoco = pytest.importorskip('mujoco')

from formation_ros.core.settings.params import load_config  # noqa: E402, I100
from formation_ros.physics.engine import Engine  # noqa: E402, I100
from formation_ros.physics.parts import ModelKind  # noqa: E402, I100
from formation_ros.physics.scene import build_scene, WORLD_FILE  # noqa: E402, I100
from physics_helpers import bases, team, yaw_difference  # noqa: E402, I100

STARTS = [[0.0, 0.0], [1.0, 0.5], [-1.2, 0.7], [0.3, -1.5], [2.0, 2.0]]
HEADINGS = [0.0, 0.5 * math.pi, -2.0, 3.0, -0.4]


@pytest.mark.parametrize('make', [bases, lambda starts, headings: team(
    starts, 2, headings, {'command.frame': 'body'})])
def test_the_scene_puts_every_robot_at_its_start_with_its_heading(make):
    engine = Engine(make(STARTS, HEADINGS))
    pose = engine.poses()
    assert np.allclose(pose.positions[:, :2], STARTS, atol=1e-12)
    assert np.allclose(yaw_difference(pose.headings, np.array(HEADINGS)), 0.0, atol=1e-9)
    assert np.allclose(np.linalg.norm(pose.orientations, axis=1), 1.0)
    assert engine.scene.names == tuple(f'robot_{i}' for i in range(1, 6))


def test_flying_bodies_start_at_their_3d_starts():
    starts = [[0.0, 0.0, 1.0], [1.0, 2.0, 3.0], [-1.0, 0.5, 2.0]]
    engine = Engine(team(starts, 3))
    assert engine.model.kind is ModelKind.FLYER
    assert np.allclose(engine.poses().positions, starts, atol=1e-12)


@pytest.mark.parametrize('params, kind, actuators', [
    ('unicycle_2d.yaml', ModelKind.DIFF_DRIVE, 2),
    ('lab_holonomic.yaml', ModelKind.HOLONOMIC, 3),
    ('helix_3d.yaml', ModelKind.FLYER, 4)])
def test_world_xml_loads_from_its_path_as_it_is(tmp_path, params, kind, actuators):
    config = load_config(f'config/{params}')
    scene = build_scene(config)
    path = scene.write(str(tmp_path / 'out'))
    assert path == str(tmp_path / 'out' / WORLD_FILE)
    model = mujoco.MjModel.from_xml_path(path)
    assert scene.model.kind is kind
    assert model.nu == actuators * config.num_robots
    assert model.opt.timestep == pytest.approx(0.002)
    text = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, 'world_frame')
    begin = model.text_adr[text]
    stored = bytes(model.text_data[begin:begin + model.text_size[text] - 1]).decode()
    assert stored == config.world_frame
    data = mujoco.MjData(model)
    mujoco.mj_step(model, data, 10)
    assert np.all(np.isfinite(data.qpos))


def test_a_unicycle_without_a_radius_gets_a_footprint_around_its_wheels():
    config = team([[0.0, 0.0], [1.0, 0.0]], 2, [0.0, 0.0], {
        'body.kind': 'unicycle', 'body.hand_distance': 0.1})
    model = build_scene(config).model
    assert model.footprint > 0.5 * model.track
    assert model.caster_position[0] < model.centre_of_mass[0] < 0.0


def test_the_scene_needs_a_start():
    config = load_config('config/square_4.yaml', 'reference')
    with pytest.raises(ValueError, match='start positions'):
        build_scene(config)


def test_measured_poses_carry_seeded_gaussian_noise_on_the_positions_only():
    starts = [[0.3 * (i % 10), 0.3 * (i // 10)] for i in range(100)]
    draws = []
    for _ in range(2):
        engine = Engine(team(starts, 2, None, {'world.pose_noise': 0.01, 'start.seed': 3}))
        truth, measured = engine.poses(), engine.measured_poses()
        draws.append(measured.positions - truth.positions)
        assert np.array_equal(measured.orientations, truth.orientations)
    assert np.array_equal(draws[0], draws[1])
    assert np.all(draws[0][:, 2] == 0.0)
    assert 0.008 < np.std(draws[0][:, :2]) < 0.012
    quiet = Engine(team(starts, 2))
    assert np.array_equal(quiet.measured_poses().positions, quiet.poses().positions)
