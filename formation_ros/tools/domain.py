# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A ROS 2 domain of the launcher's own: a free one, unless the user chose one.

Two teams on one domain hear each other's plant and reference and neither forms. Unless
ROS_DOMAIN_ID is set or ``--domain-id`` given, the launcher runs its team on a domain where no
DDS participant is seen (:func:`choose_domain`), in two looks, the cheap one first (the
second only with discovery beyond this host: ports tell everything about this host):

1. ports (microseconds per domain): on this host, Fast DDS binds the metatraffic unicast port
   ``7400 + 250 d + 10 + 2 p`` of participant p on domain d (the RTPS well-known ports). A
   domain on which one of the first :data:`PARTICIPANTS` such ports cannot be bound has a
   participant here.
2. with ROS_AUTOMATIC_DISCOVERY_RANGE SUBNET (``--discovery subnet``), discovery: a child
   process (``python -m formation_ros.tools.domain --look S``) joins the domain with rclpy for
   up to :data:`LOOK` s and counts the nodes it sees, on other computers too (2 to 5 s with
   rclpy's start on the 2-core machine, against 0.08 s for the ports of all 101 domains).
   Bounded by :data:`CHILD_TIMEOUT`; if the child cannot tell (no rclpy), the ports decide,
   and the launcher says so.

The candidates are the domains 1 to 101 (the range safe on every Linux machine; 0 is left out:
every ROS 2 user who sets nothing is on it), starting from one derived from the user's id, so
that two users tend to start apart and one user's second run takes the next free domain. At
most :data:`TRIES` port-free candidates are looked at.

A domain the user chose is looked at for another team before anything starts
(:class:`TeamLook`; the rule is ``core.rules.occupants``): with discovery on this host only, a
domain with no participant port bound here holds none; else a child (``--team S``) reads the
ROS graph, and only the graph, for up to :data:`TEAM_LOOK` s.
"""

import dataclasses
import json
import os
import socket
import subprocess
import sys
import time
from typing import List, Mapping, Optional, Sequence, Set, Tuple

from formation_ros.core.rules.occupants import occupants

FIRST, LAST = 1, 101
PORT_BASE, DOMAIN_GAIN, UNICAST_OFFSET, PARTICIPANT_GAIN = 7400, 250, 10, 2
PARTICIPANTS = 16
"""Participant ports checked per domain: a domain with 16 processes on this host is taken."""
LOOK = 1.5
"""How long the child looks for nodes on a candidate domain, s: Fast DDS sends a new
participant's five initial announcements 0.1 s apart, and every participant answers one."""
CHILD_TIMEOUT = 30.0
"""Longest the child may take, rclpy's start on a busy machine included, s."""
TRIES = 5
PARTICIPANT_IDS = 120
"""Participant ids whose ports fit in a domain's 250 (10 + 2 p < 250)."""
TEAM_LOOK = 3.5
"""Longest the launcher looks at a domain it was given for another team, s, from the moment its
participant exists: a running participant's endpoints reached a new one within 0.3 s in half
the looks, else only with its next announcement, up to 3 s later (Fast DDS's period; 2-core
machine, 2026-12-03)."""
SETTLE = 0.15
"""With every participant bound on this host seen and its nodes named, how long the graph must
stay the same before the look ends with no team found, s (a participant's endpoints come in
one burst; a plant, relay or world is found by its name as soon as its nodes are named)."""
DOMAIN_ENV = 'ROS_DOMAIN_ID'
DISCOVERY_ENV = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
PROBE_NODE = 'formation_domain_probe'
CLOCK = '/clock'
DISCOVERY_INFO = 'ros_discovery_info'
"""The topic on which every ROS 2 participant tells its nodes: one writer per participant."""
UNKNOWN_NAME = '_NODE_NAME_UNKNOWN_'
"""What rmw calls a node whose ROS name has not reached this participant yet."""
UNNAMED = 'a node not yet named in the ROS graph'


def participant_ports(domain: int, count: int = PARTICIPANTS) -> List[int]:
    """Return the metatraffic unicast ports of participants 0.. on ``domain`` (RTPS 9.6.1.1)."""
    base = PORT_BASE + DOMAIN_GAIN * domain + UNICAST_OFFSET
    return [base + PARTICIPANT_GAIN * p for p in range(count)]


def port_in_use(port: int) -> bool:
    """Tell whether a UDP ``port`` is bound on this host (a bind to it fails)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(('0.0.0.0', port))
        except OSError:
            return True
    return False


def ports_busy(domain: int) -> bool:
    """Tell whether a participant of this host holds one of ``domain``'s participant ports."""
    return any(port_in_use(port) for port in participant_ports(domain))


def participants_here(domain: int) -> int:
    """Count the participants of this host on ``domain``: its participant ports bound."""
    return sum(port_in_use(port) for port in participant_ports(domain, PARTICIPANT_IDS))


def candidates(uid: int) -> List[int]:
    """Return the domains FIRST..LAST in the order they are tried for user ``uid``."""
    span = LAST - FIRST + 1
    start = (uid * 37) % span
    return [FIRST + (start + k) % span for k in range(span)]


def nodes_seen(domain: int, env: Mapping[str, str], seconds: float = LOOK) -> Optional[int]:
    """
    Return how many nodes a child process sees on ``domain`` within ``seconds`` s.

    None if the child could not tell (it failed or took longer than CHILD_TIMEOUT).
    """
    child_env = dict(env, **{DOMAIN_ENV: str(domain)})
    try:
        result = subprocess.run([sys.executable, '-m', 'formation_ros.tools.domain', '--look',
                                 str(seconds)], env=child_env, stdin=subprocess.DEVNULL,
                                capture_output=True, text=True, timeout=CHILD_TIMEOUT)
    except (OSError, subprocess.TimeoutExpired):
        return None
    words = result.stdout.split()
    if result.returncode != 0 or not words or not words[-1].isdigit():
        return None
    return int(words[-1])


def choose_domain(env: Mapping[str, str], uid: Optional[int] = None) -> Tuple[int, str]:
    """
    Return a free domain for a run with environment ``env``, and how it was found free.

    Raises LookupError when no candidate is free.
    """
    tried = 0
    subnet = env.get(DISCOVERY_ENV, '').upper() == 'SUBNET'
    for domain in candidates(os.getuid() if uid is None else uid):
        if ports_busy(domain):
            continue
        if not subnet:
            return domain, 'no participant of this host on it'
        seen = nodes_seen(domain, env)
        if seen is None:
            return domain, 'no participant of this host on it; the discovery look failed'
        if seen == 0:
            return domain, 'no node seen on it'
        tried += 1
        if tried >= TRIES:
            break
    raise LookupError(f'no free ROS 2 domain found among {FIRST}..{LAST}')


@dataclasses.dataclass(frozen=True)
class TeamSeen:
    """
    What a look at a domain for another team found.

    found: the nodes that show one (``core.rules.occupants``; empty: none); clock: those of them
    that publish /clock; seconds: how long the look's participant looked (0: no participant was
    needed); complete: whether it ended because it had seen every participant of this host.
    """

    found: Tuple[str, ...] = ()
    clock: Tuple[str, ...] = ()
    seconds: float = 0.0
    complete: bool = True


class TeamLook:
    """
    A look at ``domain`` for another team, under way while the launcher reads its parameters.

    env: the nodes' environment (its discovery range). With discovery on this host only, a
    domain with no participant port bound here holds no team, and nothing joins it. Else a
    child process (``--team``, :func:`team_in_graph`) joins it and reads its graph for up to
    ``seconds`` s.
    """

    def __init__(self, domain: int, env: Mapping[str, str], seconds: float = TEAM_LOOK) -> None:
        """Start the look."""
        self.child: Optional[subprocess.Popen] = None
        self.failed = False
        local = env.get(DISCOVERY_ENV, '').upper() == 'LOCALHOST'
        if local and not participants_here(domain):
            return
        try:
            self.child = subprocess.Popen(
                [sys.executable, '-m', 'formation_ros.tools.domain', '--team', str(seconds)]
                + (['--local'] if local else []), env=dict(env, **{DOMAIN_ENV: str(domain)}),
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                text=True)
        except OSError:
            self.failed = True

    def result(self) -> Optional[TeamSeen]:
        """Wait for the look (CHILD_TIMEOUT s at most); return what it found, None: cannot tell."""
        if self.failed:
            return None
        if self.child is None:
            return TeamSeen()
        try:
            out, _ = self.child.communicate(timeout=CHILD_TIMEOUT)
        except subprocess.TimeoutExpired:
            self.cancel()
            return None
        lines = out.strip().splitlines()
        if self.child.returncode != 0 or not lines:
            return None
        try:
            seen = json.loads(lines[-1])
            return TeamSeen(tuple(seen['found']), tuple(seen['clock']), float(seen['seconds']),
                            bool(seen['complete']))
        except (ValueError, KeyError, TypeError):
            return None

    def cancel(self) -> None:
        """End the look now, if it is still under way."""
        if self.child is not None and self.child.poll() is None:
            self.child.kill()
            self.child.communicate()


def _full_name(namespace: str, name: str) -> str:
    return namespace.rstrip('/') + '/' + name


def _prefixes(infos: Sequence, named: bool = False) -> Set[bytes]:
    """Return the participants (GUID prefixes) of endpoints ``infos``; ``named``: known names."""
    return {bytes(info.endpoint_gid)[:12] for info in infos
            if not named or info.node_name != UNKNOWN_NAME}


def team_in_graph(seconds: float, local: bool) -> TeamSeen:
    """
    Join ROS_DOMAIN_ID and read its graph for up to ``seconds`` s: what shows another team.

    The node makes no publisher or subscriber of a team's topics (no /rosout, no parameter
    services), and sends nothing there. The look ends as soon as ``core.rules.occupants`` finds a
    node; with ``local`` (discovery on this host only) also once every participant bound here
    is seen (its writer on ros_discovery_info) with its nodes named (their /parameter_events
    writers) and the graph has not changed for SETTLE s. A /clock publisher still unnamed at
    the end counts as UNNAMED.
    """
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node(PROBE_NODE, context=context, enable_rosout=False,
                                 start_parameter_services=False)
        start = time.monotonic()
        domain = context.get_domain_id()
        view: Optional[tuple] = None
        since = start
        while True:
            now = time.monotonic()
            clock = sorted(_full_name(info.node_namespace, info.node_name)
                           for info in node.get_publishers_info_by_topic(CLOCK))
            nodes = sorted(_full_name(namespace, name)
                           for name, namespace in node.get_node_names_and_namespaces())
            named = [name for name in clock if UNKNOWN_NAME not in name]
            over = now - start >= seconds
            if over:
                named = [UNNAMED if UNKNOWN_NAME in name else name for name in clock]
            found = occupants(named, nodes)
            if found or over:
                break
            if local:
                participants = _prefixes(node.get_publishers_info_by_topic(
                    DISCOVERY_INFO, no_mangle=True))
                if (participants, clock, nodes) != view:
                    view, since = (participants, clock, nodes), now
                everyone = (len(participants) >= participants_here(domain)
                            and participants <= _prefixes(node.get_publishers_info_by_topic(
                                '/parameter_events'), named=True))
                if everyone and len(named) == len(clock) and now - since >= SETTLE:
                    break
            time.sleep(0.05)
        looked = time.monotonic() - start
        node.destroy_node()
        return TeamSeen(tuple(found), tuple(name for name in found if name in named), looked,
                        not found and not over)
    finally:
        rclpy.shutdown(context=context)


def look(seconds: float) -> int:
    """Join ROS_DOMAIN_ID for up to ``seconds`` s; return how many other nodes were seen."""
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node(PROBE_NODE, context=context)
        deadline = time.monotonic() + seconds
        others = 0
        while time.monotonic() < deadline and not others:
            time.sleep(0.05)
            others = sum(1 for name, _ in node.get_node_names_and_namespaces()
                         if name != PROBE_NODE)
        node.destroy_node()
        return others
    finally:
        rclpy.shutdown(context=context)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """
    Run the child of a look: ``--look S`` prints the nodes seen on ROS_DOMAIN_ID.

    ``--team S [--local]`` prints what :func:`team_in_graph` found, as JSON.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) == 2 and args[0] == '--look':
        print(look(float(args[1])))
        return 0
    if len(args) in (2, 3) and args[0] == '--team' and args[2:] in ([], ['--local']):
        print(json.dumps(dataclasses.asdict(team_in_graph(float(args[1]), len(args) == 3))),
              flush=True)
        os._exit(0)  # the interpreter's teardown after rclpy's took 0.2 to 0.7 s; nobody needs it
    print('usage: python -m formation_ros.tools.domain --look SECONDS | --team SECONDS '
          '[--local]', file=sys.stderr)
    return 2


if __name__ == '__main__':
    sys.exit(main())
