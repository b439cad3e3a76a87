# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A fleet's link to its robots reads a state once: a byte-for-byte copy is heard anew, not read.

The plant sends the state again while it waits for answers (20 a second while a thousand
robots start), and each read of a thousand poses and each sensing costs a fleet milliseconds.
Two robot nodes of the square team in one fleet, linked as the ``fleet`` executable links
them, are given states as the ``/formation/states`` callback would give them.
"""

import os

from formation_ros.nodes import robots_link
from formation_ros.nodes.robot import RobotNode
from formation_ros.nodes.robots_link import RobotsLink
from geometry_msgs.msg import Point, Pose, PoseArray
import pytest
import rclpy
from rclpy.serialization import serialize_message

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')


def state(stamp_s, shift=0.0):
    """Return the bytes of a square_4 state at ``stamp_s``, every body moved ``shift`` in x."""
    message = PoseArray()
    message.header.frame_id = 'world'
    message.header.stamp.sec = int(stamp_s)
    message.header.stamp.nanosec = int(round((stamp_s % 1.0) * 1e9))
    corners = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)]
    message.poses = [Pose(position=Point(x=x + shift, y=y)) for x, y in corners]
    return serialize_message(message)


@pytest.fixture
def link(monkeypatch):
    """Yield the link of robots 1 and 2 and the list of states it read, then clean up."""
    reads = []
    real = robots_link.read_pose_array

    def counted(data, most):
        reads.append(data)
        return real(data, most)

    monkeypatch.setattr(robots_link, 'read_pose_array', counted)
    context = rclpy.Context()
    rclpy.init(context=context, args=['--ros-args', '--params-file', SQUARE,
                                      '-p', 'transport:=team', '-p', 'use_sim_time:=true'])
    nodes = []
    try:
        nodes.append(RobotNode(namespace='/robot_1', context=context))
        nodes.append(RobotNode(namespace='/robot_2', leader=nodes[0], reports=False,
                               context=context))
        yield RobotsLink(nodes), reads
    finally:
        for node in nodes:
            node.destroy_node()
        rclpy.shutdown(context=context)


def test_a_copy_of_the_state_taken_is_heard_but_not_read_again(link):
    team, reads = link
    leader = team.leader
    team.on_states(state(1.0))
    team.take_state()
    assert len(reads) == 1 and leader.policy.states == 1
    first = team.state
    heard_ns = leader.policy.received_ns['pose']
    team.on_states(state(1.0))
    team.take_state()
    assert len(reads) == 1, 'a copy was read again'
    assert leader.policy.states == 2 and team.state is first
    assert leader.policy.received_ns['pose'] >= heard_ns
    assert leader.policy.received_ns['neighbour'] == leader.policy.received_ns['pose']


def test_a_state_that_differs_in_any_byte_is_read(link):
    team, reads = link
    team.on_states(state(1.0))
    team.take_state()
    team.on_states(state(1.0, shift=1e-9))
    team.take_state()
    assert len(reads) == 2
    assert team.state.positions[0][0] == pytest.approx(-2.0 + 1e-9, abs=1e-15)
    team.on_states(state(1.1, shift=1e-9))
    team.take_state()
    assert len(reads) == 3 and team.state.stamp_ns == 1_100_000_000


def test_a_refused_state_is_not_taken_for_its_copy(link):
    team, reads = link
    team.on_states(state(1.0, shift=float('nan')))
    team.take_state()
    team.on_states(state(1.0, shift=float('nan')))
    team.take_state()
    assert len(reads) == 2 and team.state is None and team.leader.policy.states == 0
