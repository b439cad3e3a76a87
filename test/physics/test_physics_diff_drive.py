# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A differential-drive base on the engine: speeds, limits, turning in place, pitch, timeout."""

import math

import numpy as np
import pytest

pytest.importorskip('mujoco')

from formation_ros.physics.engine import Engine  # noqa: E402, I100
from formation_ros.physics.diff_drive import DiffDrive, WHEEL_ARMATURE  # noqa: E402, I100
from physics_helpers import bases, forward_speed, run, tilt, yaw_difference  # noqa: E402, I100

FAR = [[0.0, 0.0], [5.0, 5.0]]
"""A base at the origin facing +x; the second robot of the team stands far away."""


def lone_base(extra=None):
    """Return a lone base whose commands stay live for 10 s unless ``extra`` says otherwise."""
    return Engine(bases(FAR, [0.0, 0.0], {'world.cmd_timeout': 10.0, **(extra or {})}))


def test_a_base_reaches_v_within_the_motors_limits_but_not_at_once():
    engine = lone_base()
    model = engine.model
    engine.apply([[0.15, 0.0], [0.0, 0.0]])
    speeds = []
    for _ in range(250):
        engine.step()
        speeds.append(forward_speed(engine)[0])
    speeds = np.array(speeds)
    dt = engine.world.timestep
    assert speeds[0] < 0.05, 'the base reached its speed in one step'
    assert np.argmax(speeds >= 0.95 * 0.15) * dt > 0.01
    assert abs(np.mean(speeds[-50:]) - 0.15) < 0.005
    torque_bound = 2.0 * engine.world.wheel_torque / model.wheel_radius / engine.world.mass
    assert np.max(np.diff(speeds)) / dt <= 1.1 * torque_bound
    position = engine.poses().positions[0]
    assert 0.05 < position[0] < 0.15 * 0.5 and abs(position[1]) < 1e-3


def test_torque_and_mass_set_the_acceleration():
    """With weak motors (no slip) a base speeds up at 2 tau / r over its mass and armature."""
    reached = []
    for mass in (1.0, 4.0):
        engine = lone_base({'world.mass': mass, 'world.wheel_torque': 0.05})
        engine.apply([[0.2, 0.0], [0.0, 0.0]])
        steps = 0
        while forward_speed(engine)[0] < 0.1:
            engine.step()
            steps += 1
        r = engine.model.wheel_radius
        expected = 2.0 * 0.05 / r / (mass + 2.0 * WHEEL_ARMATURE / r ** 2)
        measured = 0.1 / (steps * engine.world.timestep)
        assert abs(measured / expected - 1.0) < 0.15, (mass, measured, expected)
        reached.append(steps)
    assert reached[1] > 2 * reached[0]


def test_a_command_beyond_the_limits_gives_the_limits():
    engine = lone_base()
    engine.apply([[3.0, 0.0], [0.0, 0.0]])
    run(engine, 0.5)
    assert abs(forward_speed(engine)[0] - 0.22) < 0.01
    engine.apply([[0.0, 50.0], [0.0, 0.0]])
    run(engine, 0.3)
    before = engine.poses().headings[0]
    run(engine, 0.2)
    rate = yaw_difference(engine.poses().headings[0], before) / 0.2
    assert abs(rate - 2.84) < 0.1


def test_zero_speed_and_a_turn_rate_turn_the_base_in_place():
    engine = lone_base()
    engine.apply([[0.0, 1.5], [0.0, 0.0]])
    poses = run(engine, 1.0, every=5)
    positions = np.array([pose.positions[0, :2] for pose in poses])
    assert np.max(np.linalg.norm(positions, axis=1)) < 0.005
    turned = np.unwrap([pose.headings[0] for pose in poses])
    assert 1.3 < turned[-1] < 1.5


@pytest.mark.parametrize('torque', [0.2, 2.0])
def test_a_base_does_not_pitch_over_at_full_acceleration_or_braking(torque):
    engine = lone_base({'world.wheel_torque': torque})
    worst = 0.0
    for command in ((0.22, 0.0), (-0.22, 0.0), (0.22, 0.0), (0.0, 0.0), (0.22, 2.84),
                    (-0.22, -2.84)):
        engine.apply([command, [0.0, 0.0]])
        for pose in run(engine, 0.4):
            worst = max(worst, float(tilt(pose.orientations)[0]))
    assert worst < math.radians(5.0), math.degrees(worst)
    assert abs(engine.poses().positions[0, 2] - engine.model.wheel_radius) < 2e-3


