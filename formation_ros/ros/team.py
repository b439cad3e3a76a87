# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
One team per domain: the values every node must agree on, and the second publishers of a topic.

Every formation node announces ``core.settings.team.team_values`` and who it is (host, process,
node) in its ``/diagnostics`` status (:func:`announced`); the plant and the reference hear them all
and name each node whose values differ (:class:`TeamCheck`; a shape just switched counts as the
same for :data:`RECENT` checks). :class:`PublisherWatch` looks up the graph for a second
publisher of a topic (``core.settings.team.duplicate_due`` decides when one is reported) and names
it with its host; :class:`DomainWatch` is what the plant watches with them while it runs. The
rules: docs/faults.md (two publishers on one cmd_vel; a second plant or publisher; nodes that
disagree).
"""

from collections import deque
import os
import socket
import time
from typing import Callable, Collection, Dict, List, Mapping, Optional, Sequence, Set, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.rules.turns import Turns
from formation_ros.core.settings.params import FormationConfig
from formation_ros.core.settings.team import differences, duplicate_due, team_values
from formation_ros.ros import qos, topics
from formation_ros.ros.once import OnceLog
import numpy as np
from numpy.typing import NDArray
from rclpy.node import Node

PREFIX = 'team: '
TRANSIENT = ('shape in force',)
RECENT = 3
HOST, PROCESS, NODE = 'host', 'process', 'node'
LIVE_FOR = 3.0
"""A process that announced itself on /diagnostics within this many seconds (three of its
once-a-second statuses) is taken to be running."""
PENDING = 4096
"""Arrays heard between two looks that are kept (a look comes once a second: N / 25 arrays a
second from fleets of 25, one a second from each other node)."""
Process = Tuple[str, str]
"""(host name, process id) as a node announces them."""
GRAPH_LOOKS = 100
"""Topics looked up in the graph per look for a second publisher (of 3N + 2, in turn)."""
DOUBLED_WITHIN = 1.5
"""Team transport: two processes that announced one robot node within this many seconds (their
statuses come once a second) both run it; a restarted process announces its first status more
than that after the one it replaces announced its last."""
UNKNOWN_NAME = '_NODE_NAME_UNKNOWN_'
"""What rmw calls a node whose ROS name has not reached this participant yet."""
UNNAMED = 'a node not yet named in the ROS graph'
NAMES_WAIT = 5.0
"""How long a line naming publishers waits for their ROS names, s (steady clock)."""


def full_name(namespace: str, name: str) -> str:
    """Return a node's fully qualified name: ``/plant``, ``/robot_1/robot``."""
    return namespace.rstrip('/') + '/' + name


def identity(node: Optional[Node] = None) -> Dict[str, str]:
    """Return this process's host name and id, and ``node``'s fully qualified name."""
    found = {HOST: socket.gethostname(), PROCESS: str(os.getpid())}
    if node is not None:
        found[NODE] = node.get_fully_qualified_name()
    return found


def announced(values: Mapping[str, str], node: Optional[Node] = None) -> Dict[str, str]:
    """
    Return the diagnostics keys of the team values (``team: num_robots`` ...) and who says so.

    ``host`` and ``process`` (this process), and with ``node`` its name (``node``).
    """
    return {**identity(node), **{PREFIX + name: text for name, text in values.items()}}


