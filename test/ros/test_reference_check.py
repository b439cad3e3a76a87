# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot node on simulated time wired to its reference track and answer policy.

The track's rules (samples unlike the frame evaluated, samples from another clock) are tested
in test/core/test_reference_track.py; here through the node's callbacks and timers.
"""

import os

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.nodes.robot import RobotNode
from geometry_msgs.msg import Point, Pose, PoseArray
import pytest
import rclpy
from rclpy.serialization import serialize_message
import wire

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')
LOGGED = f'reference-{Reason.OTHER_REFERENCE.name}'


@pytest.fixture
def robot(monkeypatch):
    """Yield robot 1 of the square on simulated time, following a circle, its clock at 5 s."""
    context = rclpy.Context()
    rclpy.init(context=context, args=[
        '--ros-args', '--params-file', SQUARE, '-p', 'use_sim_time:=true',
        '-p', 'reference.kind:=circle', '-p', 'reference.radius:=1.0',
        '-p', 'reference.speed:=0.5', '-p', 'wait_for_subscribers:=0'])
    steady = [10 ** 12]
    monkeypatch.setattr(RobotNode, 'now_ns', staticmethod(lambda: steady[0]))
    node = RobotNode(namespace='/robot_1', context=context)
    node.steady_ns = steady
    try:
        node.on_pose(wire.pose_stamped_bytes(5 * NS_PER_S, 'world', (-2.0, -2.0)))
        yield node
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def sample(node, stamp_s, shift=0.0):
    """Return the bytes of the sample the robot evaluates at ``stamp_s``, moved by ``shift`` m."""
    stamp_ns = int(round(stamp_s * NS_PER_S))
    frame = node.changes.reference.frame_at(stamp_ns)
    moved = FrameSample(frame.t, frame.q_od + shift, frame.qdot_od, frame.J, frame.Jdot)
    return serialize_message(wire.reference_odometry(moved, stamp_ns, 2))


def refused(node, reason):
    return node.inputs.refused.get(('reference', reason), 0)


def test_a_sample_unlike_the_frame_is_refused_through_the_callback(robot):
    robot.on_reference(sample(robot, 5.0))
    robot.on_reference(sample(robot, 5.02, shift=0.5))
    robot.on_reference(sample(robot, 5.04, shift=0.5))
    assert refused(robot, Reason.OTHER_REFERENCE) == 2 and len(robot.track.samples) == 1
    assert robot.once.is_active(LOGGED)
    robot.on_reference(sample(robot, 5.06))
    assert len(robot.track.samples) == 2 and not robot.once.is_active(LOGGED)


def test_a_sample_on_the_wall_clock_is_refused_as_another_clock_not_another_reference(robot):
    """The reference started without use_sim_time beside a plant holding its clock at 0."""
    robot.steady_ns[0] += robot.timeout_ns + 1
    robot.on_pose(wire.pose_stamped_bytes(0, 'world', (-2.0, -2.0)))
    assert robot.get_clock().now().nanoseconds == 0
    robot.on_neighbours(neighbours(0.0))
    robot.on_reference(sample(robot, 1.7e9, shift=0.5))
    robot.on_reference(sample(robot, 1.7e9 + 0.02, shift=0.5))
    assert refused(robot, Reason.OTHER_REFERENCE) == 0
    robot.on_watchdog()
    assert refused(robot, Reason.CLOCK) == 1


def neighbours(stamp_s):
    """Return the bytes of what robot 1 senses, robots 2 to 4 of the square, at ``stamp_s``."""
    message = PoseArray()
    message.header.frame_id = 'world'
    message.header.stamp.sec = int(stamp_s)
    message.header.stamp.nanosec = int(round((stamp_s % 1.0) * NS_PER_S))
    message.poses = [Pose(position=Point(x=x, y=y)) for x, y in ((2.0, -2.0), (2.0, 2.0),
                                                                 (-2.0, 2.0))]
    return serialize_message(message)


def test_a_silent_reference_is_stale_not_from_another_clock(robot):
    robot.on_reference(sample(robot, 5.0))
    robot.on_neighbours(neighbours(5.0))
    robot.steady_ns[0] += robot.timeout_ns + 1
    robot.on_pose(wire.pose_stamped_bytes(int(5.6 * NS_PER_S), 'world', (-2.0, -2.0)))
    robot.on_neighbours(neighbours(5.6))
    robot.on_watchdog()
    assert robot.policy.stale == ['reference']
    assert refused(robot, Reason.CLOCK) == 0
    robot.on_reference(sample(robot, 5.0))
    robot.on_watchdog()
    assert refused(robot, Reason.CLOCK) == 1
