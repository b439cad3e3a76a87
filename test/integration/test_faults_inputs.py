# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Faults on the wire: clocks mixed up, forged commands and messages, wrong identities."""

import json
import math
import os
import signal
import subprocess

from formation_ros.core.maths.law import robot_command
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import messages, qos
from formation_ros.tools.supervise import ProcessSpec
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from helpers import (CONFIG, exe, logged, node, SimClock, SQUARE, wait_exit, watch_commands,
                     write_params)
from nav_msgs.msg import Odometry
import numpy as np
import pytest
import wire

pytestmark = pytest.mark.faults
START_UP = 90.0
BOUND = load_config(SQUARE).law().u_bound
CIRCLE = os.path.join(CONFIG, 'circle_2d.yaml')


def start_robots(processes, install, robots, sim_time=True):
    for i in range(1, robots + 1):
        extra = ['-p', 'use_sim_time:=true'] if sim_time else []
        processes.start(node(install, 'robot', SQUARE, '-r', f'__ns:=/robot_{i}', *extra,
                             process=f'robot_{i}'))


def test_a_reference_on_wall_time_is_refused_and_the_team_waits(processes, install, probe):
    """The reference started without use_sim_time: robots publish zero and say why, once."""
    heard, _ = watch_commands(probe, 4)
    processes.start(node(install, 'plant', SQUARE))
    start_robots(processes, install, 4)
    processes.start(node(install, 'reference', SQUARE, process='wall_reference'))
    assert probe.spin_until(lambda: len(heard) >= 200, START_UP), processes.log('robot_1')
    assert all(not any(u) for _, u in heard), heard[:5]
    log = processes.log('robot_1')
    assert log.count('stamps from another clock') == 1 and 'use_sim_time:=true' in log, log
    assert probe.spin_until(lambda: 'robots refuse its samples'
                            in processes.log('wall_reference'), 30)
    processes.stop(['wall_reference'])
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    moving = len(heard)
    assert probe.spin_until(lambda: any(any(u) for _, u in heard[moving:]), START_UP), \
        processes.log('robot_1')
    assert max(max(abs(c) for c in u) for _, u in heard) <= BOUND


def test_a_moving_reference_on_wall_time_is_on_another_clock_not_another_reference(
        processes, install, probe):
    """A circle started without use_sim_time: the robots say it runs on another clock."""
    heard, _ = watch_commands(probe, 6)
    processes.start(node(install, 'plant', CIRCLE))
    processes.start(ProcessSpec('fleet', [exe(install, 'fleet'), '--robots', '1-6', '--ros-args',
                                          '--params-file', CIRCLE, '-p', 'use_sim_time:=true']))
    processes.start(node(install, 'reference', CIRCLE, process='wall_reference'))
    assert probe.spin_until(lambda: len(heard) >= 100 and 'robots refuse its samples'
                            in processes.log('wall_reference'), START_UP), processes.log('fleet')
    assert all(not any(u) for _, u in heard), heard[:5]
    log = logged(probe, processes, 'fleet', 'ignoring reference messages with stamps from '
                                            'another clock', 'start the reference with '
                                                             'use_sim_time:=true')
    assert 'a frame other than the one its reference' not in log, log


def test_forged_commands_are_refused_or_saturated(processes, install, probe, tmp_path):
    """A command from the future counts as zero; 1e9 m/s is saturated; garbage bytes counted."""
    out = tmp_path / 'plant'
    processes.start(node(install, 'plant', SQUARE, '-p', 'plant.wait_for_robots:=false',
                         '-p', f'plant.output_dir:={out}'))
    future = probe.create_publisher(TwistStamped, '/robot_1/cmd_vel', qos.COMMAND)
    huge = probe.create_publisher(TwistStamped, '/robot_2/cmd_vel', qos.COMMAND)
    garbage = probe.create_publisher(TwistStamped, '/robot_3/cmd_vel', qos.COMMAND)
    clock = SimClock(probe)

    def send():
        now = max(0, int(clock.seconds * 1e9))
        future.publish(wire.twist_stamped(np.array([0.5, 0.0]), 2_000_000_000 * 10 ** 9, 2))
        huge.publish(wire.twist_stamped(np.array([1e9, -1e9]), now, 2))
        garbage.publish(b'\x00\x01\x00\x00' + bytes(range(9)))
        return clock.seconds >= 3.0

    assert probe.spin_until(send, START_UP), processes.log('plant')
    [info] = processes.stop(['plant'])
    assert info.returncode == 0, processes.log('plant')
    stats = json.loads((out / 'plant_stats.json').read_text())
    assert stats['by_robot']['future'].get('1', 0) > 0, stats
    assert stats['by_robot']['saturated'].get('2', 0) > 0, stats
    assert stats['bound_violations'] > 0
    assert stats['malformed_command_messages'].get('3', 0) > 0, stats
    assert stats['by_robot']['missing'].get('3', 0) == stats['steps'], stats
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert np.ptp(trajectory.q[:, 0, :], axis=0).max() == 0.0
    step = np.abs(np.diff(trajectory.q[:, 1, :], axis=0)) / np.diff(trajectory.t)[:, None]
    assert step.max() <= BOUND * (1.0 + 1e-9)
    assert step.max() > 0.9 * BOUND
    log = processes.log('plant')
    assert log.count('after the present state') == 1 and log.count('saturating it') == 1
    assert log.count('not a TwistStamped') == 1, log


