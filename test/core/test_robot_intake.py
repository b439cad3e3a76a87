# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A robot's state intake: the frame / finite / orientation rule, the clock rule and its jumps."""

from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.robot_intake import StateIntake
import pytest

TIMEOUT = NS_PER_S // 2
STEADY = 10 ** 12


def intake(sim_time=True):
    return StateIntake('world', TIMEOUT, sim_time, follows_states=sim_time,
                       heading_of='a unicycle')


def take(rule, stamp_s, heard_ns, steady_ns=STEADY, frame='world', finite=True, oriented=True):
    """Admit a state as the robot does; return the refusal's reason name or the time after."""
    stopped = rule.stopped(heard_ns, steady_ns)
    stamp = int(round(stamp_s * NS_PER_S))
    refused = rule.refusal(frame, stamp, finite, oriented, rule.now_ns, stopped)
    if refused is not None:
        return refused.reason.name
    rule.advance(stamp, stopped)
    return rule.now_ns / NS_PER_S


def test_the_first_rule_broken_is_named_with_its_detail():
    rule = intake()
    frame = rule.refusal('map', 0, False, False, 0, False)
    assert frame.reason is Reason.FRAME and "'map'" in frame.detail and "'world'" in frame.detail
    assert rule.refusal('world', 0, False, False, 0, False).reason is Reason.NON_FINITE
    oriented = rule.refusal('world', 0, True, False, 0, False)
    assert oriented.reason is Reason.ORIENTATION and 'a unicycle' in oriented.detail
    assert rule.refusal('world', 0, True, True, 0, False) is None


def test_the_time_follows_the_states_forward_only_while_they_come():
    rule = intake()
    assert take(rule, 5.0, None) == 5.0
    assert take(rule, 4.9, STEADY) == 5.0
    assert take(rule, 5.25, STEADY) == 5.25
    assert take(rule, 1000.0, STEADY) == 'CLOCK'
    assert rule.now_ns == int(5.25 * NS_PER_S)


def test_once_the_states_stopped_the_next_one_sets_the_time_either_way():
    rule = intake()
    take(rule, 5.0, None)
    later = STEADY + TIMEOUT + 1
    assert take(rule, 20.0, STEADY, later) == 20.0
    assert take(rule, 40.0, later, later) == 'CLOCK'
    assert take(rule, 0.5, later, later + TIMEOUT + 1) == 0.5


def test_a_clock_refusal_gives_the_gap_in_seconds():
    rule = intake()
    take(rule, 5.0, None)
    refused = rule.refusal('world', int(3.0 * NS_PER_S), True, True, rule.now_ns, False)
    assert refused.reason is Reason.CLOCK and refused.gap_s == pytest.approx(-2.0)


def test_on_the_wall_clock_simulated_stamps_are_refused_and_the_time_is_not_set():
    rule = intake(sim_time=False)
    wall = 1_700_000_000 * NS_PER_S
    assert not rule.stopped(None, STEADY)
    refused = rule.refusal('world', 5 * NS_PER_S, True, True, wall, False)
    assert refused.reason is Reason.CLOCK
    assert rule.refusal('world', wall + 1000, True, True, wall, False) is None
    assert not rule.advance(wall, True) and rule.now_ns == 0


def test_before_its_time_starts_a_robot_on_simulated_time_takes_any_stamp():
    rule = intake()
    assert rule.refusal('world', 10 ** 18, True, True, 0, False) is None
