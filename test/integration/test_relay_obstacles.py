# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The relay tells each robot its obstacles from the parameters file's arena map (a lab's).

The probe plays the motion-capture system for five unicycles; every ``obstacles`` message is
checked against the plant's rule (``told_obstacles`` of the measured poses, surface points
closest to the hand points), stamped as the pose it goes with, and empty for a robot with
nothing within its R_i.
"""

import itertools
import math

from formation_ros.core.maths.obstacles import Obstacles, quaternion_normals, told_obstacles
from formation_ros.core.maths.unicycle import hand_points, quaternions_from_headings
from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseArray, PoseStamped
from helpers import node, write_params
import numpy as np
import wire

START_UP = 90.0
PENTAGON = [1.5 * v for k in range(5)
            for v in (math.cos(0.4 * math.pi * k), math.sin(0.4 * math.pi * k))]
HAND = 0.2
MAP = {'num_robots': 5, 'world_frame': 'map', 'formation.vertices': PENTAGON,
       'sensing_radii': [1.0, 1.0, 2.0, 1.0, 1.5], 'repulsion_radius': 0.5,
       'body.kind': 'unicycle', 'body.hand_distance': HAND,
       'obstacles.circles': [0.3, -0.5, 0.2], 'obstacles.walls': [3.0, -3.0, 3.0, 3.0, 0.1],
       'obstacles.clearance': 0.3}
POSITIONS = np.array([[0.0, 0.0], [0.9, 0.0], [0.0, 1.5], [0.0, -1.0], [1.2, 1.2]])
HEADINGS = np.array([0.3, -2.0, 1.0, 2.9, -0.7])


def test_relay_tells_each_robot_its_obstacles_from_the_map(processes, install, probe,
                                                           tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', MAP)
    told = {i: {} for i in range(1, 6)}
    poses = {i: {} for i in range(1, 6)}
    for i in range(1, 6):
        probe.create_subscription(
            PoseArray, f'/robot_{i}/obstacles',
            lambda m, i=i: told[i].setdefault(fields.stamp_to_ns(m.header.stamp), m),
            qos.STATE)
        probe.create_subscription(
            PoseStamped, f'/robot_{i}/pose',
            lambda m, i=i: poses[i].setdefault(fields.stamp_to_ns(m.header.stamp), m),
            qos.STATE)
    processes.start(node(install, 'relay', params))
    publishers = [probe.create_publisher(PoseStamped, f'/robot_{i}/measured_pose', qos.STATE)
                  for i in range(1, 6)]
    turned = quaternions_from_headings(HEADINGS)
    stamps = itertools.count(3)

    def complete():
        return sorted(set.intersection(*(set(told[i]) & set(poses[i]) for i in range(1, 6))))

    def measure():
        stamp = next(stamps)
        for i, publisher in enumerate(publishers):
            publisher.publish(wire.pose_stamped_bytes(stamp, 'map', POSITIONS[i], turned[i]))
        return len(complete()) >= 3

    assert probe.spin_until(measure, START_UP), processes.log('relay')
    obstacles = Obstacles(MAP['obstacles.circles'], MAP['obstacles.walls'], [], 0.3, 2)
    rule = told_obstacles(obstacles, POSITIONS, hand_points(POSITIONS, HEADINGS, HAND),
                          MAP['sensing_radii'])
    assert rule.listed.sum(axis=1).tolist() == [1, 1, 1, 1, 0]
    for stamp in complete():
        for i in range(1, 6):
            message = told[i][stamp]
            assert message.header.frame_id == 'map'
            points = np.array([[p.position.x, p.position.y] for p in message.poses])
            quats = np.array([[p.orientation.x, p.orientation.y, p.orientation.z,
                               p.orientation.w] for p in message.poses])
            expected = rule.points[i - 1][rule.listed[i - 1]]
            assert np.allclose(points.reshape(-1, 2), expected, rtol=0.0, atol=1e-12), i
            if len(expected):
                assert np.allclose(quaternion_normals(quats, 2),
                                   rule.normals[i - 1][rule.listed[i - 1]], atol=1e-12)
                assert abs(math.dist(points[0], (0.3, -0.5)) - 0.2) < 1e-12
    assert 'Traceback' not in processes.log('relay')
