# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Single nodes driven by the test over DDS: exact commands, bad messages."""

import json
import math

from formation_ros.core.maths.law import robot_command
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, messages, qos
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from helpers import node, SQUARE
from nav_msgs.msg import Odometry
import numpy as np
import wire

STAMP_NS = 123_450_000_000


def test_robot_publishes_the_core_command_and_survives_bad_poses(processes, install, probe):
    config = load_config(SQUARE)
    processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_1', '-p', 'robot_id:=1',
                         '-p', 'use_sim_time:=true', process='robot_1'))
    own = np.array([0.2, -0.1])
    neighbours = np.array([[0.6, 0.2], [3.5, 0.0], [0.2, -0.8]])
    pose_pub = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)
    neighbours_pub = probe.create_publisher(PoseArray, '/robot_1/neighbors', qos.STATE)
    reference_pub = probe.create_publisher(Odometry, '/formation/reference', qos.REFERENCE)
    heard = []
    probe.create_subscription(TwistStamped, '/robot_1/cmd_vel', heard.append, qos.COMMAND)
    bad = wire.pose_stamped(np.array([math.nan, 0.0]), STAMP_NS + 1, 2)

    def publish(pose):
        pose_pub.publish(pose)
        neighbours_pub.publish(messages.pose_array(neighbours, STAMP_NS, 2))
        reference_pub.publish(wire.reference_odometry(None, STAMP_NS, 2))

    def answered():
        publish(wire.pose_stamped(own, STAMP_NS, 2))
        return any(fields.stamp_to_ns(m.header.stamp) == STAMP_NS for m in heard)

    assert probe.spin_until(answered, 60), processes.log('robot_1')
    expected = robot_command(own, config.vertices[0], neighbours, config.sensing_radii[0],
                             config.law()).u
    command = [m for m in heard if fields.stamp_to_ns(m.header.stamp) == STAMP_NS][-1]
    assert np.max(np.abs(wire.velocity_of(command, 2) - expected)) < 1e-12
    assert np.any(expected != robot_command(own, config.vertices[0], neighbours[1:2],
                                            config.sensing_radii[0], config.law()).u)
    count = len(heard)

    def rejected_while_answering():
        publish(bad)
        return 'non-finite' in processes.log('robot_1') and len(heard) > count + 5

    assert probe.spin_until(rejected_while_answering, 10), processes.log('robot_1')
    assert all(fields.stamp_to_ns(m.header.stamp) == STAMP_NS for m in heard[count:])
    assert processes.running('robot_1')
    assert processes.log('robot_1').count('non-finite') == 1


def test_plant_refuses_a_non_finite_command_and_counts_it(processes, install, probe, tmp_path):
    """The rule of the plant and the world: dropped at intake, counted; nothing moves."""
    out = tmp_path / 'plant'
    processes.start(node(install, 'plant', SQUARE, '-p', 'plant.wait_for_robots:=false',
                         '-p', f'plant.output_dir:={out}'))
    command_pub = probe.create_publisher(TwistStamped, '/robot_1/cmd_vel', qos.COMMAND)
    clock = []
    probe.create_subscription(PoseStamped, '/robot_1/pose',
                              lambda m: clock.append(fields.stamp_to_ns(m.header.stamp)),
                              qos.STATE)

    def send():
        stamp = clock[-1] if clock else 0
        command_pub.publish(wire.twist_stamped(np.array([math.nan, 1.0]), stamp, 2))
        return len(clock) > 60

    assert probe.spin_until(send, 60), processes.log('plant')
    [info] = processes.stop(['plant'])
    assert info.returncode == 0, processes.log('plant')
    stats = json.loads((out / 'plant_stats.json').read_text())
    assert stats['non_finite_command_messages']['1'] > 0 and stats['bad_command_steps'] == 0
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert np.ptp(trajectory.q[:, 0, :], axis=0).max() == 0.0
    log = processes.log('plant')
    assert log.count('non-finite command') == 1 and 'Traceback' not in log


def test_several_robot_nodes_share_one_process_and_executor(probe):
    """Two RobotNode instances live in one process and executor (no module-level state)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from formation_ros.nodes.robot import RobotNode
    context = rclpy.Context()
    rclpy.init(context=context, args=['--ros-args', '--params-file', SQUARE])
    executor = SingleThreadedExecutor(context=context)
    robots = [RobotNode(context=context, namespace=f'/robot_{i}',
                        parameter_overrides=[Parameter('robot_id', Parameter.Type.INTEGER, i)])
              for i in (1, 2)]
    try:
        for robot in robots:
            executor.add_node(robot)
        assert [robot.index for robot in robots] == [0, 1]
        assert not np.array_equal(robots[0].vertex, robots[1].vertex)

        def both_visible():
            executor.spin_once(timeout_sec=0.01)
            return all(probe.count_publishers(f'/robot_{i}/cmd_vel') == 1 for i in (1, 2))

        assert probe.spin_until(both_visible, 20)
    finally:
        executor.shutdown()
        for robot in robots:
            robot.destroy_node()
        rclpy.shutdown(context=context)
