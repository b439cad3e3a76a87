# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's start gate (core/rules/plant_gate.py): look at the domain, hold the clock, start."""

from formation_ros.core.rules.plant_gate import (CLOCK_MATCH_WAIT, ClockMatch, domain_verdict,
                                                 LOOK_LIMIT, LOOK_PERIOD, LOOK_TIME, Phase,
                                                 refusal_line, StartGate, Verdict, waiting_line)
import pytest

OWN = '/plant'


def test_domain_verdict_names_another_team_by_name_announcement_or_clock():
    assert domain_verdict([], [], False, OWN) is Verdict.FREE
    assert domain_verdict([OWN], [], False, OWN) is Verdict.LEFTOVER
    assert domain_verdict([OWN], [OWN], False, OWN) is Verdict.OTHER_TEAM
    assert domain_verdict([OWN], [], True, OWN) is Verdict.OTHER_TEAM
    assert domain_verdict(['/probe'], [], False, OWN) is Verdict.OTHER_TEAM
    assert domain_verdict([OWN, '/probe'], [], False, OWN) is Verdict.OTHER_TEAM


def test_the_look_waits_for_look_time_then_starts_on_a_free_domain():
    gate = StartGate(10.0, hold=True, own_name=OWN)
    assert gate.phase is Phase.LOOKING and not gate.looked
    assert not gate.look_due(10.0 + LOOK_TIME - 0.01)
    assert gate.look_due(10.0 + LOOK_TIME)
    assert gate.heard(None, [], False, 12.0) is Verdict.FREE
    assert gate.phase is Phase.LOOKING
    assert gate.heard([], [], False, 12.0) is Verdict.FREE
    assert gate.phase is Phase.WAITING and gate.looked


def test_without_holding_for_the_robots_the_look_starts_the_run():
    gate = StartGate(0.0, hold=False, own_name=OWN)
    gate.heard([], [], False, LOOK_TIME)
    assert gate.phase is Phase.RUNNING and gate.looked


def test_a_silent_publisher_of_its_own_name_is_a_leftover_and_the_plant_starts():
    gate = StartGate(0.0, hold=True, own_name=OWN)
    assert gate.heard([OWN], [], False, LOOK_TIME) is Verdict.LEFTOVER
    assert gate.phase is Phase.WAITING and gate.refused == []


def test_an_announced_plant_is_refused_at_once():
    gate = StartGate(0.0, hold=True, own_name=OWN)
    assert gate.heard([OWN], [OWN], False, LOOK_TIME) is Verdict.OTHER_TEAM
    assert gate.phase is Phase.REFUSED and gate.refused == [OWN]
    assert not gate.looked and not gate.look_due(100.0, at_once=True)
    gate.start()
    assert gate.phase is Phase.REFUSED


@pytest.mark.parametrize('others, sent_clock', [(['/probe'], False), ([OWN], True)])
def test_an_unannounced_other_waits_look_limit_for_its_host_then_is_refused(others, sent_clock):
    gate = StartGate(0.0, hold=True, own_name=OWN)
    assert gate.heard(others, [], sent_clock, LOOK_LIMIT - 0.1) is Verdict.OTHER_TEAM
    assert gate.phase is Phase.LOOKING
    gate.heard(others, [], sent_clock, LOOK_LIMIT)
    assert gate.phase is Phase.REFUSED and gate.refused == others


def test_while_waiting_it_looks_every_look_period_and_refuses_another_name_at_once():
    gate = StartGate(0.0, hold=True, own_name=OWN)
    gate.heard([], [], False, 2.0)
    assert gate.look_due(3.0) and not gate.look_due(3.0 + LOOK_PERIOD - 0.01)
    assert gate.look_due(3.0 + 0.1, at_once=True)
    assert gate.look_due(3.1 + LOOK_PERIOD)
    assert gate.heard([OWN], [], True, 4.0) is Verdict.LEFTOVER
    assert gate.phase is Phase.WAITING
    gate.heard(['/probe'], [], False, 4.0)
    assert gate.phase is Phase.REFUSED and gate.refused == ['/probe']


def test_the_clock_waits_for_its_subscribers_at_most_clock_match_wait():
    gate = StartGate(0.0, hold=True, own_name=OWN)
    gate.heard([], [], False, 2.0)
    assert gate.clock_match(True, 20.0) is ClockMatch.WAIT
    assert gate.clock_match(True, 20.0 + CLOCK_MATCH_WAIT - 0.01) is ClockMatch.WAIT
    assert gate.clock_match(True, 20.0 + CLOCK_MATCH_WAIT) is ClockMatch.GAVE_UP
    assert gate.clock_match(False, 20.0) is ClockMatch.MATCHED
    gate.start()
    assert gate.phase is Phase.RUNNING and not gate.look_due(100.0, at_once=True)


def test_the_lines_say_what_is_awaited_and_who_is_refused():
    line = waiting_line(list(range(1, 13)), 12, 0, '/formation/states')
    assert line == ('waiting for 12 of 12 robots to send a command (robots '
                    '[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]...) and for a subscriber of '
                    '/formation/states')
    assert waiting_line([2], 4, 2, None).endswith('and for 2 subscribers on every pose topic')
    assert refusal_line(['/plant'], 91, '/plant on host vm (process 1)').startswith(
        'refusing to start: another plant is on ROS_DOMAIN_ID 91: /plant on host vm '
        '(process 1) publishes /clock (another team?')
    assert 'another /clock publisher is' in refusal_line(['/probe'], 3, '/probe')
