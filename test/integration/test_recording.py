# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Recording real runs: rosbag2 (MCAP) from the recorder, the report, diagnostics, markers."""

import json

from formation_ros.core.runs.metrics import compute_metrics
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from formation_ros.simulation.simulate import simulate
from formation_ros.tools.bag import read_messages
from geometry_msgs.msg import PoseArray, PoseStamped
from helpers import (launch, node, plant_value, SimClock, SQUARE, Statuses, stop_when,
                     write_params)
import numpy as np
from visualization_msgs.msg import MarkerArray


def test_recorded_run_reads_back_and_agrees_with_the_plant(processes, install, probe,
                                                           tmp_path):
    markers = []
    probe.create_subscription(MarkerArray, '/formation/markers', markers.append, qos.MARKERS)
    statuses = Statuses(probe)
    bag, out = tmp_path / 'bag', tmp_path / 'run'
    launch(processes, install, SQUARE, out=out, record=bag, plots=True, per_process=4)
    info = stop_when(probe, processes, lambda: plant_value(
        statuses, 'steps with fresh commands') >= 500 and bool(markers), timeout=300)
    assert info.returncode == 0, processes.log('launcher')
    topics, counts = read_messages(str(bag))
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    for i in range(1, 5):
        assert counts[f'/robot_{i}/pose'] > 100 and counts[f'/robot_{i}/cmd_vel'] > 100
    assert counts['/clock'] > 100 and counts['/formation/reference'] > 10
    bound = load_config(SQUARE).law().u_bound
    commands = [m for i in range(1, 5) for _, m in topics[f'/robot_{i}/cmd_vel']]
    assert max(max(abs(m.twist.linear.x), abs(m.twist.linear.y)) for m in commands) <= bound
    statuses = {s.name for _, m in topics['/diagnostics'] for s in m.status}
    assert {'formation_ros/plant', 'formation_ros/reference'} <= statuses
    assert {f'formation_ros/robot_{i}' for i in range(1, 5)} <= statuses
    from_bag = json.loads((out / 'metrics.json').read_text())
    plant = Trajectory.load(str(out / 'trajectory.npz'))
    stepped = set(np.round(plant.t * 1e9).astype(np.int64).tolist())
    for i in range(1, 5):
        recorded = {fields.stamp_to_ns(m.header.stamp) for _, m in topics[f'/robot_{i}/pose']}
        assert stepped <= recorded, sorted(stepped - recorded)[:10]
    printed = compute_metrics(plant.t, plant.q, plant.u, plant.u_hat, plant.q_desired, bound)
    assert from_bag['source'] == 'rosbag2'
    assert from_bag['min_pair_distance'] == printed['min_pair_distance']
    assert from_bag['max_abs_u_component'] == printed['max_abs_u_component']
    assert abs(from_bag['final_max_error'] - printed['final_max_error']) < 1e-3
    assert abs(from_bag['settle_time'] - printed['settle_time']) < 0.05
    assert from_bag['collisions'] == 0 and from_bag['bound_violations'] == 0
    assert (out / 'trajectories.png').exists()
    assert markers and {m.ns for m in markers[-1].markers} >= {'robots', 'sensing', 'repulsion',
                                                               'desired'}
    robots = [m for m in markers[-1].markers if m.ns == 'robots'][0]
    assert len(robots.points) == 4


def test_lockstep_bag_reproduces_formation_sim(processes, install, probe, tmp_path):
    changes = {'plant.lockstep': True, 'plant.realtime_factor': 200.0}
    params = write_params(tmp_path, 'circle_2d.yaml', changes)
    clock = SimClock(probe)
    bag = tmp_path / 'bag'
    launch(processes, install, params, record=bag, per_process=4)
    info = stop_when(probe, processes, lambda: clock.seconds >= 1.5)
    assert info.returncode == 0, processes.log('launcher')
    topics, _ = read_messages(str(bag))
    config = load_config(params)
    poses = {}
    for i in range(config.num_robots):
        for _, message in topics[f'/robot_{i + 1}/pose']:
            stamp = fields.stamp_to_ns(message.header.stamp)
            poses.setdefault(stamp, {})[i] = (message.pose.position.x, message.pose.position.y)
    stamps = sorted(s for s, seen in poses.items() if len(seen) == config.num_robots)
    steps = [round(s / 1e7) for s in stamps]
    assert steps[-1] >= 150, steps[-5:]
    assert len(steps) >= 0.9 * (steps[-1] + 1), 'the bag lost more than a tenth of the states'

    sim = simulate(config, duration=steps[-1] * 0.01, dt=0.01, sample_dt=0.01)
    recorded = np.array([[poses[s][i] for i in range(config.num_robots)] for s in stamps])
    assert np.max(np.abs(recorded - sim.q[steps])) < 1e-9


def test_bag_of_a_run_stopped_with_sigint_is_complete(processes, install, probe, tmp_path):
    clock = SimClock(probe)
    bag = tmp_path / 'bag'
    launch(processes, install, SQUARE, record=bag, per_process=4)
    info = stop_when(probe, processes, lambda: clock.seconds >= 2.0)
    assert info.returncode == 0, processes.log('launcher')
    topics, counts = read_messages(str(bag))
    assert counts['/robot_1/cmd_vel'] > 20, processes.log('launcher')[-3000:]
    assert counts == {topic: len(messages) for topic, messages in topics.items()}
    assert (bag / 'metrics.json').exists()


def test_recorder_refuses_an_existing_bag(processes, install, tmp_path):
    bag = tmp_path / 'bag'
    bag.mkdir()
    (bag / 'metadata.yaml').write_text('not yours\n')
    processes.start(node(install, 'record', SQUARE, '-p', f'record.path:={bag}'))
    info = processes.wait('record', 60)
    assert info is not None and info.returncode == 2, processes.log('record')
    assert 'refusing to overwrite' in processes.log('record')
    assert (bag / 'metadata.yaml').read_text() == 'not yours\n'


def test_recorder_records_commands_only_once_the_states_reach_it(processes, install, probe,
                                                                 tmp_path):
    processes.start(node(install, 'record', SQUARE, '-p', f'record.path:={tmp_path / "bag"}'))
    assert probe.spin_until(lambda: probe.count_subscribers('/robot_1/pose') == 1, 60), \
        processes.log('record')
    pose = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)
    assert probe.spin_until(lambda: pose.get_subscription_count() == 1, 20)
    # Robot 2's cmd_vel being taken shows that the recorder has looked at its readers since
    # robot 1's pose matched: robot 1, without neighbours, must still be left out.
    probe.create_publisher(PoseStamped, '/robot_2/pose', qos.STATE)
    probe.create_publisher(PoseArray, '/robot_2/neighbors', qos.STATE)
    assert probe.spin_until(lambda: probe.count_subscribers('/robot_2/cmd_vel') == 1, 20), \
        processes.log('record')
    assert probe.count_subscribers('/robot_1/cmd_vel') == 0
    probe.create_publisher(PoseArray, '/robot_1/neighbors', qos.STATE)
    assert probe.spin_until(lambda: probe.count_subscribers('/robot_1/cmd_vel') == 1, 20), \
        processes.log('record')
    assert probe.count_subscribers('/robot_3/cmd_vel') == 0
    assert 'recorded once their pose and neighbours are' in processes.log('record')
    [info] = processes.stop(['record'])
    assert info.returncode == 0, processes.log('record')
