# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A robot's answers without ROS: lockstep, start-up, watchdog, flood, stale inputs, stop."""

from dataclasses import dataclass, field, replace
import os
from typing import Optional, Tuple

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.answers import AnswerPolicy, BURST
from formation_ros.core.rules.control import Control
from formation_ros.core.rules.reference_track import ReferenceTrack
from formation_ros.core.rules.robot_core import Note, RobotCore, Said
from formation_ros.core.runs.timeline import (Mode, ReferenceTimeline, Shape, TeamState,
                                              Timeline)
from formation_ros.core.settings.params import load_params_file, validate
import numpy as np
import pytest

SQUARE = os.path.join(os.path.dirname(__file__), '..', '..', 'config', 'square_4.yaml')
PERIOD = 20_000_000
TIMEOUT = NS_PER_S // 2
WATCH = 10_000_000
STEADY = 10 ** 12
"""Steady time of the first input heard, ns."""
START = 5 * NS_PER_S
"""Stamp of the first state, ns (simulated time)."""


@dataclass(frozen=True)
class Sample:
    """A reference sample as ``ros.cdr.OdometryData`` reads one (what the track needs)."""

    stamp_ns: int
    carried: FrameSample
    frame_id: str = 'world'
    linear: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    angular: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    finite: bool = True

    def frame(self, dim):
        return self.carried


@dataclass
class Changes:
    """The shapes and team states in force (``ros.changes.Changes``)."""

    shapes: Timeline
    states: Timeline
    differs: bool = False


@dataclass
class Robot:
    """One robot's core beside what it senses, with its listeners to set."""

    core: RobotCore
    control: Control
    changes: Changes
    timeline: ReferenceTimeline
    listeners: list = field(default_factory=lambda: [1])
    position: np.ndarray = field(default_factory=lambda: np.array([0.3, -0.2]))
    unseen: Optional[str] = None

    def sensed(self):
        return replace(self.control.alone(0, self.position, [0.0, 0.0, 0.0, 1.0],
                                          np.array([[1.0, 0.5]]),
                                          np.array([[0.0, 0.0, 0.0, 1.0]])), unseen=self.unseen)

    def sample(self, stamp_ns):
        """Admit the reference sample of ``stamp_ns`` as the reference node sends it."""
        refused = self.core.track.refusal(Sample(stamp_ns, self.timeline.frame_at(stamp_ns)),
                                          stamp_ns, lambda: False)
        assert refused is None

    def state(self, stamp_ns, now_ns, new=True):
        """Hear a whole state stamped ``stamp_ns`` at steady ``now_ns``."""
        self.core.state_heard(stamp_ns, now_ns, new)


def make_robot(lockstep, wait_subscribers=1, evaluates=True):
    config = validate(load_params_file(SQUARE))
    base = config.reference()
    states = Timeline(TeamState.of(Mode.RUNNING, config.shape_name, base))
    timeline = ReferenceTimeline(base, states)
    changes = Changes(Timeline(Shape('', config.vertices)), states)
    control = Control(config.law(), [1.5], 2, False, 0.0, False)
    track = ReferenceTrack(timeline, 2, config.world_frame, base.rate_limits(), evaluates,
                           TIMEOUT)
    policy = AnswerPolicy(PERIOD, TIMEOUT, WATCH, wait_subscribers)
    holder = {}
    core = RobotCore(control, lambda: holder['robot'].sensed(), policy, track, changes,
                     lambda: holder['robot'].listeners[0], 'cmd_vel', lockstep, evaluates,
                     TIMEOUT)
    robot = holder['robot'] = Robot(core, control, changes, timeline)
    return robot


def started(robot, stamp_ns=START, now_ns=STEADY):
    """Hear every input once (the reference's sample of ``stamp_ns``); return the answer."""
    robot.sample(stamp_ns)
    robot.core.reference_heard(now_ns)
    robot.state(stamp_ns, now_ns)
    return robot.core.on_state(now_ns, stamp_ns)


def expected(robot, stamp_ns):
    """Return the commands of the law at the frame evaluated for ``stamp_ns``: (1, 2)."""
    vertices = robot.changes.shapes.at(stamp_ns).vertices[[0]]
    return robot.control.commands(robot.sensed(), vertices,
                                  robot.timeline.frame_at(stamp_ns)).published


def said(answer, what):
    return [note for note in answer.notes if note.said is what]


