# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Conditions logged once when they start and once when they end, alone or many at once."""

from formation_ros.core.rules.admission import Reason
from formation_ros.ros.once import OnceLog, RefusalLog, robots_named


class Logger:
    """Keeps what is logged as (level, message)."""

    def __init__(self):
        self.lines = []

    def warning(self, message):
        self.lines.append(('warning', message))

    def info(self, message):
        self.lines.append(('info', message))

    def error(self, message):
        self.lines.append(('error', message))


def test_a_group_starting_at_once_is_one_line_and_only_the_new_ones_are_named():
    logger = Logger()
    once = OnceLog(logger)
    assert once.start('stale-1', 'robot 2 late')
    named = []
    new = once.start_group(['stale-0', 'stale-1', 'stale-2'],
                           lambda keys: named.append(list(keys)) or f'{len(keys)} late')
    assert new == ['stale-0', 'stale-2'] and named == [['stale-0', 'stale-2']]
    assert logger.lines == [('warning', 'robot 2 late'), ('warning', '2 late')]
    assert once.start_group(['stale-0', 'stale-2'], lambda keys: 'again') == []
    assert len(logger.lines) == 2
    assert all(once.is_active(f'stale-{i}') for i in range(3))


def test_a_group_ending_names_only_those_that_were_active():
    logger = Logger()
    once = OnceLog(logger)
    once.start_group(['a', 'b'], lambda keys: 'started', level='error')
    ended = once.end_group(['b', 'c'], lambda keys: f"{','.join(keys)} ended")
    assert ended == ['b'] and logger.lines == [('error', 'started'), ('info', 'b ended')]
    assert once.is_active('a') and not once.is_active('b')
    assert once.end_group(['b', 'c'], lambda keys: 'never') == []
    assert len(logger.lines) == 2


def test_robots_are_named_one_by_one_up_to_five_then_counted():
    assert robots_named([3]) == 'robot 4'
    assert robots_named([6, 0, 3]) == 'robots 1, 4 and 7'
    assert robots_named(range(100)) == 'robots 1, 2, 3, 4, 5 and 95 more'


def test_followed_conditions_are_logged_as_they_start_and_end():
    logger = Logger()
    once = OnceLog(logger)
    once.follow('doubled', {'/robot_1/robot': 'robot 1 twice'}, [], lambda name: f'{name} ok')
    once.follow('doubled', {'/robot_1/robot': 'robot 1 twice', '/robot_2/robot': 'robot 2 twice'},
                ['/robot_1/robot'], lambda name: f'{name} ok')
    once.follow('doubled', {'/robot_2/robot': 'robot 2 twice'},
                ['/robot_1/robot', '/robot_2/robot'], lambda name: f'{name} ok')
    assert logger.lines == [('error', 'robot 1 twice'), ('error', 'robot 2 twice'),
                            ('info', '/robot_1/robot ok')]
    assert once.is_active('doubled-/robot_2/robot')
    assert not once.is_active('doubled-/robot_1/robot')


def test_a_refusal_is_counted_every_time_and_logged_once_while_it_lasts():
    logger = Logger()
    log = RefusalLog(OnceLog(logger), lambda source, reason, detail:
                     f'ignoring {source} with {reason.value}{detail}')
    assert log.refuse('pose', Reason.FRAME, ' (map)') is False
    log.refuse('pose', Reason.FRAME, ' (map)')
    log.refuse('pose', Reason.CLOCK, log=False)
    assert log.refusals[('pose', Reason.FRAME)] == 2
    assert log.refusals[('pose', Reason.CLOCK)] == 1
    assert logger.lines == [('error', 'ignoring pose with a frame other than world_frame (map)')]
    log.admitted('pose', Reason.FRAME, 'pose in world_frame again')
    log.admitted('pose', Reason.CLOCK, 'never logged: not said')
    log.refuse('pose', Reason.FRAME, ' (map)')
    assert logger.lines[1:] == [('info', 'pose in world_frame again'),
                                ('error', 'ignoring pose with a frame other than world_frame '
                                          '(map)')]
