# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world's laser scans over DDS: frame, stamp, shape, rate; bad scanner values refused."""

import math
import os

from formation_ros.core.settings.exits import REFUSED
from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import qos
from helpers import CONFIG, node, SimClock, wait_exit
import numpy as np
from sensor_msgs.msg import LaserScan

START_UP = 90.0
PILLAR = (0.0, 1.0, 0.1)
"""A pillar on robot 1's left: x, y, r (m)."""
BODY = 0.11
"""The bases' body.radius (lab_turtlebot3.yaml), m."""
SCANS = 11
"""Scans heard before the test looks: two simulated seconds at 5 Hz."""


def scan_params(folder):
    """Write two of a lab's bases 0.6 m apart along x, both heading +x, and a pillar."""
    values = load_params_file(os.path.join(CONFIG, 'lab_turtlebot3.yaml'))
    values = {name: value for name, value in values.items()
              if not name.startswith(('relay.', 'start.'))}
    values.update({'num_robots': 2, 'formation.vertices': [0.6, 0.0, -0.6, 0.0],
                   'start.positions': [0.0, 0.0, 0.6, 0.0], 'start.headings': [0.0, 0.0],
                   'obstacles.circles': [float(v) for v in PILLAR],
                   'obstacles.clearance': 0.3})
    path = os.path.join(str(folder), 'params.yaml')
    write_params_file(path, values)
    return path


def stamp(message):
    """Return a message's stamp, s."""
    return message.header.stamp.sec + message.header.stamp.nanosec * 1e-9


def test_the_world_publishes_each_base_s_scan_in_its_frame_at_the_scan_rate(
        processes, install, probe, tmp_path):
    processes.start(node(install, 'world', scan_params(tmp_path)))
    clock = SimClock(probe)
    scans = {1: [], 2: []}
    for i in scans:
        probe.create_subscription(LaserScan, f'/robot_{i}/scan', scans[i].append,
                                  qos.MEASUREMENT)
    assert probe.spin_until(lambda: len(scans[1]) >= SCANS and scans[2], START_UP), \
        processes.log('world')
    assert 'scans of 360 rays at 5 Hz' in processes.log('world')
    last = scans[1][-1]
    assert last.header.frame_id == 'robot_1/base_scan'
    assert scans[2][-1].header.frame_id == 'robot_2/base_scan'
    assert len(last.ranges) == 360 and not last.intensities
    assert last.angle_min == 0.0
    assert math.isclose(last.angle_increment, 2 * math.pi / 360, rel_tol=1e-6)
    assert math.isclose(last.angle_max, 359 * 2 * math.pi / 360, rel_tol=1e-6)
    assert math.isclose(last.range_min, 0.12, rel_tol=1e-6)
    assert math.isclose(last.range_max, 3.5, rel_tol=1e-6)
    assert math.isclose(last.scan_time, 0.2, rel_tol=1e-6) and last.time_increment == 0.0
    # Stamped in simulated time, every 0.2 s (best effort may drop one; none comes early).
    stamps = np.array([stamp(scan) for scan in scans[1]])
    steps = np.round(stamps / 0.2)
    assert np.allclose(stamps, 0.2 * steps, atol=1e-9), stamps
    gaps = np.diff(steps)
    assert np.all(gaps >= 1) and np.mean(gaps == 1) > 0.8, stamps
    assert stamps[-1] <= clock.seconds + 1e-9
    ranges = np.array(last.ranges)
    assert math.isclose(ranges[0], 0.6 - BODY, abs_tol=1e-3), 'robot 2, straight ahead'
    assert math.isclose(ranges[90], PILLAR[1] - PILLAR[2], abs_tol=1e-3), 'the pillar, left'
    assert np.isinf(ranges[180]) and ranges[180] > 0, 'nothing behind within 3.5 m'


HOSTILE = {'rays_zero': ('world.scan_rays:=0', "'world.scan_rays': must be >= 1"),
           'range_crossed': ('world.scan_range_min:=4.0',
                             "'world.scan_range_min': 4 m is not less than world.scan_range_max"),
           'noise_negative': ('world.scan_noise:=-0.1', "'world.scan_noise': must be >= 0")}


def test_bad_scanner_values_give_one_line_and_exit_2(processes, install, probe, tmp_path):
    params = scan_params(tmp_path)
    for name, (value, _) in HOSTILE.items():
        processes.start(node(install, 'world', params, '-p', value, process=name))
    for name, (_, text) in HOSTILE.items():
        info = wait_exit(probe, processes, name, START_UP)
        log = processes.log(name)
        assert info is not None and info.returncode == REFUSED, (name, log)
        assert text in log and 'Traceback' not in log, (name, log)
        assert len([line for line in log.splitlines() if line.strip()]) == 1, (name, log)
