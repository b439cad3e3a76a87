# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Start a whole formation with ``ros2 launch``: the system that scripts/launch_formation.sh starts.

The plant, and on its simulated time the reference node and one ``robot`` node per robot
(namespace ``/robot_<i>``, ``robot_id`` i; with ``robots_per_process`` above 1, ``fleet``
processes of that many robot nodes each), all with one parameters file; ``num_robots`` is read
from that file, which is checked as the launcher checks it. The first node to exit ends the
launch::

    ros2 launch formation_ros formation.launch.py params_file:=my.yaml
    ros2 launch formation_ros formation.launch.py record:=runs/bag output_dir:=runs/out
    ros2 launch formation_ros formation.launch.py robots_per_process:=10   # fleet processes
    ros2 launch formation_ros formation.launch.py discovery:=subnet domain_id:=7

As with scripts/launch_formation.sh, the nodes stay on this computer
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) unless the environment sets a range or
``discovery`` is ``subnet``; ``domain_id`` sets ROS_DOMAIN_ID (0 to 232). The nodes and their
environment are those of the launcher (``formation_ros.tools.system``); ``lab.launch.py``
starts a lab.

It runs until Ctrl-C; ``formation_report`` reads the bag or the output directory afterwards.
"""

import os

from ament_index_python.packages import get_package_share_directory
from formation_ros.tools.system import launch_file_nodes, SHARED_LAUNCH_ARGUMENTS
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration

PACKAGE = 'formation_ros'
ARGUMENTS = ('params_file', 'output_dir', 'robots_per_process') + tuple(
    name for name, _, _ in SHARED_LAUNCH_ARGUMENTS)


def formation_nodes(context):
    """Return the nodes for the launch arguments' parameters file, bag path and output dir."""
    return launch_file_nodes({name: LaunchConfiguration(name).perform(context)
                              for name in ARGUMENTS}, plant=True)


def generate_launch_description():
    """Declare the launch arguments; the nodes follow once the parameters file is known."""
    default_params = os.path.join(get_package_share_directory(PACKAGE), 'config',
                                  'paper_section5.yaml')
    return LaunchDescription([
        DeclareLaunchArgument('params_file', default_value=default_params,
                              description='ROS 2 parameters file of the formation'),
        DeclareLaunchArgument('output_dir', default_value='',
                              description='where the plant writes trajectory.npz and '
                                          'plant_stats.json (empty: nowhere)'),
        DeclareLaunchArgument('robots_per_process', default_value='1',
                              description="robots per process (above 1: 'fleet' processes)"),
        *[DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in SHARED_LAUNCH_ARGUMENTS],
        OpaqueFunction(function=formation_nodes),
    ])
