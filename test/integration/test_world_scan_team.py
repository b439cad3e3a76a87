# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The team on the physics world avoiding a pillar with their own scanners (``source: scan``).

Three TurtleBot3-like bases on the world through the relay, as ``launch_formation.sh --world``
starts them; a pillar stands on robot 1's way to its vertex. The robots read no map (a robot
never does) and, with ``obstacles.source: scan``, do not listen to what the relay tells: they
see the pillar in the world's LDS-like scans only. The run stops once robot 1's hand point is
past the pillar, 0.3 m from its vertex; the world counted no contact, robot 1 reported returns
used, and the world's commands stayed within the law's bound.
"""

import json

from formation_ros.core.maths.unicycle import hand_points, headings_from_quaternions
from formation_ros.core.settings.params import load_config
from formation_ros.ros import qos
from geometry_msgs.msg import PoseStamped
from helpers import launch, START_UP, Statuses, stop_when, write_params
import numpy as np

PILLAR = [-0.6, 0.75, 0.08]
"""Across robot 1's straight way from its start to its vertex: x, y, r (m)."""
TEAM = {
    'num_robots': 3,
    'formation.vertices': [0.0, 0.6, -0.5196, -0.3, 0.5196, -0.3],
    'start.positions': [-1.3, 0.5, -0.45, -0.25, 0.45, -0.25],
    'start.headings': [0.0, 1.0, 2.0],
    'obstacles.circles': PILLAR, 'obstacles.clearance': 0.2, 'obstacles.source': 'scan',
    'world.realtime_factor': 2.0,
}


def test_bases_go_round_a_pillar_their_scanners_see(processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'world_turtlebot3.yaml', TEAM)
    config = load_config(params, 'world')
    hand = config.body.hand_distance
    poses = {}
    probe.create_subscription(PoseStamped, '/robot_1/measured_pose',
                              lambda m: poses.update(last=m), qos.MEASUREMENT)
    statuses = Statuses(probe)
    seen = []

    def past_the_pillar():
        status = statuses.get('formation_ros/robot_1')
        if status is not None:
            seen.append(int({kv.key: kv.value for kv in status.values}.get(
                'obstacle points from the scan', 0)))
        if 'last' not in poses:
            return False
        p, o = poses['last'].pose.position, poses['last'].pose.orientation
        heading = headings_from_quaternions(np.array([[o.x, o.y, o.z, o.w]]))
        point = hand_points(np.array([[p.x, p.y]]), heading, hand)[0]
        return point[0] > PILLAR[0] + 0.35 and np.hypot(*(point - config.vertices[0])) < 0.3

    out = tmp_path / 'run'
    launch(processes, install, params, out=out, options=('--world',), per_process=3)
    info = stop_when(probe, processes, past_the_pillar, timeout=START_UP + 120)
    log = processes.log('launcher')
    assert info.returncode == 0, log[-4000:]
    assert 'Traceback' not in log and 'cannot be placed' not in log, log[-4000:]
    assert seen and max(seen) > 0, 'robot 1 used returns of its scan'
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['obstacle_contacts'] == 0 and stats['contacts'] == 0, stats
    assert stats['min_obstacle_gap'] > 0.0, stats
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['bound_violations'] == 0 and metrics['obstacle_contacts'] == 0, metrics
