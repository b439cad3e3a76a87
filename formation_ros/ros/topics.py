# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Every topic name of the formation, in one place, and what the recorder records.

Robot topics are relative (``pose``, ``neighbors``, ``cmd_vel``): a robot node started in
namespace ``/robot_<i>`` resolves them to ``/robot_<i>/pose`` and so on, and the plant, which
serves every robot, uses :func:`robot_topic`. The formation-wide topics are absolute, among them
the team transport's (``transport: team``): :data:`STATES` and :data:`TEAM_COMMANDS`.
"""

from dataclasses import dataclass
import enum
from typing import Dict, List

from formation_ros.core.settings.names import robot_name


POSE = 'pose'
NEIGHBOURS = 'neighbors'
OBSTACLES = 'obstacles'
"""Robot i's obstacles, ``/robot_<i>/obstacles``: a PoseArray sent with each pose by the plant and
the relay when the map has obstacles (docs/ros_interface.md, "Obstacles")."""
CMD_VEL = 'cmd_vel'
REFERENCE = '/formation/reference'
CLOCK = '/clock'
DIAGNOSTICS = '/diagnostics'
MARKERS = '/formation/markers'
PARAMS = '/formation/params'
SHAPE = '/formation/shape'
STATUS = '/formation/status'
STOP = '/formation/stop'
START = '/formation/start'
STATES = '/formation/states'
"""Team transport: every robot's pose in one PoseArray per state (``core.rules.transport``)."""
TEAM_COMMANDS = '/formation/commands'
"""Team transport: one MultiDOFJointTrajectory per robot process or fleet per state."""
TEAM_OBSTACLES = '/formation/obstacles'
"""Team transport with obstacles: every robot's obstacles of a state, one MultiDOFJointTrajectory
(``ros.cdr.encode_team_obstacles``), sent before the state."""
MEASURED_POSE = 'measured_pose'
"""The world's ground truth of robot i, ``/robot_<i>/measured_pose`` (the relay's default
source, ``relay.source_topic``): what a motion-capture driver gives a lab."""
ODOM = 'odom'
"""The world's wheel odometry of a differential-drive robot i, ``/robot_<i>/odom``."""
SCAN = 'scan'
"""A world robot's laser scan, ``/robot_<i>/scan`` (a TurtleBot3's ``/scan`` in its namespace)."""
MEASUREMENT_TYPES: Dict[str, str] = {
    'pose': 'geometry_msgs/msg/PoseStamped',
    'odometry': 'nav_msgs/msg/Odometry',
}
"""ROS type of the relay's measured poses by ``relay.source_type`` value (topics: the template
``relay.source_topic``, ``core.settings.params.RelaySettings.source``)."""


class QosKind(enum.Enum):
    """Which profile of ``ros.qos`` a topic uses."""

    STATE = 'state'
    COMMAND = 'command'
    REFERENCE = 'reference'
    CLOCK = 'clock'
    DIAGNOSTICS = 'diagnostics'
    MARKERS = 'markers'
    CHANGES = 'changes'
    MEASUREMENT = 'measurement'


@dataclass(frozen=True)
class Topic:
    """A topic of the formation: absolute name, ROS type name, QoS kind."""

    name: str
    type_name: str
    qos: QosKind


def robot_namespace(robot_id: int) -> str:
    """Return the namespace of robot ``robot_id`` (1-based): ``/robot_<i>``."""
    return f'/{robot_name(robot_id)}'


def robot_node_name(robot_id: int) -> str:
    """Return the fully qualified name of robot ``robot_id``'s node: ``/robot_<i>/robot``."""
    return f'{robot_namespace(robot_id)}/robot'


def robot_topic(robot_id: int, name: str) -> str:
    """Return the absolute name of a robot topic: (3, CMD_VEL) gives ``/robot_3/cmd_vel``."""
    return f'{robot_namespace(robot_id)}/{name}'


