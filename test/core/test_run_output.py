# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A node's run output (core/runs/output.py): chunks, the files at the end, a failure once."""

import json
import math
import os

from formation_ros.core.maths.law import make_law
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, PLANT_STATS_FILE, PlantModel
from formation_ros.core.rules.admission import Refusals
from formation_ros.core.rules.plant_stats import RunStats, trajectory_sample
from formation_ros.core.runs.output import (ChunkShapeError, FixedShape, RunOutput, stats_text,
                                            trajectory_from_chunks)
from formation_ros.core.runs.trajectory import CHUNKS_DIR, ChunkWriter, Trajectory, TRAJECTORY_FILE
from formation_ros.core.runs.world_stats import (BlowUp, Contact, ObstacleContact,
                                                 WorldRunStats)
import numpy as np
import pytest

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
FIXED = Reference('fixed', 2)
MS = 10_000_000
SHAPE = FixedShape(np.zeros((3, 2)))


def model():
    start = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    return PlantModel(start, np.full(3, 1.0), MS, LAW, FIXED, 50 * MS, 1e-3)


def plant_output(tmp_path, steps):
    """Return a plant model stepped ``steps`` times and its output, each step a sample."""
    plant = model()
    output = RunOutput(str(tmp_path), 'plant', 'the plant goes on controlling')
    assert output.start(plant.t) is None
    commands = Commands.empty(3, 2)
    for _ in range(steps):
        commands.store_all(np.zeros((3, 2)), plant.t_ns)
        t, q, u, extras = trajectory_sample(plant.advance(commands), False)
        output.append(t, q, u, **extras)
    return plant, output


def test_run_output_writes_both_files_then_drops_the_chunks(tmp_path):
    plant, output = plant_output(tmp_path, 3)
    assert output.flush(plant.t) is None and output.chunks.count == 1
    record = RunStats(plant, 1, False, False).record(plant, 1.0, Refusals(), 0, [], {}, 'robot')
    assert output.write(PLANT_STATS_FILE, record, FIXED.sample, SHAPE, False, plant.t) is None
    assert output.trajectory_written and output.running
    assert json.loads((tmp_path / PLANT_STATS_FILE).read_text()) == json.loads(stats_text(record))
    assert len(Trajectory.load(str(tmp_path / TRAJECTORY_FILE)).t) == 3
    assert not os.path.exists(tmp_path / CHUNKS_DIR)


def test_run_output_that_cannot_write_says_so_once_and_keeps_the_chunks(tmp_path):
    _, output = plant_output(tmp_path, 1)
    (tmp_path / PLANT_STATS_FILE).mkdir()
    line = output.write(PLANT_STATS_FILE, {}, FIXED.sample, SHAPE, False, 0.01)
    assert output.failure is not None and not output.running
    assert line.startswith('plant: output stopped at t = 0.01 s: cannot write to ')
    assert 'keeps the trajectory up to t = 0.00 s in 1 chunks' in line
    assert line.endswith('the plant goes on controlling and writes nothing more there')
    assert os.path.exists(tmp_path / CHUNKS_DIR)
    assert output.flush(0.02) is None and output.write(PLANT_STATS_FILE, {}, FIXED.sample, SHAPE,
                                                       False, 0.02) is None


def test_a_start_that_cannot_write_its_first_file_says_so_and_keeps_nothing(tmp_path):
    output = RunOutput(str(tmp_path), 'world', 'the world goes on')

    def first(directory):
        raise PermissionError(13, 'Permission denied')

    line = output.start(1.5, first)
    assert line == (f'world: output stopped at t = 1.50 s: cannot write to {tmp_path} '
                    f'(Permission denied); {tmp_path} keeps nothing of the trajectory; the world '
                    'goes on and writes nothing more there')
    assert not output.running and output.chunks is None
    output.append(0.0, np.zeros((3, 2)), np.zeros((3, 2)))
    assert not os.path.exists(tmp_path / CHUNKS_DIR)


def test_the_trajectory_from_chunks_checks_the_robots_and_reads_held_commands(tmp_path):
    writer = ChunkWriter(str(tmp_path / CHUNKS_DIR))
    for k in range(4):
        writer.append(0.5 * k, np.full((3, 2), float(k)), np.ones((3, 2)),
                      u_held=np.full((3, 2), 2.0))
    writer.flush()
    trajectory = trajectory_from_chunks(writer.folder, FIXED.sample, SHAPE, False, (3, 2))
    assert trajectory.t.tolist() == [0.0, 0.5, 1.0, 1.5] and trajectory.heading is None
    assert np.all(trajectory.u_held == 2.0) and trajectory.u_hat_held is not None
    each = trajectory_from_chunks(writer.folder, FIXED.sample, lambda t: np.zeros((3, 2)), False)
    assert np.array_equal(each.q_desired, trajectory.q_desired)
    with pytest.raises(ChunkShapeError) as caught:
        trajectory_from_chunks(writer.folder, FIXED.sample, SHAPE, False, (4, 2))
    assert caught.value.found == (3, 2) and str(caught.value).endswith(': 3 robots in 2D')
    with pytest.raises(ValueError):
        trajectory_from_chunks(str(tmp_path), FIXED.sample, SHAPE, False)


def test_world_stats_record_every_field_once_and_no_infinity():
    stats = WorldRunStats(
        contacts=1, min_body_distance=math.inf, min_footprint_gap=-math.inf,
        obstacle_contacts=1, min_obstacle_gap=-0.002, steps=10,
        engine_realtime_factor=40.0, achieved_realtime_factor=1.0, realtime_factor=None,
        wall_time=0.02, simulated_time=0.02, steps_per_second=500.0, ticks_behind=0,
        simulated_time_let_go=0.0, contact_events=[Contact(1, 2, 0.01)],
        obstacle_contact_events=[ObstacleContact(2, 'wall 1', 0.004)],
        stale_command_messages={3: 1, 1: 2}, model='diff_drive', timestep=0.002,
        unstable=BlowUp(2, 0.02, 'its pose moved'), refused_command_messages={'frame': {2: 5}},
        engine_wall_time=0.0005, mujoco_version='3')
    record = json.loads(stats_text(stats.record()))
    assert list(record) == [
        'contacts', 'min_body_distance', 'min_footprint_gap', 'obstacle_contacts',
        'min_obstacle_gap', 'steps', 'engine_realtime_factor', 'achieved_realtime_factor',
        'realtime_factor', 'wall_time', 'simulated_time', 'steps_per_second', 'ticks_behind',
        'simulated_time_let_go', 'contact_events', 'obstacle_contact_events',
        'stale_command_messages', 'model', 'timestep', 'unstable', 'refused_command_messages',
        'engine_wall_time', 'mujoco_version']
    assert record['min_body_distance'] is None and record['realtime_factor'] is None
    assert record['contact_events'] == [{'i': 1, 'j': 2, 't': 0.01}]
    assert record['obstacle_contact_events'] == [{'robot': 2, 'obstacle': 'wall 1', 't': 0.004}]
    assert record['obstacle_contacts'] == 1 and record['min_obstacle_gap'] == -0.002
    assert record['stale_command_messages'] == {'1': 2, '3': 1}
    assert record['refused_command_messages'] == {'frame': {'2': 5}}
    assert record['unstable'] == {'robot': 2, 't': 0.02, 'what': 'its pose moved'}
