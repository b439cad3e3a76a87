# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A lab without the plant, started as a lab starts it: ``launch_formation.sh --no-plant``.

The lab is the stand-in of lab_standin.py: bodies that lag their commands and cannot accelerate
without limit, a noisy 100 Hz mocap that stamps every body on its own in frame ``map``
(``/vrpn_mocap/<name>/pose``), bases that take what real ones take (plain Twist in the body
frame of a mecanum-like holonomic base on ``/base<i>/cmd_vel``; TwistStamped (v, w) in
``robot_<i>/base_link`` of a TurtleBot3-like diff-drive base on ``/<name>/cmd_vel``, which
drops old stamps). The launcher starts relay, reference and robots on wall-clock time, each
robot's cmd_vel remapped onto its base's topic (``--cmd-topic``); once the bodies are in
formation it is stopped with Ctrl-C and must end cleanly, leaving no process behind.
"""

import math

from formation_ros.core.settings.params import load_config
from formation_ros.core.settings.params_file import load_params_file, write_params_file
from helpers import CONFIG, launch, project_processes, START_UP, stop_when
from lab_standin import Base, Lab
import numpy as np

MOCAP = '/vrpn_mocap/{name}/pose'
START = [[0.3, 0.1], [-0.4, 0.3], [-0.2, -0.5], [0.5, -0.3]]
BODIES = {'lag': 0.05, 'max_acceleration': 2.0, 'noise': 0.003, 'rate': 100.0}


def lab_params(folder, source, changes, drop=()):
    """Write a shipped config in world_frame 'map' with ``changes``, without ``drop``."""
    values = load_params_file(f'{CONFIG}/{source}')
    values.update({'world_frame': 'map'}, **changes)
    for name in drop:
        values.pop(name, None)
    path = str(folder / 'lab.yaml')
    write_params_file(path, values)
    return path


def converged(lab, targets, tolerance, points=None):
    """Whether the latest control points (``points(q, heading)``) are within ``tolerance``."""
    latest = lab.latest()
    if latest is None:
        return False
    _, q, heading = latest
    where = q if points is None else points(q, heading)
    return bool(np.max(np.linalg.norm(where - targets, axis=1)) < tolerance)


def run_lab(processes, install, probe, lab, params, options, done):
    """Launch the lab on ``lab``, Ctrl-C the launcher once ``done()``; assert a clean end."""
    lab.attach(probe)
    launch(processes, install, params, options=('--no-plant', *options))
    info = stop_when(probe, processes, done, timeout=START_UP + 60)
    log = processes.log('launcher')
    assert info.returncode == 0, log[-4000:]
    assert '[relay]' in log and '[plant]' not in log and 'Traceback' not in log, log[-4000:]
    assert project_processes(install) == []


def test_mecanum_like_bases_taking_body_frame_twists_form(processes, install, probe, tmp_path):
    names = ['mec1', 'mec2', 'mec3', 'mec4']
    params = lab_params(tmp_path, 'square_4.yaml', {
        'controller.gain': 0.6, 'body.radius': 0.1, 'command.type': 'twist',
        'command.frame': 'body', 'relay.source_topic': MOCAP, 'relay.source_names': names})
    config = load_config(params)
    bound = config.law().u_bound
    lab = Lab(q=START, heading=[0.0, 1.3, -2.1, 2.8], base=Base.HOLONOMIC_BODY,
              command_topic='/base{i}/cmd_vel', mocap_topic=MOCAP, names=names, frame='map',
              **BODIES)
    run_lab(processes, install, probe, lab, params, ('--cmd-topic', '/base{i}/cmd_vel'),
            lambda: converged(lab, config.vertices, 0.05))
    assert {robot for _, robot, _ in lab.heard} == {1, 2, 3, 4}
    assert not lab.dropped, lab.dropped
    largest = 0.0
    for _, robot, (vx, vy, vz, ax, ay, az) in lab.heard:
        heading = lab.heading[robot - 1]
        world = (math.cos(heading) * vx - math.sin(heading) * vy,
                 math.sin(heading) * vx + math.cos(heading) * vy)
        assert max(map(abs, world)) <= bound * (1.0 + 1e-9), (robot, world, bound)
        assert vz == ax == ay == az == 0.0
        largest = max(largest, *map(abs, world))
    assert largest > 0.5 * bound
    assert lab.closest_pair() > 2.0 * config.body.radius


def hand_points(q, heading, hand):
    return q + hand * np.stack((np.cos(heading), np.sin(heading)), axis=1)


def test_turtlebot3_like_diff_drive_bases_form(processes, install, probe, tmp_path):
    hand = 0.2
    names = ['tb1', 'tb2', 'tb3', 'tb4']
    params = lab_params(tmp_path, 'unicycle_2d.yaml', {
        'num_robots': 4, 'formation.vertices': [0.6, 0.6, -0.6, 0.6, -0.6, -0.6, 0.6, -0.6],
        'controller.gain': 0.6, 'body.hand_distance': hand, 'body.radius': 0.05,
        'start.random_radius': 0.8, 'start.min_separation': 0.5, 'relay.source_names': names},
        drop=('body.max_linear', 'body.max_angular', 'relay.source_topic'))
    config = load_config(params)
    v_bound = math.sqrt(2.0) * config.law().u_bound
    w_bound = v_bound / hand
    lab = Lab(q=START, heading=[0.5, 2.0, -1.0, -2.5], base=Base.DIFF_DRIVE,
              command_topic='/{name}/cmd_vel', mocap_topic=MOCAP, names=names, frame='map',
              max_angular_acceleration=10.0, cmd_vel_timeout=0.5, **BODIES)
    run_lab(processes, install, probe, lab, params,
            ('--cmd-topic', '/{name}/cmd_vel', '--source-topic', MOCAP),
            lambda: converged(lab, config.vertices, 0.08,
                              lambda q, th: hand_points(q, th, hand)))
    assert {robot for _, robot, _ in lab.commands} == {1, 2, 3, 4}
    assert not [why for why in lab.dropped if why.startswith('frame')], lab.dropped
    for _, robot, (v, vy, vz, ax, ay, w) in lab.heard:
        assert abs(v) <= v_bound * (1.0 + 1e-9) and abs(w) <= w_bound * (1.0 + 1e-9)
        assert vy == vz == ax == ay == 0.0
    assert max(abs(c[0]) for _, _, c in lab.commands) > 0.3 * v_bound
    assert max(abs(c[5]) for _, _, c in lab.commands) > 0.3 * w_bound
    assert lab.closest_pair() > 2.0 * config.body.radius
