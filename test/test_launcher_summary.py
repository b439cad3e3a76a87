# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The launcher's closing line of a world run, read from world_stats.json."""

import json

from formation_ros.tools.launcher import world_summary


def write_stats(tmp_path, **fields):
    """Write a world_stats.json with the fields the line reads; return its folder."""
    stats = {'contacts': 0, 'min_body_distance': 0.5, 'min_footprint_gap': 0.28,
             'simulated_time': 12.0, 'achieved_realtime_factor': 0.98, 'obstacle_contacts': 0,
             'min_obstacle_gap': None, **fields}
    (tmp_path / 'world_stats.json').write_text(json.dumps(stats), encoding='utf-8')
    return str(tmp_path)


def test_the_line_states_contacts_and_the_closest_approach(tmp_path):
    line = world_summary(write_stats(tmp_path, contacts=2))
    assert line.startswith('world: 2 contacts between robots, closest approach of two bodies '
                           '0.5 m (footprints +0.28 m apart), 12.00 s simulated at 0.98 x')


def test_a_run_without_a_measured_pair_says_so(tmp_path):
    line = world_summary(write_stats(tmp_path, min_body_distance=None, min_footprint_gap=None))
    assert 'no two bodies measured' in line and 'no statistics' not in line


def test_a_missing_file_is_named(tmp_path):
    assert world_summary(str(tmp_path)).startswith('world: no statistics in ')


def test_a_run_among_obstacles_states_their_contacts_and_closest_gap(tmp_path):
    line = world_summary(write_stats(tmp_path, obstacle_contacts=1, min_obstacle_gap=-0.002))
    assert '(footprints +0.28 m apart), 1 with obstacles (closest footprint -0.002 m from a ' \
           'surface), 12.00 s' in line
    assert 'with obstacles' not in world_summary(write_stats(tmp_path))