def test_robot_ignores_forged_poses_and_floods(processes, install, probe):
    """Wrong frame, 10,000 neighbours, a bad reference, garbage bytes: logged once each."""
    config = load_config(SQUARE)
    start_robots(processes, install, 1, sim_time=False)
    pose_pub = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)
    neighbours_pub = probe.create_publisher(PoseArray, '/robot_1/neighbors', qos.STATE)
    reference_pub = probe.create_publisher(Odometry, '/formation/reference', qos.REFERENCE)
    heard = []
    probe.create_subscription(TwistStamped, '/robot_1/cmd_vel', heard.append, qos.COMMAND)
    flood = messages.pose_array(np.zeros((10_000, 2)), 0, 2)
    ticks = []
    logged_at = []

    def publish():
        ticks.append(len(ticks))
        stamp = probe.get_clock().now().nanoseconds
        forged_pose = wire.pose_stamped(np.array([5.0, 5.0]), stamp, 2)
        forged_pose.header.frame_id = 'robot_1/base_link'
        fast = wire.reference_odometry(None, stamp, 2)
        fast.twist.twist.linear.x = 1e9
        flood.header.stamp = messages.ns_to_stamp(stamp)
        good = ((wire.pose_stamped(np.array([0.2, -0.1]), stamp, 2), pose_pub),
                (messages.pose_array(np.array([[0.6, 0.2]]), stamp, 2), neighbours_pub),
                (wire.reference_odometry(None, stamp, 2), reference_pub))
        forged = ((forged_pose, pose_pub), (flood, neighbours_pub), (fast, reference_pub),
                  (b'\x00\x01\x00\x00\x07', pose_pub))
        for message, publisher in (forged if len(ticks) % 3 == 0 else good):
            publisher.publish(message)
        log = processes.log('robot_1')
        if not logged_at and all(reason in log for reason in (
                'a frame other than world_frame', 'more neighbours than there are robots',
                'a speed or turn rate', 'not a whole message of its type')):
            logged_at.append(len(heard))
        return bool(logged_at) and len(heard) > logged_at[0] + 20

    assert probe.spin_until(publish, START_UP), processes.log('robot_1')
    answers = [u for u in (wire.velocity_of(m, 2) for m in heard[logged_at[0]:]) if np.any(u)]
    assert answers, 'the robot only published zero (its watchdog) after the forged messages'
    expected = robot_command(np.array([0.2, -0.1]), config.vertices[0], np.array([[0.6, 0.2]]),
                             config.sensing_radii[0], config.law()).u
    assert all(np.max(np.abs(u - expected)) < 1e-12 for u in answers), answers[:5]
    log = processes.log('robot_1')
    for reason in ('a frame other than world_frame', 'more neighbours than there are robots',
                   'a speed or turn rate', 'not a whole message of its type'):
        assert log.count(reason) == 1, (reason, log)
    assert processes.running('robot_1')


def test_identity_comes_from_the_namespace(processes, install, probe):
    wrong = processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_2',
                                 '-p', 'robot_id:=1', process='wrong'))
    assert wrong is not None
    info = wait_exit(probe, processes, 'wrong', 60)
    assert info is not None and info.returncode == 2, processes.log('wrong')
    log = processes.log('wrong')
    assert "parameter 'robot_id'" in log and '/robot_2' in log and 'Traceback' not in log
    processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_3', process='robot_3'))
    assert probe.spin_until(lambda: 'robot 3/4' in processes.log('robot_3'), 60), \
        processes.log('robot_3')


