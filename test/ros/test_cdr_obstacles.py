# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Obstacle messages as bytes: what rclpy reads of them, and untrusted bytes refused."""

from formation_ros.core.maths.obstacles import Obstacles, quaternion_normals, told_obstacles
from formation_ros.ros.cdr import (CdrError, encode_obstacles, encode_team_obstacles,
                                   read_laser_scan, read_pose_array, read_team_obstacles,
                                   TooManyPoses, TooManyRays)
from geometry_msgs.msg import PoseArray, Transform
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import LaserScan
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

MAP = Obstacles([0.0, 0.0, 1.0, 3.0, 2.0, 0.4], [-2.0, -3.0, 2.0, -3.0, 0.1], [], 0.5, 2)
Q = np.array([[1.6, 0.2], [9.0, 9.0], [2.3, 2.0]])


def told():
    return told_obstacles(MAP, Q, Q, np.full(3, 2.0))


def test_each_robot_gets_a_pose_array_of_its_surface_points_and_normals():
    data = encode_obstacles(7_000_000_005, 'world', told())
    assert len(data) == 3
    messages = [deserialize_message(raw, PoseArray) for raw in data]
    assert [len(m.poses) for m in messages] == [2, 0, 1]
    for message in messages:
        assert message.header.frame_id == 'world'
        assert (message.header.stamp.sec, message.header.stamp.nanosec) == (7, 5)
    first = messages[0].poses[0]
    normal = (Q[0] - 0.0) / np.linalg.norm(Q[0])
    assert np.allclose([first.position.x, first.position.y], normal)  # on the unit circle
    quat = [first.orientation.x, first.orientation.y, first.orientation.z, first.orientation.w]
    assert np.allclose(quaternion_normals(np.array([quat]), 2)[0], normal)
    heard = read_pose_array(data[0], 256)
    assert np.array_equal(heard.positions[:, :2], told().points[0][told().listed[0]])


def test_the_team_message_names_the_robot_of_every_point():
    data = encode_team_obstacles(3_000_000_000, 'world', told())
    message = deserialize_message(data, MultiDOFJointTrajectory)
    assert list(message.joint_names) == ['robot_1', 'robot_1', 'robot_3']
    [point] = message.points
    assert len(point.transforms) == 3 and not point.velocities and not point.accelerations
    read = read_team_obstacles(data, 3, 256)
    assert read.robots.tolist() == [0, 0, 2] and read.stamp_ns == 3_000_000_000
    expected = told()
    assert np.array_equal(read.positions[:, :2], expected.points[expected.listed])
    assert np.allclose(quaternion_normals(read.orientations, 2),
                       expected.normals[expected.listed])
    empty = told_obstacles(MAP, Q + 50.0, Q + 50.0, np.full(3, 2.0))
    nothing = read_team_obstacles(encode_team_obstacles(1, 'world', empty), 3, 256)
    assert len(nothing.robots) == 0


def test_the_robots_read_what_rclpy_writes():
    message = MultiDOFJointTrajectory()
    message.header.frame_id = 'world'
    message.joint_names = ['robot_2', 'robot_2']
    point = MultiDOFJointTrajectoryPoint()
    point.transforms = [Transform(), Transform()]
    point.transforms[1].translation.x = 4.5
    message.points = [point]
    read = read_team_obstacles(serialize_message(message), 2, 256)
    assert read.robots.tolist() == [1, 1] and read.positions[1, 0] == 4.5
    assert read.orientations[0].tolist() == [0.0, 0.0, 0.0, 1.0]


def test_untrusted_team_obstacles_are_refused():
    data = encode_team_obstacles(1, 'world', told())
    with pytest.raises(TooManyPoses):
        read_team_obstacles(data, 3, 2)
    with pytest.raises(CdrError, match='robot_<i>'):
        read_team_obstacles(data, 2, 256)
    for cut in (10, len(data) // 2, len(data) - 9):
        with pytest.raises(CdrError):
            read_team_obstacles(data[:cut], 3, 256)
    with pytest.raises(CdrError):
        read_team_obstacles(data + b'\x00' * 8, 3, 256)
    other = MultiDOFJointTrajectory()
    other.joint_names = ['robot_1']
    point = MultiDOFJointTrajectoryPoint()
    point.transforms = [Transform()]
    other.points = [point, MultiDOFJointTrajectoryPoint()]
    with pytest.raises(CdrError, match='one trajectory point'):
        read_team_obstacles(serialize_message(other), 3, 256)


def laser_scan(rays=360):
    message = LaserScan()
    message.header.frame_id = 'robot_2/base_scan'
    message.header.stamp.sec, message.header.stamp.nanosec = 12, 34
    message.angle_min, message.angle_max = 0.25, 6.0
    message.angle_increment = 0.0175
    message.range_min, message.range_max = 0.12, 3.5
    message.ranges = [float(k % 7) / 2.0 for k in range(rays - 1)] + [float('inf')]
    message.intensities = [1.0] * rays
    return message


def test_a_laser_scan_reads_as_rclpy_wrote_it():
    scan = read_laser_scan(serialize_message(laser_scan()), 1000)
    assert (scan.stamp_ns, scan.frame_id) == (12_000_000_034, 'robot_2/base_scan')
    assert np.isclose(scan.angle_min, 0.25) and np.isclose(scan.angle_increment, 0.0175)
    assert np.isclose(scan.range_min, 0.12) and np.isclose(scan.range_max, 3.5)
    assert np.array_equal(scan.ranges, np.float32(laser_scan().ranges).astype(float))


def test_untrusted_scan_bytes_are_refused_whole():
    data = serialize_message(laser_scan())
    with pytest.raises(TooManyRays):
        read_laser_scan(data, 359)
    for cut in (10, len(data) // 2, len(data) - 8):
        with pytest.raises(CdrError):
            read_laser_scan(data[:cut], 1000)
    with pytest.raises(CdrError):
        read_laser_scan(serialize_message(PoseArray()), 1000)