class TeamCheck:
    """Hears every node's ``/diagnostics``; :meth:`disagreeing` compares with this node's."""

    def __init__(self, node: Node, own_name: str) -> None:
        """Subscribe ``node`` (whose own status is named ``own_name``) to /diagnostics."""
        self.own_name = own_name
        own = identity()
        self.own_process: Process = (own[HOST], own[PROCESS])
        self.heard: Dict[str, Dict[str, str]] = {}
        self.processes: Dict[str, Dict[Process, float]] = {}
        self.own_recent: deque = deque(maxlen=RECENT)
        self.pending: deque = deque(maxlen=PENDING)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self.store,
                                 qos.DIAGNOSTICS)

    def store(self, msg: DiagnosticArray) -> None:
        """Keep an array heard, and when, for the next look (the oldest beyond PENDING go)."""
        self.pending.append((time.monotonic(), msg))

    def _take(self) -> None:
        """Read the arrays heard since the last look (:meth:`_read`)."""
        while self.pending:
            self._read(*self.pending.popleft())

    def _read(self, heard_at: float, msg: DiagnosticArray) -> None:
        """
        Keep the team values each formation node announced last, and when each process spoke.

        A status from this very process (this node, or another node of a fleet) is skipped; one
        with this node's status name from another process (a second plant) is kept.
        """
        for status in msg.status:
            if not status.name.startswith('formation_ros/'):
                continue
            keys = {kv.key: kv.value for kv in status.values}
            process = (keys.get(HOST, ''), keys.get(PROCESS, ''))
            if process == self.own_process or (status.name == self.own_name
                                               and not keys.get(PROCESS)):
                continue
            if keys.get(PROCESS):
                name = keys.get(NODE) or status.name
                self.processes.setdefault(name, {})[process] = heard_at
            values = {key[len(PREFIX):]: value for key, value in keys.items()
                      if key.startswith(PREFIX)}
            if values:
                self.heard[status.name] = values

    def running(self, node_name: str, now: float, within: float = LIVE_FOR) -> List[Process]:
        """Return the other processes that announced ``node_name`` in the last ``within`` s."""
        self._take()
        return sorted(process for process, when in self.processes.get(node_name, {}).items()
                      if now - when <= within)

    def describe(self, node_name: str, now: float) -> str:
        """Name a node with its host and process, where it announced them; else say so."""
        found = self.running(node_name, now)
        if not found:
            heard = self.processes.get(node_name, {})
            if not heard:
                return f'{node_name} (host unknown: it announces none on /diagnostics)'
            (host, pid), when = max(heard.items(), key=lambda item: item[1])
            return (f'{node_name} (silent on /diagnostics for {now - when:.0f} s; last on host '
                    f'{host} (process {pid}))')
        return f'{node_name} on ' + ', '.join(f'host {host} (process {pid})'
                                              for host, pid in found)

    def disagreeing(self, own: Mapping[str, str]) -> Dict[str, Dict[str, str]]:
        """Return {node: {value: 'theirs (here: ours)'}} of the nodes whose last word differs."""
        self._take()
        self.own_recent.append(dict(own))
        found: Dict[str, Dict[str, str]] = {}
        for name, values in self.heard.items():
            differ = differences(own, values)
            for key in TRANSIENT:
                if key in differ and any(values[key] == mine.get(key)
                                         for mine in self.own_recent):
                    del differ[key]
            if differ:
                found[name] = differ
        return found


def describe(found: Mapping[str, Mapping[str, str]]) -> List[str]:
    """Return one line per disagreeing node: its name and the values that differ."""
    return [f"{name}: {'; '.join(f'{key} {text}' for key, text in values.items())}"
            for name, values in sorted(found.items())]


def team_problems(check: TeamCheck, config: FormationConfig, shape: NDArray[np.float64],
                  once: OnceLog) -> List[str]:
    """
    Compare the team values heard with this node's; log each disagreeing node once.

    Returns one line per node that differs (for the node's diagnostics); a node that agrees
    again is logged once more as agreeing.
    """
    found = check.disagreeing(team_values(config, shape))
    lines = describe(found)
    for name, line in zip(sorted(found), lines):
        once.start(f'team-{name}', f'{line}: another parameters file? (the team cannot form '
                                   'while its nodes disagree)', 'error')
    for name in check.heard:
        if name not in found:
            once.end(f'team-{name}', f'{name} agrees with the team again')
    return lines


def _without(names: Sequence[str], own: Optional[str]) -> List[str]:
    """Return ``names`` less one ``own`` (the expected publisher; None: keep all)."""
    others = list(names)
    if own is not None and own in others:
        others.remove(own)
    return others


