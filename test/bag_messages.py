# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""rosbags messages the bag tests write: headers, planar poses with a heading, twists."""

from formation_ros.core.maths.unicycle import quaternions_from_headings
from formation_ros.ros.bag_writer import TYPESTORE

NS = 1_000_000_000
TYPES = TYPESTORE.types


def header(stamp_ns, frame):
    """Return a std_msgs/Header stamped ``stamp_ns`` (ns) in ``frame``."""
    return TYPES['std_msgs/msg/Header'](
        stamp=TYPES['builtin_interfaces/msg/Time'](sec=stamp_ns // NS, nanosec=stamp_ns % NS),
        frame_id=frame)


def vector3(x, y, z):
    """Return a geometry_msgs/Vector3."""
    return TYPES['geometry_msgs/msg/Vector3'](x=float(x), y=float(y), z=float(z))


def pose_msg(stamp_ns, position, heading):
    """Return a PoseStamped in 'world' at ``position`` (x, y) m, turned by ``heading`` rad."""
    qx, qy, qz, qw = quaternions_from_headings(heading)
    return TYPES['geometry_msgs/msg/PoseStamped'](
        header=header(stamp_ns, 'world'),
        pose=TYPES['geometry_msgs/msg/Pose'](
            position=TYPES['geometry_msgs/msg/Point'](x=float(position[0]),
                                                      y=float(position[1]), z=0.0),
            orientation=TYPES['geometry_msgs/msg/Quaternion'](x=qx, y=qy, z=qz, w=qw)))


def unicycle_twist(v, w):
    """Return a Twist carrying (v, w): linear.x m/s, angular.z rad/s."""
    return TYPES['geometry_msgs/msg/Twist'](linear=vector3(v, 0, 0), angular=vector3(0, 0, w))