@pytest.mark.parametrize('transport', ['robot', 'team'])
def test_two_publishers_on_one_cmd_vel_are_reported(processes, install, probe, tmp_path,
                                                    transport):
    """
    Two robot processes with robot_id 1: named by the plant, with either transport.

    Robot transport: two publishers of /robot_1/cmd_vel. Team transport (where a robot's
    cmd_vel publisher is made only for a subscriber): one robot node announced by two
    processes on /diagnostics.
    """
    params = write_params(tmp_path, 'square_4.yaml', {'transport': transport})
    processes.start(node(install, 'plant', params))
    started = [processes.start(node(install, 'robot', params, '-r', '__ns:=/robot_1',
                                    '-p', 'use_sim_time:=true', process=name))
               for name in ('robot_1', 'robot_1_again')]
    said = ('/robot_1/cmd_vel has more than one publisher: /robot_1/robot' if transport == 'robot'
            else '/robot_1/robot runs in more than one process: /robot_1/robot on ')
    assert probe.spin_until(lambda: said in processes.log('plant'), START_UP), \
        processes.log('plant')
    log = processes.log('plant')
    assert log.count(said) == 1, log
    assert 'a second node with this robot_id?' in log
    if transport == 'team':
        line = next(line for line in log.splitlines() if said in line)
        assert all(f'(process {robot.pid})' in line for robot in started), line
    assert not math.isnan(BOUND)


@pytest.mark.parametrize('content', [None, '', 'garbage: [\n', '- a list\n'])
def test_a_bad_parameters_file_is_one_line_and_exit_2(install, ros_env, tmp_path, content):
    path = tmp_path / 'params.yaml'
    if content is not None:
        path.write_text(content)
    for name in ('plant', 'robot', 'reference', 'record'):
        result = subprocess.run([exe(install, name), '--ros-args', '--params-file', str(path)],
                                env=ros_env, capture_output=True, text=True, timeout=60)
        assert result.returncode == 2, (name, result.stderr)
        lines = [line for line in (result.stdout + result.stderr).splitlines() if line]
        assert len(lines) == 1 and str(path) in lines[0], (name, lines)


def test_use_sim_time_that_is_not_a_bool_is_one_line_and_exit_2(install, ros_env):
    """A use_sim_time rclpy refuses as it makes the node is one line too (exit 2)."""
    for name, extra in (('plant', []), ('robot', []), ('reference', []), ('record', []),
                        ('relay', []), ('fleet', ['--robots', '1-2'])):
        result = subprocess.run([exe(install, name), *extra, '--ros-args', '--params-file',
                                 SQUARE, '-p', 'use_sim_time:=1'],
                                env=ros_env, capture_output=True, text=True, timeout=60)
        assert result.returncode == 2, (name, result.stderr)
        lines = [line for line in (result.stdout + result.stderr).splitlines() if line]
        assert len(lines) == 1 and "parameter 'use_sim_time'" in lines[0], (name, lines)


def test_a_killed_plant_loses_at_most_its_last_second(processes, install, probe, tmp_path):
    """SIGKILL of the plant: formation_report rebuilds the run from the chunks it wrote."""
    out = tmp_path / 'run'
    out.mkdir()
    (out / 'params.yaml').write_text(open(SQUARE).read())
    clock = SimClock(probe)
    processes.start(node(install, 'plant', SQUARE, '-p', f'plant.output_dir:={out}'))
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    start_robots(processes, install, 4)
    assert probe.spin_until(lambda: clock.seconds >= 4.0, START_UP), processes.log('plant')
    [killed] = processes.stop(['plant'], sig=signal.SIGKILL)
    assert killed.signal_name == 'SIGKILL'
    reached = clock.seconds
    assert not (out / 'trajectory.npz').exists()
    result = subprocess.run([exe(install, 'formation_report'), str(out), '--out',
                             str(tmp_path / 'report'), '--no-plots'], env=processes.env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert 'rebuilt' in result.stderr and 'Traceback' not in result.stderr
    metrics = json.loads((tmp_path / 'report' / 'metrics.json').read_text())
    assert metrics['duration'] >= reached - 1.5, (metrics['duration'], reached)
    assert metrics['max_abs_u_hat_component'] <= BOUND
