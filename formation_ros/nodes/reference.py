# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Reference node (executable ``reference``): broadcasts the desired formation frame (Section 6).

Publishes ``/formation/reference`` (nav_msgs/Odometry) at ``reference.rate``: pose.position =
q_od(t), orientation = the frame J as a quaternion (the rotation J^T from formation axes to world
axes), twist.linear = qdot_od and twist.angular = the frame's angular velocity w, both in the
world frame (``world_frame``, the header's frame_id), with ``Jdot = -J [w]x``, so a robot has J
and Jdot without differentiating.
header.stamp is the time t of the sample. With ``use_sim_time`` t is the plant's simulated time;
without it, t counts from the node's start. The timer runs on the wall clock at
``reference.rate``, so samples keep coming (with the same stamp) while the plant holds its clock,
e.g. while it waits for the robots. In lockstep it publishes one sample for every new value of
the simulated clock as soon as the clock moves (a jump callback of its clock arms a one-shot
timer, ``formation_ros.ros.wake``; the timer at ``reference.rate`` publishes the first sample
and any it missed), together with the sample of the next step (``plant.rate`` gives it), so
the robots have it before the state it belongs to. The topic is transient local: a late robot
gets the latest sample.
"""

from typing import List, Optional

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.declarations import Exe
from formation_ros.core.frames import frame_to_pose
from formation_ros.ros import fields, messages, qos, topics
from formation_ros.ros.cdr import encode_odometry
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.once import OnceLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.wake import Wake
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType, JumpThreshold
from rclpy.duration import Duration
from rclpy.node import Node


class ReferenceNode(Node):
    """Publishes q_od(t), J(t), qdot_od(t) and the frame's angular velocity."""

    def __init__(self) -> None:
        """Declare and check parameters, then start publishing."""
        super().__init__('reference')
        config = declare_parameters(self, Exe.REFERENCE)
        settings = config.reference_node
        assert settings is not None
        self.dim = config.dim
        self.world_frame = config.world_frame
        self.reference = config.reference()
        self.lockstep = config.lockstep
        self.step_ns = settings.step_ns
        self.sim_time = self.get_parameter('use_sim_time').value
        self.epoch_ns = 0 if self.sim_time else self.get_clock().now().nanoseconds
        self.last_stamp: Optional[int] = None
        self.once = OnceLog(self.get_logger())
        self.pub = self.create_publisher(Odometry, topics.REFERENCE, qos.REFERENCE)
        self.published = 0
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS,
                                                     qos.DIAGNOSTICS)
        self.diagnostics_timer = self.create_timer(
            PERIOD, self.on_diagnostics, clock=Clock(clock_type=ClockType.STEADY_TIME))
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.timer = self.create_timer(1.0 / settings.rate, self.on_timer, clock=steady)
        if self.lockstep:
            self.clock_moved = Wake(self, self.on_timer, steady)
            self.jump_handle = self.get_clock().create_jump_callback(
                JumpThreshold(min_forward=Duration(nanoseconds=1), min_backward=None),
                post_callback=lambda jump: self.clock_moved.arm())
        self.get_logger().info(
            f'reference: {self.reference.kind} in {self.dim}D, '
            + ('lockstep' if self.lockstep else f'{settings.rate:g} Hz')
            + (', simulated time' if self.sim_time else ', wall-clock time from start'))
        if self.lockstep and not self.sim_time:
            self.get_logger().warning('lockstep without use_sim_time: samples will not match '
                                      'the plant state stamps')

    def on_timer(self) -> None:
        """
        Publish the sample of the current time.

        In lockstep: once per value of the clock, and the sample of the next step with it, so
        that it is with the robots before the state it belongs to (the plant's step is known).
        """
        now = self.get_clock().now().nanoseconds
        if not self.lockstep:
            self._publish(now)
            return
        for stamp in (now, now + self.step_ns):
            if self.last_stamp is None or stamp > self.last_stamp:
                self._publish(stamp)

    def _publish(self, stamp: int) -> None:
        self.last_stamp = stamp
        frame = self.reference.sample((stamp - self.epoch_ns) / fields.NS_PER_S)
        self.pub.publish(encode_odometry(stamp, self.world_frame, messages.FORMATION_FRAME,
                                         *frame_to_pose(frame, self.dim)))
        self.published += 1

    def on_diagnostics(self) -> None:
        """Publish the reference node's status: kind, time, samples published."""
        values = {'kind': self.reference.kind, 'samples published': self.published,
                  'time [s]': ('none yet' if self.last_stamp is None
                               else (self.last_stamp - self.epoch_ns) / fields.NS_PER_S)}
        level, message = ('ok', 'publishing') if self.published else ('warn', 'no sample yet')
        if not self.sim_time and self.count_publishers(topics.CLOCK) > 0:
            level, message = 'error', 'on wall-clock time while /clock is published'
            self.once.start('clock', f'{topics.CLOCK} is published (a plant runs) but this node '
                                     'runs on wall-clock time: robots refuse its samples, '
                                     'stamped in another time base; restart it with '
                                     'use_sim_time:=true', 'error')
        self.diagnostics_pub.publish(diagnostics('formation_ros/reference', level, message,
                                                 values))


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros reference``."""
    return run(ReferenceNode, args, name='reference')
