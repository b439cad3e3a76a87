# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A lab with a pillar: the relay tells the robots of it from the file's map, no body touches it.

The lab is the stand-in of lab_standin.py (lagging, acceleration-limited mecanum-like bodies, a
noisy 100 Hz mocap in frame ``map``, bases on the robots' own ``cmd_vel``); the launcher starts
relay, reference and a fleet of the four robots on wall-clock time (``--no-plant``). The pillar
stands on robot 1's way to its place (without the map its body passes 0.11 m from the pillar's
axis, closer than the pillar's radius and its own: a contact); the bodies must form with every
body farther than its radius from the pillar all along, and every command within c M1.
"""

import math

from formation_ros.core.settings.params import load_config
from formation_ros.ros import qos
from geometry_msgs.msg import PoseArray
from lab_standin import Base, Lab
import numpy as np
from test_lab import BODIES, converged, lab_params, MOCAP, run_lab, START

PILLAR = (0.52, 0.655, 0.1)


def test_a_lab_forms_round_a_pillar_of_its_map(processes, install, probe, tmp_path):
    names = ['mec1', 'mec2', 'mec3', 'mec4']
    params = lab_params(tmp_path, 'square_4.yaml', {
        'controller.gain': 0.6, 'body.radius': 0.1, 'command.type': 'twist',
        'command.frame': 'body', 'relay.source_topic': MOCAP, 'relay.source_names': names,
        'obstacles.circles': list(PILLAR), 'obstacles.clearance': 0.35})
    config = load_config(params)
    bound = config.law().u_bound
    lab = Lab(q=START, heading=[0.0, 1.3, -2.1, 2.8], base=Base.HOLONOMIC_BODY,
              command_topic='/robot_{i}/cmd_vel', mocap_topic=MOCAP, names=names, frame='map',
              **BODIES)
    told = []
    probe.create_subscription(PoseArray, '/robot_1/obstacles', told.append, qos.STATE)
    run_lab(processes, install, probe, lab, params, ('--robots-per-process', '4'),
            lambda: converged(lab, config.vertices, 0.05))
    gaps = np.array([np.linalg.norm(q - PILLAR[:2], axis=1) for _, q, _ in lab.history])
    assert told and all(m.header.frame_id == 'map' for m in told)
    assert any(len(m.poses) == 1 for m in told)
    for message in told:
        for pose in message.poses:
            assert abs(math.dist((pose.position.x, pose.position.y), PILLAR[:2])
                       - PILLAR[2]) < 1e-9
    assert len(gaps) > 100 and gaps.min() > PILLAR[2] + config.body.radius, gaps.min()
    repelling = PILLAR[2] + config.body.radius + config.obstacles.clearance
    assert gaps[:, 0].min() < repelling, 'robot 1 came where the pillar repels it'
    for _, robot, (vx, vy, vz, ax, ay, az) in lab.heard:
        heading = lab.heading[robot - 1]
        world = (math.cos(heading) * vx - math.sin(heading) * vy,
                 math.sin(heading) * vx + math.cos(heading) * vy)
        assert max(map(abs, world)) <= bound * (1.0 + 1e-9), (robot, world, bound)
