# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot node on simulated time: no ``/clock`` subscription, its clock set from its states.

The rule (forward only, a jump once the states stopped) is tested in
test/core/test_robot_intake.py; here robot 1 of the square team is given serialized states as
its callbacks would give them, and its rclpy clock is read as its timers read it.
"""

import os
import time

from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.settings.declarations import ParamError
from formation_ros.nodes.robot import RobotNode
from formation_ros.nodes.robots_link import RobotsLink
from geometry_msgs.msg import Point, Pose, PoseArray
import pytest
import rclpy
from rclpy.parameter import Parameter
from rclpy.serialization import serialize_message
import wire

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')
CORNER = (-2.0, -2.0)


def robot_node(sim_time, transport='robot'):
    """Return (robot 1 with ``use_sim_time``, its context)."""
    context = rclpy.Context()
    rclpy.init(context=context, args=['--ros-args', '--params-file', SQUARE,
                                      '-p', f'use_sim_time:={str(sim_time).lower()}',
                                      '-p', f'transport:={transport}'])
    return RobotNode(namespace='/robot_1', context=context), context


class Steady:
    """The robots' steady clock, moved by the test (ns)."""

    def __init__(self):
        self.ns = 10 ** 12

    def __call__(self):
        return self.ns

    def wait(self, node):
        """Let more than the robot's input_timeout pass."""
        self.ns += node.timeout_ns + 1


@pytest.fixture
def steady(monkeypatch):
    clock = Steady()
    monkeypatch.setattr(RobotNode, 'now_ns', staticmethod(clock))
    return clock


@pytest.fixture
def sim_robot(steady):
    """Yield robot 1 on simulated time, then clean up."""
    node, context = robot_node(True)
    try:
        yield node
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def pose(stamp_s, frame='world'):
    return wire.pose_stamped_bytes(int(round(stamp_s * NS_PER_S)), frame, CORNER)


def now_s(node):
    return node.get_clock().now().nanoseconds / NS_PER_S


def team_state(stamp_s):
    """Return the bytes of a square_4 team state at ``stamp_s``."""
    message = PoseArray()
    message.header.frame_id = 'world'
    message.header.stamp.sec = int(stamp_s)
    message.header.stamp.nanosec = int(round((stamp_s % 1.0) * NS_PER_S))
    message.poses = [Pose(position=Point(x=x, y=y))
                     for x, y in ((-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0))]
    return serialize_message(message)


def test_a_robot_on_simulated_time_has_no_clock_subscription(sim_robot):
    topics = {subscription.topic_name for subscription in sim_robot.subscriptions}
    assert '/clock' not in topics
    assert {'/robot_1/pose', '/robot_1/neighbors', '/formation/reference'} <= topics
    assert now_s(sim_robot) == 0.0
    assert sim_robot.get_clock().ros_time_is_active
    assert sim_robot.get_parameter('use_sim_time').value is True


@pytest.mark.parametrize('given', [None, [Parameter('use_sim_time', value=True)]],
                         ids=['command line', 'node overrides'])
def test_a_robot_on_simulated_time_never_makes_a_clock_subscription(monkeypatch, given):
    """Not even for a moment: every participant would hear of it (1000 robots, 1000 readers)."""
    made = []
    create = RobotNode.create_subscription

    def spy(self, msg_type, topic, *args, **kwargs):
        made.append(topic)
        return create(self, msg_type, topic, *args, **kwargs)

    monkeypatch.setattr(RobotNode, 'create_subscription', spy)
    context = rclpy.Context()
    rclpy.init(context=context, args=['--ros-args', '--params-file', SQUARE, '-p',
                                      f"use_sim_time:={'false' if given else 'true'}"])
    try:
        node = RobotNode(namespace='/robot_1', context=context, parameter_overrides=given)
        assert node.sim_time and node.get_clock().ros_time_is_active
        assert 'pose' in made and '/clock' not in made, made
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)


def test_a_use_sim_time_that_is_not_a_bool_is_refused():
    context = rclpy.Context()
    rclpy.init(context=context, args=['--ros-args', '--params-file', SQUARE,
                                      '-p', 'use_sim_time:=1'])
    try:
        with pytest.raises(ParamError, match="parameter 'use_sim_time': must be true or false"):
            RobotNode(namespace='/robot_1', context=context)
    finally:
        rclpy.shutdown(context=context)


def test_its_clock_follows_the_poses_it_accepts_forward_only(sim_robot):
    sim_robot.on_pose(pose(5.0))
    assert now_s(sim_robot) == 5.0 and sim_robot.policy.states == 1
    sim_robot.on_pose(pose(4.9))
    assert sim_robot.policy.states == 2 and now_s(sim_robot) == 5.0
    sim_robot.on_pose(pose(5.25))
    assert now_s(sim_robot) == 5.25


def test_a_refused_pose_leaves_its_clock_alone(sim_robot):
    sim_robot.on_pose(pose(5.0))
    sim_robot.on_pose(pose(1000.0))
    sim_robot.on_pose(pose(5.5, frame='map'))
    assert now_s(sim_robot) == 5.0 and sim_robot.policy.states == 1
    rejected = {reason.name: count for (name, reason), count in sim_robot.inputs.refused.items()
                if name == 'pose'}
    assert rejected == {'CLOCK': 1, 'FRAME': 1}


def test_once_its_states_stopped_the_next_one_sets_its_clock_either_way(sim_robot, steady):
    sim_robot.on_pose(pose(5.0))
    steady.wait(sim_robot)
    sim_robot.on_pose(pose(20.0))
    assert now_s(sim_robot) == 20.0 and sim_robot.policy.states == 2
    sim_robot.on_pose(pose(40.0))
    assert now_s(sim_robot) == 20.0 and sim_robot.policy.states == 2
    steady.wait(sim_robot)
    sim_robot.on_pose(pose(0.5))
    assert now_s(sim_robot) == 0.5 and sim_robot.policy.states == 3
    assert {(name, reason.name): count for (name, reason), count
            in sim_robot.inputs.refused.items()} == {('pose', 'CLOCK'): 1}


def test_a_team_process_follows_its_states_the_same_way(steady):
    node, context = robot_node(True, 'team')
    try:
        link = RobotsLink([node])
        for stamp, later, taken in ((5.0, False, 5.0), (9.0, False, 5.0), (9.0, True, 9.0),
                                    (2.0, True, 2.0)):
            if later:
                steady.wait(node)
            link.on_states(team_state(stamp))
            link.take_state()
            assert now_s(node) == taken, (stamp, later)
        assert {(name, reason.name): count for (name, reason), count
                in node.inputs.refused.items()} == {('states', 'CLOCK'): 1}
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def test_its_use_sim_time_cannot_change_while_it_runs(sim_robot):
    [result] = sim_robot.set_parameters([Parameter('use_sim_time', value=False)])
    assert not result.successful and 'fixed at start' in result.reason
    assert sim_robot.get_parameter('use_sim_time').value is True


def test_a_robot_on_the_wall_clock_refuses_simulated_stamps():
    node, context = robot_node(False)
    try:
        before = time.time()
        node.on_pose(pose(5.0))
        assert node.policy.states == 0 and now_s(node) >= before
        assert '/clock' not in {subscription.topic_name for subscription in node.subscriptions}
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)