def robot_topics(robot_id: int, stamped_commands: bool = True) -> List[Topic]:
    """
    Return the three topics of robot ``robot_id``: pose, neighbours, command.

    The command is a TwistStamped, or a Twist without ``stamped_commands`` (``command.type``).
    """
    command_type = 'geometry_msgs/msg/TwistStamped' if stamped_commands else \
        'geometry_msgs/msg/Twist'
    return [
        Topic(robot_topic(robot_id, POSE), 'geometry_msgs/msg/PoseStamped', QosKind.STATE),
        Topic(robot_topic(robot_id, NEIGHBOURS), 'geometry_msgs/msg/PoseArray', QosKind.STATE),
        Topic(robot_topic(robot_id, CMD_VEL), command_type, QosKind.COMMAND),
    ]


def team_topics() -> List[Topic]:
    """Return the two topics of the team transport: the team's states and its commands."""
    return [Topic(STATES, 'geometry_msgs/msg/PoseArray', QosKind.STATE),
            Topic(TEAM_COMMANDS, 'trajectory_msgs/msg/MultiDOFJointTrajectory', QosKind.COMMAND)]


def obstacle_topics(robot_id: int) -> List[Topic]:
    """
    Return the obstacle topics of robot ``robot_id`` and of the team transport.

    Published by the plant and the relay only when the map has obstacles
    (docs/ros_interface.md, "Obstacles").
    """
    return [Topic(robot_topic(robot_id, OBSTACLES), 'geometry_msgs/msg/PoseArray', QosKind.STATE),
            Topic(TEAM_OBSTACLES, 'trajectory_msgs/msg/MultiDOFJointTrajectory', QosKind.STATE)]


def world_topics(robot_id: int, wheeled: bool) -> List[Topic]:
    """
    Return what the ``world`` node publishes for robot ``robot_id``: measured pose, odometry.

    wheeled: differential-drive bases (``body.kind: unicycle``), which have wheel odometry.
    """
    found = [Topic(robot_topic(robot_id, MEASURED_POSE), MEASUREMENT_TYPES['pose'],
                   QosKind.MEASUREMENT)]
    if wheeled:
        found.append(Topic(robot_topic(robot_id, ODOM), MEASUREMENT_TYPES['odometry'],
                           QosKind.MEASUREMENT))
    return found


def scan_topic(robot_id: int) -> Topic:
    """Return the laser scan the ``world`` node publishes for robot ``robot_id`` (planar)."""
    return Topic(robot_topic(robot_id, SCAN), 'sensor_msgs/msg/LaserScan', QosKind.MEASUREMENT)


def recorded_topics(num_robots: int, markers: bool, stamped_commands: bool = True,
                    obstacles: bool = False) -> List[Topic]:
    """
    Return every topic a recording of the formation holds (``/formation/params`` aside).

    obstacles: the map has obstacles, so each robot's ``obstacles`` is recorded too.
    """
    topics = [topic for i in range(1, num_robots + 1)
              for topic in robot_topics(i, stamped_commands)]
    if obstacles:
        topics += [obstacle_topics(i)[0] for i in range(1, num_robots + 1)]
    topics += [
        Topic(REFERENCE, 'nav_msgs/msg/Odometry', QosKind.REFERENCE),
        Topic(CLOCK, 'rosgraph_msgs/msg/Clock', QosKind.CLOCK),
        Topic(DIAGNOSTICS, 'diagnostic_msgs/msg/DiagnosticArray', QosKind.DIAGNOSTICS),
        Topic(SHAPE, 'geometry_msgs/msg/PoseArray', QosKind.CHANGES),
        Topic(STATUS, 'diagnostic_msgs/msg/DiagnosticArray', QosKind.CHANGES),
    ]
    if markers:
        topics.append(Topic(MARKERS, 'visualization_msgs/msg/MarkerArray', QosKind.MARKERS))
    return topics
