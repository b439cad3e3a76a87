# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Body-frame commands (frames.py, bodies.py): rotations against independent ones."""

import math

from formation_ros.core.maths.frames import from_body_frame, to_body_frame, valid_quaternions
from formation_ros.core.maths.unicycle import quaternions_from_headings
from formation_ros.core.model.bodies import PointBodies
import numpy as np
from scipy.spatial.transform import Rotation


def test_planar_rotation_is_the_yaw_of_the_orientation():
    rng = np.random.default_rng(3)
    heading = rng.uniform(-math.pi, math.pi, 20)
    u = rng.normal(size=(20, 2))
    body = to_body_frame(u, quaternions_from_headings(heading))
    c, s = np.cos(heading), np.sin(heading)
    expected = np.column_stack([c * u[:, 0] + s * u[:, 1], -s * u[:, 0] + c * u[:, 1]])
    assert np.allclose(body, expected, atol=1e-12)
    assert np.allclose(from_body_frame(body, quaternions_from_headings(heading)), u, atol=1e-12)


def test_a_tilted_body_in_the_plane_keeps_its_yaw():
    tilt = Rotation.from_euler('ZYX', [0.7, 0.05, -0.03]).as_quat()
    u = np.array([[1.0, 0.0]])
    assert np.allclose(to_body_frame(u, [tilt]), [[math.cos(0.7), -math.sin(0.7)]], atol=1e-12)


def test_spatial_rotation_equals_scipys():
    rng = np.random.default_rng(4)
    rotation = Rotation.random(15, random_state=5)
    u = rng.normal(size=(15, 3))
    body = to_body_frame(u, rotation.as_quat())
    assert np.allclose(body, rotation.inv().apply(u), atol=1e-12)
    assert np.allclose(from_body_frame(body, rotation.as_quat()), u, atol=1e-12)


def test_inputs_are_not_changed():
    u = np.ones((2, 2))
    quat = quaternions_from_headings([0.3, 1.0])
    kept_u, kept_q = u.copy(), quat.copy()
    to_body_frame(u, quat)
    from_body_frame(u, quat)
    assert np.array_equal(u, kept_u) and np.array_equal(quat, kept_q)


def test_valid_orientations_are_unit_quaternions():
    quat = np.array([[0, 0, 0, 1], [0, 0, 0, 0], [0, 0, 0, 1.01], [0, 0, 0, 1.0005],
                     [0, 0, math.nan, 1], [0.5, 0.5, 0.5, 0.5]], dtype=float)
    assert valid_quaternions(quat).tolist() == [True, False, False, True, False, True]


def test_body_frame_points_move_by_the_turned_command():
    bodies = PointBodies(body_frame=True)
    heading = np.array([math.pi / 2, 0.0])
    command = np.array([[1.0, 0.0], [0.0, 2.0]])
    world = bodies.world_velocity(command, heading)
    assert np.allclose(world, [[0.0, 1.0], [0.0, 2.0]], atol=1e-12)
    assert np.allclose(bodies.body_command(world, heading), command, atol=1e-12)
    world_bodies = PointBodies()
    assert world_bodies.world_velocity(command, heading) is command


def test_a_body_frame_step_moves_along_the_turned_command():
    bodies = PointBodies(body_frame=True)
    q, heading = np.zeros((2, 2)), np.array([math.pi / 2, math.pi])
    moved, kept = bodies.step(q, heading, np.array([[1.0, 0.0], [1.0, 0.0]]), 0.5)
    assert np.allclose(moved, [[0.0, 0.5], [-0.5, 0.0]], atol=1e-12) and kept is heading
