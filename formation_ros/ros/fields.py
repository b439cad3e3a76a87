# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Read the fields of formation messages into numpy arrays, without importing ROS.

The functions only use attribute names (``msg.header.stamp.sec``, ``msg.pose.position.x``...),
so they serve rclpy's messages in the nodes and the messages that ``rosbags`` deserialises from
a bag alike.
"""

from formation_ros.core.maths.frames import frame_from_pose
from formation_ros.core.maths.units import NS_PER_S
import numpy as np


def stamp_to_ns(stamp):
    """Convert a builtin_interfaces/Time (or anything with sec, nanosec) to nanoseconds."""
    return int(stamp.sec) * NS_PER_S + int(stamp.nanosec)


def position_of(msg, dim):
    """Return the position of a PoseStamped as (dim,)."""
    p = msg.pose.position
    return np.array([p.x, p.y, p.z][:dim])


def points_of(msg, dim):
    """Return the positions of a PoseArray as (K, dim)."""
    points = np.array([[p.position.x, p.position.y, p.position.z] for p in msg.poses])
    return points.reshape(-1, 3)[:, :dim]


def frame_of(msg, dim):
    """Return the FrameSample carried by a reference Odometry message."""
    pose, twist = msg.pose.pose, msg.twist.twist
    o = pose.orientation
    return frame_from_pose(
        stamp_to_ns(msg.header.stamp) / NS_PER_S,
        [pose.position.x, pose.position.y, pose.position.z], [o.x, o.y, o.z, o.w],
        [twist.linear.x, twist.linear.y, twist.linear.z],
        [twist.angular.x, twist.angular.y, twist.angular.z], dim)
