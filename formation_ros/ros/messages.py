# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Build ROS messages from the numpy arrays of the core (reading them is ``fields``).

The nodes write their hot topics as bytes (``cdr``); these typed messages are what tools and
tests publish, and what the byte writers are tested against.
"""

from builtin_interfaces.msg import Time
from formation_ros.core.frames import frame_to_pose
from formation_ros.ros.fields import NS_PER_S
from geometry_msgs.msg import Pose, PoseArray, PoseStamped, TwistStamped
from nav_msgs.msg import Odometry

WORLD_FRAME = 'world'
FORMATION_FRAME = 'formation'
BODY_FRAME = 'base_link'


def body_frame(robot_id):
    """Return robot ``robot_id``'s body frame, ``robot_<i>/base_link`` (unicycle commands)."""
    return f'robot_{int(robot_id)}/{BODY_FRAME}'


def ns_to_stamp(ns):
    """Convert integer nanoseconds to a builtin_interfaces/Time."""
    return Time(sec=int(ns // NS_PER_S), nanosec=int(ns % NS_PER_S))


def _xyz(vector, dim):
    values = [0.0, 0.0, 0.0]
    values[:dim] = [float(v) for v in vector[:dim]]
    return values


def _stamped(msg, stamp_ns):
    msg.header.stamp = ns_to_stamp(stamp_ns)
    msg.header.frame_id = WORLD_FRAME
    return msg


def pose_stamped(position, stamp_ns, dim):
    """Build a PoseStamped at ``position`` ((dim,), m), identity orientation, frame 'world'."""
    msg = _stamped(PoseStamped(), stamp_ns)
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = _xyz(position, dim)
    msg.pose.orientation.w = 1.0
    return msg


def pose_array(points, stamp_ns, dim):
    """Build a PoseArray of the rows of ``points`` ((K, dim), m), frame 'world'."""
    msg = _stamped(PoseArray(), stamp_ns)
    for point in points:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = _xyz(point, dim)
        pose.orientation.w = 1.0
        msg.poses.append(pose)
    return msg


def twist_stamped(velocity, stamp_ns, dim):
    """Build a TwistStamped with linear = ``velocity`` ((dim,), m/s), frame 'world'."""
    msg = _stamped(TwistStamped(), stamp_ns)
    msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = _xyz(velocity, dim)
    return msg


def reference_odometry(frame, stamp_ns, dim):
    """Build the nav_msgs/Odometry of a reference sample (``core.frames.frame_to_pose``)."""
    position, quat, linear, angular = frame_to_pose(frame, dim)
    msg = _stamped(Odometry(), stamp_ns)
    msg.child_frame_id = FORMATION_FRAME
    pose, twist = msg.pose.pose, msg.twist.twist
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in position)
    (pose.orientation.x, pose.orientation.y, pose.orientation.z,
     pose.orientation.w) = (float(v) for v in quat)
    twist.linear.x, twist.linear.y, twist.linear.z = (float(v) for v in linear)
    twist.angular.x, twist.angular.y, twist.angular.z = (float(v) for v in angular)
    return msg
