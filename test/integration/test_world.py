# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world node over DDS: cmd_vel moves a body, a stale command stops it, bad ones counted."""

import json
import math
import os
import shutil
import signal
import time

from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import qos
from formation_ros.tools.report import load_run
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from helpers import CONFIG, logged, node, SimClock, Statuses, wait_exit
from nav_msgs.msg import Odometry
import numpy as np
import wire

START_UP = 90.0
TIMEOUT = 0.3
"""world.cmd_timeout of the tests, s."""
BRAKING = 0.2
"""Time a base at 0.2 m/s takes to stop once its motors' set points are zero, with room, s
(0.064 s by docs/physics.md) plus a pose period."""
STATUS = 'formation_ros/world'


def world_params(folder, source='lab_turtlebot3.yaml', **changes):
    """
    Write two robots of a lab's config (no relay, no random start); return the path.

    By default TurtleBot3-like bases, 0.6 m apart along x, both heading +x.
    """
    values = load_params_file(os.path.join(CONFIG, source))
    values = {name: value for name, value in values.items()
              if not name.startswith(('relay.', 'start.'))}
    values.update({'num_robots': 2, 'formation.vertices': [0.6, 0.0, -0.6, 0.0],
                   'start.positions': [0.0, 0.0, 0.6, 0.0], 'start.headings': [0.0, 0.0],
                   'world.cmd_timeout': TIMEOUT})
    values.update(changes)
    path = os.path.join(str(folder), 'params.yaml')
    write_params_file(path, values)
    return path


class Poses:
    """Every measured pose of robots 1 and 2 heard: (stamp s, x, y) lists."""

    def __init__(self, probe):
        self.heard = {1: [], 2: []}
        for i in self.heard:
            probe.create_subscription(PoseStamped, f'/robot_{i}/measured_pose',
                                      lambda msg, i=i: self._store(i, msg), qos.MEASUREMENT)

    def _store(self, i, msg):
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        self.heard[i].append((stamp, msg.pose.position.x, msg.pose.position.y))

    def latest(self, i):
        return np.array(self.heard[i][-1]) if self.heard[i] else None

    def at(self, i, t):
        """Return robot i's first pose stamped at t s or later: (stamp, x, y)."""
        return np.array(next(pose for pose in self.heard[i] if pose[0] >= t))


def value(statuses, key):
    status = statuses.get(STATUS)
    values = {kv.key: kv.value for kv in status.values} if status is not None else {}
    return float(values.get(key, 0))


def command(v, stamp_ns, frame='robot_1/base_link'):
    msg = wire.twist_stamped(np.array([v, 0.0]), stamp_ns, 2)
    msg.header.frame_id = frame
    return msg


