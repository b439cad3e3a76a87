# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What the relay reads and writes as bytes: exact readers, forwarded orientations."""

from formation_ros.core.maths.sensing import sensed_pairs
from formation_ros.ros.cdr import (CdrError, encode_odometry, read_odometry, read_pose_stamped,
                                   StateEncoder)
from geometry_msgs.msg import PoseArray, PoseStamped
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
import wire

ODOMETRY = encode_odometry(5, 'map', 'tb1', (1.0, 2.0, 0.0), (0.0, 0.0, 0.0, 1.0),
                           (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
POSE = wire.pose_stamped_bytes(5, 'map', (1.0, 2.0), (0.0, 0.0, 0.0, 1.0))


def test_an_odometry_read_as_a_pose_is_refused_only_when_exact():
    assert read_pose_stamped(ODOMETRY).frame_id == 'map'
    with pytest.raises(CdrError, match='left over'):
        read_pose_stamped(ODOMETRY, exact=True)
    with pytest.raises(CdrError):
        read_odometry(POSE, exact=True)


@pytest.mark.parametrize('padding', [0, 1, 3])
def test_exact_readers_take_whole_messages_and_a_final_padding(padding):
    pose = serialize_message(wire.pose_stamped(np.array([0.5, -1.5]), 7, 2))
    assert read_pose_stamped(pose + b'\x00' * padding, exact=True).position == (0.5, -1.5, 0.0)
    assert read_odometry(ODOMETRY + b'\x00' * padding, exact=True).position == (1.0, 2.0, 0.0)
    with pytest.raises(CdrError):
        read_pose_stamped(pose + b'\x00' * 4, exact=True)


def test_orientations_given_are_written_as_they_are():
    rng = np.random.default_rng(3)
    q = rng.uniform(-1.0, 1.0, (5, 2))
    orientations = rng.normal(size=(5, 4))
    orientations /= np.linalg.norm(orientations, axis=1)[:, None]
    observer, seen = sensed_pairs(q, np.full(5, 1.5))
    before = orientations.copy()
    poses, arrays = StateEncoder(5, 2, 'map').encode(q, observer, seen, 9,
                                                     orientations=orientations)
    assert np.array_equal(orientations, before)
    for i in range(5):
        pose = deserialize_message(poses[i], PoseStamped)
        assert pose.header.frame_id == 'map'
        o = pose.pose.orientation
        assert (o.x, o.y, o.z, o.w) == tuple(orientations[i])
        array = deserialize_message(arrays[i], PoseArray)
        for listed, j in zip(array.poses, seen[observer == i]):
            o = listed.orientation
            assert (o.x, o.y, o.z, o.w) == tuple(orientations[j])
