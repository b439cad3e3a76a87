# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What K >= 1 robots of one process do with the states they hear: when and what they answer.

:class:`RobotCore` is the decision loop of a robot node (K = 1) and of a process's link to its
robots (``transport: team``, K robots in one law call), without ROS: it notes the states heard
(:meth:`RobotCore.pose_heard`, :meth:`RobotCore.neighbours_heard`,
:meth:`RobotCore.obstacles_heard`, :meth:`RobotCore.state_heard`,
:meth:`RobotCore.reference_heard`), says when to look
(:class:`Wake`), and at a look (:meth:`RobotCore.on_state`, :meth:`RobotCore.on_watchdog`)
returns an :class:`Answer`: the commands to publish (None: zero) or the answer to send again,
and the lines to log once. Which states it answers is ``core.rules.answers.AnswerPolicy``'s
rule, the reference frame at a stamp ``core.rules.reference_track.ReferenceTrack``'s, the
commands ``core.rules.control.Control``'s. The rules: docs/ros_interface.md ("Start-up",
"Watchdog", "Answering", "Reference timing").
"""

from dataclasses import dataclass
import enum
from typing import Callable, List, Optional, Protocol, Tuple

from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.answers import Act, AnswerPolicy
from formation_ros.core.rules.control import Commands, Control, Sensed
from formation_ros.core.rules.reference_track import ReferenceTrack
from formation_ros.core.runs.timeline import Mode, Shape, TeamState, Timeline
import numpy as np
from numpy.typing import NDArray


class Said(enum.Enum):
    """What a :class:`Note` says."""

    START = 'a condition begins: its line, once while it lasts'
    END = 'a condition ends: its closing line, if any'
    REFERENCE_CLOCK = 'the reference is on another clock than the states (a refusal)'
    REFERENCE_ON_CLOCK = 'the reference is on the clock of the states (again)'


@dataclass(frozen=True)
class Note:
    """
    A line for the robot's log: ``said`` of condition ``key``.

    text: the line (START) or the closing line (END, None: none); level: 'info', 'warning' or
    'error'; gap_s: how far (s) the newest reference sample is from the state
    (REFERENCE_CLOCK).
    """

    said: Said
    key: str = ''
    text: Optional[str] = None
    level: str = 'warning'
    gap_s: float = 0.0


@dataclass(frozen=True)
class Answer:
    """
    What the robots do at a look.

    publish: publish ``commands`` (K, width) in their command frames, None for zero,
    answering the state stamped ``stamp_ns``; resend: publish the answer sent last again;
    started: the robots just started answering (start-up is over); notes: the lines to log,
    in order; watchdog: look again (:meth:`RobotCore.watchdog_delay_ns` from the time the
    answer went).
    """

    publish: bool = False
    commands: Optional[NDArray[np.float64]] = None
    stamp_ns: int = 0
    resend: bool = False
    started: bool = False
    notes: Tuple[Note, ...] = ()
    watchdog: bool = False


NOTHING = Answer()


@dataclass(frozen=True)
class Wake:
    """When to answer a state heard: ``now`` (at once) or in ``after_ns``; neither: not."""

    now: bool = False
    after_ns: Optional[int] = None


class TeamChanges(Protocol):
    """The shapes and team states in force (``ros.changes.Changes``)."""

    differs: bool
    shapes: Timeline[Shape]
    states: Timeline[TeamState]


class RobotCore:
    """
    The answering of K robots of one process.

    control: their law and command frames (K rows); senses: what they know of the state
    heard last (:class:`Sensed`); policy: which states they answer; track: the reference they
    follow; changes: the shapes and team states announced; listeners: the command subscribers
    every robot has, and what: what they subscribe to (start-up waits for them); lockstep:
    ``plant.lockstep``; evaluates: whether the frame is evaluated at each stamp
    (``ReferenceTrack.frame_at``); timeout_ns: ``input_timeout``, ns.
    """

    def __init__(self, control: Control, senses: Callable[[], Sensed], policy: AnswerPolicy,
                 track: ReferenceTrack, changes: TeamChanges, listeners: Callable[[], int],
                 what: str, lockstep: bool, evaluates: bool, timeout_ns: int) -> None:
        """Start with no state heard."""
        self.control = control
        self.senses = senses
        self.policy = policy
        self.track = track
        self.changes = changes
        self.listeners = listeners
        self.what = what
        self.lockstep = lockstep
        self.evaluates = evaluates
        self.timeout_ns = timeout_ns
        self.pose_ns: Optional[int] = None
        """The stamp of the latest pose (or state) heard, ns (None: none yet)."""
        self.neighbours_ns: Optional[int] = None
        """The stamp of the latest neighbours heard, ns (None: none yet)."""
        self.obstacles_ns: Optional[int] = None
        """The stamp of the latest obstacles heard, ns (None: none yet)."""
        self.awaiting_neighbours = False
        self.latest: Optional[Commands] = None
        """The commands computed last (K rows)."""

    @property
    def paired(self) -> bool:
        """
        Whether the pose and the neighbours heard last are of one state (same stamp).

        Once obstacles were heard, their latest must be of that state too (the plant and
        the relay send them with every pose); before, a robot answers as without obstacles.
        """
        return (self.pose_ns is not None and self.neighbours_ns == self.pose_ns
                and (self.obstacles_ns is None or self.obstacles_ns == self.pose_ns))

    def pose_heard(self, stamp_ns: int, now_ns: int) -> Wake:
        """
        Note an admitted pose stamped ``stamp_ns``, heard at ``now_ns`` (steady, ns).

        Answered at once with its neighbours; out of lockstep, a watchdog period later
        without them (the neighbours may not come: a robot that senses none).
        """
        self.pose_ns = stamp_ns
        self.policy.heard(['pose'], now_ns, state=True)
        if self.paired:
            self.awaiting_neighbours = False
            return Wake(now=True)
        if self.lockstep:
            return Wake()
        self.awaiting_neighbours = True
        return Wake(after_ns=self.policy.watch_ns)

    def neighbours_heard(self, stamp_ns: int, now_ns: int) -> Wake:
        """Note admitted neighbours stamped ``stamp_ns``, heard at ``now_ns``; answer if paired."""
        self.neighbours_ns = stamp_ns
        self.policy.heard(['neighbour'], now_ns)
        if self.paired:
            self.awaiting_neighbours = False
            return Wake(now=True)
        return Wake()

    def obstacles_heard(self, stamp_ns: int, now_ns: int) -> Wake:
        """
        Note admitted obstacles stamped ``stamp_ns``, heard at ``now_ns``; answer if paired.

        From the first, obstacles are an input that goes stale as the pose does (no obstacle
        message for input_timeout: zero), and a state waits for its own.
        """
        self.obstacles_ns = stamp_ns
        self.policy.heard(['obstacles'], now_ns)
        if self.paired:
            self.awaiting_neighbours = False
            return Wake(now=True)
        return Wake()

    def state_heard(self, stamp_ns: int, now_ns: int, new: bool,
                    obstacles: bool = False) -> None:
        """
        Note a state (pose and neighbours) stamped ``stamp_ns``; ``new``: one to answer.

        obstacles: the obstacles of the state came with it (:meth:`obstacles_heard`).
        """
        self.pose_ns = self.neighbours_ns = stamp_ns
        self.policy.heard(['pose', 'neighbour'], now_ns, state=new)
        if obstacles:
            self.obstacles_ns = stamp_ns
            self.policy.heard(['obstacles'], now_ns)

    def reference_heard(self, now_ns: int) -> Wake:
        """Note a reference sample admitted at ``now_ns``: in lockstep, answer at once."""
        self.policy.heard(['reference'], now_ns)
        return Wake(now=self.lockstep)

    def on_state(self, now_ns: int, clock_ns: int) -> Answer:
        """Answer a state whose pose and neighbours are in (steady ``now_ns``, clock ns)."""
        if self.lockstep:
            return self._answer_lockstep(now_ns, clock_ns)
        if self.paired or (self.awaiting_neighbours and self.neighbours_ns is not None):
            self.awaiting_neighbours = False
            return self._answer_newest(now_ns, clock_ns)
        return NOTHING

    def on_watchdog(self, now_ns: int, clock_ns: int) -> Answer:
        """Look: zero while an input is stale, else answer a state left over; say when next."""
        answer = self._answer_newest(now_ns, clock_ns)
        return Answer(answer.publish, answer.commands, answer.stamp_ns, answer.resend,
                      answer.started, answer.notes, watchdog=True)

    def watchdog_delay_ns(self, now_ns: int) -> int:
        """Return when the watchdog looks next, ns from ``now_ns`` (``AnswerPolicy``)."""
        return self.policy.watchdog_delay_ns(now_ns)

    def last_stamp(self) -> Optional[int]:
        """Return the stamp of the latest state heard (None: none), for the last zero."""
        return self.pose_ns

    def _ready(self, notes: List[Note]) -> Optional[bool]:
        """
        Start-up (``AnswerPolicy.missing``): say once what the robots wait for.

        None while they wait; True as they start; False once started.
        """
        if not self.policy.waiting:
            return False
        missing = self.policy.missing(self.listeners(), self.what)
        if missing:
            notes.append(Note(Said.START, 'waiting', f"waiting for {', '.join(missing)}",
                              'info'))
            return None
        notes.append(Note(Said.END, 'waiting'))
        return True

    def _answer_newest(self, now_ns: int, clock_ns: int) -> Answer:
        """Answer the newest state once: compute its commands (zero if an input is stale)."""
        notes: List[Note] = []
        started = self._ready(notes)
        if started is None:
            return Answer(notes=tuple(notes))
        assert self.pose_ns is not None
        stamp = self.pose_ns
        act = self.policy.newest(stamp, now_ns, clock_ns)
        if act is Act.ZERO:
            notes.append(Note(Said.START, 'stale', f"no new {', '.join(self.policy.stale)} for "
                                                   f'{self.timeout_ns / NS_PER_S:g} s: '
                                                   'publishing zero'))
            return Answer(True, None, stamp, started=started, notes=tuple(notes))
        notes.append(Note(Said.END, 'stale', 'inputs fresh again: controlling'))
        return self._act(act, stamp, False, started, notes)

    def _answer_lockstep(self, now_ns: int, clock_ns: int) -> Answer:
        """Answer each state the plant sends, once, with the reference sample of its stamp."""
        if self.pose_ns is None or not self.policy.unanswered:
            return NOTHING
        notes: List[Note] = []
        started = self._ready(notes)
        if started is None or not self.paired:
            return Answer(started=bool(started), notes=tuple(notes))
        stamp = self.pose_ns
        if stamp != self.policy.answered_stamp and self._frame_at(stamp, True, notes) is None:
            return Answer(started=started, notes=tuple(notes))
        act = self.policy.admit(stamp, now_ns, clock_ns)
        return self._act(act, stamp, True, started, notes)

    def _act(self, act: Act, stamp: int, exact: bool, started: bool,
             notes: List[Note]) -> Answer:
        """Do what the policy decided for the state stamped ``stamp``."""
        if act is Act.ANSWER:
            commands = self._commands(stamp, exact, notes)
            self.policy.answered_state(stamp)
            return Answer(True, commands, stamp, started=started, notes=tuple(notes))
        if act is Act.FLOOD:
            period = self.policy.budget.period_ns / NS_PER_S
            notes.append(Note(Said.START, 'flooding', f'states arrive faster than one per '
                                                      f"{period:.3g} s (the plant's or relay's "
                                                      'period): answering at most about one '
                                                      'per period, the others are dropped '
                                                      '(logged once; counted in diagnostics)',
                              'warning'))
        return Answer(resend=act is Act.RESEND, started=started, notes=tuple(notes),
                      watchdog=self.policy.unanswered)

    def _frame_at(self, stamp_ns: int, exact: bool,
                  notes: List[Note]) -> Optional[FrameSample]:
        """Return the reference frame at ``stamp_ns`` (``ReferenceTrack.frame_at``), or None."""
        frame, gap = self.track.frame_at(stamp_ns, exact, self.evaluates, self.timeout_ns)
        if gap is not None:
            notes.append(Note(Said.REFERENCE_CLOCK, gap_s=gap))
        elif frame is not None:
            notes.append(Note(Said.REFERENCE_ON_CLOCK))
        return frame

    def _commands(self, stamp_ns: int, exact: bool,
                  notes: List[Note]) -> Optional[NDArray[np.float64]]:
        """Return the commands (K, width) answering the state ``stamp_ns``; None: zero."""
        frame = self._frame_at(stamp_ns, exact, notes)
        if frame is None:
            return None
        if self.changes.differs:
            notes.append(Note(Said.START, 'other-shape', "following the reference's shape: it "
                                                         "differs from this robot's "
                                                         'formation.vertices (another '
                                                         'parameters file?)', 'warning'))
        if self.changes.states.at(stamp_ns).mode is Mode.STOPPED:
            notes.append(Note(Said.START, 'stopped', 'team stopped: holding still', 'info'))
            return None
        notes.append(Note(Said.END, 'stopped', 'team running again'))
        sensed = self.senses()
        if sensed.unseen is not None:
            notes.append(Note(Said.START, 'unseen', f'{sensed.unseen}: holding still'))
            return None
        notes.append(Note(Said.END, 'unseen', 'obstacles seen again: controlling'))
        vertices = self.changes.shapes.at(stamp_ns).vertices[sensed.indices]
        self.latest = self.control.commands(sensed, vertices, frame)
        return self.latest.published
