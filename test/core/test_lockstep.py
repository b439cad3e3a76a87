# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A lockstep plant's wait for answers (lockstep.py): who is named, when, and the end."""

from formation_ros.core.rules.lockstep import (AnswerWait, NAME_AFTER, REPEAT_EVERY,
                                               robots_and_names, WAITED, WAITING_FOR)
from formation_ros.core.rules.plant_intake import CommandIntake

S = 1_000_000_000


def test_a_silent_robot_is_named_after_the_wait_then_again_and_the_end_said_once():
    wait = AnswerWait()
    wait.published(5 * S // 100, 100.0)
    assert wait.look([3], 100.0 + NAME_AFTER - 0.01) is None
    assert wait.values(100.0 + NAME_AFTER - 0.01) == {}
    line = wait.look([3], 100.0 + NAME_AFTER)
    assert line is not None
    assert line.startswith('lockstep: waiting for robot 3 (robot_3), no answer for 2.0 s at '
                           '0.050 s simulated')
    assert wait.values(101.0 + NAME_AFTER) == {WAITING_FOR: '3', WAITED: 1.0 + NAME_AFTER}
    assert wait.look([3], 100.0 + NAME_AFTER + REPEAT_EVERY - 0.01) is None
    again = wait.look([3], 100.0 + NAME_AFTER + REPEAT_EVERY)
    assert again is not None and 'no answer for 12.0 s' in again
    wait.published(5 * S // 100, 120.0)  # the state sent again: the same wait goes on
    end = wait.look([], 120.5)
    assert end == ('lockstep: every robot answered after 20.5 s; the run goes on at 0.050 s '
                   'simulated')
    assert wait.look([], 120.6) is None and wait.values(120.6) == {}


def test_a_short_wait_is_never_named_and_a_new_state_starts_a_new_wait():
    wait = AnswerWait()
    assert wait.look([1], 50.0) is None  # nothing published yet
    wait.published(S, 10.0)
    assert wait.look([1, 2], 11.0) is None
    assert wait.look([], 11.5) is None
    wait.published(2 * S, 11.5)
    assert wait.look([2], 11.5 + NAME_AFTER - 0.1) is None
    wait.published(3 * S, 13.4)
    assert wait.look([2], 13.4 + NAME_AFTER - 0.1) is None
    assert wait.look([2], 13.4 + NAME_AFTER) is not None


def test_many_silent_robots_are_counted_beyond_five():
    assert robots_and_names([4]) == 'robot 4 (robot_4)'
    assert robots_and_names(list(range(1, 9))) == (
        'robots 1 (robot_1), 2 (robot_2), 3 (robot_3), 4 (robot_4), 5 (robot_5) and 3 more')


def test_the_intake_names_the_robots_whose_latest_command_answers_another_state():
    intake = CommandIntake(['world'] * 3, 'world', 2, False, True)
    assert intake.silent(S) == [1, 2, 3]
    for index in (0, 2):
        assert intake.take(index, 'world', (0.1, 0.0, 0.0), (0.0, 0.0, 0.0), S, 5) is None
    assert intake.take(1, 'world', (0.1, 0.0, 0.0), (0.0, 0.0, 0.0), S - 10, 5) is None
    assert intake.silent(S) == [2] and not intake.answered(S)
    assert intake.take(1, 'world', (0.1, 0.0, 0.0), (0.0, 0.0, 0.0), S, 6) is None
    assert intake.silent(S) == [] and intake.answered(S)
