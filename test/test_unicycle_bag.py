# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The report of a recorded unicycle run (bag.py): hand points from poses and headings."""

import json
import os

from bag_messages import header, pose_msg, unicycle_twist
from formation_ros.core.settings.params import load_config
from formation_ros.ros.bag_writer import BagWriter, TYPESTORE
from formation_ros.simulation.simulate import run_metrics, simulate
from formation_ros.tools.report import main as report_main
import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HEXAGON = os.path.join(ROOT, 'config', 'unicycle_2d.yaml')
NS = 1_000_000_000
TYPES = TYPESTORE.types


def twist_msg(stamp_ns, robot, command):
    return TYPES['geometry_msgs/msg/TwistStamped'](
        header=header(stamp_ns, f'robot_{robot}/base_link'),
        twist=unicycle_twist(command[0], command[1]))


def test_report_of_a_unicycle_bag_equals_the_simulation(tmp_path):
    config = load_config(HEXAGON)
    trajectory = simulate(config, duration=6.0, dt=0.01, sample_dt=0.02)
    bag_dir = tmp_path / 'bag'
    with BagWriter(str(bag_dir)) as bag:
        for i in range(1, config.num_robots + 1):
            bag.add_topic(f'/robot_{i}/pose', 'geometry_msgs/msg/PoseStamped')
            bag.add_topic(f'/robot_{i}/cmd_vel', 'geometry_msgs/msg/TwistStamped')
        bag.write_params(config.values, 1)
        for k, t in enumerate(trajectory.t):
            stamp = int(round(t * NS))
            for i in range(config.num_robots):
                bag.write(f'/robot_{i + 1}/pose', stamp + 2, TYPESTORE.serialize_cdr(
                    pose_msg(stamp, trajectory.q_body[k, i], trajectory.heading[k, i]),
                    'geometry_msgs/msg/PoseStamped'))
                bag.write(f'/robot_{i + 1}/cmd_vel', stamp + 3, TYPESTORE.serialize_cdr(
                    twist_msg(stamp, i + 1, trajectory.body_command[k, i]),
                    'geometry_msgs/msg/TwistStamped'))
    assert report_main([str(bag_dir), '--out', str(tmp_path / 'report')]) == 0
    from_bag = json.loads((tmp_path / 'report' / 'metrics.json').read_text())
    direct = run_metrics(trajectory, config, 'test')
    for key in ('min_pair_distance', 'final_max_error', 'max_abs_u_hat_component',
                'min_body_distance', 'max_abs_v', 'max_abs_omega', 'v_bound', 'omega_bound'):
        assert from_bag[key] == pytest.approx(direct[key], rel=1e-9, abs=1e-12), key
    assert from_bag['body_kind'] == 'unicycle'
    assert (tmp_path / 'report' / 'controls.png').stat().st_size > 10000
    assert np.max(trajectory.body_command[..., 1]) > 0.1
