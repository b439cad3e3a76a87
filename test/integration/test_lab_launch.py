# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A lab without the plant: launch_formation.sh --no-plant, the probe playing mocap and bases.

The probe is a trivial lab: every robot's body is a point q_i' = u_i, moved by the last command
it heard on its base's topic (``/base_<i>/cmd_vel``, where ``--cmd-topic`` sends it), and a
motion capture system publishes every body's measured pose (best effort PoseStamped in the
file's ``world_frame``, about 50 Hz) on the relay's source topics. No ``/clock`` exists: the
relay, the reference node and the robots run on wall-clock time.
"""

import json
import time

from formation_ros.core.maths.frames import desired_positions
from formation_ros.core.settings.params import load_config
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.ros import qos
from formation_ros.tools.bag import read_messages
from geometry_msgs.msg import PoseStamped, TwistStamped
from helpers import launch, project_processes, START_UP, stop_when, write_params
import numpy as np
from rclpy.qos import qos_profile_sensor_data
import wire

MOCAP_PERIOD = 0.02
NAMES = ['tb1', 'tb2', 'tb3', 'tb4']


class Lab:
    """Bodies q_i' = u_i moved by the commands on /base_<i>/cmd_vel, seen by a mocap."""

    def __init__(self, probe, params):
        """Place the bodies at the file's start; publish their poses, hear their commands."""
        config = load_config(params)
        values = load_params_file(params)
        self.frame = config.world_frame
        self.dim = config.dim
        self.q = np.array(config.start, dtype=float)
        self.u = np.zeros_like(self.q)
        self.target = desired_positions(config.vertices, config.reference().sample(0.0))
        self.bound = config.law().u_bound
        self.clock = probe.get_clock()
        self.heard = [0] * config.num_robots
        self.largest = 0.0
        topic = values['relay.source_topic']
        self.mocap = [probe.create_publisher(PoseStamped, topic.format(i=i, name=name),
                                             qos_profile_sensor_data)
                      for i, name in enumerate(NAMES, start=1)]
        self.bases = [probe.create_subscription(
            TwistStamped, f'/base_{i}/cmd_vel', lambda msg, k=i - 1: self.on_command(k, msg),
            qos.COMMAND) for i in range(1, config.num_robots + 1)]
        self.last = time.monotonic()
        self.timer = probe.create_timer(MOCAP_PERIOD, self.step)
        self.start_error = self.error()

    def on_command(self, k, msg):
        """Keep base k's latest command (a base driver takes the newest)."""
        self.u[k] = wire.velocity_of(msg, self.dim)
        self.heard[k] += 1
        self.largest = max(self.largest, float(np.max(np.abs(self.u[k]))))

    def step(self):
        """Move every body by its command over the time since the last step; publish poses."""
        now = time.monotonic()
        self.q = self.q + self.u * (now - self.last)
        self.last = now
        stamp = self.clock.now().nanoseconds
        for k, publisher in enumerate(self.mocap):
            msg = wire.pose_stamped(self.q[k], stamp, self.dim)
            msg.header.frame_id = self.frame
            publisher.publish(msg)

    def error(self):
        """Largest distance of a body from its place in the formation, m."""
        return float(np.max(np.linalg.norm(self.q - self.target, axis=1)))


def test_a_lab_forms_with_the_relay_and_remapped_commands(processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {
        'relay.source_names': NAMES, 'relay.source_topic': '/mocap/{name}/pose'})
    lab = Lab(probe, params)
    assert lab.start_error > 0.5
    launch(processes, install, params,
           options=('--no-plant', '--cmd-topic', '/base_{i}/cmd_vel'))

    unremapped = []

    def formed():
        if not (min(lab.heard) > 0 and lab.error() < 0.1 * lab.start_error):
            return False
        unremapped.append(sum(probe.count_publishers(f'/robot_{i}/cmd_vel')
                              for i in range(1, 5)))
        return True

    info = stop_when(probe, processes, formed, timeout=START_UP + 60)
    assert info.returncode == 0, processes.log('launcher')
    log = processes.log('launcher')
    assert '[relay]' in log and '[plant]' not in log and 'Traceback' not in log
    assert unremapped and set(unremapped) == {0}, 'a robot publishes on /robot_<i>/cmd_vel'
    assert 0.0 < lab.largest <= lab.bound
    assert project_processes(install) == []


def test_a_recorded_lab_keeps_the_remapped_commands_and_reports_from_its_bag(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {
        'relay.source_names': NAMES, 'relay.source_topic': '/mocap/{name}/pose'})
    lab = Lab(probe, params)
    bag = tmp_path / 'bag'
    launch(processes, install, params, record=bag,
           options=('--no-plant', '--cmd-topic', '/base_{i}/cmd_vel'))
    info = stop_when(probe, processes, lambda: min(lab.heard) > 20, timeout=START_UP + 60)
    assert info.returncode == 0, processes.log('launcher')
    recorded, _ = read_messages(str(bag))
    for i in range(1, 5):
        assert len(recorded.get(f'/robot_{i}/cmd_vel', [])) > 0, sorted(recorded)
        assert len(recorded.get(f'/robot_{i}/pose', [])) > 0, sorted(recorded)
    assert '/clock' not in recorded
    metrics = json.loads((bag / 'metrics.json').read_text())
    assert metrics['num_samples'] > 2
    assert 0.0 < metrics['max_abs_u_component'] <= lab.bound
    assert project_processes(install) == []
