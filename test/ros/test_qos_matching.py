# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Which profiles offer and ask for what, and who matches whom over real DDS.

The command inputs (plant, world) must match every publisher a ROS user has; the robots offer
a liveliness lease for a monitor that asks for one; the recorder matches everything.
"""

from formation_ros.ros import qos
from formation_ros.ros.topics import QosKind
from geometry_msgs.msg import Twist
import pytest
import rclpy
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import (LivelinessPolicy, qos_profile_sensor_data, QoSProfile,
                       ReliabilityPolicy)

MATCH_WITHIN = 20.0
"""Seconds discovery may take on a busy core (a match is waited for, not timed)."""
LEASED = QoSProfile(depth=10, liveliness=LivelinessPolicy.AUTOMATIC,
                    liveliness_lease_duration=Duration(seconds=2.0))
PUBLISHERS = {'default (ros2 topic pub, teleop)': QoSProfile(depth=10),
              'best effort (sensor data)': qos_profile_sensor_data,
              'with a lease': LEASED,
              'a robot of this package': qos.COMMAND}


def test_commands_and_states_offer_the_lease_and_the_inputs_ask_for_none():
    lease_ns = int(qos.LIVELINESS_LEASE * 1e9)
    for profile in (qos.COMMAND, qos.STATE):
        assert profile.liveliness == LivelinessPolicy.MANUAL_BY_TOPIC
        assert profile.liveliness_lease_duration.nanoseconds == lease_ns
        recorded = qos.recording(profile)
        assert recorded.liveliness_lease_duration.nanoseconds == 0
        assert (recorded.reliability, recorded.durability) == (profile.reliability,
                                                               profile.durability)
    for kind in (QosKind.REFERENCE, QosKind.CLOCK, QosKind.DIAGNOSTICS, QosKind.MARKERS):
        assert qos.BY_KIND[kind].liveliness_lease_duration.nanoseconds == 0
    for asked in (qos.COMMAND_INPUT, qos.team_commands_input(100), qos.STATE_INPUT):
        assert asked.liveliness_lease_duration.nanoseconds == 0
        assert asked.reliability == ReliabilityPolicy.BEST_EFFORT
    assert qos.team_commands_input(100).depth == 100
    assert qos.TEAM_CMD_VEL.liveliness_lease_duration.nanoseconds == 0
    assert (qos.TEAM_CMD_VEL.reliability, qos.TEAM_CMD_VEL.durability, qos.TEAM_CMD_VEL.depth) \
        == (qos.COMMAND.reliability, qos.COMMAND.durability, qos.COMMAND.depth)


@pytest.mark.parametrize('offered', list(PUBLISHERS), ids=list(PUBLISHERS))
def test_every_kind_of_command_publisher_reaches_the_command_input(offered):
    context = rclpy.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    try:
        base = rclpy.create_node('base_stand_in', context=context)
        heard = []
        base.create_subscription(Twist, '/robot_1/cmd_vel', heard.append, qos.COMMAND_INPUT)
        user = rclpy.create_node('teleop_stand_in', context=context)
        pub = user.create_publisher(Twist, '/robot_1/cmd_vel', PUBLISHERS[offered])
        executor.add_node(base)
        clock = base.get_clock()
        start = clock.now()
        while not heard and (clock.now() - start).nanoseconds < MATCH_WITHIN * 1e9:
            pub.publish(Twist())
            executor.spin_once(timeout_sec=0.05)
        assert heard, f'{offered}: nothing heard'
    finally:
        executor.shutdown()
        rclpy.shutdown(context=context)
