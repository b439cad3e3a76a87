# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The plant's status, without ROS: its ``/diagnostics`` values and level, and its command lines.

:class:`PlantStatus` makes the values, level and message the node publishes once a second from
the model's counters, the refusals, the start gate and what the node heard on the graph
(:class:`Heard`); the keys are docs/faults.md's. :class:`CommandWatch` says which robots'
command status changed each step, as notes for ``ros.once.OnceLog`` (docs/faults.md: commands
stamped in the future or too old).
"""

from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.plant import CommandStatus, PlantModel, StepReport
from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.lockstep import WAITED, WAITING_FOR
from formation_ros.core.rules.plant_gate import Phase
from formation_ros.core.rules.plant_intake import refused_by_robot, Source, TEAM
from formation_ros.core.settings.params import FormationConfig
import numpy as np
from numpy.typing import NDArray

FRESH_PERIODS = 2
"""A command is fresh (``steps with fresh commands``) while the state it answers is at most this
many state periods old (as bench_capacity's fresh share)."""
NAMED_STATUSES = (CommandStatus.STALE, CommandStatus.FUTURE, CommandStatus.NON_FINITE,
                  CommandStatus.SATURATED)


def robots_named(indices: Sequence[int], shown: int = 5) -> str:
    """Return 'robot 4', 'robots 1, 4 and 7' or 'robots 1, 2, 3, 4, 5 and 95 more' (0-based in)."""
    ids = sorted(i + 1 for i in indices)
    if len(ids) == 1:
        return f'robot {ids[0]}'
    if len(ids) <= shown:
        return f"robots {', '.join(map(str, ids[:-1]))} and {ids[-1]}"
    return f"robots {', '.join(map(str, ids[:shown]))} and {len(ids) - shown} more"


def _counts(counts: Dict[int, int]) -> str:
    """Return '1: 3, 4: 1' of {robot: count}."""
    return ', '.join(f'{robot}: {count}' for robot, count in counts.items())


def start_line(config: FormationConfig, dt: float) -> str:
    """Return the plant's first line: the team, the step, the reference, how it runs (dt: s)."""
    imperfections = config.imperfections
    plant = config.plant
    assert plant is not None
    return (f'plant: {config.num_robots} robots in {config.dim}D, dt = {dt:g} s, reference '
            f'{config.reference_kind.value}, '
            + ('lockstep' if config.lockstep else f'realtime factor {plant.realtime_factor:g}')
            + (', team transport' if config.team_transport else '')
            + ('' if imperfections.is_ideal else ', bodies beyond the paper: ' + ', '.join(
                f'{name} = {value:g}' for name, value in imperfections.as_dict().items()
                if value)))


@dataclass
class Heard:
    """
    What the plant node read for its status: commands' ages, publishers and other nodes.

    command_states: each robot's 'alive', 'lost' or 'unknown'; team_publishers: matched
    publishers of /formation/commands; listened: (N,) robots whose pose and neighbors are
    published; announced: this node's team values and identity (``ros.team.announced``);
    disagreeing: one line per node with other team values; doubled: {robot node: its
    processes}; plants: the other plants running, described ('' for none); shared: {topic:
    its other publishers}; waiting: a lockstep wait being named (``core.rules.lockstep``).
    """

    command_states: List[str]
    team_publishers: int = 0
    listened: Optional[NDArray[np.bool_]] = None
    announced: Dict[str, str] = field(default_factory=dict)
    disagreeing: List[str] = field(default_factory=list)
    doubled: Dict[str, str] = field(default_factory=dict)
    plants: str = ''
    shared: Dict[str, str] = field(default_factory=dict)
    waiting: Dict[str, object] = field(default_factory=dict)


class PlantStatus:
    """
    The plant's status once a period.

    lockstep, unicycles, team_transport: as configured; target_rate: steps per second asked
    for (realtime factor / dt); publish_every: steps per published state; u_bound: c M1, m/s;
    now: steady clock, s (the step rate is counted from there).
    """

    def __init__(self, lockstep: bool, unicycles: bool, team_transport: bool,
                 target_rate: float, publish_every: int, u_bound: float, now: float) -> None:
        """Count the step rate from ``now``."""
        self.lockstep, self.unicycles = lockstep, unicycles
        self.team_transport = team_transport
        self.target_rate = target_rate
        self.fresh_age_steps = FRESH_PERIODS * publish_every
        self.u_bound = u_bound
        self.rate_window: Tuple[float, int] = (now, 0)

    def restart(self, now: float, steps: int) -> None:
        """Count the step rate from ``now`` on, at ``steps`` steps (the clock starts)."""
        self.rate_window = (now, steps)

    def report(self, now: float, model: PlantModel, phase: Phase, mode: str, held_steps: int,
               refusals: 'Refusals[Source]', heard: Heard) -> Tuple[str, str, Dict[str, Any]]:
        """
        Return (level, message, values) of the status now (steady clock, s).

        mode: the team's ('running', 'stopped'); held_steps: steps run while stopped.
        """
        since, steps = self.rate_window
        counts = model.counts
        rate = (counts.steps - steps) / (now - since) if now > since else 0.0
        self.rate_window = (now, counts.steps)
        values: Dict[str, Any] = {
            'simulated time [s]': model.t, 'step rate achieved [Hz]': rate,
            'step rate target [Hz]': 'lockstep' if self.lockstep else self.target_rate,
            'min pair distance [m]': model.closest_pair_distance(),
            **({'min body distance [m]': model.closest_body_distance()}
               if self.unicycles else {}),
            'bound c*M1 [m/s]': self.u_bound,
            'oldest command counted [s]': counts.oldest_counted_ns / NS_PER_S,
            'steps with fresh commands': counts.fresh_steps(self.fresh_age_steps)}
        values.update({name.replace('_', ' '): count for name, count in counts.totals().items()})
        wrong_frame = refused_by_robot(refusals, Reason.FRAME)
        if wrong_frame:
            values['robots with cmd_vel in a frame other than their command frame'] = \
                _counts(wrong_frame)
        values['team'] = mode
        values['held steps'] = held_steps
        values.update({f'refused {source} messages': count
                       for (source, reason), count in refusals.items()
                       if reason is Reason.CHANGE})
        malformed = refused_by_robot(refusals, Reason.MALFORMED)
        if malformed:
            values['robots with malformed cmd_vel messages'] = _counts(malformed)
        non_finite = refused_by_robot(refusals, Reason.NON_FINITE)
        if non_finite:
            values['robots with non-finite cmd_vel messages'] = _counts(non_finite)
        if self.team_transport:
            listened = np.zeros(0, bool) if heard.listened is None else heard.listened
            values['transport'] = 'team'
            values['malformed team command messages'] = refusals.count(TEAM, Reason.MALFORMED)
            values['team command messages in another frame'] = refusals.count(
                TEAM, Reason.FRAME)
            values['non-finite team command messages'] = refusals.count(TEAM, Reason.NON_FINITE)
            values['team command publishers'] = heard.team_publishers
            values['robots with pose and neighbors published'] = ', '.join(
                str(i + 1) for i in np.flatnonzero(listened).tolist()) or 'none'
        for status in NAMED_STATUSES:
            robots = counts.by_robot(status)
            if robots:
                name = status.name.lower().replace('_', '-')
                values[f'robots with {name} commands'] = _counts(robots)
        states = heard.command_states
        for state in ('alive', 'lost'):
            values[f'robots with {state} cmd_vel'] = ', '.join(
                str(i + 1) for i, s in enumerate(states) if s == state) or 'none'
        values.update(heard.waiting)
        values.update(heard.announced)
        if heard.disagreeing:
            values['nodes with other team values'] = ' | '.join(heard.disagreeing)
        if heard.doubled:
            values['robot nodes in more than one process'] = ' | '.join(
                f'{name}: {processes}' for name, processes in sorted(heard.doubled.items()))
        if heard.plants:
            values['other plants'] = heard.plants
        if heard.shared:
            values['topics with more than one publisher'] = ' | '.join(
                f'{topic}: {names}' for topic, names in sorted(heard.shared.items()))
        return self._level(model, phase, rate, heard) + (values,)

    def _level(self, model: PlantModel, phase: Phase, rate: float,
               heard: Heard) -> Tuple[str, str]:
        """Return the level and message: errors first, then start-up, lost robots, rate."""
        counts = model.counts
        if (counts.collisions or counts.bound_violations or heard.shared or heard.doubled
                or heard.disagreeing or heard.plants):
            return 'error', (f'{counts.collisions} collisions, '
                             f'{counts.bound_violations} commands above the bound, '
                             f'{len(heard.shared)} topics with several publishers, '
                             f'{len(heard.doubled)} robots in several processes, '
                             f'{len(heard.disagreeing)} nodes with other team values')
        if phase in (Phase.LOOKING, Phase.REFUSED):
            return 'ok', Phase.LOOKING.value
        if phase is Phase.WAITING:
            return 'ok', Phase.WAITING.value
        if heard.waiting:
            robots, waited = heard.waiting[WAITING_FOR], heard.waiting[WAITED]
            return 'warn', f'lockstep: waiting for robots {robots} for {waited:.1f} s'
        lost = heard.command_states.count('lost')
        if lost:
            return 'warn', f'{lost} robots gone (no recent cmd_vel)'
        if not self.lockstep and rate < 0.9 * self.target_rate:
            return 'warn', f'stepping at {rate:.1f} Hz of {self.target_rate:.1f} Hz'
        return 'ok', 'running'


@dataclass(frozen=True)
class Note:
    """
    A condition of some robots that starts or ends, for ``ros.once.OnceLog``.

    keys: the conditions' keys; line(keys): the line of those that start (or end), None for
    none; level: a start's.
    """

    starts: bool
    keys: Tuple[str, ...]
    line: Optional[Callable[[List[str]], str]]
    level: str = 'warning'


class CommandWatch:
    """Each robot's command status as of the last step, and what changed (:meth:`update`)."""

    def __init__(self, num_robots: int) -> None:
        """Start with every robot's command missing."""
        self.command_status: NDArray[np.int8] = np.full(num_robots, CommandStatus.MISSING,
                                                        dtype=np.int8)

    def update(self, status: NDArray[np.int8], stamp_ns: NDArray[np.int64],
               t_ns: int) -> List[Note]:
        """
        Take a step's statuses (N,); return the notes of the robots whose status changed.

        stamp_ns: (N,) the stamps their commands answer, ns; t_ns: the step's state, ns. The
        robots whose commands went stale (or fresh again) in one step share one line.
        """
        changed = np.flatnonzero(status != self.command_status)
        self.command_status = np.array(status, dtype=np.int8)
        if not changed.size:
            return []
        now = status[changed]
        stale = {f'stale-{i}': i for i in changed[now == CommandStatus.STALE].tolist()}
        ages = {key: (t_ns - int(stamp_ns[i])) / NS_PER_S for key, i in stale.items()}
        fresh = {f'stale-{i}': i for i in changed[(now == CommandStatus.APPLIED)
                                                  | (now == CommandStatus.SATURATED)].tolist()}
        notes = [
            Note(True, tuple(stale), lambda keys: (
                f'{robots_named([stale[key] for key in keys])}: latest '
                f"command{'' if len(keys) == 1 else 's'} {max(ages[key] for key in keys):.3g} "
                f"s old{'' if len(keys) == 1 else ' at most'}; using zero")),
            Note(False, tuple(fresh), lambda keys: (
                f'{robots_named([fresh[key] for key in keys])}: commands fresh again'))]
        for i in changed[now != CommandStatus.STALE].tolist():
            notes += self._robot_notes(i, CommandStatus(status[i]),
                                       (t_ns - int(stamp_ns[i])) / NS_PER_S)
        return [note for note in notes if note.keys]

    @staticmethod
    def _robot_notes(i: int, status: CommandStatus, age: float) -> List[Note]:
        """Return the notes of robot ``i`` whose command's status became ``status``."""
        def line(text: str) -> Callable[[List[str]], str]:
            return lambda keys: text
        notes = []
        if status is CommandStatus.FUTURE:
            notes.append(Note(True, (f'future-{i}',), line(
                f'robot {i + 1}: command stamped {-age:.3g} s after the present state (a '
                'sender on another clock? check use_sim_time); using zero'), 'error'))
        elif status is CommandStatus.NON_FINITE:
            notes.append(Note(True, (f'bad-{i}',), line(
                f'robot {i + 1} sent a non-finite command; using zero (logged once; counted in '
                'bad command steps)'), 'error'))
        elif status is CommandStatus.SATURATED:
            notes.append(Note(True, (f'saturated-{i}',), line(
                f'robot {i + 1}: command beyond what the law allows; saturating it (counted in '
                'saturated command steps)'), 'error'))
        if status in (CommandStatus.APPLIED, CommandStatus.SATURATED):
            notes.append(Note(False, (f'future-{i}',), line(
                f'robot {i + 1}: commands answer present states again')))
        if status is CommandStatus.APPLIED:
            notes.append(Note(False, (f'saturated-{i}',), None))
        return notes


def violation_lines(report: StepReport, u_bound: float, so_far: int) -> List[str]:
    """Return a line per new command above the bound c M1 (``u_bound``, m/s) of a step."""
    return [f'robot {robot + 1}: command component {value:.6g} m/s above the bound '
            f'c*M1 = {u_bound:.6g} m/s ({so_far} so far)' for robot, value in report.violations]


def collision_lines(report: StepReport, t: float, body_contact: bool) -> List[str]:
    """Return a line per collision of a step (t: after it, s; body_contact: bodies have size)."""
    limit = ('2 x body.radius or plant.collision_distance' if body_contact
             else 'plant.collision_distance')
    return [f'collision: robots {i + 1} and {j + 1} are {distance:.3g} m apart at t = '
            f'{t:.3f} s (< {limit})' for i, j, distance in report.collisions]
