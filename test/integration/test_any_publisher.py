# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Any publisher of commands drives a body: the QoS a ROS user's tools have, not only ours.

``ros2 topic pub``, teleop_twist_keyboard, nav2 and a user's own node publish ``cmd_vel`` with
rclpy's or rclcpp's default QoS (reliable, automatic liveliness, no lease); a joystick driver
or a sensor-data style node publishes best effort. The world and the plant, which stand in for
a lab's base drivers, take both (``qos.COMMAND_INPUT``); a commander that goes silent is
noticed by its commands' age, not by refusing to match it.
"""

import os

from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import qos
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from helpers import CONFIG, node, plant_value, SimClock, Statuses
import numpy as np
import pytest
from rclpy.qos import qos_profile_sensor_data, QoSProfile
import wire

START_UP = 90.0
DEFAULT = QoSProfile(depth=10)
"""What ``ros2 topic pub`` and a node's ``create_publisher(Twist, 'cmd_vel', 10)`` offer."""
SPEED = 0.2
MOVED = 0.1
"""How far (m) each driven body must go along x: it stands still without its commands."""


def params_of(folder, source, changes):
    """Write two robots of ``source`` at rest 0.6 m apart, heading +x; return the path."""
    values = load_params_file(os.path.join(CONFIG, source))
    values = {name: value for name, value in values.items()
              if not name.startswith(('relay.', 'start.'))}
    values.update({'num_robots': 2, 'formation.vertices': [0.6, 0.0, -0.6, 0.0],
                   'start.positions': [0.0, 0.0, 0.6, 0.0]})
    values.update(changes)
    path = os.path.join(str(folder), 'params.yaml')
    write_params_file(path, values)
    return path


class Positions:
    """The latest x of each robot on ``/robot_<i>/<topic>`` (PoseStamped), None before any."""

    def __init__(self, probe, topic, profile):
        self.x = {1: None, 2: None}
        for i in self.x:
            probe.create_subscription(
                PoseStamped, f'/robot_{i}/{topic}',
                lambda msg, i=i: self.x.__setitem__(i, msg.pose.position.x), profile)


def drive(probe, clock, positions, stamped, frames):
    """Publish SPEED forward to both robots, robot 1 default QoS, robot 2 best effort."""
    kind = TwistStamped if stamped else Twist
    pubs = {1: probe.create_publisher(kind, '/robot_1/cmd_vel', DEFAULT),
            2: probe.create_publisher(kind, '/robot_2/cmd_vel', qos_profile_sensor_data)}
    assert probe.spin_until(lambda: all(pub.get_subscription_count() for pub in pubs.values())
                            and None not in positions.x.values() and clock.seconds > 0.1,
                            START_UP)
    start = dict(positions.x)

    def send():
        for i, pub in pubs.items():
            if stamped:
                message = wire.twist_stamped(np.array([SPEED, 0.0]),
                                             int(round(clock.seconds * 1e9)), 2)
                message.header.frame_id = frames[i]
            else:
                message = Twist()
                message.linear.x = SPEED
            pub.publish(message)
        return all(positions.x[i] - start[i] > MOVED for i in pubs)

    assert probe.spin_until(send, 60), (start, positions.x)
    return pubs


@pytest.mark.parametrize('command_type', ['twist', 'twist_stamped'])
def test_a_default_and_a_best_effort_publisher_drive_world_robots(
        processes, install, probe, tmp_path, command_type):
    params = params_of(tmp_path, 'lab_turtlebot3.yaml', {
        'command.type': command_type, 'start.headings': [0.0, 0.0],
        'world.cmd_timeout': 0.3})
    processes.start(node(install, 'world', params))
    clock, statuses = SimClock(probe), Statuses(probe)
    positions = Positions(probe, 'measured_pose', qos.MEASUREMENT)
    drive(probe, clock, positions, command_type == 'twist_stamped',
          {i: f'robot_{i}/base_link' for i in (1, 2)})
    assert probe.spin_until(lambda: 'formation_ros/world' in statuses, 30)
    values = {kv.key: kv.value for kv in statuses['formation_ros/world'].values}
    assert values['refused cmd_vel messages'] == '0', values
    assert 'incompatible QoS' not in processes.log('world')


def test_a_default_and_a_best_effort_publisher_drive_plant_robots_and_silence_shows(
        processes, install, probe, tmp_path):
    params = params_of(tmp_path, 'square_4.yaml', {
        'command.type': 'twist', 'plant.wait_for_robots': False,
        'controller.gain': 0.5, 'input_timeout': 0.5})
    processes.start(node(install, 'plant', params))
    clock, statuses = SimClock(probe), Statuses(probe)
    positions = Positions(probe, 'pose', qos.STATE_INPUT)
    drive(probe, clock, positions, False, {})
    assert probe.spin_until(
        lambda: statuses.get('formation_ros/plant') is not None
        and {kv.key: kv.value for kv in statuses['formation_ros/plant'].values}.get(
            'robots with lost cmd_vel') == '1, 2', 30), statuses.get('formation_ros/plant')
    assert plant_value(statuses, 'steps') > 0
    log = processes.log('plant')
    assert 'incompatible QoS' not in log, log
