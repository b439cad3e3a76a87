# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's intake of commands (core/rules/plant_intake.py): frame check, storing, refusals."""

from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.plant_intake import CommandIntake, refused_by_robot, TEAM
import numpy as np

WORLD = 'world'


def intake(stamped=True, unicycles=False, frames=(WORLD, WORLD, WORLD)):
    return CommandIntake(list(frames), WORLD, 2, unicycles, stamped)


def test_a_command_is_stored_with_its_stamp_and_arrival():
    taken = intake()
    linear = np.array([1.0, -2.0, 9.0])
    assert taken.take(1, WORLD, linear, (0.0, 0.0, 5.0), 40, 1234) is None
    assert np.array_equal(taken.commands.u[1], [1.0, -2.0])
    assert taken.commands.stamp_ns[1] == 40 and taken.arrived_ns[1] == 1234
    assert taken.commands.present.tolist() == [False, True, False]
    assert taken.missing() == [1, 3]
    assert np.array_equal(linear, [1.0, -2.0, 9.0])


def test_a_command_in_a_foreign_frame_is_refused_and_not_stored():
    taken = intake(frames=(WORLD, 'robot_2/base_link', WORLD))
    assert taken.take(1, WORLD, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0), 40, 1) is Reason.FRAME
    assert not taken.commands.present.any() and taken.arrived_ns[1] == 0
    assert taken.take(1, 'robot_2/base_link', (1.0, 0.0, 0.0), (0, 0, 0), 40, 1) is None
    line = taken.line(1, Reason.FRAME, WORLD)
    assert line == ("robot 2: ignoring cmd_vel in frame 'world': its commands are in "
                    "'robot_2/base_link' (logged once, counted in diagnostics)")


def test_a_non_finite_command_is_refused_and_the_last_one_still_holds():
    """The one rule of the plant and the world (core.rules.admission.command_refusal)."""
    taken = intake()
    assert taken.take(0, WORLD, (0.5, 0.0, 0.0), (0.0, 0.0, 0.0), 40, 1) is None
    nan = float('nan')
    assert taken.take(0, WORLD, (nan, 0.0, 0.0), (0.0, 0.0, 0.0), 60, 2) is Reason.NON_FINITE
    assert taken.take(0, WORLD, (0.1, 0.0, nan), (0.0, 0.0, 0.0), 60, 3) is None
    assert taken.commands.u[0].tolist() == [0.1, 0.0] and taken.arrived_ns[0] == 3
    assert taken.take(0, 'map', (nan, 0.0, 0.0), (0, 0, 0), 60, 4) is Reason.FRAME
    unstamped = intake(stamped=False)
    assert unstamped.take(1, '', (0.0, float('inf')), (0, 0, 0), 0, 5) is Reason.NON_FINITE
    team = intake()
    assert team.take_team([0, 2], WORLD, [[0.1, 0.0, 0.0], [nan, 0.0, 0.0]], np.zeros((2, 3)),
                          80, 6) is Reason.NON_FINITE
    assert not team.commands.present.any()
    assert taken.line(0, Reason.NON_FINITE, 'linear (nan, 0.0, 0.0), angular (0, 0, 0)') == (
        'robot 1: ignoring a non-finite command on cmd_vel (linear (nan, 0.0, 0.0), angular '
        '(0, 0, 0); its last one holds until it is stale; logged once, counted in diagnostics)')
    assert 'non-finite' in team.line(TEAM, Reason.NON_FINITE, WORLD)


def test_a_twist_answers_the_latest_state_published_and_a_unicycle_keeps_v_and_w():
    taken = intake(stamped=False, unicycles=True)
    taken.state_stamp_ns = 70
    assert taken.take(0, 'anything', (0.5, 0.1, 0.0), (0.0, 0.0, -0.25), 999, 5) is None
    assert np.array_equal(taken.commands.u[0], [0.5, -0.25])
    assert taken.commands.stamp_ns[0] == 70


def test_a_team_message_stores_its_robots_or_is_refused_for_its_frame():
    taken = intake()
    linear = np.array([[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]])
    angular = np.zeros((2, 3))
    assert taken.take_team([2, 0], 'map', linear, angular, 60, 7) is Reason.FRAME
    assert not taken.commands.present.any()
    assert taken.take_team([2, 0], WORLD, linear, angular, 60, 7) is None
    assert np.array_equal(taken.commands.u, [[3.0, 4.0], [0.0, 0.0], [1.0, 2.0]])
    assert taken.commands.stamp_ns.tolist() == [60, 0, 60]
    assert not taken.answered(60)
    taken.take(1, WORLD, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 60, 8)
    assert taken.answered(60) and not taken.answered(50)


def test_arrival_states_from_the_latest_command_within_the_lease():
    taken = intake()
    taken.take(0, WORLD, (0, 0, 0), (0, 0, 0), 0, 1_000)
    taken.take(1, WORLD, (0, 0, 0), (0, 0, 0), 0, 5_000)
    assert taken.arrival_states(6_000, 2_000) == ['lost', 'alive', 'unknown']


def test_refusals_are_counted_by_robot_in_order_and_the_team_apart():
    refusals = Refusals()
    for source, reason in [(4, Reason.FRAME), (0, Reason.FRAME), (4, Reason.FRAME),
                           (2, Reason.MALFORMED), (TEAM, Reason.FRAME), ('shape', Reason.CHANGE)]:
        refusals.add(source, reason)
    assert list(refused_by_robot(refusals, Reason.FRAME).items()) == [(1, 1), (5, 2)]
    assert refused_by_robot(refusals, Reason.MALFORMED) == {3: 1}
    assert refusals.count(TEAM, Reason.FRAME) == 1
    taken = intake()
    assert taken.line('shape', Reason.CHANGE, 'a frame other than world_frame') == (
        'ignoring a shape with a frame other than world_frame (logged once; counted in '
        'diagnostics)')
    assert taken.line(TEAM, Reason.MALFORMED, 'cut short').startswith(
        'ignoring /formation/commands bytes that are not a team command (cut short;')
