# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
One team: announce the values every node must agree on, and name the nodes that differ.

Every formation node adds ``core.team.team_values`` to its ``/diagnostics`` status under keys
``team: <name>``. The plant and the reference hear every node's status (:class:`TeamCheck`: the
callback stores, the node's diagnostics timer compares) and name each node whose values differ
from their own. The shape in force may differ for a moment after a switch (a node takes it a
few milliseconds later, and announcements are a second apart), so a shape counts as different
only when it is none of the shapes this node itself had in force in its last
:data:`RECENT` checks.
"""

from collections import deque
from typing import Dict, List, Mapping

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.params import FormationConfig
from formation_ros.core.team import differences, team_values
from formation_ros.ros import qos, topics
from formation_ros.ros.once import OnceLog
import numpy as np
from numpy.typing import NDArray
from rclpy.node import Node

PREFIX = 'team: '
TRANSIENT = ('shape in force',)
RECENT = 3


def announced(values: Mapping[str, str]) -> Dict[str, str]:
    """Return the diagnostics keys of the team values: ``team: num_robots`` and so on."""
    return {PREFIX + name: text for name, text in values.items()}


class TeamCheck:
    """Hears every node's ``/diagnostics``; :meth:`disagreeing` compares with this node's."""

    def __init__(self, node: Node, own_name: str) -> None:
        """Subscribe ``node`` (whose own status is named ``own_name``) to /diagnostics."""
        self.own_name = own_name
        self.heard: Dict[str, Dict[str, str]] = {}
        self.own_recent: deque = deque(maxlen=RECENT)
        node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS, self.store,
                                 qos.DIAGNOSTICS)

    def store(self, msg: DiagnosticArray) -> None:
        """Keep the team values each formation node announced last."""
        for status in msg.status:
            if status.name == self.own_name or not status.name.startswith('formation_ros/'):
                continue
            values = {kv.key[len(PREFIX):]: kv.value for kv in status.values
                      if kv.key.startswith(PREFIX)}
            if values:
                self.heard[status.name] = values

    def disagreeing(self, own: Mapping[str, str]) -> Dict[str, Dict[str, str]]:
        """Return {node: {value: 'theirs (here: ours)'}} of the nodes whose last word differs."""
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
