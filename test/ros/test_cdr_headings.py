# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Headings on the wire: state messages of unicycles against rclpy's deserialisation."""

from formation_ros.core.maths.sensing import sensed_pairs
from formation_ros.core.maths.unicycle import headings_from_quaternions, quaternions_from_headings
from formation_ros.ros.cdr import read_pose_array, StateEncoder
from geometry_msgs.msg import Pose, PoseArray, PoseStamped
import numpy as np
from rclpy.serialization import deserialize_message, serialize_message
from scipy.spatial import cKDTree


def test_state_messages_carry_each_robots_heading():
    rng = np.random.default_rng(5)
    q = rng.uniform(-1.0, 1.0, (7, 2))
    headings = rng.uniform(-np.pi, np.pi, 7)
    observer, seen = sensed_pairs(q, np.full(7, 1.2), cKDTree(q))
    encoder = StateEncoder(7, 2, 'world')
    poses, arrays = encoder.encode(q, observer, seen, 123_000_000_789, headings)
    for i in range(7):
        pose = deserialize_message(poses[i], PoseStamped).pose
        o = pose.orientation
        assert (pose.position.x, pose.position.y) == tuple(q[i])
        assert abs(headings_from_quaternions([o.x, o.y, o.z, o.w]) - headings[i]) < 1e-15
        array = deserialize_message(arrays[i], PoseArray)
        expected = seen[observer == i]
        assert len(array.poses) == len(expected)
        for pose, j in zip(array.poses, expected):
            o = pose.orientation
            assert (pose.position.x, pose.position.y) == tuple(q[j])
            assert abs(headings_from_quaternions([o.x, o.y, o.z, o.w]) - headings[j]) < 1e-15
    plain, _ = StateEncoder(7, 2, 'world').encode(q, observer, seen, 5)
    assert deserialize_message(plain[0], PoseStamped).pose.orientation.w == 1.0


def test_pose_array_orientations_are_read_as_sent():
    message = PoseArray()
    quaternions = quaternions_from_headings(np.array([0.3, -2.0, 3.1]))
    for k, quaternion in enumerate(quaternions):
        pose = Pose()
        pose.position.x = float(k)
        (pose.orientation.x, pose.orientation.y, pose.orientation.z,
         pose.orientation.w) = (float(v) for v in quaternion)
        message.poses.append(pose)
    read = read_pose_array(serialize_message(message), max_poses=3)
    assert np.array_equal(read.orientations, quaternions)
    assert read.positions[:, 0].tolist() == [0.0, 1.0, 2.0]
