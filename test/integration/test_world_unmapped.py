# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A world with an obstacle the robots' map lacks: ``launch_formation.sh --world --world-params``.

The world starts from a file of its own, the robots' file plus an unmapped chair (a pillar west
of the team); relay, reference and robots read the robots' file. Three bases start about 0.1 m
from a triangle between the mapped pillar and the chair. Once every robot has answered, the
relay has told robot 1 its obstacles and the reference has checked the team twice more, the
run is stopped: the world built both pillars (its start-up line, ``world.xml``), robot 1 was
told only the mapped one, and no node was named for other team values (obstacles are not on
the team's must-agree list).
"""

import json

from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import qos
from geometry_msgs.msg import PoseArray, TwistStamped
from helpers import launch, project_processes, SimClock, START_UP, Statuses, stop_when, \
    write_params
import numpy as np

MAPPED = (1.2, 0.6, 0.1)
CHAIR = (-1.2, 0.6, 0.1)
"""Pillars, x, y, r (m): robot 1 (near (0, 0.6)) has both within its R_i = 1.5 m."""
TEAM = {'num_robots': 3, 'formation.vertices': [0.0, 0.6, -0.5196, -0.3, 0.5196, -0.3],
        'start.positions': [0.1686, 0.4988, -0.3865, -0.1502, 0.3541, -0.1841],
        'start.headings': [2.601, -2.297, -0.611], 'obstacles.circles': list(MAPPED),
        'obstacles.clearance': 0.3}
REFERENCE = 'formation_ros/reference'
TEAM_STATUSES = ('formation_ros/relay', 'formation_ros/robot_1', 'formation_ros/robot_2',
                 'formation_ros/robot_3')


def test_a_world_with_an_unmapped_chair_runs_the_team_without_a_team_mismatch(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'world_turtlebot3.yaml', TEAM)
    lab = str(tmp_path / 'lab.yaml')
    write_params_file(lab, dict(load_params_file(params),
                                **{'obstacles.circles': [*MAPPED, *CHAIR]}))
    clock, statuses = SimClock(probe), Statuses(probe)
    answered = [0, 0, 0]
    for i in range(1, 4):
        probe.create_subscription(TwistStamped, f'/robot_{i}/cmd_vel',
                                  lambda msg, k=i - 1: answered.__setitem__(k, answered[k] + 1),
                                  qos.COMMAND)
    told = []
    probe.create_subscription(PoseArray, '/robot_1/obstacles',
                              lambda msg: told.append([(p.position.x, p.position.y)
                                                       for p in msg.poses]), qos.STATE)
    checked = {}

    def done():
        if not (all(answered) and any(told) and clock.seconds > 2.0
                and all(name in statuses for name in TEAM_STATUSES)):
            return False
        heard = statuses.heard.get(REFERENCE, 0)
        checked.setdefault('after', heard + 2)
        return heard >= checked['after']

    out = tmp_path / 'run'
    launch(processes, install, params, out=out, per_process=3,
           options=('--world', '--world-params', lab))
    info = stop_when(probe, processes, done, timeout=START_UP + 60)
    log = processes.log('launcher')
    assert info.returncode == 0, log[-4000:]
    assert f', the world from {lab}' in log, log[:2000]
    assert 'Traceback' not in log, log[-4000:]
    world_lines = [line for line in log.splitlines() if line.startswith('[world]')]
    assert any(', obstacles: 2' in line for line in world_lines), world_lines[:5]
    scene = (out / 'world.xml').read_text()
    assert 'obstacle_circle_1' in scene and 'obstacle_circle_2' in scene
    assert (out / 'world_params.yaml').read_text() == open(lab).read()
    assert (out / 'params.yaml').read_text() == open(params).read()

    points = np.array([p for message in told for p in message])
    assert np.all(np.linalg.norm(points - MAPPED[:2], axis=1) < MAPPED[2] + 1e-6), \
        'robot 1 was told only the mapped pillar'
    reference = {kv.key: kv.value for kv in statuses[REFERENCE].values}
    assert 'nodes with other team values' not in reference, reference
    assert 'another parameters file?' not in log, log[-4000:]
    stats = json.loads((out / 'world_stats.json').read_text())
    assert stats['contacts'] == 0 and stats['obstacle_contacts'] == 0, stats
    assert project_processes(install) == []
