# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Messages the tests send and read as other programs would: built with rclpy's own types.

The nodes read and write their hot topics as bytes (``formation_ros.ros.cdr``); these typed
messages, serialized by rclpy, are what a motion-capture driver, a base driver or a probe sends,
and so an independent reference for the package's readers and writers.
"""

from formation_ros.core.maths.frames import frame_to_pose
from formation_ros.ros.messages import FORMATION_FRAME, stamped, WORLD_FRAME, xyz
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
from rclpy.serialization import serialize_message


def pose_stamped(position, stamp_ns, dim, frame_id=WORLD_FRAME,
                 orientation=(0.0, 0.0, 0.0, 1.0)):
    """Build a PoseStamped at ``position`` ((dim,), m) with a quaternion (x, y, z, w)."""
    msg = stamped(PoseStamped(), stamp_ns, frame_id)
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = xyz(position, dim)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = (float(v) for v in orientation)
    return msg


def pose_stamped_bytes(stamp_ns, frame_id, position, orientation=(0.0, 0.0, 0.0, 1.0)):
    """Return a serialized PoseStamped: ``position`` ((dim,) m, z = 0 in 2D), a quaternion."""
    return serialize_message(pose_stamped(position, stamp_ns, len(position), frame_id,
                                          orientation))


def twist_stamped(velocity, stamp_ns, dim):
    """Build a TwistStamped with linear = ``velocity`` ((dim,), m/s), frame 'world'."""
    msg = stamped(TwistStamped(), stamp_ns)
    msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = xyz(velocity, dim)
    return msg


def velocity_of(msg, dim):
    """Return the linear velocity of a TwistStamped as (dim,)."""
    v = msg.twist.linear
    return np.array([v.x, v.y, v.z][:dim])


def reference_odometry(frame, stamp_ns, dim):
    """Build the nav_msgs/Odometry of a reference sample (``core.maths.frames.frame_to_pose``)."""
    position, quat, linear, angular = frame_to_pose(frame, dim)
    msg = stamped(Odometry(), stamp_ns)
    msg.child_frame_id = FORMATION_FRAME
    pose, twist = msg.pose.pose, msg.twist.twist
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in position)
    (pose.orientation.x, pose.orientation.y, pose.orientation.z,
     pose.orientation.w) = (float(v) for v in quat)
    twist.linear.x, twist.linear.y, twist.linear.z = (float(v) for v in linear)
    twist.angular.x, twist.angular.y, twist.angular.z = (float(v) for v in angular)
    return msg
