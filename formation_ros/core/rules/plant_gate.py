# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
When the plant (or the world) may publish its first state and start its clock, without ROS.

The plant node reads the graph (the other ``/clock`` publishers, who announced them, the
subscribers) and feeds it here (``ros.clock_look``); the gate decides. The world node looks
through the same gate, without holding its clock for the robots. Another team on the domain is
``core.rules.occupants``'s rule, which the launcher applies too (:func:`domain_verdict`); the
start-up order is docs/ros_interface.md ("Behaviour of the nodes", Start-up) and docs/faults.md
(another team's plant already on the domain). Times are steady clock seconds.
"""

import enum
from typing import List, Optional, Sequence

from formation_ros.core.rules.occupants import occupants

LOOK_TIME = 2.0
"""How long the plant looks for another /clock publisher before its first state, s."""
WORLD_LOOK_TIME = 3.5
"""How long a world looks, s: a participant whose first announcements a busy host missed is
seen at its next one, Fast DDS's announcement period (3 s) later. A world started beside a
running world or plant saw neither in 2 s on a loaded 2-core machine (about 1 start in 5
under the test suite) and started beside it; a plant keeps LOOK_TIME, as every test starts
one."""
LOOK_LIMIT = 5.0
"""With another /clock publisher found, how long the plant waits to hear its host on
/diagnostics before refusing without it, s."""
LOOK_PERIOD = 0.5
"""Seconds between looks at the graph while the clock waits for the robots."""
CLOCK_MATCH_WAIT = 5.0
"""Once every robot is up, how long the clock waits at most for each /clock subscriber the
graph shows to be matched to its publisher, s (one that never matches cannot hold the team)."""
CLOCK_MATCH_LINE = 'every robot is up: waiting for /clock to reach its subscribers'
CLOCK_MAKERS = ('plant', 'world')
"""The names of the nodes that make a team's simulated clock."""
GAVE_UP_LINE = (f'a /clock subscriber is still not matched after {CLOCK_MATCH_WAIT:g} s (a QoS '
                '/clock does not offer?): starting the clock all the same')


class Verdict(enum.Enum):
    """What the other /clock publishers of a domain are."""

    FREE = 'no other /clock publisher'
    LEFTOVER = "what is left of a killed plant of this node's name"
    OTHER_TEAM = 'another team'


def domain_verdict(others: Sequence[str], announced: Sequence[str], sent_clock: bool,
                   own_name: str) -> Verdict:
    """
    Return what the /clock publishers ``others`` (fully qualified, its own writer left out) are.

    announced: those of them another process announces on /diagnostics; sent_clock: whether
    /clock messages came from another node. The rule is ``core.rules.occupants.occupants``, the
    launcher's too: a leftover is a silent one of this node's name.
    """
    if occupants(others, (), own_name, announced, sent_clock):
        return Verdict.OTHER_TEAM
    return Verdict.LEFTOVER if others else Verdict.FREE


class Phase(enum.Enum):
    """Where the plant is in its start-up."""

    LOOKING = 'looking for another plant on this domain'
    REFUSED = 'refused to start'
    WAITING = 'waiting for the robots'
    RUNNING = 'running'


class ClockMatch(enum.Enum):
    """Whether the clock may start as far as its subscribers go."""

    WAIT = 'a /clock subscriber is not matched yet'
    MATCHED = 'every /clock subscriber is matched'
    GAVE_UP = 'a /clock subscriber is still not matched after CLOCK_MATCH_WAIT s'


class StartGate:
    """
    The start-up of a node that makes the clock: look at the domain, hold the clock, run.

    created: when the node was made, s; hold: whether the clock waits for every robot
    (``plant.wait_for_robots`` or lockstep; never for the world); own_name: the node's fully
    qualified name.
    """

    def __init__(self, created: float, hold: bool, own_name: str,
                 look_time: float = LOOK_TIME) -> None:
        """Start looking at the domain, for ``look_time`` s."""
        self.created = created
        self.look_time = look_time
        self.hold = hold
        self.own_name = own_name
        self.phase = Phase.LOOKING
        self.refused: List[str] = []
        """The /clock publishers this plant refused to start beside (empty unless REFUSED)."""
        self.next_look = 0.0
        self.clock_match_since: Optional[float] = None

    @property
    def looked(self) -> bool:
        """Whether the domain was found free of another team (the look is over)."""
        return self.phase in (Phase.WAITING, Phase.RUNNING)

    def look_due(self, now: float, at_once: bool = False) -> bool:
        """
        Return whether the node should look up the /clock publishers now (and count the look).

        While looking: from ``look_time`` s after ``created`` on. While waiting for the robots:
        every LOOK_PERIOD s, or now with ``at_once``. Never once refused or running.
        """
        if self.phase is Phase.LOOKING:
            return now - self.created >= self.look_time
        if self.phase is not Phase.WAITING or (now < self.next_look and not at_once):
            return False
        self.next_look = now + LOOK_PERIOD
        return True

    def heard(self, others: Optional[Sequence[str]], announced: Sequence[str],
              sent_clock: bool, now: float) -> Verdict:
        """
        Take what a look found; return its verdict (FREE while the names are not known yet).

        others: the /clock publishers other than this node (None while the graph has not named
        them all); announced, sent_clock: as in :func:`domain_verdict` (sent_clock counts while
        looking only: the node hears /clock until its look is over). While looking, a free
        domain or a leftover ends the look; another team refuses at once when announced, else
        once LOOK_LIMIT s have passed (time to hear its host). While waiting for the robots,
        another team refuses at once: this plant has not moved a body yet.
        """
        if others is None or self.phase not in (Phase.LOOKING, Phase.WAITING):
            return Verdict.FREE
        looking = self.phase is Phase.LOOKING
        verdict = domain_verdict(others, announced, sent_clock and looking, self.own_name)
        if verdict is Verdict.OTHER_TEAM:
            if not looking or announced or now - self.created >= LOOK_LIMIT:
                self.phase = Phase.REFUSED
                self.refused = list(others)
        elif looking:
            self.phase = Phase.WAITING if self.hold else Phase.RUNNING
        return verdict

    def clock_match(self, unmatched: bool, now: float) -> ClockMatch:
        """
        Return whether the clock may start as far as its subscribers go.

        unmatched: whether a /clock subscriber the graph shows is not matched to the plant's
        publisher. The wait counts from the first call, at most CLOCK_MATCH_WAIT s.
        """
        if self.clock_match_since is None:
            self.clock_match_since = now
        if not unmatched:
            return ClockMatch.MATCHED
        if now - self.clock_match_since >= CLOCK_MATCH_WAIT:
            return ClockMatch.GAVE_UP
        return ClockMatch.WAIT

    def start(self) -> None:
        """Every robot is up: the clock runs from now on."""
        if self.phase is Phase.WAITING:
            self.phase = Phase.RUNNING


def waiting_line(missing: Sequence[int], num_robots: int, wanted: int,
                 states_topic: Optional[str]) -> str:
    """
    Return the line that says what the clock waits for.

    missing: the robots (1-based) without a command yet; wanted: the subscribers awaited on
    every pose topic; states_topic: the team transport's states topic (None: robot transport).
    """
    more = '...' if len(missing) > 10 else ''
    listeners = f'{wanted} subscribers on every pose topic'
    if states_topic is not None:
        listeners = f'a subscriber of {states_topic}' + (f' and {listeners}' if wanted > 0
                                                         else '')
    return (f'waiting for {len(missing)} of {num_robots} robots to send a command (robots '
            f'{list(missing[:10])}{more}) and for {listeners}')


def clock_maker(names: Sequence[str]) -> str:
    """Return what the /clock publishers ``names`` are: 'plant', 'world' or '/clock publisher'."""
    kinds = [name.rsplit('/', 1)[-1] for name in names]
    return next((kind for kind in kinds if kind in CLOCK_MAKERS), '/clock publisher')


def leftover_line(name: str, waited: float) -> str:
    """Return the line of a silent /clock publisher ``name`` taken for a killed node's."""
    maker = clock_maker([name])
    killed = maker if maker in CLOCK_MAKERS else 'plant'
    return (f'{name} is listed as a /clock publisher but sent nothing for {waited:.1f} s: taken '
            f'for what is left of a {killed} that was killed (DDS forgets it within about 20 '
            's); starting')


def refusal_line(others: Sequence[str], domain_id: int, named: str) -> str:
    """
    Return the line of a plant or world refusing to start beside the /clock publishers ``others``.

    domain_id: the ROS_DOMAIN_ID; named: ``others`` named with their hosts where known.
    """
    return (f'refusing to start: another {clock_maker(others)} is on '
            f'ROS_DOMAIN_ID {domain_id}: {named} publishes /clock (another team? stop it, or '
            'run this team on a domain of its own: export ROS_DOMAIN_ID=N, or the launcher '
            'without ROS_DOMAIN_ID set)')
