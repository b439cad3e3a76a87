# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Start a formation in a lab with ``ros2 launch``: what ``launch_formation.sh --no-plant`` starts.

No plant and no ``/clock``: the ``relay`` turns every robot's measured pose (motion capture or
localisation: ``relay.source_topic``, ``relay.source_names``, ``relay.source_type`` of the
parameters file, or ``source_topic``) into ``/robot_<i>/pose`` and ``/robot_<i>/neighbors``;
the reference node and one ``robot`` node per robot run on wall-clock time (``use_sim_time``
false). ``cmd_topic`` remaps each robot's ``cmd_vel`` onto its base's topic, ``{i}`` the
robot id and ``{name}`` its entry of ``relay.source_names``; a robot sends its first command
once that topic has a subscriber (the base driver; 2 with ``record``). The first node to exit
ends the launch::

    ros2 launch formation_ros lab.launch.py params_file:=lab.yaml cmd_topic:=/tb{i}/cmd_vel
    ros2 launch formation_ros lab.launch.py params_file:=lab.yaml \\
        source_topic:=/vrpn_mocap/{name}/pose cmd_topic:=/{name}/cmd_vel record:=runs/lab_bag
    ros2 launch formation_ros lab.launch.py params_file:=lab.yaml discovery:=subnet domain_id:=7

``params_file`` is required (a lab's own file: its ``world_frame``, ``command.type`` and the
relay's sources); ``robots_per_process`` above 1 runs ``fleet`` processes, but not with
``cmd_topic`` (a fleet's remappings apply to all of its robots). ``discovery`` and
``domain_id`` as for ``formation.launch.py``: in a lab whose bases are other computers, give
``discovery:=subnet``. The nodes are those of the launcher (``formation_ros.tools.system``).
It runs until Ctrl-C; ``formation_report`` reads the bag afterwards.
"""

from formation_ros.tools.system import launch_file_nodes, SHARED_LAUNCH_ARGUMENTS
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration

ARGUMENTS = ('params_file', 'cmd_topic', 'source_topic', 'robots_per_process') + tuple(
    name for name, _, _ in SHARED_LAUNCH_ARGUMENTS)


def lab_nodes(context):
    """Return relay, reference and robots for the launch arguments."""
    return launch_file_nodes({name: LaunchConfiguration(name).perform(context)
                              for name in ARGUMENTS}, plant=False)


def generate_launch_description():
    """Declare the launch arguments; the nodes follow once the parameters file is known."""
    return LaunchDescription([
        DeclareLaunchArgument('params_file',
                              description='ROS 2 parameters file of the formation and the relay'),
        DeclareLaunchArgument('cmd_topic', default_value='',
                              description="each robot's command topic: {i} the robot id, "
                                          '{name} its entry of relay.source_names, e.g. '
                                          '/tb{i}/cmd_vel (empty: /robot_<i>/cmd_vel)'),
        DeclareLaunchArgument('source_topic', default_value='',
                              description="relay.source_topic instead of the file's, e.g. "
                                          "/vrpn_mocap/{name}/pose (empty: the file's)"),
        DeclareLaunchArgument('robots_per_process', default_value='1',
                              description="robots per process (above 1: 'fleet' processes; "
                                          'not with cmd_topic)'),
        *[DeclareLaunchArgument(name, default_value=default, description=text)
          for name, default, text in SHARED_LAUNCH_ARGUMENTS],
        OpaqueFunction(function=lab_nodes),
    ])
