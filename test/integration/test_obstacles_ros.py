# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Obstacles through ROS: the plant tells each robot its obstacles, the robots go round them.

A pillar stands between robot 1's start and its place; robot 4 senses only 0.6 m and is never
that near; a second pillar is far from everyone. Over real DDS, every ``obstacles`` message is
checked against the one rule (``told_obstacles`` of the pose with its stamp), the commands
against c M1, the plant's own count of contacts, and the lockstep trajectory against the law
with the map grown by the footprint stepped offline; with either transport (the team's carries
the obstacles in ``/formation/obstacles``, a robot's own topics go while someone listens).
"""

import json

from formation_ros.core.maths.law import team_command
from formation_ros.core.maths.obstacles import quaternion_normals, told_obstacles
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from helpers import launch, logged, stop_when, write_params
import numpy as np
import pytest

PILLARS = {
    'start.positions': [-1.3, -1.1, 0.0, 1.6, -1.6, 0.0, 1.6, 0.0],
    'start.random_radius': None, 'start.min_separation': None,
    'repulsion_radius': 0.5, 'sensing_radii': [2.0, 2.0, 2.0, 0.6],
    'obstacles.circles': [0.0, 0.0, 0.3, 10.0, 0.0, 0.5], 'obstacles.clearance': 0.4,
    'plant.lockstep': True, 'plant.realtime_factor': 2.0,
}


@pytest.mark.parametrize('transport', ['robot', 'team'])
def test_robots_go_round_a_pillar_they_are_told_of(processes, install, probe, tmp_path,
                                                   transport):
    params = write_params(tmp_path, 'square_4.yaml', {**PILLARS, 'transport': transport})
    config = load_config(params, 'plant')
    bound = config.law().u_bound
    told, poses, commands = {1: {}, 4: {}}, {1: {}, 4: {}}, []
    for i in (1, 4):
        probe.create_subscription(
            PoseArray, f'/robot_{i}/obstacles',
            lambda m, i=i: told[i].setdefault(fields.stamp_to_ns(m.header.stamp), m),
            qos.recording(qos.STATE))
        probe.create_subscription(
            PoseStamped, f'/robot_{i}/pose',
            lambda m, i=i: poses[i].setdefault(fields.stamp_to_ns(m.header.stamp), m),
            qos.recording(qos.STATE))
    for i in range(1, 5):
        probe.create_subscription(
            TwistStamped, f'/robot_{i}/cmd_vel',
            lambda m: commands.append((m.twist.linear.x, m.twist.linear.y)),
            qos.COMMAND_INPUT)
    out = tmp_path / 'out'
    launch(processes, install, params, out=out, per_process=4)

    def arrived():
        if not poses[1]:
            return False
        last = poses[1][max(poses[1])].pose.position
        return np.hypot(last.x - 1.0, last.y - 1.0) < 0.05

    info = stop_when(probe, processes, arrived, timeout=240)
    assert info.returncode == 0, processes.log('launcher')
    log = logged(probe, processes, 'launcher', 'obstacle contacts')
    assert '0 obstacle contacts' in log, log[-3000:]

    stats = json.loads((out / 'plant_stats.json').read_text())
    assert stats['obstacle_contacts'] == 0 and stats['min_obstacle_gap'] > 0.0, stats
    assert commands and np.max(np.abs(commands)) <= bound + 1e-9

    both = [stamp for stamp in told[1] if stamp in poses[1]]
    assert len(both) > 50, (len(told[1]), len(poses[1]))
    near = 0
    for stamp in both:
        message, pose = told[1][stamp], poses[1][stamp].pose.position
        assert message.header.frame_id == config.world_frame
        q = np.array([[pose.x, pose.y]])
        rule = told_obstacles(config.obstacles, q, q, config.sensing_radii[:1])
        points = np.array([[p.position.x, p.position.y] for p in message.poses]).reshape(-1, 2)
        assert np.array_equal(points, rule.points[0][rule.listed[0]])
        assert len(points) == 1, 'the pillar near, never the far one'
        assert abs(np.hypot(*points[0]) - 0.3) < 1e-12  # on the surface
        quats = [[p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w]
                 for p in message.poses]
        assert np.allclose(quaternion_normals(np.array(quats), 2)[0], points[0] / 0.3)
        near += 1
    assert near == len(both)
    assert told[4] and all(len(m.poses) == 0 for m in told[4].values()), 'nothing near: empty'

    run = Trajectory.load(str(out / 'trajectory.npz'))
    assert len(run.t) > 200
    # Robot 1's whole path from the plant's run: with the team transport the probe hears its
    # own pose topic only once the plant has seen the probe listen (topics made on demand).
    path = run.q[:, 0]
    assert np.min(np.hypot(path[:, 0], path[:, 1])) > 0.3, 'robot 1 went round, not through'
    assert np.max(path[:, 0]) > 0.9 and np.min(path[:, 0]) < -1.0
    dt, law, grown = config.plant.step_ns * 1e-9, config.law(), config.law_obstacles()
    q = run.q[0]
    for k in range(len(run.t) - 1):
        frame = config.reference().sample(run.t[k])
        q = q + dt * team_command(q, config.vertices, config.sensing_radii, law, frame,
                                  obstacles=grown).u
        assert np.max(np.abs(q - run.q[k + 1])) < 1e-9, k


def test_unicycles_are_told_the_points_closest_to_their_hand_points(processes, install, probe,
                                                                    tmp_path):
    hand = 0.1
    params = write_params(tmp_path, 'square_4.yaml', {
        **PILLARS, 'body.kind': 'unicycle', 'body.hand_distance': hand,
        'start.headings': [0.9, -1.6, 0.0, 3.1]})
    config = load_config(params, 'plant')
    told, poses = {}, {}
    probe.create_subscription(
        PoseArray, '/robot_1/obstacles',
        lambda m: told.setdefault(fields.stamp_to_ns(m.header.stamp), m), qos.recording(qos.STATE))
    probe.create_subscription(
        PoseStamped, '/robot_1/pose',
        lambda m: poses.setdefault(fields.stamp_to_ns(m.header.stamp), m),
        qos.recording(qos.STATE))
    out = tmp_path / 'out'
    launch(processes, install, params, out=out, per_process=4)

    def hand_point(message):
        p, o = message.pose.position, message.pose.orientation
        heading = 2.0 * np.arctan2(o.z, o.w)
        return np.array([p.x, p.y]) + hand * np.array([np.cos(heading), np.sin(heading)])

    def arrived():
        return bool(poses) and np.hypot(*(hand_point(poses[max(poses)]) - 1.0)) < 0.05

    info = stop_when(probe, processes, arrived, timeout=240)
    assert info.returncode == 0, processes.log('launcher')
    stats = json.loads((out / 'plant_stats.json').read_text())
    assert stats['obstacle_contacts'] == 0 and stats['min_obstacle_gap'] > 0.0, stats
    both = [stamp for stamp in told if stamp in poses]
    assert len(both) > 50
    for stamp in both:
        pose = poses[stamp].pose.position
        body, point = np.array([[pose.x, pose.y]]), hand_point(poses[stamp])[None]
        rule = told_obstacles(config.obstacles, body, point, config.sensing_radii[:1])
        points = np.array([[p.position.x, p.position.y]
                           for p in told[stamp].poses]).reshape(-1, 2)
        assert np.allclose(points, rule.points[0][rule.listed[0]], rtol=0.0, atol=1e-12)
    near = [stamp for stamp in both if told[stamp].poses]
    assert near, 'robot 1 was told of the pillar'
    bodies = np.array([[poses[s].pose.position.x, poses[s].pose.position.y] for s in both])
    assert np.min(np.hypot(bodies[:, 0], bodies[:, 1])) > 0.3, 'its body went round'
