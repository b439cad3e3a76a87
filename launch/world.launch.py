# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Start a formation on the physics world with ``ros2 launch``: what ``--world`` starts.

A simulated lab: the ``world`` node (MuJoCo, docs/physics.md) publishes ``/clock`` and every
robot's ``/robot_<i>/measured_pose`` and drives the bodies from ``/robot_<i>/cmd_vel``; the
``relay`` reads those poses (``relay.source_topic`` of the file must be the world's, as by
default, or ``source_topic``) and, with the reference node and one ``robot`` node per robot
(``fleet`` processes with ``robots_per_process`` above 1), runs on the world's ``/clock``
(``use_sim_time`` true; the robots are given ``relay.rate`` as the rate of their states). The
first node to exit ends the launch::

    ros2 launch formation_ros world.launch.py
    ros2 launch formation_ros world.launch.py params_file:=world.yaml output_dir:=runs/w \\
        record:=runs/w_bag

``params_file`` defaults to the installed ``config/world_turtlebot3.yaml``; ``output_dir``
sets ``world.output_dir`` (``world.xml``, ``trajectory.npz``, ``world_stats.json``).
``discovery`` and ``domain_id`` as for ``formation.launch.py``. The nodes are those of the
launcher (``formation_ros.tools.system``). It runs until Ctrl-C; ``formation_report`` reads
the output directory or the bag afterwards.
"""

import os

from ament_index_python.packages import get_package_share_directory
from formation_ros.tools.system import launch_file_nodes, SHARED_LAUNCH_ARGUMENTS
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration

PACKAGE = 'formation_ros'
ARGUMENTS = ('params_file', 'output_dir', 'source_topic', 'robots_per_process') + tuple(
    name for name, _, _ in SHARED_LAUNCH_ARGUMENTS)


def world_nodes(context):
    """Return world, relay, reference and robots for the launch arguments."""
    return launch_file_nodes({name: LaunchConfiguration(name).perform(context)
                              for name in ARGUMENTS}, plant=False, world=True)


def generate_launch_description():
    """Declare the launch arguments; the nodes follow once the parameters file is known."""
    default_params = os.path.join(get_package_share_directory(PACKAGE), 'config',
                                  'world_turtlebot3.yaml')
    return LaunchDescription([
        DeclareLaunchArgument('params_file', default_value=default_params,
                              description='ROS 2 parameters file of the formation and the '
                                          'world'),
        DeclareLaunchArgument('output_dir', default_value='',
                              description='where the world writes world.xml, trajectory.npz '
                                          'and world_stats.json (empty: nowhere)'),
        DeclareLaunchArgument('source_topic', default_value='',
                              description="relay.source_topic instead of the file's (the "
                                          "world's: /robot_{i}/measured_pose)"),
        DeclareLaunchArgument('robots_per_process', default_value='1',
                              description="robots per process (above 1: 'fleet' processes)"),
        *[DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in SHARED_LAUNCH_ARGUMENTS],
        OpaqueFunction(function=world_nodes),
    ])