class PublisherWatch:
    """
    Publishers besides the expected one on some topics, looked up in the ROS graph on a timer.

    A look costs one ``count_publishers`` per topic, a lookup in the node's graph cache that
    grows with the graph (every endpoint of every node), and the publishers' names only where
    there are more than one. A plant watches three topics per robot, so :meth:`check` looks at
    ``limit`` topics at most per call, in turn (topics known to have several publishers at
    every call): a second publisher on one of T topics is seen within ceil(T / limit) calls.
    A second publisher with another node name is reported at once; one with the expected
    node's own name may be what is left of a process killed a moment ago (DDS forgets it about
    20 s later), so it is reported at once only with evidence that it runs (``alive``), else
    after ``core.settings.team.DUPLICATE_GRACE`` s.
    """

    def __init__(self, node: Node, team: Optional[TeamCheck] = None,
                 limit: Optional[int] = None) -> None:
        """Look up the graph of ``node`` (``limit`` topics a call, None: all); name hosts."""
        self.node = node
        self.team = team
        self.turns = Turns(limit)
        self.since: Dict[str, float] = {}
        self.listed: Dict[str, List[str]] = {}
        """Every topic's publishers where there were several when it was looked at last."""
        self.unnamed_since: Dict[str, float] = {}

    def publishers(self, topic: str) -> List[str]:
        """Return the fully qualified names of the nodes publishing ``topic`` (one per writer)."""
        if self.node.count_publishers(topic) <= 1:
            return []
        return sorted(full_name(info.node_namespace, info.node_name)
                      for info in self.node.get_publishers_info_by_topic(topic))

    def named_publishers(self, topic: str, now: float) -> Optional[List[str]]:
        """
        Return :meth:`publishers` once the graph knows every one's ROS name; None until then.

        DDS announces a writer before its participant's ROS node names arrive (a moment, or
        seconds on a busy machine), and rmw names such a writer ``_NODE_NAME_UNKNOWN_``. A line
        that names the publishers waits for the names, at most NAMES_WAIT s (``now``: steady
        clock, s), then calls the nameless ones so.
        """
        names = self.publishers(topic)
        if not any(UNKNOWN_NAME in name for name in names):
            self.unnamed_since.pop(topic, None)
            return names
        if now - self.unnamed_since.setdefault(topic, now) < NAMES_WAIT:
            return None
        return [UNNAMED if UNKNOWN_NAME in name else name for name in names]

    def _looked_at(self, topics: Sequence[str]) -> List[str]:
        """Return the topics of this call: the next ``limit`` in turn, and those with several."""
        turn = [topics[i] for i in self.turns.due(len(topics))]
        chosen = set(turn)
        return turn + [topic for topic in self.listed if topic not in chosen]

    def check(self, expected: Mapping[str, Optional[str]], now: float,
              alive: Callable[[str, Sequence[str]], bool] = lambda topic, names: False
              ) -> Dict[str, str]:
        """
        Return {topic: the other publishers, named} for each topic of ``expected`` now due.

        expected: {topic: the one node that should publish it (fully qualified), or None for
        any one node}; alive(topic, names): whether a same-named second publisher is known to
        run.
        """
        for topic in self._looked_at(list(expected)):
            names = self.named_publishers(topic, now) if topic in expected else []
            if names is None:
                continue
            if names:
                self.listed[topic] = names
                self.since.setdefault(topic, now)
            else:
                self.listed.pop(topic, None)
                self.since.pop(topic, None)
        due: Dict[str, str] = {}
        for topic, names in self.listed.items():
            if topic not in expected:
                continue
            own = expected[topic]
            if duplicate_due(names, own, now - self.since[topic], alive(topic, names)):
                due[topic] = self.name_others(names, own, now)
        return due

    def others(self, topic: str, own: Optional[str]) -> str:
        """
        Name the publishers of ``topic`` other than ``own`` as last looked at, without hosts.

        A condition's key: the hosts :meth:`name_others` adds come and go with the
        announcements on ``/diagnostics`` (late on a busy machine), the names do not.
        """
        return ', '.join(sorted(set(_without(self.listed.get(topic, []), own))))

    def name_others(self, names: Sequence[str], own: Optional[str], now: float) -> str:
        """Describe the publishers of a topic other than ``own`` (all of them if it is None)."""
        others = _without(names, own)
        described = []
        for name in sorted(set(others)):
            text = self.team.describe(name, now) if self.team is not None else name
            count = others.count(name)
            described.append(text + (f' ({count} publishers)' if count > 1 else ''))
        return ', '.join(described)