def test_start_up_waits_for_every_input_and_the_subscribers_then_starts_once():
    robot = make_robot(lockstep=True)
    robot.listeners[0] = 0
    robot.state(START, STEADY)
    answer = robot.core.on_state(STEADY, START)
    assert not answer.publish and not answer.started
    waiting = said(answer, Said.START)
    assert [note.key for note in waiting] == ['waiting']
    assert waiting[0].text == 'waiting for reference, 1 cmd_vel subscribers (have 0)'
    assert waiting[0].level == 'info'
    robot.listeners[0] = 1
    answer = started(robot, START + PERIOD, STEADY + PERIOD)
    assert answer.started and answer.publish and answer.stamp_ns == START + PERIOD
    robot.sample(START + 2 * PERIOD)
    robot.state(START + 2 * PERIOD, STEADY + 2 * PERIOD)
    assert not robot.core.on_state(STEADY + 2 * PERIOD, START + 2 * PERIOD).started


def test_lockstep_answers_a_state_once_with_the_reference_of_its_stamp():
    robot = make_robot(lockstep=True)
    robot.state(START, STEADY)
    robot.core.reference_heard(STEADY)
    robot.sample(START - PERIOD)
    answer = robot.core.on_state(STEADY, START)
    assert not answer.publish and not answer.resend, 'a sample of another stamp is not used'
    robot.sample(START)
    assert robot.core.reference_heard(STEADY + 1).now
    answer = robot.core.on_state(STEADY + 1, START)
    assert answer.publish and answer.stamp_ns == START
    assert np.array_equal(answer.commands, expected(robot, START))
    assert np.array_equal(robot.core.latest.published, answer.commands)
    assert said(answer, Said.REFERENCE_ON_CLOCK)
    again = robot.core.on_state(STEADY + 2, START)
    assert not again.publish and not again.resend, 'answered once'
    assert not answer.watchdog and not again.watchdog


def test_lockstep_sends_a_copy_the_answer_again_at_most_once_a_period():
    robot = make_robot(lockstep=True)
    assert started(robot).publish
    robot.state(START, STEADY + PERIOD)
    copy = robot.core.on_state(STEADY + PERIOD, START)
    assert copy.resend and not copy.publish
    robot.state(START, STEADY + PERIOD + 1)
    assert not robot.core.on_state(STEADY + PERIOD + 1, START).resend


def test_lockstep_waits_for_the_neighbours_of_the_pose():
    robot = make_robot(lockstep=True)
    robot.sample(START)
    robot.core.reference_heard(STEADY)
    robot.core.neighbours_heard(START - PERIOD, STEADY)
    assert robot.core.pose_heard(START, STEADY).after_ns is None
    assert not robot.core.on_state(STEADY, START).publish
    wake = robot.core.neighbours_heard(START, STEADY + 1)
    assert wake.now
    assert robot.core.on_state(STEADY + 1, START).publish


def test_out_of_lockstep_a_pose_alone_is_answered_a_watchdog_period_later():
    robot = make_robot(lockstep=False)
    assert started(robot).publish
    again = robot.core.on_state(STEADY, START)
    assert not again.publish and not again.resend and not again.watchdog, 'answered: dropped'
    robot.sample(START + PERIOD)
    wake = robot.core.pose_heard(START + PERIOD, STEADY + PERIOD)
    assert not wake.now and wake.after_ns == WATCH
    answer = robot.core.on_state(STEADY + PERIOD + WATCH, START + PERIOD)
    assert answer.publish and answer.stamp_ns == START + PERIOD
    assert not robot.core.on_state(STEADY + PERIOD + WATCH, START + PERIOD).publish


def test_the_watchdog_publishes_zero_while_an_input_is_stale_and_says_it_once():
    robot = make_robot(lockstep=False)
    assert started(robot).publish
    late = STEADY + TIMEOUT + 1
    robot.core.state_heard(START + PERIOD, late, True)
    answer = robot.core.on_watchdog(late, START + PERIOD)
    assert answer.publish and answer.commands is None and answer.watchdog
    assert said(answer, Said.START) == [Note(Said.START, 'stale', 'no new reference for 0.5 s: '
                                                                  'publishing zero')]
    assert robot.core.watchdog_delay_ns(late) == WATCH
    robot.sample(START + PERIOD)
    robot.core.reference_heard(late + 1)
    answer = robot.core.on_watchdog(late + 1, START + PERIOD)
    assert answer.publish and np.array_equal(answer.commands, expected(robot, START + PERIOD))
    assert Note(Said.END, 'stale', 'inputs fresh again: controlling') in answer.notes


