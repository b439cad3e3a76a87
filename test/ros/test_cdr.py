# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Reading serialized PoseArrays with numpy equals rclpy's own deserialisation."""

from formation_ros.ros import messages
from formation_ros.ros.cdr import CdrError, read_pose_array
from formation_ros.ros.fields import points_of, stamp_to_ns
from geometry_msgs.msg import Pose, PoseArray
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message


@pytest.mark.parametrize('frame', ['', 'w', 'world', 'abc', 'world_frame_x', 'é'])
@pytest.mark.parametrize('count', [0, 1, 2, 31])
def test_positions_stamp_and_frame_equal_rclpys(frame, count):
    rng = np.random.default_rng(count)
    message = messages.pose_array(rng.normal(size=(count, 3)) * 1e3, 1_700_000_123_456_789, 3)
    message.header.frame_id = frame
    data = serialize_message(message)
    read = read_pose_array(data, max_poses=31)
    reference = deserialize_message(data, PoseArray)
    assert read.stamp_ns == stamp_to_ns(reference.header.stamp)
    assert read.frame_id == reference.header.frame_id
    assert np.array_equal(read.positions, points_of(reference, 3))
    assert read.positions.shape == (count, 3) and read.positions.flags.writeable


def test_orientations_do_not_leak_into_positions():
    message = PoseArray()
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = 1.0, 2.0, 3.0
    pose.orientation.x, pose.orientation.w = 0.5, 0.5
    message.poses = [pose, pose]
    read = read_pose_array(serialize_message(message), max_poses=5)
    assert read.positions.tolist() == [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]]


def test_too_many_poses_are_refused_before_reading_them():
    data = serialize_message(messages.pose_array(np.zeros((10, 2)), 0, 2))
    with pytest.raises(CdrError, match='10 poses, more than 9'):
        read_pose_array(data, max_poses=9)
    assert len(read_pose_array(data, max_poses=10).positions) == 10


def test_every_cut_and_bad_header_is_a_cdr_error():
    data = serialize_message(messages.pose_array(np.ones((3, 2)), 5, 2))
    for end in range(len(data)):
        with pytest.raises(CdrError):
            read_pose_array(data[:end], max_poses=10)
    with pytest.raises(CdrError, match='encapsulation'):
        read_pose_array(b'\x07\x07' + data[2:], max_poses=10)
    unterminated = bytearray(data)
    unterminated[16 + 5] = ord('x')
    with pytest.raises(CdrError, match='frame_id'):
        read_pose_array(bytes(unterminated), max_poses=10)


def test_big_endian_bytes_read_as_the_same_values():
    import struct
    values = [1.5, -2.25, 3.0, 0.0, 0.0, 0.0, 1.0]
    data = (b'\x00\x00\x00\x00' + struct.pack('>iII', 3, 7, 6) + b'world\x00' + b'\x00\x00'
            + struct.pack('>I', 1) + struct.pack('>7d', *values))
    read = read_pose_array(data, max_poses=1)
    assert read.stamp_ns == 3_000_000_007 and read.frame_id == 'world'
    assert read.positions.tolist() == [values[:3]]
