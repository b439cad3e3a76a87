# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Forged obstacle messages: a robot refuses them, says each reason once, and steers as before.

The probe plays the plant for robot 1 (with ``obstacles.clearance``): good pose, neighbours,
reference and obstacles, and every third tick an obstacle message in another frame, one with
more points than a robot takes, garbage bytes, a normal with no direction in the plane, or
non-finite numbers. The robot's commands are those the good messages give, within c M1.
"""

from formation_ros.core.maths.law import robot_command
from formation_ros.core.maths.obstacles import HeardObstacles
from formation_ros.core.settings.params import load_config
from formation_ros.ros import messages, qos
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from helpers import node, write_params
from nav_msgs.msg import Odometry
import numpy as np
import pytest
import wire

pytestmark = pytest.mark.faults
START_UP = 90.0
CLEARANCE = 0.4
POINT, FACING = np.array([0.5, -0.1]), (0.0, 0.0, 1.0, 0.0)
"""A surface point 0.3 m ahead of the robot, its outward normal -x (a half turn about z)."""
REASONS = ('a frame other than world_frame', 'more obstacle points than a robot takes',
           'not a whole message of its type', 'a normal (the x axis of an orientation)',
           'non-finite values')


def obstacles(stamp, points, orientation=FACING, frame='world'):
    message = messages.pose_array(points, stamp, 2, frame)
    for pose in message.poses:
        pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w = \
            orientation
    return message


def test_robot_refuses_forged_obstacles_once_each_and_steers_by_the_good_ones(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {'obstacles.clearance': CLEARANCE})
    config = load_config(params, 'plant')
    processes.start(node(install, 'robot', params, '-r', '__ns:=/robot_1', process='robot_1'))
    pose_pub = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)
    neighbours_pub = probe.create_publisher(PoseArray, '/robot_1/neighbors', qos.STATE)
    obstacles_pub = probe.create_publisher(PoseArray, '/robot_1/obstacles', qos.STATE)
    reference_pub = probe.create_publisher(Odometry, '/formation/reference', qos.REFERENCE)
    heard = []
    probe.create_subscription(TwistStamped, '/robot_1/cmd_vel', heard.append, qos.COMMAND)
    ticks, logged_at = [], []

    def publish():
        ticks.append(len(ticks))
        stamp = probe.get_clock().now().nanoseconds
        forged = [obstacles(stamp, [POINT], frame='map'),
                  obstacles(stamp, np.zeros((300, 2))),
                  b'\x00\x01\x00\x00\x07',
                  obstacles(stamp, [POINT], (0.0, -np.sqrt(0.5), 0.0, np.sqrt(0.5))),
                  obstacles(stamp, [[np.nan, 0.0]])]
        good = obstacles(stamp, [POINT])
        sent = forged[(len(ticks) // 3) % len(forged)] if len(ticks) % 3 == 0 else good
        obstacles_pub.publish(sent)
        pose_pub.publish(wire.pose_stamped(np.array([0.2, -0.1]), stamp, 2))
        neighbours_pub.publish(messages.pose_array(np.array([[0.6, 0.6]]), stamp, 2))
        reference_pub.publish(wire.reference_odometry(None, stamp, 2))
        log = processes.log('robot_1')
        if not logged_at and all(reason in log for reason in REASONS):
            logged_at.append(len(heard))
        return bool(logged_at) and len(heard) > logged_at[0] + 20

    assert probe.spin_until(publish, START_UP), processes.log('robot_1')
    answers = [u for u in (wire.velocity_of(m, 2) for m in heard[logged_at[0]:]) if np.any(u)]
    assert answers, 'the robot only published zero after the forged messages'
    heard_map = HeardObstacles.from_lists([([POINT], [[-1.0, 0.0]])], 2, 0.0, CLEARANCE)
    expected = robot_command(np.array([0.2, -0.1]), config.vertices[0], np.array([[0.6, 0.6]]),
                             config.sensing_radii[0], config.law(), obstacles=heard_map).u
    without = robot_command(np.array([0.2, -0.1]), config.vertices[0], np.array([[0.6, 0.6]]),
                            config.sensing_radii[0], config.law()).u
    assert np.max(np.abs(expected - without)) > 0.1, 'the obstacle must matter'
    assert all(np.max(np.abs(u - expected)) < 1e-12 for u in answers), (answers[:5], expected)
    assert max(np.max(np.abs(u)) for u in answers) <= config.law().u_bound
    log = processes.log('robot_1')
    for reason in REASONS:
        assert log.count(reason) == 1, (reason, log)
    assert 'Traceback' not in log and processes.running('robot_1')
