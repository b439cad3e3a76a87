# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The plant's team-command history holds a whole state's answers, over real DDS.

Every fleet answers a state at once on the one ``/formation/commands`` topic, whose history a
reader keeps per topic (it has no keys), not per publisher: while the plant steps, the
answers wait there. Here 30 publishers (30 fleets) each send one command while the reader's
node is not spinning; once every sample is acknowledged (a reliable reader) or sent (the
plant's best-effort one), the reader takes what it kept until nothing more comes.
"""

from typing import List

from formation_ros.ros import qos
from geometry_msgs.msg import Vector3
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile

FLEETS = 30
ACKED = 20.0
"""Seconds a publisher may take to have its sample acknowledged (discovery on a busy core)."""
EMPTY = 0.2
"""Seconds a wait finds nothing before the history counts as empty (every sample is in it)."""


def kept_after_burst(profile: QoSProfile) -> List[float]:
    """Send one sample from each of FLEETS publishers, all acked, then take what was kept."""
    context = rclpy.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    try:
        plant = rclpy.create_node('plant_stand_in', context=context)
        heard: List[float] = []
        plant.create_subscription(Vector3, '/formation/burst', lambda m: heard.append(m.x),
                                  profile)
        fleets = rclpy.create_node('fleets_stand_in', context=context)
        pubs = [fleets.create_publisher(Vector3, '/formation/burst', qos.COMMAND)
                for _ in range(FLEETS)]
        executor.add_node(plant)
        while any(pub.get_subscription_count() < 1 for pub in pubs):
            executor.spin_once(timeout_sec=0.05)
        assert not heard
        for k, pub in enumerate(pubs):
            pub.publish(Vector3(x=float(k)))
        for pub in pubs:
            assert pub.wait_for_all_acked(rclpy.duration.Duration(seconds=ACKED))
        idle = 0
        while idle < 2:  # the executor alternates: a wait, then the callback it found
            before = len(heard)
            executor.spin_once(timeout_sec=EMPTY)
            idle = idle + 1 if len(heard) == before else 0
        return heard
    finally:
        executor.shutdown()
        rclpy.shutdown(context=context)


@pytest.mark.parametrize('depth_for', ['team', 'command'])
def test_a_burst_of_fleet_answers_is_kept_whole_only_with_the_team_history(depth_for):
    profile = (qos.team_commands_input(FLEETS) if depth_for == 'team' else qos.COMMAND)
    heard = kept_after_burst(profile)
    if depth_for == 'team':
        assert sorted(heard) == [float(k) for k in range(FLEETS)]
    else:
        # the answers overwrite each other: only the newest COMMAND.depth are left
        assert len(heard) == qos.COMMAND.depth < FLEETS


def test_the_team_history_is_never_shallower_than_a_command_history():
    assert qos.team_commands_input(1).depth == qos.COMMAND.depth
    deep = qos.team_commands_input(1000)
    assert deep.depth == 1000
    assert (deep.reliability, deep.durability, deep.liveliness_lease_duration) == (
        qos.COMMAND_INPUT.reliability, qos.COMMAND_INPUT.durability,
        qos.COMMAND_INPUT.liveliness_lease_duration)
