# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A plant in lockstep that waits for answers says for whom, and for how long.

In lockstep the plant steps only once every robot has answered its state, so one robot that
stops answering (its process stopped, its link cut, a fleet stuck) halts the run. An
:class:`AnswerWait` turns that silence into lines: once a state has waited :data:`NAME_AFTER`
seconds (steady clock) it names the robots that have not answered, again every
:data:`REPEAT_EVERY` seconds while they stay silent, and says once when the run goes on. The
plant node passes the times; the rule is here, tested without ROS (docs/faults.md).
"""

from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence

from formation_ros.core.settings.names import robot_name

NAME_AFTER = 2.0
"""Seconds a state waits for answers before the robots still silent are named."""
REPEAT_EVERY = 10.0
"""Seconds between two lines about the same wait."""
NAMED = 5
"""Robots named in one line; the others are counted."""
WAITING_FOR = 'lockstep waiting for robots'
WAITED = 'lockstep waiting for [s]'
"""The keys of a named wait in the plant's /diagnostics."""


def robots_and_names(robots: Sequence[int], shown: int = NAMED) -> str:
    """Return 'robot 3 (robot_3)' or 'robots 3 (robot_3), 4 (robot_4) and 9 more'."""
    named = ', '.join(f'{i} ({robot_name(i)})' for i in robots[:shown])
    more = f' and {len(robots) - shown} more' if len(robots) > shown else ''
    return f"robot{'s' if len(robots) > 1 else ''} {named}{more}"


@dataclass
class Wait:
    """A state waiting for answers: its stamp (ns), since when (s, steady), who is silent."""

    stamp_ns: int
    since: float
    silent: List[int]


class AnswerWait:
    """
    How long the current lockstep state has waited, and which robots (1-based) it waits for.

    name_after and repeat_every: s (steady clock); all times passed are steady, s.
    """

    def __init__(self, name_after: float = NAME_AFTER,
                 repeat_every: float = REPEAT_EVERY) -> None:
        """Start with no state published."""
        self.name_after = name_after
        self.repeat_every = repeat_every
        self.wait: Optional[Wait] = None
        self.said_at: Optional[float] = None

    def published(self, stamp_ns: int, now: float) -> None:
        """Note a state stamped ``stamp_ns`` sent at ``now`` (a resent one changes nothing)."""
        if self.wait is None or self.wait.stamp_ns != stamp_ns:
            self.wait = Wait(stamp_ns, now, [])

    def look(self, silent: Sequence[int], now: float) -> Optional[str]:
        """
        Return a line to log now, or None: ``silent`` are the robots yet to answer the state.

        A wait is named once it has lasted ``name_after``, again every ``repeat_every``; an
        end is said once, when every robot has answered a wait that was named.
        """
        if self.wait is None:
            return None
        self.wait.silent = list(silent)
        waited = now - self.wait.since
        if not silent:
            if self.said_at is None:
                return None
            self.said_at = None
            return (f'lockstep: every robot answered after {waited:.1f} s; the run goes on '
                    f'at {self.wait.stamp_ns * 1e-9:.3f} s simulated')
        if waited < self.name_after:
            return None
        if self.said_at is not None and now - self.said_at < self.repeat_every:
            return None
        self.said_at = now
        return (f'lockstep: waiting for {robots_and_names(silent)}, no answer for '
                f'{waited:.1f} s at {self.wait.stamp_ns * 1e-9:.3f} s simulated (a stopped '
                'or stuck robot process, or a cut link?)')

    def values(self, now: float) -> Dict[str, object]:
        """Return the wait for /diagnostics: who, since how long (s); empty while none is named."""
        if self.wait is None or self.said_at is None or not self.wait.silent:
            return {}
        return {WAITING_FOR: ', '.join(map(str, self.wait.silent)),
                WAITED: now - self.wait.since}
