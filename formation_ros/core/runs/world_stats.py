# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a run on the physics engine did: the one schema of ``world_stats.json``.

The world node and ``formation_sim --engine mujoco`` both fill a :class:`WorldRunStats` and
write its :meth:`WorldRunStats.record` (``core.runs.output.stats_text``), so each field has one
meaning in both files; the fields: docs/physics.md ("What world_stats.json holds"). Times are
s, distances m; robots are named 1-based, as strings in the JSON objects.
"""

from dataclasses import asdict, dataclass
from typing import Any, Dict, List, Optional

WORLD_STATS_FILE = 'world_stats.json'
"""The file name of a run's engine statistics in its output directory."""


@dataclass(frozen=True)
class Contact:
    """Robots ``i`` and ``j`` (1-based) came into contact at ``t`` s (simulated)."""

    i: int
    j: int
    t: float


@dataclass(frozen=True)
class ObstacleContact:
    """Robot ``robot`` (1-based) touched ``obstacle`` ('circle 1', 'wall 2'...) at ``t`` s."""

    robot: int
    obstacle: str
    t: float


@dataclass(frozen=True)
class BlowUp:
    """The engine blew up: robot ``robot`` (1-based) got an absurd pose at ``t`` s; ``what``."""

    robot: int
    t: float
    what: str


@dataclass(frozen=True)
class WorldRunStats:
    """
    A run on the engine, field by field as ``world_stats.json`` holds them.

    contacts: contact events between robots; min_body_distance: the closest approach of two
    robots' positions, m; min_footprint_gap: that less twice the footprint radius, m (< 0: they
    overlapped); obstacle_contacts: contact events between a robot and an obstacle (counted
    apart from ``contacts``); min_obstacle_gap: the smallest gap of a body to an obstacle's
    surface, m, its footprint radius subtracted (< 0: it overlapped; inf, written null, without
    obstacles); steps: engine steps; engine_realtime_factor: simulated_time over
    engine_wall_time; achieved_realtime_factor: simulated_time over wall_time; realtime_factor:
    the factor asked for (None: as fast as it can, offline); wall_time: wall-clock s from the
    first step to the end (the node's whole run, or the offline loop of law and engine);
    simulated_time: s; steps_per_second: steps over wall_time; ticks_behind: times the world fell
    further behind than it may catch up at once; simulated_time_let_go: simulated s let go
    then; contact_events: each new contact; obstacle_contact_events: each new contact with an
    obstacle; stale_command_messages: {robot: commands already
    older than world.cmd_timeout when applied}; model: the engine's body model; timestep: s;
    unstable: where the engine blew up, None if it did not; refused_command_messages: {reason:
    {robot: cmd_vel refused}}; engine_wall_time: wall-clock s spent in the engine's steps;
    mujoco_version: MuJoCo's.
    """

    contacts: int
    min_body_distance: float
    min_footprint_gap: float
    obstacle_contacts: int
    min_obstacle_gap: float
    steps: int
    engine_realtime_factor: float
    achieved_realtime_factor: float
    realtime_factor: Optional[float]
    wall_time: float
    simulated_time: float
    steps_per_second: float
    ticks_behind: int
    simulated_time_let_go: float
    contact_events: List[Contact]
    obstacle_contact_events: List[ObstacleContact]
    stale_command_messages: Dict[int, int]
    model: str
    timestep: float
    unstable: Optional[BlowUp]
    refused_command_messages: Dict[str, Dict[int, int]]
    engine_wall_time: float
    mujoco_version: str

    def record(self) -> Dict[str, Any]:
        """Return the JSON object of ``world_stats.json``, in the order of the fields."""
        record = asdict(self)
        record['stale_command_messages'] = _by_robot(self.stale_command_messages)
        record['refused_command_messages'] = {
            reason: _by_robot(counts) for reason, counts in self.refused_command_messages.items()}
        return record


def _by_robot(counts: Dict[int, int]) -> Dict[str, int]:
    """Return {robot: count} with the robots as JSON keys (strings), in order."""
    return {str(robot): count for robot, count in sorted(counts.items())}


def ratio(numerator: float, denominator: float) -> float:
    """Return numerator / denominator, 0.0 for a denominator of 0 (nothing timed yet)."""
    return numerator / denominator if denominator > 0.0 else 0.0
