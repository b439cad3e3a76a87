# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Start a whole formation with ``ros2 launch``: the system that scripts/launch_formation.sh starts.

The plant, the reference node on the plant's simulated time, and one ``robot`` node per robot
(namespace ``/robot_<i>``, ``robot_id`` i; with ``robots_per_process`` above 1, ``fleet``
processes of that many robot nodes each), all with one parameters file; ``num_robots`` is read
from that file. The first node to exit ends the launch::

    ros2 launch formation_ros formation.launch.py params_file:=my.yaml
    ros2 launch formation_ros formation.launch.py record:=runs/bag output_dir:=runs/out
    ros2 launch formation_ros formation.launch.py robots_per_process:=10   # fleet processes
    ros2 launch formation_ros formation.launch.py discovery:=subnet domain_id:=7

As with scripts/launch_formation.sh, the nodes stay on this computer
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) unless the environment sets a range or
``discovery`` is ``subnet``; ``domain_id`` sets ROS_DOMAIN_ID (0 to 232).

It runs until Ctrl-C; ``formation_report`` reads the bag or the output directory afterwards.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, Shutdown
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
import yaml

PACKAGE = 'formation_ros'


def network_environment(discovery, domain_id):
    """Return the variables that set the nodes' discovery range and domain."""
    env = {}
    if discovery:
        if discovery not in ('localhost', 'subnet'):
            raise ValueError(f"discovery must be 'localhost' or 'subnet', got '{discovery}'")
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = discovery.upper()
    elif not os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE'):
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    if domain_id:
        if not (domain_id.isdigit() and int(domain_id) <= 232):
            raise ValueError(f"domain_id must be a whole number from 0 to 232, got '{domain_id}'")
        env['ROS_DOMAIN_ID'] = str(int(domain_id))
    return env


def formation_nodes(context):
    """Return the nodes for the launch arguments' parameters file, bag path and output dir."""
    params_file = LaunchConfiguration('params_file').perform(context)
    record = LaunchConfiguration('record').perform(context)
    output_dir = LaunchConfiguration('output_dir').perform(context)
    per_process = int(LaunchConfiguration('robots_per_process').perform(context))
    if per_process < 1:
        raise ValueError(f'robots_per_process must be >= 1, got {per_process}')
    with open(params_file) as stream:
        num_robots = yaml.safe_load(stream)['/**']['ros__parameters']['num_robots']
    subscribers = 2 if record else 1
    env = network_environment(LaunchConfiguration('discovery').perform(context),
                              LaunchConfiguration('domain_id').perform(context))

    def node(executable, *overrides, namespace=None, arguments=None):
        return Node(package=PACKAGE, executable=executable, namespace=namespace,
                    arguments=arguments, additional_env=env,
                    parameters=[params_file, *filter(None, overrides)], output='screen',
                    on_exit=Shutdown(reason=f'{executable} exited'))

    nodes = []
    if record:
        nodes.append(node('record', {'record.path': record}))
    nodes.append(node('plant',
                      {'plant.wait_for_subscribers': 2} if record else {},
                      {'plant.output_dir': output_dir} if output_dir else {}))
    nodes.append(node('reference', {'use_sim_time': True}))
    robot_params = {'wait_for_subscribers': subscribers, 'use_sim_time': True}
    if per_process == 1:
        nodes += [node('robot', {'robot_id': i, **robot_params}, namespace=f'robot_{i}')
                  for i in range(1, num_robots + 1)]
        return nodes
    for first in range(1, num_robots + 1, per_process):
        last = min(first + per_process - 1, num_robots)
        nodes.append(node('fleet', robot_params, arguments=['--robots', f'{first}-{last}']))
    return nodes


def generate_launch_description():
    """Declare the launch arguments; the nodes follow once the parameters file is known."""
    default_params = os.path.join(get_package_share_directory(PACKAGE), 'config',
                                  'paper_section5.yaml')
    return LaunchDescription([
        DeclareLaunchArgument('params_file', default_value=default_params,
                              description='ROS 2 parameters file of the formation'),
        DeclareLaunchArgument('record', default_value='',
                              description='rosbag2 directory to record into (empty: none)'),
        DeclareLaunchArgument('output_dir', default_value='',
                              description='where the plant writes trajectory.npz and '
                                          'plant_stats.json (empty: nowhere)'),
        DeclareLaunchArgument('robots_per_process', default_value='1',
                              description="robots per process (above 1: 'fleet' processes)"),
        DeclareLaunchArgument('discovery', default_value='',
                              description="'localhost' or 'subnet' (empty: the environment's "
                                          'ROS_AUTOMATIC_DISCOVERY_RANGE, else localhost)'),
        DeclareLaunchArgument('domain_id', default_value='',
                              description="ROS_DOMAIN_ID of the nodes (empty: the environment's)"),
        OpaqueFunction(function=formation_nodes),
    ])
