# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant node publishes what its model says the robots sense: noisy, late, honestly stamped."""

import json

from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.model.plant import Commands, PlantModel
from formation_ros.core.settings.declarations import Exe
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseStamped
from helpers import node, write_params
import numpy as np
from rosgraph_msgs.msg import Clock as ClockMsg

DELAY_STEPS = 5


def test_plant_publishes_noisy_states_a_delay_late_stamped_when_measured(
        processes, install, probe, tmp_path):
    out = tmp_path / 'plant'
    params = write_params(tmp_path, 'square_4.yaml', {
        'plant.state_delay': 0.05, 'plant.pose_noise': 0.02, 'plant.rate': 100.0,
        'plant.publish_rate': 100.0, 'plant.wait_for_robots': False,
        'plant.output_dir': str(out)})
    processes.start(node(install, 'plant', params))
    poses, clocks = {}, []
    probe.create_subscription(
        PoseStamped, '/robot_2/pose',
        lambda m: poses.setdefault(fields.stamp_to_ns(m.header.stamp),
                                   [m.pose.position.x, m.pose.position.y]),
        qos.recording(qos.STATE))
    probe.create_subscription(ClockMsg, '/clock',
                              lambda m: clocks.append(fields.stamp_to_ns(m.clock)),
                              qos.recording(qos.CLOCK))
    assert probe.spin_until(lambda: len(poses) > 30, 60), processes.log('plant')
    [info] = processes.stop(['plant'])
    assert info.returncode == 0, processes.log('plant')

    config = load_config(params, Exe.PLANT)
    settings = config.plant
    model = PlantModel(config.start, config.sensing_radii, settings.step_ns, config.law(),
                       config.reference(), settings.input_timeout_ns,
                       settings.collision_distance, bodies=make_bodies(config.body),
                       imperfections=config.imperfections)
    assert model.delay_steps == DELAY_STEPS
    sensed = {}
    while model.t_ns <= max(clocks):
        state = model.sensed()
        sensed[model.t_ns] = (state.stamp_ns, state.q[1].tolist())
        model.advance(Commands.empty(config.num_robots, config.dim))
    step = settings.step_ns
    first = min(stamp for stamp in poses if stamp > 0)
    late = [clock for clock in clocks if clock - DELAY_STEPS * step >= first]
    assert late and all(clock - DELAY_STEPS * step in poses for clock in late[:-1])
    for clock in late[:-1]:
        stamp, position = sensed[clock]
        assert stamp == clock - DELAY_STEPS * step and poses[stamp] == position
    noise = np.array([poses[s] for s in poses]) - config.start[1]
    assert np.all(np.abs(noise) > 0.0) and np.all(np.abs(noise) < 0.2)
    stats = json.loads((out / 'plant_stats.json').read_text())
    last_clock = int(round(stats['simulated_time'] * 1e9))
    assert max(poses) <= last_clock - DELAY_STEPS * step, (max(poses), last_clock)
    assert stats['imperfections'] == {'plant.actuator_lag': 0.0, 'plant.max_acceleration': 0.0,
                                      'plant.pose_noise': 0.02, 'plant.state_delay': 0.05}
    assert stats['state_delay_steps'] == DELAY_STEPS
