# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Which states a robot answers: copies, floods, the budget, stale inputs, start-up, watchdog."""

from formation_ros.core.rules.answers import (Act, AnswerPolicy, BURST, COPY_GAP_NS, FAST_COPIES,
                                              INPUTS, STALE_MARGIN_NS)
import pytest

PERIOD = 20_000_000
TIMEOUT = 500_000_000
WATCH = 20_000_000
STEADY = 10 ** 12


@pytest.fixture
def policy():
    """Return a robot's policy that heard every input once at STEADY and no longer waits."""
    answers = AnswerPolicy(PERIOD, TIMEOUT, WATCH, wait_subscribers=1)
    answers.heard(INPUTS, STEADY)
    assert answers.missing(1, 'cmd_vel') == [] and not answers.waiting
    return answers


def test_start_up_waits_for_every_input_and_the_subscribers():
    answers = AnswerPolicy(PERIOD, TIMEOUT, WATCH, wait_subscribers=2)
    assert answers.missing(5, 'cmd_vel') == list(INPUTS)
    answers.heard(INPUTS, STEADY)
    assert answers.missing(1, 'cmd_vel') == ['2 cmd_vel subscribers (have 1)']
    assert answers.waiting
    assert answers.missing(2, 'cmd_vel') == [] and not answers.waiting


def test_a_new_state_is_answered_once_and_its_copies_resent_at_most_once_a_period(policy):
    policy.heard(['pose', 'neighbour'], STEADY, state=True)
    assert policy.newest(7, STEADY, 0) is Act.ANSWER
    policy.answered_state(7)
    assert policy.newest(7, STEADY, 0) is Act.DROP
    policy.heard(['pose'], STEADY + PERIOD * 2, state=True)
    assert policy.newest(7, STEADY + PERIOD * 2, 0) is Act.RESEND
    policy.heard(['pose'], STEADY + PERIOD * 3 - 1, state=True)
    assert policy.newest(7, STEADY + PERIOD * 3 - 1, 0) is Act.DROP
    assert not policy.unanswered and policy.flooded == 0


def test_more_than_fast_copies_in_a_row_are_a_flood(policy):
    policy.heard(['pose'], STEADY, state=True)
    policy.newest(7, STEADY, 0)
    policy.answered_state(7)
    acts = []
    for k in range(1, FAST_COPIES + 3):
        now = STEADY + k * (COPY_GAP_NS - 1)
        policy.heard(['pose'], now, state=True)
        acts.append(policy.newest(7, now, 0))
    assert Act.FLOOD not in acts[:FAST_COPIES] and acts[FAST_COPIES:] == [Act.FLOOD] * 2
    assert policy.flooded == 2


def test_new_states_beyond_the_budget_are_a_flood_counted_once_each(policy):
    """States 9 times the state rate: at most 1.1 per period and the burst are answered."""
    answered = 0
    stamps = range(1, 9 * 50 + 1)
    for stamp in stamps:
        clock = stamp * PERIOD // 9
        policy.heard(['pose', 'neighbour', 'reference'], STEADY, state=True)
        act = policy.newest(stamp, STEADY, clock)
        assert act in (Act.ANSWER, Act.FLOOD)
        if act is Act.ANSWER:
            answered += 1
            policy.answered_state(stamp)
        assert policy.newest(stamp, STEADY, clock) in (Act.DROP, Act.ANSWER, Act.RESEND)
    assert answered <= 1.1 * 50 + BURST
    assert policy.flooded >= len(stamps) - answered - 1
    assert answered >= 50


def test_stale_inputs_mean_zero_and_keep_the_watchdog_looking(policy):
    later = STEADY + TIMEOUT + 1
    policy.heard(['pose', 'neighbour'], later, state=True)
    assert policy.newest(1, later, 0) is Act.ZERO and policy.stale == ['reference']
    assert policy.watchdog_delay_ns(later) == WATCH
    policy.heard(['reference'], later)
    assert policy.newest(1, later, 0) is Act.ANSWER and policy.stale == []


def test_the_watchdog_looks_when_the_oldest_input_is_due_to_turn_stale(policy):
    policy.heard(['pose'], STEADY, state=True)
    assert policy.watchdog_delay_ns(STEADY) == WATCH
    policy.newest(1, STEADY, 0)
    policy.answered_state(1)
    policy.heard(['pose', 'neighbour'], STEADY + 100_000_000)
    assert policy.watchdog_delay_ns(STEADY + 200_000_000) == (
        TIMEOUT + STALE_MARGIN_NS - 200_000_000)
    assert policy.watchdog_delay_ns(STEADY + TIMEOUT) == WATCH
    policy.waiting = True
    assert policy.watchdog_delay_ns(STEADY) == WATCH
