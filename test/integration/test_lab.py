# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A lab without the plant: relay + robots + reference against the stand-in of lab_standin.py.

The bodies lag their commands and cannot accelerate without limit, the mocap is noisy and
stamps every body on its own, the bases take what real ones take (plain Twist in the body frame
of a holonomic base; TwistStamped (v, w) in base_link of a diff_drive-like one, which drops
old stamps). Every node runs on wall-clock time in world_frame 'map', and each robot's cmd_vel
is remapped onto its base's topic, as in a lab.
"""

import math

from formation_ros.core.params import load_config
from formation_ros.core.params_file import load_params_file, write_params_file
from helpers import CONFIG, node
from lab_standin import Base, Lab
import numpy as np

START_UP = 90.0
NAMES = ['rb1', 'rb2', 'rb3', 'rb4']
LAB = {'world_frame': 'map', 'relay.source_topic': '/mocap/{name}/pose',
       'relay.source_names': NAMES}
START = [[0.3, 0.1], [-0.4, 0.3], [-0.2, -0.5], [0.5, -0.3]]
BODIES = {'lag': 0.05, 'max_acceleration': 2.0, 'noise': 0.003, 'rate': 100.0}


def lab_params(folder, source, changes, drop=()):
    """Write a shipped config with ``changes`` and without the parameters in ``drop``."""
    values = load_params_file(f'{CONFIG}/{source}')
    values.update(LAB, **changes)
    for name in drop:
        values.pop(name, None)
    path = str(folder / 'lab.yaml')
    write_params_file(path, values)
    return path


def start_lab(processes, install, params):
    processes.start(node(install, 'relay', params))
    processes.start(node(install, 'reference', params))
    for i in range(1, 5):
        processes.start(node(install, 'robot', params, '-r', f'__ns:=/robot_{i}',
                             '-r', f'cmd_vel:=/base_{i}/cmd_vel', process=f'robot_{i}'))


def converged(lab, targets, tolerance, points=None):
    """Whether the latest control points (``points(q, heading)``) are within ``tolerance``."""
    latest = lab.latest()
    if latest is None:
        return False
    _, q, heading = latest
    where = q if points is None else points(q, heading)
    return bool(np.max(np.linalg.norm(where - targets, axis=1)) < tolerance)


def test_holonomic_bases_taking_body_frame_twists_converge(processes, install, probe, tmp_path):
    params = lab_params(tmp_path, 'square_4.yaml', {
        'controller.gain': 0.6, 'body.radius': 0.1, 'command.type': 'twist',
        'command.frame': 'body'})
    config = load_config(params)
    bound = config.law().u_bound
    lab = Lab(q=START, heading=[0.0, 1.3, -2.1, 2.8], base=Base.HOLONOMIC_BODY,
              command_topic='/base_{i}/cmd_vel', mocap_topic='/mocap/rb{i}/pose', frame='map',
              **BODIES)
    lab.attach(probe)
    start_lab(processes, install, params)
    assert probe.spin_until(lambda: converged(lab, config.vertices, 0.05), START_UP), \
        (lab.latest(), processes.log('robot_2'), processes.log('relay'))
    assert lab.commands and not lab.dropped, lab.dropped
    largest = 0.0
    for _, robot, (vx, vy, vz, ax, ay, az) in lab.commands:
        heading = lab.heading[robot - 1]
        world = (math.cos(heading) * vx - math.sin(heading) * vy,
                 math.sin(heading) * vx + math.cos(heading) * vy)
        assert max(map(abs, world)) <= bound * (1.0 + 1e-9), (robot, world, bound)
        assert vz == ax == ay == az == 0.0
        largest = max(largest, *map(abs, world))
    assert largest > 0.5 * bound
    assert lab.closest_pair() > 2.0 * config.body.radius
    for name in ('relay', 'robot_1'):
        assert 'Traceback' not in processes.log(name)


def hand_points(q, heading, hand):
    return q + hand * np.stack((np.cos(heading), np.sin(heading)), axis=1)


def test_unicycles_on_diff_drive_bases_converge(processes, install, probe, tmp_path):
    hand = 0.2
    params = lab_params(tmp_path, 'unicycle_2d.yaml', {
        'num_robots': 4, 'formation.vertices': [0.6, 0.6, -0.6, 0.6, -0.6, -0.6, 0.6, -0.6],
        'controller.gain': 0.6, 'body.hand_distance': hand, 'body.radius': 0.05,
        'start.random_radius': 0.8, 'start.min_separation': 0.5},
        drop=('body.max_linear', 'body.max_angular'))
    config = load_config(params)
    v_bound = math.sqrt(2.0) * config.law().u_bound
    w_bound = v_bound / hand
    lab = Lab(q=START, heading=[0.5, 2.0, -1.0, -2.5], base=Base.DIFF_DRIVE,
              command_topic='/base_{i}/cmd_vel', mocap_topic='/mocap/rb{i}/pose', frame='map',
              max_angular_acceleration=10.0, cmd_vel_timeout=0.5, **BODIES)
    lab.attach(probe)
    start_lab(processes, install, params)

    def done():
        return converged(lab, config.vertices, 0.08, lambda q, th: hand_points(q, th, hand))

    assert probe.spin_until(done, START_UP), \
        (lab.latest(), lab.dropped, processes.log('robot_2'), processes.log('relay'))
    assert lab.commands
    assert not [why for why in lab.dropped if why.startswith('frame')], lab.dropped
    for _, robot, (v, vy, vz, ax, ay, w) in lab.commands:
        assert abs(v) <= v_bound * (1.0 + 1e-9) and abs(w) <= w_bound * (1.0 + 1e-9)
        assert vy == vz == ax == ay == 0.0
    assert max(abs(c[0]) for _, _, c in lab.commands) > 0.3 * v_bound
    assert max(abs(c[5]) for _, _, c in lab.commands) > 0.3 * w_bound
    assert lab.closest_pair() > 2.0 * config.body.radius
    for name in ('relay', 'robot_1'):
        assert 'Traceback' not in processes.log(name)
