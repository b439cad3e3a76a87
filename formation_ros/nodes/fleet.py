# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Fleet process (executable ``fleet``): several robot nodes in one process.

Each robot is the same :class:`formation_ros.nodes.robot.RobotNode` as the ``robot``
executable starts, in its own namespace ``/robot_<i>`` with its own parameters; only the
process (its memory, its executor thread, its DDS participant) is shared. The first robot
hears the reference and the changes for the others that share its values, publishes every
robot's status on ``/diagnostics``, and with ``transport: team`` carries the process's
:class:`formation_ros.nodes.robots_link.RobotsLink`. What a fleet shares and how to start one:
docs/ros_interface.md ("Many robots: fleet processes")::

    ros2 run formation_ros fleet --robots 1-5 --ros-args \\
        --params-file config/paper_section5.yaml -p use_sim_time:=true
"""

import re
import sys
from typing import List, Optional, Sequence

from formation_ros.core.settings.declarations import ParamError
from formation_ros.nodes.robot import RobotNode
from formation_ros.nodes.robots_link import RobotsLink
from formation_ros.ros.runner import run
from formation_ros.ros.topics import robot_namespace
from rclpy.parameter import Parameter
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM
from rclpy.utilities import remove_ros_args

PROG = 'fleet'
USAGE = f"""\
usage: {PROG} --robots IDS [--ros-args ...]

Runs robot nodes i in IDS (e.g. 1-5 or 1,3,7-9), robot i in namespace /robot_<i>, in this one
process; the ROS arguments (parameters files, -p) apply to every robot.
"""
MAX_ROBOTS = 100_000
RESERVED_REMAPS = ('__ns:=', '__node:=', '__name:=')


class UsageError(ValueError):
    """A bad fleet command line: the fleet exits 2 with this message."""


def parse_ids(text: str) -> List[int]:
    """Return the robot ids of ``text``: comma-separated ids and ranges ``a-b`` (ids >= 1)."""
    ids: List[int] = []
    for part in text.split(','):
        match = re.fullmatch(r'\s*([0-9]+)\s*(?:-\s*([0-9]+)\s*)?', part)
        if match is None:
            raise UsageError(f"--robots: '{part}' is neither an id nor a range a-b")
        first = int(match.group(1))
        last = int(match.group(2)) if match.group(2) else first
        if first < 1 or last < first:
            raise UsageError(f"--robots: '{part.strip()}' is empty or has an id below 1")
        if last - first >= MAX_ROBOTS or len(ids) + last - first >= MAX_ROBOTS:
            raise UsageError(f'--robots: more than {MAX_ROBOTS} robots')
        ids.extend(range(first, last + 1))
    seen = set()
    for i in ids:
        if i in seen:
            raise UsageError(f'--robots: robot {i} is given twice')
        seen.add(i)
    return ids


def parse_command_line(argv: Sequence[str]) -> Optional[List[int]]:
    """Return the robot ids of a fleet command line (None for --help); UsageError if bad."""
    own = remove_ros_args(list(argv))[1:]
    ros = argv[list(argv).index('--ros-args') + 1:] if '--ros-args' in argv else []
    reserved = [arg for arg in ros if arg.startswith(RESERVED_REMAPS)]
    if reserved:
        raise UsageError(f"'{reserved[0]}' cannot be used: the fleet puts robot i in "
                         '/robot_<i> and names it robot itself')
    if any(arg in ('-h', '--help') for arg in own):
        return None
    if len(own) != 2 or own[0] != '--robots':
        raise UsageError('give the robots as --robots IDS (e.g. --robots 1-5)'
                         + (f", not {' '.join(own)}" if own else ''))
    return parse_ids(own[1])


def make_fleet(ids: Sequence[int]) -> List[RobotNode]:
    """
    Build one robot node per id, robot i in ``/robot_<i>``.

    Each node checks its parameters as a robot process does (a ``robot_id`` given to the fleet
    disagrees with every namespace but one and is refused there). The first robot publishes
    every robot's status on /diagnostics, one DiagnosticArray a period for the whole fleet.
    With ``transport: team`` the fleet's robots hear the team's states and send their commands
    through one :class:`formation_ros.nodes.robots_link.RobotsLink`: one message in and one out
    per state.
    """
    if not ids:
        return []
    first = RobotNode(namespace=robot_namespace(ids[0]))
    team = first.config.team_transport
    settings = first.config.robot
    assert settings is not None
    services = settings.parameter_services
    lean = [] if services else [Parameter(START_TYPE_DESCRIPTION_SERVICE_PARAM, value=False)]
    nodes = [first] + [RobotNode(namespace=robot_namespace(i), leader=first,
                                 reports=False, start_parameter_services=services,
                                 parameter_overrides=lean, enable_rosout=services)
                       for i in ids[1:]]
    differing = [node for node in nodes[1:] if node.config.robot is not None
                 and node.config.robot.parameter_services != services]
    if differing:
        for node in nodes:
            node.destroy_node()
        raise ParamError([('fleet.parameter_services', 'must be the same for every robot of a '
                                                       "fleet (the first robot's value "
                                                       'decides how the others are made)')])
    if not services:
        first.get_logger().info(f'fleet of {len(nodes)} robots: parameter and type '
                                'description services and /rosout on '
                                f'{first.get_fully_qualified_name()} alone '
                                '(fleet.parameter_services false)')
    first.reported = nodes
    if team:
        RobotsLink(nodes)
    return nodes


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros fleet``."""
    argv = sys.argv if args is None else args
    try:
        ids = parse_command_line(argv)
    except UsageError as exc:
        print(f'{PROG}: {exc}', file=sys.stderr)
        return 2
    if ids is None:
        print(USAGE, end='')
        return 0
    return run(lambda: make_fleet(ids), args, name=PROG)
