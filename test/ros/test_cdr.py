# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Reading and writing the formation messages as bytes equals rclpy's own serialisation."""

import math

from formation_ros.core.maths.frames import frame_from_pose, frame_to_pose
from formation_ros.ros import messages
from formation_ros.ros.cdr import (CdrError, encode_clock, encode_odometry, encode_twist,
                                   encode_twist_stamped, read_odometry, read_pose_array,
                                   read_pose_stamped, read_twist, read_twist_stamped)
from formation_ros.ros.fields import points_of, stamp_to_ns
from geometry_msgs.msg import (Point, Pose, PoseArray, PoseStamped, Quaternion, Twist,
                               TwistStamped, Vector3)
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rosgraph_msgs.msg import Clock
import wire


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


def _vector(values):
    return {'x': values[0], 'y': values[1], 'z': values[2]}


@pytest.mark.parametrize('frame', ['', 'world', 'robot_12/base_link'])
def test_pose_twist_and_odometry_readers_equal_rclpys(frame):
    rng = np.random.default_rng(len(frame))
    values = rng.normal(size=20) * 100.0
    stamp = 1_234_567_890_123_456_789
    pose = PoseStamped()
    pose.header.stamp = messages.ns_to_stamp(stamp)
    pose.header.frame_id = frame
    pose.pose.position = Point(**_vector(values[:3]))
    pose.pose.orientation = Quaternion(x=values[3], y=values[4], z=values[5], w=values[6])
    read = read_pose_stamped(serialize_message(pose))
    assert (read.stamp_ns, read.frame_id) == (stamp, frame)
    assert read.position == tuple(values[:3]) and read.orientation == tuple(values[3:7])

    twist = TwistStamped()
    twist.header = pose.header
    twist.twist.linear = Vector3(**_vector(values[7:10]))
    twist.twist.angular = Vector3(**_vector(values[10:13]))
    read_twist = read_twist_stamped(serialize_message(twist))
    assert (read_twist.stamp_ns, read_twist.frame_id) == (stamp, frame)
    assert read_twist.linear == tuple(values[7:10])
    assert read_twist.angular == tuple(values[10:13])

    odometry = Odometry()
    odometry.header = pose.header
    odometry.child_frame_id = frame + 'x'
    odometry.pose.pose = pose.pose
    odometry.pose.covariance = rng.normal(size=36)
    odometry.twist.twist = twist.twist
    odometry.twist.covariance = rng.normal(size=36)
    read_odom = read_odometry(serialize_message(odometry))
    assert (read_odom.stamp_ns, read_odom.frame_id, read_odom.child_frame_id) == (
        stamp, frame, frame + 'x')
    assert read_odom.position == tuple(values[:3])
    assert read_odom.orientation == tuple(values[3:7])
    assert read_odom.linear == tuple(values[7:10]) and read_odom.angular == tuple(values[10:13])


@pytest.mark.parametrize('reader, message', [
    (read_pose_stamped, wire.pose_stamped(np.array([1.0, 2.0]), 7, 2)),
    (read_twist_stamped, wire.twist_stamped(np.array([1.0, 2.0]), 7, 2)),
    (read_odometry, wire.reference_odometry(None, 7, 2))])
def test_every_cut_of_a_message_is_a_cdr_error(reader, message):
    data = serialize_message(message)
    reader(data)
    for end in range(len(data)):
        with pytest.raises(CdrError):
            reader(data[:end])
    with pytest.raises(CdrError, match='encapsulation'):
        reader(b'\x05\x05' + data[2:])


def test_finite_tells_non_finite_values_and_a_zero_quaternion():
    good = read_odometry(serialize_message(wire.reference_odometry(None, 7, 2)))
    assert good.finite
    message = wire.reference_odometry(None, 7, 2)
    message.twist.twist.angular.z = math.inf
    assert not read_odometry(serialize_message(message)).finite
    message = wire.reference_odometry(None, 7, 2)
    message.pose.pose.orientation.w = 0.0
    assert not read_odometry(serialize_message(message)).finite
    pose = wire.pose_stamped(np.array([math.nan, 0.0]), 7, 2)
    assert not read_pose_stamped(serialize_message(pose)).finite


@pytest.mark.parametrize('stamp', [0, 999_999_999, 1_000_000_000, 1_700_000_123_456_789])
def test_written_messages_are_what_rclpy_writes_and_reads(stamp):
    rng = np.random.default_rng(stamp % 1000)
    u, w = rng.normal(size=3), rng.normal(size=3)
    cases = [
        (encode_twist_stamped(stamp, 'world', u[:2]), wire.twist_stamped(u, stamp, 2)),
        (encode_clock(stamp), Clock(clock=messages.ns_to_stamp(stamp)))]
    quaternion = rng.normal(size=4)
    frame = frame_from_pose(stamp / 1e9, rng.normal(size=3), quaternion / np.linalg.norm(
        quaternion), rng.normal(size=3), rng.normal(size=3), 3)
    odometry = wire.reference_odometry(frame, stamp, 3)
    position, quaternion, linear, angular = frame_to_pose(frame, 3)
    cases.append((encode_odometry(stamp, 'world', 'formation', position, quaternion, linear,
                                  angular), odometry))
    twist = wire.twist_stamped(u, stamp, 3)
    twist.twist.angular = Vector3(**_vector(w))
    cases.append((encode_twist_stamped(stamp, 'world', u, w), twist))
    for data, message in cases:
        expected = serialize_message(message)
        assert isinstance(data, bytes) and len(data) == len(expected)
        assert deserialize_message(data, type(message)) == message


def test_twist_without_header_is_what_rclpy_writes_and_reads():
    rng = np.random.default_rng(11)
    linear, angular = rng.normal(size=3), rng.normal(size=3)
    message = Twist(linear=Vector3(**_vector(linear)), angular=Vector3(**_vector(angular)))
    data = encode_twist(linear, angular)
    assert data == serialize_message(message)
    read = read_twist(serialize_message(message))
    assert read.linear == tuple(linear) and read.angular == tuple(angular)
    assert (read.stamp_ns, read.frame_id) == (0, '')
    for end in range(len(data)):
        with pytest.raises(CdrError):
            read_twist(data[:end])
