# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Build ROS messages from the numpy arrays of the core (reading them is ``fields``).

The nodes write their hot topics as bytes (``cdr``); the typed messages they publish besides
(a shape's PoseArray, diagnostics, the team's status) are built here.
"""

from array import array
import math

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.runs.timeline import Mode, TeamState
from formation_ros.core.settings.names import robot_name
from geometry_msgs.msg import Pose, PoseArray
from sensor_msgs.msg import LaserScan

WORLD_FRAME = 'world'
FORMATION_FRAME = 'formation'
BODY_FRAME = 'base_link'


def body_frame(robot_id):
    """Return robot ``robot_id``'s body frame, ``robot_<i>/base_link`` (unicycle commands)."""
    return f'{robot_name(int(robot_id))}/{BODY_FRAME}'


def ns_to_stamp(ns):
    """Convert integer nanoseconds to a builtin_interfaces/Time."""
    return Time(sec=int(ns // NS_PER_S), nanosec=int(ns % NS_PER_S))


def xyz(vector, dim):
    """Return the first ``dim`` values of ``vector`` as x, y, z floats (0.0 beyond dim)."""
    values = [0.0, 0.0, 0.0]
    values[:dim] = [float(v) for v in vector[:dim]]
    return values


def stamped(msg, stamp_ns, frame_id=WORLD_FRAME):
    """Return ``msg`` with its header at ``stamp_ns`` in ``frame_id`` (set in place)."""
    msg.header.stamp = ns_to_stamp(stamp_ns)
    msg.header.frame_id = frame_id
    return msg


def pose_array(points, stamp_ns, dim, frame_id=WORLD_FRAME):
    """Build a PoseArray of the rows of ``points`` ((K, dim), m), frame ``frame_id``."""
    msg = stamped(PoseArray(), stamp_ns, frame_id)
    for point in points:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = xyz(point, dim)
        pose.orientation.w = 1.0
        msg.poses.append(pose)
    return msg


def laser_scan(stamp_ns, frame_id, shape, ranges, scan_time):
    """
    Build a LaserScan of ``ranges`` ((R,), m; +inf: no return) stamped ``stamp_ns``.

    shape: the scan's ``core.maths.scan.ScanShape`` (its mount is the frame's origin); ray k
    at ``angle_min + k * angle_increment`` counter-clockwise, angle_max the last ray's;
    scan_time: s between two scans. All rays are taken at the stamp (time_increment 0); no
    intensities.
    """
    msg = stamped(LaserScan(), stamp_ns, frame_id)
    msg.angle_min = float(shape.angle_min)
    msg.angle_increment = float(shape.angle_increment)
    msg.angle_max = float(shape.angle_min + (len(ranges) - 1) * shape.angle_increment)
    msg.time_increment = 0.0
    msg.scan_time = float(scan_time)
    msg.range_min = float(shape.range_min)
    msg.range_max = float(shape.range_max)
    msg.ranges = array('f', [float(value) for value in ranges])
    return msg


TEAM_STATUS = 'formation_ros/team'
MODE_LEVELS = {'running': DiagnosticStatus.OK, 'stopped': DiagnosticStatus.WARN}


def team_status(mode, since_ns, values):
    """
    Build the ``/formation/status`` message: the team's mode and reference from ``since_ns``.

    mode: 'running' or 'stopped'; values: {key: text} (the shape's name, the reference's
    origin, speed and phase in force). The header's stamp is the time from which it holds.
    """
    status = DiagnosticStatus(level=MODE_LEVELS[mode], name=TEAM_STATUS, message=mode,
                              hardware_id='formation_ros')
    status.values = [KeyValue(key=key, value=str(value)) for key, value in values.items()]
    array = DiagnosticArray(status=[status])
    array.header.stamp = ns_to_stamp(since_ns)
    return array


def team_state_of(msg, dim):
    """
    Read a ``/formation/status`` message (:func:`team_status`) into a ``runs.timeline.TeamState``.

    Raises ValueError when it is not one: no team status, an unknown mode, missing or
    non-finite values, an origin that is not dim values.
    """
    statuses = [status for status in msg.status if status.name == TEAM_STATUS]
    if not statuses:
        raise ValueError(f'no {TEAM_STATUS} status')
    status = statuses[0]
    values = {kv.key: kv.value for kv in status.values}
    try:
        mode = Mode(status.message)
        origin = tuple(float(v) for v in values['origin'].split(','))
        speed, phase = float(values['speed']), float(values['phase'])
    except (KeyError, ValueError) as exc:
        raise ValueError(f'not a team status: {exc}') from None
    if len(origin) != dim or not all(map(math.isfinite, origin + (speed, phase))):
        raise ValueError(f'origin {origin}, speed {speed}, phase {phase} do not fit')
    shape = values.get('shape', '')
    return TeamState(mode, '' if shape == 'formation.vertices' else shape, origin, speed, phase)
