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
"""

import os
import socket
import subprocess
import sys
import time
from typing import List, Mapping, Optional, Sequence, Tuple

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
DOMAIN_ENV = 'ROS_DOMAIN_ID'
DISCOVERY_ENV = 'ROS_AUTOMATIC_DISCOVERY_RANGE'
PROBE_NODE = 'formation_domain_probe'


def participant_ports(domain: int) -> List[int]:
    """Return the metatraffic unicast ports of participants 0.. on ``domain`` (RTPS 9.6.1.1)."""
    base = PORT_BASE + DOMAIN_GAIN * domain + UNICAST_OFFSET
    return [base + PARTICIPANT_GAIN * p for p in range(PARTICIPANTS)]


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
    """``python -m formation_ros.tools.domain --look S``: print the nodes seen on the domain."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 2 or args[0] != '--look':
        print('usage: python -m formation_ros.tools.domain --look SECONDS', file=sys.stderr)
        return 2
    print(look(float(args[1])))
    return 0


if __name__ == '__main__':
    sys.exit(main())
