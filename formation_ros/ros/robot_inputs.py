# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot node's gate for what it hears: read the bytes, admit them, count and say refusals.

:class:`InputGate` reads a message's bytes (``ros.cdr``), admits a state by
``core.rules.robot_intake.StateIntake`` and lets it set the robot's clock (``ros.sim_clock``),
counts every refusal and logs it once while it lasts (``ros.once.RefusalLog``), for stamps from
another clock with the advice the graph gives (``ros.sim_clock.clock_advice``), and looks who
publishes ``/clock`` and the reference. What a robot refuses and why: docs/faults.md.
"""

import time
from typing import Callable, Dict, Optional, TypeVar

from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.robot_intake import Refused, StateIntake
from formation_ros.ros.cdr import CdrError, PoseArrayData, TooManyPoses, TooManyRays
from formation_ros.ros.once import OnceLog, RefusalLog
from formation_ros.ros.sim_clock import clock_advice, StateClock
from formation_ros.ros.team import PublisherWatch
from rclpy.node import Node

Read = TypeVar('Read')


def refusal_line(name: str, reason: Reason, detail: str) -> str:
    """Return the log line of a message of input ``name`` refused for ``reason``."""
    return (f'ignoring {name} messages with {reason.value}{detail} (logged once; diagnostics '
            'count them)')


class InputGate:
    """
    The inputs of one robot node: read, admitted, refused.

    expected: {topic: None} of the topics that must have one publisher (/clock, the
    reference), shared by the robots of a process that hear them through one.
    """

    def __init__(self, node: Node, intake: StateIntake, state_clock: StateClock,
                 once: OnceLog, expected: Dict[str, Optional[str]]) -> None:
        """Gate the inputs of ``node``, logging through ``once``."""
        self.node, self.intake, self.state_clock, self.once = node, intake, state_clock, once
        self.refusals: RefusalLog[str] = RefusalLog(once, refusal_line)
        self.graph = PublisherWatch(node)
        self.expected = expected
        self.shared: Dict[str, str] = {}
        """{topic: its publishers} of the expected topics with more than one, at the last look."""

    @property
    def refused(self) -> Refusals[str]:
        """Return the refusals counted, by (input, reason)."""
        return self.refusals.refusals

    def read(self, name: str, reader: Callable[[bytes], Read], data: bytes,
             too_many: Reason = Reason.TOO_MANY) -> Optional[Read]:
        """
        Return ``reader(data)``; None, the refusal counted, if the bytes do not fit it.

        too_many: the reason of a message with more elements than the reader takes.
        """
        try:
            return reader(data)
        except TooManyRays as exc:
            self.refuse(name, Refused(Reason.TOO_MANY_RAYS, f' ({exc})'))
        except TooManyPoses as exc:
            self.refuse(name, Refused(too_many, f' ({exc})'))
        except CdrError as exc:
            self.refuse(name, Refused(Reason.MALFORMED, f' ({exc})'))
        return None

    def refuse(self, name: str, refused: Refused) -> None:
        """Count a message of input ``name`` refused; log it once (CLOCK: with advice)."""
        if refused.reason is not Reason.CLOCK:
            self.refusals.refuse(name, refused.reason, refused.detail, log=refused.log)
            return
        nodes = 'the reference' if name == 'reference' else 'the robots and the reference'
        advice = ('' if name in self.intake.advised
                  else clock_advice(self.graph, self.expected, nodes))
        if advice is not None:
            self.intake.advised.add(name)
        where = ('the state' if name == 'reference' else
                 f"the {'simulated' if self.intake.sim_time else 'wall-clock'} time of this node")
        self.refusals.refuse(name, Reason.CLOCK, f' ({refused.gap_s:+.3g} s from {where}: '
                                                 f'{advice})', log=advice is not None)

    def on_clock(self, name: str, message: str) -> None:
        """Note input ``name`` on the robot's clock again (log ``message`` if it was not)."""
        if name in self.intake.advised:
            self.intake.advised.discard(name)
            self.refusals.admitted(name, Reason.CLOCK, message)

    def admit_state(self, name: str, state: PoseArrayData, needs_orientation: bool,
                    heard_ns: Optional[int], steady_ns: int,
                    finite: Optional[bool] = None) -> bool:
        """
        Admit a state of input ``name`` (``StateIntake.poses_refusal``); let it set the clock.

        heard_ns: steady time the robot took its latest state (None: never); finite: given
        for a pose (its whole finiteness), else reckoned from the state.
        """
        stopped = self.intake.stopped(heard_ns, steady_ns)
        refused = self.intake.poses_refusal(state.frame_id, state.stamp_ns, state.positions,
                                            state.orientations, needs_orientation,
                                            self.node.get_clock().now().nanoseconds, stopped,
                                            finite)
        if refused is not None:
            self.refuse(name, refused)
            return False
        self.on_clock(name, f'{name} messages on this clock again')
        if self.intake.advance(state.stamp_ns, stopped):
            self.state_clock.set_time(state.stamp_ns)
        return True

    def shared_topics(self) -> Dict[str, str]:
        """Look who publishes the expected topics; log once each with several, and when not."""
        shared = self.graph.check(self.expected, time.monotonic())
        self.once.follow('publishers', {topic: f'{topic} has more than one publisher: {names} '
                                               '(two teams on one domain? each needs a '
                                               'ROS_DOMAIN_ID of its own)'
                                        for topic, names in shared.items()},
                         self.shared, lambda topic: f'{topic} has one publisher again')
        self.shared = shared
        return shared
