# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Point bodies on the engine: the holonomic planar base and the flying body."""

import math

import numpy as np
import pytest

pytest.importorskip('mujoco')

from formation_ros.physics.engine import Engine  # noqa: E402, I100
from formation_ros.physics.parts import GRAVITY  # noqa: E402, I100
from formation_ros.physics.points import Flyer, Holonomic  # noqa: E402, I100
from physics_helpers import run, team, yaw_difference  # noqa: E402, I100

LIVE = {'world.cmd_timeout': 10.0}


def test_a_holonomic_base_moves_sideways_in_its_body_frame():
    engine = Engine(team([[0.0, 0.0], [5.0, 5.0]], 2, [0.5 * math.pi, 0.0],
                         {'command.frame': 'body', 'body.radius': 0.2, **LIVE}))
    assert isinstance(engine.model, Holonomic) and engine.model.body_frame
    engine.apply([[0.0, 0.2], [0.0, 0.0]])
    run(engine, 1.0)
    velocity = engine.velocities()[0]
    assert velocity[0] == pytest.approx(-0.2, abs=0.005)
    assert abs(velocity[1]) < 0.005
    pose = engine.poses()
    assert -0.2 < pose.positions[0, 0] < -0.15 and abs(pose.positions[0, 1]) < 1e-3
    assert abs(yaw_difference(pose.headings[0], 0.5 * math.pi)) < 1e-3


def test_a_holonomic_base_in_the_world_frame_speeds_up_within_its_force_limit():
    engine = Engine(team([[0.0, 0.0], [5.0, 5.0]], 2, None,
                         {'world.force_limit': 2.0, 'world.mass': 2.0, **LIVE}))
    assert not engine.model.body_frame and engine.model.force == 2.0
    engine.apply([[0.3, -0.4], [0.0, 0.0]])
    speeds = []
    for _ in range(250):
        engine.step()
        speeds.append(np.linalg.norm(engine.velocities()[0, :2]))
    accelerations = np.diff(speeds) / engine.world.timestep
    limit = math.sqrt(2.0) * 2.0 / 2.0
    assert np.max(accelerations) <= 1.01 * limit
    assert speeds[-1] == pytest.approx(0.5, abs=0.005)
    assert np.allclose(engine.velocities()[0, :2], [0.3, -0.4], atol=0.005)


def test_the_floor_caps_a_holonomic_base_s_push_at_its_friction():
    engine = Engine(team([[0.0, 0.0], [5.0, 5.0]], 2, None,
                         {'world.force_limit': 100.0, 'world.floor_friction': 0.5}))
    assert engine.model.force == pytest.approx(0.5 * GRAVITY * engine.world.mass)


def test_a_flying_body_holds_its_altitude_and_follows_a_vertical_velocity():
    start = [[0.0, 0.0, 1.0], [3.0, 3.0, 1.0]]
    engine = Engine(team(start, 3, None, LIVE))
    assert isinstance(engine.model, Flyer)
    engine.apply([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    run(engine, 1.0)
    assert np.allclose(engine.poses().positions, start, atol=1e-4)
    engine.apply([[0.0, 0.0, 0.3], [0.0, 0.0, 0.0]])
    run(engine, 1.0)
    assert engine.velocities()[0, 2] == pytest.approx(0.3, abs=0.005)
    assert 1.2 < engine.poses().positions[0, 2] < 1.3
    assert np.allclose(engine.poses().positions[1], start[1], atol=1e-4)


def test_a_flying_body_whose_command_goes_stale_hovers():
    engine = Engine(team([[0.0, 0.0, 1.0], [3.0, 3.0, 1.0]], 3, None,
                         {'world.cmd_timeout': 0.3}))
    engine.apply([[0.0, 0.0, -0.3], [0.0, 0.0, 0.0]], stamps_ns=[0, 0])
    run(engine, 0.6)
    stopped = engine.poses().positions[0, 2]
    run(engine, 0.5)
    assert abs(engine.poses().positions[0, 2] - stopped) < 1e-3
    assert stopped < 0.95
