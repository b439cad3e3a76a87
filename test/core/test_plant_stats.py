# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's run statistics (plant_stats.py): latency, the record, plant_stats.json."""

import json

from formation_ros.core.maths.law import make_law
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, PlantModel
from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.plant_intake import TEAM
from formation_ros.core.rules.plant_stats import (AnswerTimes, DurationHistogram, PUBLISHES_TIMED,
                                                  RunStats)
from formation_ros.core.runs.output import stats_text
import numpy as np
import pytest

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
FIXED = Reference('fixed', 2)
MS = 10_000_000
KEYS = ['integrator', 'simulated_time', 'wall_time', 'achieved_step_rate', 'steps', 'collisions',
        'bound_violations', 'stale_command_steps', 'bad_command_steps', 'missing_command_steps',
        'future_command_steps', 'saturated_command_steps', 'held_steps', 'shape_changes',
        'events', 'imperfections', 'state_delay_steps', 'oldest_command_counted',
        'command_age_steps', 'answer_latency', 'by_robot', 'wrong_frame_command_messages',
        'malformed_command_messages', 'non_finite_command_messages', 'transport']
"""The keys of plant_stats.json, in order, as tools/report.py, bench/ and the tests read them."""


def model():
    start = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    return PlantModel(start, np.full(3, 1.0), MS, LAW, FIXED, 50 * MS, 1e-3)


def test_duration_histogram_percentiles_against_numpy():
    rng = np.random.default_rng(3)
    values = rng.exponential(2_000_000, 5000).astype(np.int64)
    histogram = DurationHistogram(bin_ns=100_000, limit_ns=10_000_000)
    assert histogram.percentile_ns(50) is None
    assert histogram.record() == {'count': 0, 'p50_ms': None, 'p99_ms': None, 'max_ms': 0.0}
    histogram.add(values[:2500])
    histogram.add(values[2500:])
    assert histogram.count == 5000 and histogram.largest_ns == values.max()
    for percent in (50, 90, 99):
        exact = np.percentile(values, percent)
        assert exact - 100_000 <= histogram.percentile_ns(percent) <= exact + 100_000, percent
    assert histogram.percentile_ns(100) == values.max()
    histogram.add([-5, 0])
    assert histogram.bins[0] >= 2


def test_answer_times_count_each_new_command_of_a_state_published_lately():
    answers = AnswerTimes(3)
    answers.published(0, 1_000_000)
    answers.published(0, 9_000_000)
    commands = Commands.empty(3, 2)
    commands.store(0, (0.0, 0.0), 0)
    commands.store(1, (0.0, 0.0), 77)
    arrived = np.array([3_000_000, 4_000_000, 0], dtype=np.int64)
    answers.time(commands, arrived)
    assert answers.latency.count == 1 and answers.latency.largest_ns == 2_000_000
    answers.time(commands, arrived)
    assert answers.latency.count == 1
    for stamp in range(1, PUBLISHES_TIMED + 1):
        answers.published(stamp, 0)
    assert 0 not in answers.published_ns and len(answers.published_ns) == PUBLISHES_TIMED


def run_steps(stats, plant, steps, held=False):
    commands = Commands.empty(3, 2)
    for _ in range(steps):
        commands.store_all(np.full((3, 2), 0.5), plant.t_ns)
        report = plant.advance(commands)
        stats.stepped(plant, report, held)
    return report


def test_the_record_keeps_the_keys_and_round_trips_through_json():
    plant = model()
    stats = RunStats(plant, publish_every=2, lockstep=True, unicycles=False)
    run_steps(stats, plant, 4, held=True)
    refusals = Refusals()
    for source, reason in [(2, Reason.FRAME), (2, Reason.FRAME), (0, Reason.MALFORMED),
                           (TEAM, Reason.MALFORMED), ('shape', Reason.CHANGE)]:
        refusals.add(source, reason)
    record = stats.record(plant, 2.0, refusals, 1, [], {'plant.pose_noise': 0.0}, 'robot')
    assert list(record) == KEYS
    assert record['steps'] == 4 and record['held_steps'] == 4
    assert record['integrator'] == 'plant, zero-order hold, dt = 0.01 s, lockstep'
    assert record['achieved_step_rate'] == 2.0
    read = json.loads(stats_text(record))
    assert list(read) == KEYS
    assert read['wrong_frame_command_messages'] == {'3': 2}
    assert read['malformed_command_messages'] == {'1': 1}
    assert read['by_robot']['missing'] == {} and read['answer_latency']['count'] == 0
    team = stats.record(plant, 0.0, refusals, 0, [], {}, 'team')
    assert list(team) == KEYS + ['malformed_team_command_messages',
                                 'non_finite_team_command_messages']
    assert team['malformed_team_command_messages'] == 1 and team['achieved_step_rate'] is None


def test_the_closest_pair_is_sampled_on_published_states_and_u_hat_kept():
    plant = model()
    stats = RunStats(plant, publish_every=3, lockstep=False, unicycles=False)
    assert stats.closest == pytest.approx(3.0)
    commands = Commands.empty(3, 2)
    commands.store_all([[0.0, 0.0], [-1.0, 0.0], [0.0, 0.0]], 0)
    sampled = []
    for _ in range(4):
        commands.stamp_ns[:] = plant.t_ns
        sampled.append(stats.stepped(plant, plant.advance(commands), False))
    assert sampled == [True, False, False, True]
    assert stats.closest == pytest.approx(3.0 - 0.04)
    assert stats.largest_u_hat == pytest.approx(1.0)
    line = stats.summary(plant, 1.0, plant.points, LAW.u_bound)
    assert line.startswith('plant: 4 steps (0.04 s simulated in 1.0 s), final max error 0 m, '
                           'min pair distance 2.96 m, max |u_hat| 1 m/s')
