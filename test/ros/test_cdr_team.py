# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The team transport's messages as bytes: what rclpy reads, and untrusted bytes refused."""

import struct

from formation_ros.ros.cdr import (CdrError, encode_header, encode_names, encode_team_commands,
                                   encode_team_states, read_pose_array, TeamCommandReader,
                                   TooManyPoses)
from geometry_msgs.msg import PoseArray, Twist
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

NAMES = ['robot_3', 'robot_12', 'robot_1']


def twists(count):
    """(count, 3) linear and angular velocities, all different."""
    linear = np.arange(3.0 * count).reshape(count, 3) + 0.25
    return linear, -2.0 * linear


def test_a_team_command_is_a_multi_dof_joint_trajectory():
    linear, angular = twists(3)
    data = encode_team_commands(12_000_000_034, 'world', encode_names(NAMES), linear, angular)
    message = deserialize_message(data, MultiDOFJointTrajectory)
    assert message.header.frame_id == 'world'
    assert (message.header.stamp.sec, message.header.stamp.nanosec) == (12, 34)
    assert list(message.joint_names) == NAMES
    [point] = message.points
    assert not point.transforms and not point.accelerations
    assert [v.linear.y for v in point.velocities] == linear[:, 1].tolist()
    assert [v.angular.z for v in point.velocities] == angular[:, 2].tolist()


@pytest.mark.parametrize('count', [0, 1, 3])
def test_the_plant_reads_what_rclpy_writes(count):
    linear, angular = twists(count)
    message = MultiDOFJointTrajectory()
    message.header.frame_id = 'map'
    message.header.stamp.sec, message.header.stamp.nanosec = 3, 5
    message.joint_names = NAMES[:count]
    point = MultiDOFJointTrajectoryPoint()
    for row, turn in zip(linear, angular):
        twist = Twist()
        twist.linear.x, twist.linear.y, twist.linear.z = row
        twist.angular.x, twist.angular.y, twist.angular.z = turn
        point.velocities.append(twist)
    message.points = [point]
    read = TeamCommandReader(20).read(serialize_message(message))
    assert (read.stamp_ns, read.frame_id) == (3_000_000_005, 'map')
    assert read.indices.tolist() == [2, 11, 0][:count]
    assert np.array_equal(read.linear, linear) and np.array_equal(read.angular, angular)


def valid():
    linear, angular = twists(3)
    return encode_team_commands(5, 'world', encode_names(NAMES), linear, angular)


@pytest.mark.parametrize('data', [
    b'', b'\x00\x01\x00\x00', valid()[:-9], valid()[:40], valid() + b'\x00' * 8,
    valid().replace(b'robot_12', b'robot_99'), valid().replace(b'robot_12', b'robot_1\x00'),
    encode_team_commands(5, 'world', encode_names(['robot_1', 'robot_1']), *twists(2)),
    encode_team_commands(5, 'world', encode_names(NAMES[:2]), *twists(3)),
])
def test_bytes_that_are_not_a_team_command_are_refused(data):
    with pytest.raises(CdrError):
        TeamCommandReader(20).read(data)


def test_an_oversized_team_command_is_refused_before_its_elements_are_read():
    reader = TeamCommandReader(2)
    with pytest.raises(TooManyPoses):
        reader.read(valid())
    head = encode_header(5, 'world')
    claim = head + b'\x00' * (-len(head) % 4) + struct.pack('<I', 10 ** 9) + b'\x00' * 64
    with pytest.raises(TooManyPoses):
        TeamCommandReader(20).read(claim)
    with pytest.raises(TooManyPoses):
        reader.read(valid() + b'\x00' * reader.limit)


def test_names_are_read_once_per_sender():
    reader = TeamCommandReader(20)
    first = reader.read(valid())
    again = reader.read(valid())
    assert again.indices is first.indices and len(reader.names) == 1


def test_a_team_state_is_a_pose_array_of_every_robot():
    rows = np.random.default_rng(1).normal(size=(5, 7))
    data = encode_team_states(7_500_000_000, 'world', rows)
    message = deserialize_message(data, PoseArray)
    assert len(message.poses) == 5 and message.header.stamp.sec == 7
    assert message.poses[4].orientation.w == rows[4, 6]
    read = read_pose_array(data, 5)
    assert np.array_equal(read.positions, rows[:, :3])
    assert np.array_equal(read.orientations, rows[:, 3:])
