# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What the world node writes: PoseStamped bytes as rclpy's, its topics where the relay looks."""

from formation_ros.core.settings.declarations import BY_NAME
from formation_ros.ros import qos, topics
from formation_ros.ros.cdr import encode_pose_stamped
from geometry_msgs.msg import PoseStamped
import numpy as np
from rclpy.serialization import deserialize_message, serialize_message
import wire


def test_a_measured_pose_is_what_rclpy_writes():
    rng = np.random.default_rng(3)
    for frame in ('world', 'mocap', ''):
        position = rng.normal(size=3)
        orientation = rng.normal(size=4)
        orientation /= np.linalg.norm(orientation)
        data = encode_pose_stamped(1_234_567_890_123, frame, position, orientation)
        expected = wire.pose_stamped(position, 1_234_567_890_123, 3, frame, orientation)
        assert len(data) == len(serialize_message(expected))
        assert deserialize_message(data, PoseStamped) == expected


def test_the_measured_poses_are_the_relays_default_source_with_its_qos():
    default = BY_NAME['relay.source_topic'].default
    [pose, odometry] = topics.world_topics(3, wheeled=True)
    assert pose.name == default.format(i=3) == '/robot_3/measured_pose'
    assert odometry.name == '/robot_3/odom'
    assert odometry.type_name == 'nav_msgs/msg/Odometry'
    assert qos.BY_KIND[pose.qos] is qos.MEASUREMENT
    assert [t.name for t in topics.world_topics(1, wheeled=False)] == ['/robot_1/measured_pose']
