# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
When a robot answers a state: at most about one per state period, once, and when it waits.

:class:`AnswerBudget` is a token bucket on the robot's own clock (simulated time beside a plant
or a world, wall-clock time with the relay in a lab; the period: ``RobotSettings.answer_period``
in ``core.settings.params``): it gains ``1 + RATE_MARGIN`` answers per expected state period
and holds at most :data:`BURST`, so over T s a robot answers at most
``(1 + RATE_MARGIN) T / period + BURST`` states. :class:`AnswerPolicy` decides for each state
heard: answer, send the last answer again, drop it (a copy, a flood) or wait (start-up, stale
inputs), and when the watchdog looks. The rules are stated in docs/ros_interface.md
("Start-up", "Watchdog", "Answering") and docs/faults.md ("a flood of forged poses").
"""

from dataclasses import dataclass
import enum
from typing import Dict, List, Optional, Sequence

RATE_MARGIN = 0.1
"""Answers per period beyond one: a relay on another host whose clock runs a little fast, or a
relay cycle late and the next on time, is not a flood."""
BURST = 3.0
"""Answers that may follow each other at once: a pose that arrives before the /clock tick of
its state, or states bunched by the network."""


@dataclass
class AnswerBudget:
    """
    Token bucket of answers: ``period_ns`` the expected time between states (robot's clock).

    tokens: answers that may be sent now; last_ns: the clock when they were counted.
    """

    period_ns: int
    tokens: float = BURST
    last_ns: Optional[int] = None

    def refill(self, now_ns: int) -> None:
        """Add what the time since the last count earns; a clock that went back restarts it."""
        if self.last_ns is not None and now_ns > self.last_ns:
            earned = (now_ns - self.last_ns) * (1.0 + RATE_MARGIN) / self.period_ns
            self.tokens = min(BURST, self.tokens + earned)
        self.last_ns = now_ns

    def take(self, now_ns: int) -> bool:
        """Spend one answer at clock ``now_ns`` (ns) if there is one; False if none is left."""
        self.refill(now_ns)
        if self.tokens < 1.0:
            return False
        self.tokens -= 1.0
        return True


INPUTS = ('pose', 'neighbour', 'reference')
"""A robot's inputs, each stale once not heard for input_timeout."""
COPY_GAP_NS = 25_000_000
"""A copy of the state answered last sooner than this after the state before is a fast copy."""
FAST_COPIES = 3
"""Fast copies in a row beyond which copies count as flooding."""
STALE_MARGIN_NS = 1_000_000
"""How long after the oldest input is due to turn stale the watchdog looks, ns."""


class Act(enum.Enum):
    """What a robot does with a state."""

    ANSWER = 'compute and publish its command'
    RESEND = 'publish the answer sent last again'
    DROP = 'send nothing'
    FLOOD = 'send nothing: a state beyond the budget (counted)'
    ZERO = 'publish zero: an input is stale'


class AnswerPolicy:
    """
    Which states a robot answers, and when its watchdog looks.

    period_ns: the expected time between states on the robot's clock (the budget's);
    timeout_ns: ``input_timeout``; watch_ns: one period of ``control_rate``; all ns. Times
    passed as ``now_ns`` are steady (ns), ``clock_ns`` the robot's clock (ns).
    """

    def __init__(self, period_ns: int, timeout_ns: int, watch_ns: int,
                 wait_subscribers: int) -> None:
        """Start waiting, nothing heard."""
        self.budget = AnswerBudget(period_ns)
        self.timeout_ns = timeout_ns
        self.watch_ns = watch_ns
        self.wait_subscribers = wait_subscribers
        self.received_ns: Dict[str, Optional[int]] = dict.fromkeys(INPUTS)
        """Steady time each input was last heard (None: never)."""
        self.states = 0
        self.answered = 0
        self.answered_stamp: Optional[int] = None
        self.waiting = True
        self.stale: List[str] = []
        """The inputs stale at the latest look (the robot then publishes zero)."""
        self.flooded = 0
        self.flood_stamp: Optional[int] = None
        self.copy_arrived_ns = 0
        self.fast_copies = 0
        self.resent_ns = 0

    def heard(self, names: Sequence[str], now_ns: int, state: bool = False) -> None:
        """Note inputs ``names`` heard at ``now_ns``; ``state``: a new state (pose) among them."""
        for name in names:
            self.received_ns[name] = now_ns
        if state:
            self.states += 1

    @property
    def unanswered(self) -> bool:
        """Whether a state came since the last one answered (or dropped as a copy)."""
        return self.states != self.answered

    def missing(self, listeners: int, what: str) -> List[str]:
        """
        Return what start-up still waits for: inputs never heard, subscribers to ``what``.

        listeners: subscribers the command output has. Empty once every input was heard and
        ``wait_for_subscribers`` listen: the robot then no longer waits.
        """
        never = [name for name in INPUTS if self.received_ns[name] is None]
        if listeners < self.wait_subscribers:
            never.append(f'{self.wait_subscribers} {what} subscribers (have {listeners})')
        if not never:
            self.waiting = False
        return never

    def stale_inputs(self, now_ns: int) -> List[str]:
        """Return (and keep as :attr:`stale`) the inputs not heard for input_timeout."""
        self.stale = [name for name, heard in self.received_ns.items()
                      if heard is None or now_ns - heard > self.timeout_ns]
        return self.stale

    def newest(self, stamp_ns: int, now_ns: int, clock_ns: int) -> Act:
        """Decide at a look on the newest state (stamped ``stamp_ns``), out of lockstep."""
        if self.stale_inputs(now_ns):
            return Act.ZERO
        if not self.unanswered:
            return Act.DROP
        return self.admit(stamp_ns, now_ns, clock_ns)

    def admit(self, stamp_ns: int, now_ns: int, clock_ns: int) -> Act:
        """
        Decide on a state stamped ``stamp_ns``: a new one is answered within the budget.

        A copy of the state answered last is not computed again: the answer already sent goes
        again at most once per state period (steady clock) whatever the copies' rate; more
        than FAST_COPIES copies in a row, each within COPY_GAP_NS of the one before, and a
        new state beyond the budget (once per stamp) count as flooding.
        """
        if stamp_ns == self.answered_stamp:
            fast = now_ns - self.copy_arrived_ns < COPY_GAP_NS
            self.fast_copies = self.fast_copies + 1 if fast else 0
            act = Act.DROP
            if self.fast_copies > FAST_COPIES:
                act = self._flooding(stamp_ns)
            elif now_ns - self.resent_ns >= max(COPY_GAP_NS, self.budget.period_ns):
                act = Act.RESEND
                self.resent_ns = now_ns
            self.copy_arrived_ns = now_ns
            self.answered = self.states
            return act
        self.copy_arrived_ns = now_ns
        if self.budget.take(clock_ns):
            return Act.ANSWER
        if stamp_ns != self.flood_stamp:
            return self._flooding(stamp_ns)
        return Act.DROP

    def _flooding(self, stamp_ns: int) -> Act:
        self.flooded += 1
        self.flood_stamp = stamp_ns
        return Act.FLOOD

    def answered_state(self, stamp_ns: int) -> None:
        """Note the newest state, stamped ``stamp_ns``, answered."""
        self.answered = self.states
        self.answered_stamp = stamp_ns

    def watchdog_delay_ns(self, now_ns: int) -> int:
        """
        Return when the watchdog looks next, ns from ``now_ns``.

        One period of ``control_rate`` while the robot waits, its inputs are stale or a state
        is unanswered; else when the oldest input is due to turn stale (and STALE_MARGIN_NS).
        """
        if self.waiting or self.stale or self.unanswered:
            return self.watch_ns
        oldest = min(ns for ns in self.received_ns.values() if ns is not None)
        return max(self.watch_ns, oldest + self.timeout_ns + STALE_MARGIN_NS - now_ns)
