# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world's intake of cmd_vel: the frame and finite rule, stamps, the latest kept per robot."""

from formation_ros.core.rules.admission import Reason
from formation_ros.physics.intake import CommandInbox
import numpy as np

NAN = float('nan')
TIMEOUT_NS = 500_000_000


def unicycles():
    return CommandInbox(['robot_1/base_link', 'robot_2/base_link'], 2, True, True, TIMEOUT_NS)


def test_a_unicycle_command_is_v_and_w_in_its_base_link():
    inbox = unicycles()
    assert inbox.take(1, 'robot_2/base_link', (0.2, 5.0, 7.0), (8.0, 9.0, -0.5), 10, 40) is None
    rows, commands, stamps = inbox.drain()
    assert rows.tolist() == [1] and commands.tolist() == [[0.2, -0.5]]
    assert stamps.tolist() == [10]
    assert len(inbox.drain()[0]) == 0


def test_foreign_frames_and_non_finite_values_used_are_refused():
    inbox = unicycles()
    assert inbox.take(0, 'world', (0.2, 0.0, 0.0), (0.0, 0.0, 0.0), 0, 0) is Reason.FRAME
    assert inbox.take(0, 'robot_1/base_link', (NAN, 0.0, 0.0), (0.0, 0.0, 0.0), 0, 0) \
        is Reason.NON_FINITE
    assert inbox.take(0, 'robot_1/base_link', (0.1, NAN, 0.0), (NAN, 0.0, 0.0), 0, 0) is None
    assert inbox.drain()[1].tolist() == [[0.1, 0.0]]


def test_a_stamp_from_another_clock_is_refused_and_one_just_ahead_is_now():
    inbox = unicycles()
    now = 3_000_000_000
    assert inbox.take(0, 'robot_1/base_link', (0.1, 0, 0), (0, 0, 0), now + TIMEOUT_NS + 1,
                      now) is Reason.CLOCK
    assert inbox.take(0, 'robot_1/base_link', (0.1, 0, 0), (0, 0, 0), now + 5, now) is None
    assert inbox.drain()[2].tolist() == [now]


def test_an_unstamped_command_is_taken_at_the_worlds_time_whatever_its_frame():
    inbox = CommandInbox(['world'] * 3, 3, False, False, TIMEOUT_NS)
    assert inbox.take(2, '', (0.1, 0.2, 0.3), (1.0, 1.0, 1.0), 0, 777) is None
    assert inbox.take(0, '', (0.1, NAN, 0.3), (0.0, 0.0, 0.0), 0, 777) is Reason.NON_FINITE
    rows, commands, stamps = inbox.drain()
    assert rows.tolist() == [2] and stamps.tolist() == [777]
    assert np.array_equal(commands, [[0.1, 0.2, 0.3]])


def test_the_latest_command_of_a_robot_replaces_the_one_before():
    inbox = CommandInbox(['world', 'world'], 2, False, True, TIMEOUT_NS)
    inbox.take(0, 'world', (1.0, 0.0, 0.0), (0, 0, 0), 5, 100)
    inbox.take(0, 'world', (0.0, 2.0, 9.0), (0, 0, 0), 7, 100)
    rows, commands, stamps = inbox.drain()
    assert rows.tolist() == [0] and commands.tolist() == [[0.0, 2.0]] and stamps.tolist() == [7]