def test_commands_drive_the_bodies_stale_ones_stop_them_bad_ones_are_counted(
        processes, install, probe, tmp_path):
    out = tmp_path / 'world'
    params = world_params(tmp_path, **{'world.output_dir': str(out)})
    processes.start(node(install, 'world', params))
    clock, poses, statuses = SimClock(probe), Poses(probe), Statuses(probe)
    odometry = []
    probe.create_subscription(Odometry, '/robot_1/odom', odometry.append, qos.MEASUREMENT)
    drive = probe.create_publisher(TwistStamped, '/robot_1/cmd_vel', qos.COMMAND)
    bad = probe.create_publisher(TwistStamped, '/robot_2/cmd_vel', qos.COMMAND)
    assert probe.spin_until(lambda: poses.heard[2] and odometry and clock.seconds > 0.2
                            and drive.get_subscription_count() and bad.get_subscription_count(),
                            START_UP), processes.log('world')
    start1, start2 = poses.latest(1), poses.latest(2)
    assert np.allclose(start1[1:], [0.0, 0.0], atol=1e-3)
    assert np.allclose(start2[1:], [0.6, 0.0], atol=1e-3)

    def now_ns():
        return int(round(clock.seconds * 1e9))

    def send_bad():
        bad.publish(command(math.nan, now_ns(), 'robot_2/base_link'))
        bad.publish(command(0.2, now_ns(), 'world'))
        bad.publish(b'\x00\x01\x00\x00' + bytes(range(9)))
        if clock.seconds > 2 * TIMEOUT:
            bad.publish(command(0.2, 0, 'robot_2/base_link'))

    sent = []

    def forward():
        sent.append(now_ns())
        drive.publish(command(0.2, sent[-1]))
        send_bad()
        return poses.latest(1)[1] > start1[1] + 0.1

    assert probe.spin_until(forward, 30), processes.log('world')
    moved = poses.latest(1)
    assert moved[1] - start1[1] > 0.1 and abs(moved[2] - start1[2]) < 0.01, moved

    last = sent[-1] * 1e-9
    assert probe.spin_until(lambda: send_bad() or clock.seconds > last + TIMEOUT + 1.0
                            + BRAKING, 30)
    held = poses.at(1, last + TIMEOUT - 0.05)[1] - poses.at(1, last + 0.05)[1]
    assert held > 0.05 * (TIMEOUT - 0.1), 'the command holds until its timeout'
    stopped, final = poses.at(1, last + TIMEOUT + BRAKING), poses.latest(1)
    assert abs(final[1] - stopped[1]) < 0.002, (stopped, final)
    assert np.allclose(poses.latest(2)[1:], start2[1:], atol=1e-3), 'bad commands moved it'
    assert odometry[-1].header.frame_id == 'world'
    assert odometry[-1].child_frame_id == 'robot_1/base_link'
    assert abs(odometry[-1].pose.pose.position.x - final[1]) < 0.02, odometry[-1].pose
    for reason in ('malformed', 'frame', 'non_finite'):
        key = f'robot 2: refused cmd_vel messages ({reason})'
        assert probe.spin_until(lambda: value(statuses, key) > 0, 10), statuses.get(STATUS)

    def into_robot_2():
        drive.publish(command(0.22, now_ns()))
        return value(statuses, 'contacts') >= 1

    assert probe.spin_until(into_robot_2, 30), processes.log('world')
    log = logged(probe, processes, 'world', 'contact 1: robots 1 and 2 touched at t = ')
    assert log.count('contact 1: ') == 1
    for text in ('robot 2: ignoring cmd_vel with non-finite values',
                 'robot 2: ignoring cmd_vel with a frame other than its command frame',
                 'robot 2: ignoring cmd_vel with bytes that are not a whole TwistStamped',
                 'robot 2: cmd_vel stamped '):
        assert log.count(text) == 1, log

    processes.send_signal('world', signal.SIGINT)
    info = wait_exit(probe, processes, 'world', 30)
    assert info is not None and info.returncode == 0, processes.log('world')
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['contacts'] >= 1 and stats['contact_events'][0]['i'] == 1
    assert stats['min_body_distance'] < 2 * 0.11 + 0.01
    assert stats['steps'] > 0 and stats['achieved_realtime_factor'] > 0.5
    refused = stats['refused_command_messages']
    assert all(refused[reason].get('2', 0) > 0 for reason in ('malformed', 'frame',
                                                              'non_finite')), refused
    assert not any(robots.get('1') for robots in refused.values()), refused
    assert stats['stale_command_messages'].get('2', 0) > 0, stats['stale_command_messages']
    import mujoco
    model = mujoco.MjModel.from_xml_path(str(out / 'world.xml'))
    assert model.nu == 4
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.q_body is not None and trajectory.q.shape[1:] == (2, 2)
    shutil.copy(params, out / 'params.yaml')
    loaded, config, _ = load_run(str(out))
    assert config.num_robots == 2 and loaded.t[-1] > last


def test_a_holonomic_base_takes_twists_in_its_body_frame_and_the_clock_keeps_pace(
        processes, install, probe, tmp_path):
    """Twists (no stamp) in the body frame; the clock at 2 x real time; output refused once."""
    blocked = tmp_path / 'file'
    blocked.write_text('not a directory')
    params = world_params(tmp_path, 'lab_holonomic.yaml', **{
        'start.positions': [0.0, 0.0, 1.5, 0.0], 'start.headings': [math.pi / 2, 0.0],
        'formation.vertices': [0.75, 0.0, -0.75, 0.0], 'world.realtime_factor': 2.0,
        'world.output_dir': str(blocked / 'out')})
    processes.start(node(install, 'world', params))
    clock, poses = SimClock(probe), Poses(probe)
    drive = probe.create_publisher(Twist, '/robot_1/cmd_vel', qos.COMMAND)
    assert probe.spin_until(lambda: poses.heard[1] and drive.get_subscription_count(),
                            START_UP), processes.log('world')
    start = poses.latest(1)
    twist = Twist()
    twist.linear.x = 0.2

    def sideways():
        drive.publish(twist)
        return poses.latest(1)[2] > start[2] + 0.1

    assert probe.spin_until(sideways, 30), processes.log('world')
    assert abs(poses.latest(1)[1] - start[1]) < 0.01, poses.latest(1)
    first, begun = clock.seconds, time.monotonic()
    assert probe.spin_until(lambda: clock.seconds > first + 2.0, 30)
    assert (clock.seconds - first) / (time.monotonic() - begun) > 1.0
    stopped = poses.at(1, first + TIMEOUT + BRAKING)
    assert abs(poses.latest(1)[2] - stopped[2]) < 0.002, (stopped, poses.latest(1))
    processes.send_signal('world', signal.SIGINT)
    info = wait_exit(probe, processes, 'world', 30)
    assert info is not None and info.returncode == 0, processes.log('world')
    log = processes.log('world')
    assert log.count('output stopped at') == 1 and 'Traceback' not in log, log
    assert 'world: wrote' not in log
