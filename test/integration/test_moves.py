# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Moves at runtime, through the reference's parameter service as ``ros2 param set`` uses it.

A fixed reference moves to a new origin and the team follows; a circle changes its speed and
its path goes on from where it was (no jump in q_od); changes a reference cannot take are
refused with the reason, and nothing changes.
"""

import math

from formation_ros.ros import fields, qos
from helpers import CONFIG, launch, node, stop_when, write_params
from nav_msgs.msg import Odometry
import numpy as np
from rcl_interfaces.srv import SetParameters
from test_changes import Poses, set_parameter


def test_a_fixed_reference_moves_and_the_team_follows(processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {})
    poses = Poses(probe, 4)
    client = probe.create_client(SetParameters, '/reference/set_parameters')
    launch(processes, install, params, per_process=4)
    square = np.array([1.0, 1.0, -1.0, 1.0, -1.0, -1.0, 1.0, -1.0])
    assert probe.spin_until(lambda: poses.error(square) < 0.01, 90), processes.log('launcher')
    refused = set_parameter(probe, client, 'reference.speed', 1.0)
    assert not refused.successful and 'circle, figure_eight and helix' in refused.reason
    nan = set_parameter(probe, client, 'reference.origin', [math.nan, 0.0])
    assert not nan.successful and 'finite' in nan.reason
    assert set_parameter(probe, client, 'reference.origin', [2.0, 1.0]).successful
    moved = square + np.tile([2.0, 1.0], 4)
    info = stop_when(probe, processes, lambda: poses.error(moved) < 0.01)
    assert info.returncode == 0, processes.log('launcher')


def test_a_circle_changes_speed_without_a_jump(processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'circle_2d.yaml', {'reference.rate': 100.0})
    samples = []
    probe.create_subscription(Odometry, '/formation/reference', lambda m: samples.append(
        (fields.stamp_to_ns(m.header.stamp), m.pose.pose.position.x, m.pose.pose.position.y,
         math.hypot(m.twist.twist.linear.x, m.twist.twist.linear.y))), qos.REFERENCE)
    processes.start(node(install, 'reference', params))
    client = probe.create_client(SetParameters, '/reference/set_parameters')
    assert probe.spin_until(lambda: len(samples) > 20, 60), processes.log('reference')
    refused = set_parameter(probe, client, 'reference.origin', [1.0, 0.0])
    assert not refused.successful and 'moves only a fixed reference' in refused.reason
    assert not set_parameter(probe, client, 'reference.speed', -1.0).successful
    before = len(samples)
    assert set_parameter(probe, client, 'reference.speed', 2.0).successful
    assert probe.spin_until(lambda: any(v > 1.9 for *_, v in samples[before:])
                            and len(samples) > before + 50, 30)
    track = np.array(samples)
    steps = np.hypot(np.diff(track[:, 1]), np.diff(track[:, 2]))
    gaps = np.diff(track[:, 0]) / 1e9
    assert np.all(steps <= 2.0 * gaps + 1e-6), (steps.max(), gaps[np.argmax(steps)])
    assert np.allclose(np.hypot(track[:, 1], track[:, 2]), 6.0, atol=1e-9)
    speeds = track[:, 3]
    assert np.all(np.isclose(speeds, 0.5) | np.isclose(speeds, 2.0))
    switched = int(np.argmax(np.isclose(speeds, 2.0)))
    assert np.all(np.isclose(speeds[switched:], 2.0)) and switched > 0


def test_a_speed_unicycles_cannot_follow_is_refused(processes, install, probe):
    params = f'{CONFIG}/unicycle_circle_2d.yaml'
    processes.start(node(install, 'reference', params))
    client = probe.create_client(SetParameters, '/reference/set_parameters')
    refused = set_parameter(probe, client, 'reference.speed', 1.0)
    assert not refused.successful and 'body.max_linear' in refused.reason
    assert set_parameter(probe, client, 'reference.speed', 0.08).successful