class DomainWatch:
    """
    The plant's topics, robot nodes and name, watched for a second of each.

    expected: {topic: its one publisher (fully qualified), None for any one}; commands: the
    cmd_vel topics (robot transport); robot_nodes: the robot nodes' names, watched for two
    processes (team transport; empty: not watched).
    """

    def __init__(self, node: Node, team_check: TeamCheck, once: OnceLog,
                 expected: Mapping[str, Optional[str]], commands: Collection[str],
                 robot_nodes: Sequence[str]) -> None:
        """Watch the graph of ``node``, whose fully qualified name is the plant's."""
        self.own_name = node.get_fully_qualified_name()
        self.team_check = team_check
        self.once = once
        self.graph = PublisherWatch(node, team_check, GRAPH_LOOKS)
        self.expected = dict(expected)
        self.commands = set(commands)
        self.robot_nodes = list(robot_nodes)
        self.shared_by: Set[str] = set()
        """The publishers (names without hosts) of each line on shared topics logged."""
        self.doubled: Dict[str, str] = {}

    def shared_topics(self, now: float, clock: str, clock_runs: bool) -> Dict[str, str]:
        """
        Return {topic: its other publishers} now (steady clock, s); log each group once.

        clock: the /clock topic, watched only once the clock runs (``clock_runs``).
        """
        expected = {topic: name for topic, name in self.expected.items()
                    if topic != clock or clock_runs}
        shared = self.graph.check(expected, now, self._alive)
        by_names: Dict[str, List[str]] = {}
        for topic in shared:
            by_names.setdefault(self.graph.others(topic, expected[topic]), []).append(topic)
        lines = {names: f'{_some(listed)} more than one publisher: {shared[listed[0]]} ('
                 + ('a second node with this robot_id?' if listed[0] in self.commands
                    else 'another team on this domain, or a node forging them?') + ')'
                 for names, listed in by_names.items()}
        self.once.follow('publishers', lines, self.shared_by,
                         lambda names: f'{names}: no longer publishing here')
        self.shared_by = set(lines)
        return shared

    def doubled_robots(self, now: float) -> Dict[str, str]:
        """
        Return {robot node: its processes} of those two processes announce; log each once.

        Two processes that run one robot both answer for it on the team topic, where the plant
        cannot tell them apart; their announcements on /diagnostics show them.
        """
        doubled = {name: self.team_check.describe(name, now) for name in self.robot_nodes
                   if len(self.team_check.running(name, now, DOUBLED_WITHIN)) >= 2}
        self.once.follow('doubled', {name: f'{name} runs in more than one process: {processes}'
                                           ' (a second node with this robot_id?)'
                                     for name, processes in doubled.items()},
                         self.doubled, lambda name: f'{name} runs in one process again')
        self.doubled = doubled
        return doubled

    def other_plants(self, now: float) -> str:
        """Describe another process that announces this plant's name ('' for none); log once."""
        if self.team_check.running(self.own_name, now):
            plants = self.team_check.describe(self.own_name, now)
            self.once.start('other-plant', f'another plant runs on this domain: {plants} '
                                           '(another team? each needs a ROS_DOMAIN_ID of its own)',
                            'error')
            return plants
        self.once.end('other-plant', 'the other plant is gone')
        return ''

    def _alive(self, topic: str, names: Sequence[str]) -> bool:
        """
        Whether a same-named second publisher of ``topic`` is known to run.

        A second robot with one name: two processes announce it on /diagnostics (the graph
        alone keeps a killed one's endpoints until DDS drops its participant, about 20 s).
        """
        now = time.monotonic()
        if topic not in self.commands:
            return bool(self.team_check.running(self.own_name, now))
        return len(self.team_check.running(names[0], now)) >= 2


def _some(topics: List[str], shown: int = 3) -> str:
    """Return '/clock has' or '/clock, /robot_1/pose and 99 more topics have'."""
    if len(topics) == 1:
        return f'{topics[0]} has'
    more = f' and {len(topics) - shown} more topics' if len(topics) > shown else ''
    return f"{', '.join(topics[:shown])}{more} have"