def test_a_base_with_its_centre_of_mass_over_the_axle_pitches_over(monkeypatch):
    """The rule the model follows: the same braking tips a base balanced over its axle."""
    monkeypatch.setattr(DiffDrive, 'centre_of_mass', property(lambda model: np.zeros(3)))
    engine = lone_base()
    worst = 0.0
    for command in ((0.22, 0.0), (-0.22, 0.0), (0.22, 0.0), (0.0, 0.0)):
        engine.apply([command, [0.0, 0.0]])
        for pose in run(engine, 0.4):
            worst = max(worst, float(tilt(pose.orientations)[0]))
    assert worst > math.radians(45.0)


def test_a_stale_command_stops_the_base():
    engine = lone_base({'world.cmd_timeout': 0.2})
    engine.apply([[0.2, 0.0], [0.2, 0.0]], stamps_ns=[0, 0])
    run(engine, 0.15)
    assert forward_speed(engine)[0] > 0.15
    run(engine, 0.35)
    assert not engine.live()[0]
    assert abs(forward_speed(engine)[0]) < 0.005
    stopped = engine.poses().positions[0].copy()
    run(engine, 0.2)
    assert np.linalg.norm(engine.poses().positions[0] - stopped) < 1e-3


def test_a_command_refreshed_within_the_timeout_keeps_the_base_going():
    engine = lone_base({'world.cmd_timeout': 0.2})
    for _ in range(5):
        engine.apply([[0.2, 0.0], [0.0, 0.0]], stamps_ns=[engine.time_ns] * 2)
        run(engine, 0.1)
    assert engine.live()[0] and forward_speed(engine)[0] > 0.18


def test_the_engine_takes_admitted_commands_only_and_keeps_the_last_one():
    """A non-finite command is the intakes' to refuse (core.rules.admission.command_refusal)."""
    engine = lone_base()
    engine.apply([[0.1, 0.0], [0.0, 0.0]])
    with pytest.raises(ValueError):
        engine.apply([[math.nan, 0.0], [0.0, math.inf]])
    run(engine, 0.4)
    assert abs(forward_speed(engine)[0] - 0.1) < 0.005


def test_wheel_odometry_follows_the_truth_while_the_wheels_roll():
    engine = lone_base()
    engine.apply([[0.15, 0.8], [0.0, 0.0]])
    run(engine, 1.5)
    positions, headings = engine.odometry()
    truth = engine.poses()
    assert np.linalg.norm(positions[0] - truth.positions[0, :2]) < 0.01
    assert abs(yaw_difference(headings[0], truth.headings[0])) < 0.02
    assert np.linalg.norm(truth.positions[0, :2]) > 0.15


def test_wheel_odometry_drifts_when_the_wheels_slip():
    """Two bases pushing against each other: their wheels turn, they hardly move."""
    engine = Engine(bases([[0.0, 0.0], [0.4, 0.0]], [0.0, math.pi], {'world.cmd_timeout': 10.0}))
    engine.apply([[0.2, 0.0], [0.2, 0.0]])
    run(engine, 2.0)
    truth = engine.poses().positions[:, 0]
    odometry = engine.odometry()[0][:, 0]
    assert truth[1] - truth[0] > 2.0 * engine.model.footprint - 0.01
    assert odometry[0] - truth[0] > 0.1 and truth[1] - odometry[1] > 0.1


def test_wheel_speeds_clip_to_the_limits_and_invert_to_the_command():
    model = DiffDrive(wheel_radius=0.033, track=0.16, footprint=0.11, mass=1.0,
                      wheel_torque=0.2, friction=1.0, max_linear=0.22, max_angular=2.84)
    commands = np.array([[0.1, 0.5], [-0.2, -2.0], [0.0, 1.0], [0.5, 0.0], [0.0, -9.0]])
    wheels = model.wheel_speeds(commands)
    assert wheels[2].tolist() == pytest.approx([-0.08 / 0.033, 0.08 / 0.033])
    assert model.body_rates(wheels) == pytest.approx(
        np.array([[0.1, 0.5], [-0.2, -2.0], [0.0, 1.0], [0.22, 0.0], [0.0, -2.84]]))