def test_states_beyond_the_budget_are_a_flood_said_and_counted():
    robot = make_robot(lockstep=False)
    answers = []
    for k in range(int(BURST) + 3):
        stamp = START + k * PERIOD
        robot.sample(stamp)
        robot.core.reference_heard(STEADY)
        robot.state(stamp, STEADY)
        answers.append(robot.core.on_state(STEADY, START))
    published = [answer.publish for answer in answers]
    assert published == [True] * int(BURST) + [False] * 3
    flooding = [note for answer in answers for note in said(answer, Said.START)
                if note.key == 'flooding']
    assert len(flooding) == 3 and flooding[0].level == 'warning'
    assert flooding[0].text.startswith('states arrive faster than one per 0.02 s')
    assert robot.core.policy.flooded == 3
    assert [answer.watchdog for answer in answers] == [False] * int(BURST) + [True] * 3, (
        'a state left unanswered: the watchdog looks again')


def test_a_reference_from_another_clock_is_refused_and_the_robot_publishes_zero():
    robot = make_robot(lockstep=False)
    assert started(robot).publish
    far = START + 3 * TIMEOUT
    robot.state(far, STEADY + PERIOD)
    answer = robot.core.on_state(STEADY + PERIOD, far)
    assert answer.publish and answer.commands is None
    clock = said(answer, Said.REFERENCE_CLOCK)
    assert len(clock) == 1 and clock[0].gap_s == pytest.approx(-3 * TIMEOUT / NS_PER_S)


def test_a_stopped_team_holds_still_and_says_when_it_runs_again():
    robot = make_robot(lockstep=True)
    config_state = robot.changes.states.at(START)
    stopped = TeamState(Mode.STOPPED, config_state.shape, config_state.origin,
                        config_state.speed, config_state.phase)
    robot.changes.states.add(START, stopped)
    answer = started(robot)
    assert answer.publish and answer.commands is None
    assert Note(Said.START, 'stopped', 'team stopped: holding still', 'info') in answer.notes
    running = TeamState(Mode.RUNNING, config_state.shape, config_state.origin,
                        config_state.speed, config_state.phase)
    robot.changes.states.add(START + PERIOD, running)
    answer = started(robot, START + PERIOD, STEADY + PERIOD)
    assert answer.publish and answer.commands is not None
    assert Note(Said.END, 'stopped', 'team running again') in answer.notes


def test_the_answer_of_k_robots_is_one_call_of_their_control():
    robot = make_robot(lockstep=True)
    control = Control(robot.control.law, [1.5, 1.5], 2, False, 0.0, False)
    points = np.array([[0.3, -0.2], [1.0, 0.5]])
    sensed = control.points(points, np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)))[0]
    from formation_ros.core.rules.control import Sensed
    team = Sensed(np.arange(2), sensed, np.zeros(2), np.tile([0.0, 0.0, 0.0, 1.0], (2, 1)),
                  np.array([0, 1]), sensed[::-1])
    core = RobotCore(control, lambda: team, robot.core.policy, robot.core.track, robot.changes,
                     lambda: 1, 'command', True, True, TIMEOUT)
    robot.sample(START)
    core.reference_heard(STEADY)
    core.state_heard(START, STEADY, True)
    answer = core.on_state(STEADY, START)
    assert answer.publish and answer.commands.shape == (2, 2)
    vertices = robot.changes.shapes.at(START).vertices[:2]
    assert np.array_equal(answer.commands, control.commands(team, vertices,
                                                            robot.timeline.frame_at(START))
                          .published)


def test_a_robot_that_cannot_tell_its_obstacles_holds_still_and_says_why():
    robot = make_robot(lockstep=True)
    robot.unseen = 'its scan cannot be placed'
    answer = started(robot)
    assert answer.publish and answer.commands is None
    assert Note(Said.START, 'unseen', 'its scan cannot be placed: holding still') in answer.notes
    robot.unseen = None
    robot.sample(START + PERIOD)
    robot.core.reference_heard(STEADY + PERIOD)
    robot.state(START + PERIOD, STEADY + PERIOD)
    answer = robot.core.on_state(STEADY + PERIOD, START + PERIOD)
    assert answer.commands is not None
    assert Note(Said.END, 'unseen', 'obstacles seen again: controlling') in answer.notes
