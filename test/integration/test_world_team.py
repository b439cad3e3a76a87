# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The team on the physics world through the lab's path: ``launch_formation.sh --world``.

The world (MuJoCo) publishes ``/clock`` and every body's ``measured_pose``; the relay turns them
into the robots' states on the world's simulated time, the robots answer on ``cmd_vel`` (stamped
with simulated time where the config says ``twist_stamped``) and the world drives the bodies.
Three robots of each shipped world config (TurtleBot3-like diff-drive bases, holonomic bases
taking body-frame Twist, flying bodies in 3D) start about 0.1 m from their places, so that they
settle in a few simulated seconds; the run is stopped once every hand point (the position, for
points) of the world's ground truth is within 0.05 m of its vertex. Then the world counted no
contact, took every command (none refused, none stale: the stamps were on its clock), and
every command the world heard was within the law's bound; the report says so too: what each
robot commanded (its stamped command read at the heading of the pose it answered, which the
world heard) is within c M1, the held command at the body's true heading within sqrt(2) c M1.
"""

import json
import math

from formation_ros.core.maths.unicycle import hand_points, headings_from_quaternions
from formation_ros.core.settings.params import load_config
from formation_ros.ros import qos
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from helpers import launch, project_processes, START_UP, stop_when, write_params
import numpy as np
import pytest

TOLERANCE = 0.05
TEAMS = {
    'turtlebot3': ('world_turtlebot3.yaml', {
        'formation.vertices': [0.0, 0.6, -0.5196, -0.3, 0.5196, -0.3],
        'start.positions': [0.1686, 0.4988, -0.3865, -0.1502, 0.3541, -0.1841],
        'start.headings': [2.601, -2.297, -0.611]}),
    'holonomic': ('world_holonomic.yaml', {
        'formation.vertices': [0.0, 0.7, -0.6062, -0.35, 0.6062, -0.35],
        'start.positions': [0.1, 0.58, -0.5, -0.28, 0.5, -0.25],
        'start.headings': [0.0, 1.3, -2.1]}),
    '3d': ('world_3d.yaml', {
        'formation.vertices': [0.0, 0.7, 1.0, -0.6062, -0.35, 1.3, 0.6062, -0.35, 0.7],
        'start.positions': [0.1, 0.58, 0.9, -0.5, -0.28, 1.2, 0.5, -0.25, 0.8]}),
}
"""Three robots of each world config, about 0.1 m (hand points) from a triangle's vertices."""


class Team:
    """What the probe hears of the world's bodies and of the commands the world takes."""

    def __init__(self, probe, config):
        """Subscribe to every measured pose and cmd_vel of ``config``'s robots."""
        self.config = config
        self.n = config.num_robots
        self.poses = [None] * self.n
        self.commands = [[] for _ in range(self.n)]
        kind = TwistStamped if config.command.stamped else Twist
        for i in range(1, self.n + 1):
            probe.create_subscription(PoseStamped, f'/robot_{i}/measured_pose',
                                      lambda msg, k=i - 1: self._pose(k, msg), qos.MEASUREMENT)
            probe.create_subscription(kind, f'/robot_{i}/cmd_vel',
                                      lambda msg, k=i - 1: self._command(k, msg), qos.COMMAND)

    def _pose(self, k, msg):
        p, o = msg.pose.position, msg.pose.orientation
        self.poses[k] = ((p.x, p.y, p.z), (o.x, o.y, o.z, o.w))

    def _command(self, k, msg):
        twist = getattr(msg, 'twist', msg)
        self.commands[k].append((twist.linear.x, twist.linear.y, twist.linear.z,
                                 twist.angular.x, twist.angular.y, twist.angular.z))

    def errors(self):
        """Each control point's distance from its vertex, m (None before every pose is in)."""
        if any(pose is None for pose in self.poses):
            return None
        dim = self.config.dim
        q = np.array([pose[0][:dim] for pose in self.poses])
        if self.config.body.is_unicycle:
            headings = headings_from_quaternions(np.array([pose[1] for pose in self.poses]))
            q = hand_points(q, headings, self.config.body.hand_distance)
        return np.linalg.norm(q - self.config.vertices, axis=1)

    def formed(self):
        """Whether every robot has been heard commanding and every point is within TOLERANCE."""
        errors = self.errors()
        return (errors is not None and all(self.commands)
                and bool(np.max(errors) < TOLERANCE))


@pytest.mark.parametrize('team', sorted(TEAMS))
def test_the_team_forms_on_the_world_through_the_relay(processes, install, probe, tmp_path,
                                                       team):
    source, changes = TEAMS[team]
    params = write_params(tmp_path, source, dict(changes, num_robots=3))
    config = load_config(params)
    start = config.start
    if config.body.is_unicycle:
        start = hand_points(start, config.start_headings, config.body.hand_distance)
    assert np.min(np.linalg.norm(start - config.vertices, axis=1)) > 1.5 * TOLERANCE
    watched = Team(probe, config)
    out = tmp_path / 'run'
    launch(processes, install, params, out=out, options=('--world',), per_process=3)
    info = stop_when(probe, processes, watched.formed, timeout=START_UP + 60)
    log = processes.log('launcher')
    assert info.returncode == 0, log[-4000:]
    assert '[world]' in log and '[relay]' in log and '[plant]' not in log, log[-4000:]
    assert 'Traceback' not in log, log[-4000:]
    assert 'carry no stamp' not in log, 'the world stamps its first poses 0: its start'
    assert 'launch_formation.sh: world: 0 contacts between robots' in log, log[-3000:]

    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['contacts'] == 0, stats['contact_events']
    assert stats['min_footprint_gap'] > 0.0
    assert not any(stats['refused_command_messages'].values()), stats
    assert stats['stale_command_messages'] == {}, stats['stale_command_messages']
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['num_robots'] == 3
    bound = config.law().u_bound
    if config.command.stamped:
        samples = metrics['num_samples'] * metrics['num_robots']
        assert metrics.get('unknown_commands', 0) < 0.1 * samples, metrics
        assert 0.0 < metrics['max_abs_u_hat_component'] <= bound * (1 + 1e-9), metrics
        assert metrics['bound_violations'] == 0
    if config.body.is_unicycle:
        assert metrics['max_abs_u_hat_held_component'] <= math.sqrt(2.0) * bound * (1 + 1e-9)
        assert metrics['u_hat_held_above_bound'] == 0

    heard = np.array([c for commands in watched.commands for c in commands])
    if config.body.is_unicycle:
        v_bound = math.sqrt(2.0) * bound
        assert np.all(np.abs(heard[:, 0]) <= v_bound * (1 + 1e-9)), np.max(np.abs(heard[:, 0]))
        assert np.all(np.abs(heard[:, 5]) <= v_bound / config.body.hand_distance * (1 + 1e-9))
        assert np.all(heard[:, 1:5] == 0.0)
    elif config.dim == 2:
        norms = np.linalg.norm(heard[:, :2], axis=1)
        assert np.all(norms <= math.sqrt(2.0) * bound * (1 + 1e-9)), np.max(norms)
    else:
        assert np.all(np.abs(heard[:, :3]) <= bound * (1 + 1e-9)), np.max(np.abs(heard[:, :3]))
    assert np.max(np.abs(heard[:, :config.dim])) > 0.0, 'no robot ever commanded a motion'
    assert project_processes(install) == []
