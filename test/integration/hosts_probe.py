# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
An independent listener that the multi-host tests run inside a host: what arrives there.

``python hosts_probe.py OUT ROBOTS [TOPICS]``: an rclpy node that writes one JSON line per
message to OUT (line-buffered): ``{"m": time.monotonic(), "clock": s}`` for ``/clock`` (at most
every 0.05 s of simulated time), ``{"m": ..., "robot": i, "topic": "cmd_vel" | "pose", "stamp":
s, "u": [x, y, z]}`` for ``/robot_<i>/cmd_vel`` and ``/robot_<i>/pose`` of each robot in ROBOTS
(comma-separated ids, may be empty; ``u`` is the command or the position); TOPICS
(comma-separated, default ``cmd_vel,pose``) says which of the two it hears. CLOCK_MONOTONIC is
one clock for every network namespace, so the test can set these times against its own. Ends
on SIGINT or SIGTERM.
"""

import json
import signal
import sys
import time

from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseStamped, TwistStamped
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock


def main(argv):
    """Listen and write until stopped."""
    out, robots = argv[1], [int(word) for word in argv[2].split(',') if word]
    heard = set((argv[3] if len(argv) > 3 else 'cmd_vel,pose').split(','))
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    stop = []
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, lambda *_: stop.append(True))
    node = rclpy.create_node('hosts_probe')
    stream = open(out, 'a', buffering=1, encoding='utf-8')
    last = [-1.0]

    def write(**record):
        stream.write(json.dumps(dict(m=time.monotonic(), **record)) + '\n')

    def on_clock(message):
        seconds = fields.stamp_to_ns(message.clock) * 1e-9
        if seconds >= last[0] + 0.05:
            last[0] = seconds
            write(clock=seconds)

    def on_command(robot, message):
        v = message.twist.linear
        write(robot=robot, topic='cmd_vel', stamp=fields.stamp_to_ns(message.header.stamp) * 1e-9,
              u=[v.x, v.y, v.z])

    def on_pose(robot, message):
        p = message.pose.position
        write(robot=robot, topic='pose', stamp=fields.stamp_to_ns(message.header.stamp) * 1e-9,
              u=[p.x, p.y, p.z])

    node.create_subscription(Clock, '/clock', on_clock, qos.CLOCK)
    for robot in robots:
        if 'cmd_vel' in heard:
            node.create_subscription(TwistStamped, f'/robot_{robot}/cmd_vel',
                                     lambda m, i=robot: on_command(i, m), qos.COMMAND)
        if 'pose' in heard:
            node.create_subscription(PoseStamped, f'/robot_{robot}/pose',
                                     lambda m, i=robot: on_pose(i, m), qos.STATE)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        while not stop:
            executor.spin_once(timeout_sec=0.1)
    finally:
        stream.close()
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown()


if __name__ == '__main__':
    main(sys.argv)
