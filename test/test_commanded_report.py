# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The report states what the robots commanded (issue 34, item 2), from a bag of unicycles.

Each robot's cmd_vel is read at the heading of the pose it answered (its stamp), not at the
heading of a later sample while the command is held; the held command at the sample's heading
is reported on its own line against its own bound sqrt(2) c M1. A real excess is still shown,
and unstamped commands, which do not say which pose they answered, are said to be unknown.
"""

import json
import math
import os

from bag_messages import header, pose_msg, unicycle_twist
from formation_ros.core.maths.unicycle import unicycle_commands
from formation_ros.core.settings.params import validate
from formation_ros.core.settings.params_file import load_params_file
from formation_ros.ros.bag_writer import BagWriter, TYPESTORE
from formation_ros.tools.report import main as report_main
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PARAMS = os.path.join(ROOT, 'config', 'world_turtlebot3.yaml')
NS = 1_000_000_000
PERIOD = 20_000_000
TYPES = TYPESTORE.types
TURN = 0.5
"""How far robot 1 turns between samples while it holds its one command, rad."""
WANTED = (0.15, 0.15)
"""Robot 1's hand-point velocity: both components at c M1, m/s."""
TURNED = max(0.15 * (math.cos(k * TURN) + math.sin(k * TURN)) for k in range(4))
"""The largest component of WANTED turned by the heading robot 1 turned since, m/s."""


def write_bag(folder, stamped, excess):
    """
    Write a bag of four unicycles over four samples; return the parameters' bound c M1.

    Robot 1 answers the first pose only, with (v, w) for WANTED at its heading, then turns by
    TURN per sample holding it; robot 2 answers every pose asking its hand point for ``excess``
    m/s along x; robots 3 and 4 ask for nothing.
    """
    values = load_params_file(PARAMS)
    values['command.type'] = 'twist_stamped' if stamped else 'twist'
    config = validate(values)
    kind = 'geometry_msgs/msg/TwistStamped' if stamped else 'geometry_msgs/msg/Twist'
    with BagWriter(str(folder)) as bag:
        for i in range(1, 5):
            bag.add_topic(f'/robot_{i}/pose', 'geometry_msgs/msg/PoseStamped')
            bag.add_topic(f'/robot_{i}/cmd_vel', kind)
        bag.write_params(config.values, 1)
        for k in range(4):
            stamp = NS + k * PERIOD
            headings = [1.0 + TURN * k, -0.4, 0.3, 2.0]
            for i in range(4):
                bag.write(f'/robot_{i + 1}/pose', stamp + 1, TYPESTORE.serialize_cdr(
                    pose_msg(stamp, config.start[i], headings[i]),
                    'geometry_msgs/msg/PoseStamped'))
            commands = {2: unicycle_commands((excess, 0.0), headings[1], 0.08)}
            if k == 0:
                commands[1] = unicycle_commands(WANTED, headings[0], 0.08)
            for i, (v, w) in commands.items():
                message = unicycle_twist(v, w)
                if stamped:
                    message = TYPES['geometry_msgs/msg/TwistStamped'](
                        header=header(stamp, f'robot_{i}/base_link'), twist=message)
                bag.write(f'/robot_{i}/cmd_vel', stamp + 2,
                          TYPESTORE.serialize_cdr(message, kind))
    return config.law().u_bound


def report(tmp_path, capsys, stamped, excess):
    """Report a bag of :func:`write_bag`; return (metrics, the report's lines, c M1)."""
    bound = write_bag(tmp_path / 'bag', stamped, excess)
    capsys.readouterr()
    assert report_main([str(tmp_path / 'bag'), '--out', str(tmp_path / 'report'),
                        '--no-plots']) == 0
    lines = capsys.readouterr().out.splitlines()
    return json.loads((tmp_path / 'report' / 'metrics.json').read_text()), lines, bound


def line(lines, start):
    return next(text for text in lines if text.strip().startswith(start))


def test_a_held_command_is_read_at_the_heading_it_answered(tmp_path, capsys):
    metrics, lines, bound = report(tmp_path, capsys, True, 0.1)
    assert metrics['max_abs_u_hat_component'] == pytest.approx(bound, rel=1e-12)
    assert metrics['bound_violations'] == 0
    assert 'unknown_commands' not in metrics
    assert line(lines, 'max |u_hat| component:').endswith(
        '0.15 m/s (bound c*M1 = 0.15 m/s, 0 above)')
    assert TURNED > bound
    assert metrics['max_abs_u_hat_held_component'] == pytest.approx(TURNED, rel=1e-9)
    assert metrics['u_hat_held_bound'] == pytest.approx(math.sqrt(2.0) * bound)
    assert metrics['u_hat_held_above_bound'] == 0
    assert '(bound sqrt(2) c M1 = 0.2121 m/s, 0 above)' in line(lines, 'max |u_hat_held|')


def test_a_command_beyond_the_bound_is_still_shown(tmp_path, capsys):
    metrics, lines, bound = report(tmp_path, capsys, True, 0.2)
    assert metrics['max_abs_u_hat_component'] == pytest.approx(0.2, rel=1e-9)
    assert metrics['bound_violations'] == 4
    assert line(lines, 'max |u_hat| component:').endswith(
        '0.2 m/s (bound c*M1 = 0.15 m/s, 4 above)')


def test_unstamped_commands_of_unicycles_are_said_to_be_unknown(tmp_path, capsys):
    metrics, lines, bound = report(tmp_path, capsys, False, 0.2)
    assert metrics['max_abs_u_hat_component'] == 0.0
    assert metrics['bound_violations'] == 0
    assert metrics['unknown_commands'] == 8
    assert line(lines, 'max |u_hat| component:').strip() == (
        'max |u_hat| component: 0 m/s (bound c*M1 = 0.15 m/s, 0 above; 8 of the 16 sampled '
        'commands not known: unstamped commands do not say which state they answered)')
    assert metrics['u_hat_held_above_bound'] == 0
    assert metrics['max_abs_u_hat_held_component'] == pytest.approx(TURNED, rel=1e-9)
