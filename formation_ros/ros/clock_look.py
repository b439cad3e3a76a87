# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The look at the domain of a node that makes the clock (the plant, the world) before it starts.

What the graph shows (the other ``/clock`` publishers, named, and which of them another process
announces on ``/diagnostics``) goes to the node's start gate, ``core.rules.plant_gate.StartGate``,
whose rule (``core.rules.occupants``, the launcher's too) decides: refuse, go on looking, or start.
This module only reads the graph for it, for both nodes; the rule is not repeated here.
"""

from typing import List, Optional, Tuple

from formation_ros.core.rules.plant_gate import refusal_line, StartGate, Verdict
from formation_ros.ros import topics
from formation_ros.ros.team import PublisherWatch, TeamCheck


def look_at_clock(watch: PublisherWatch, team_check: TeamCheck, gate: StartGate,
                  sent_clock: bool, now: float) -> Tuple[Verdict, Optional[List[str]]]:
    """
    Feed ``gate`` the /clock publishers other than its node; return its verdict and them.

    watch: the node's graph; team_check: what it heard on /diagnostics; sent_clock: whether
    /clock messages came from another node; now: steady clock, s. The publishers are None while
    the graph has not named them all (``PublisherWatch.named_publishers``).
    """
    others = watch.named_publishers(topics.CLOCK, now)
    if others is not None and gate.own_name in others:
        others.remove(gate.own_name)
    running = [name for name in others or [] if team_check.running(name, now)]
    return gate.heard(others, running, sent_clock, now), others


def refusal(watch: PublisherWatch, gate: StartGate, domain_id: int, now: float) -> str:
    """Return the one line of a node whose ``gate`` refused the domain: who holds it, where."""
    return refusal_line(gate.refused, domain_id, watch.name_others(gate.refused, None, now))
