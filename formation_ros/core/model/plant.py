# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The robots' bodies and sensors, without ROS: one model for ``formation_sim --dt`` and the plant.

:class:`PlantModel` steps the bodies with zero-order hold (q_i' = u_i, eq. 1, or the unicycles
of ``core.model.bodies`` and ``core.maths.unicycle``), in integer nanoseconds as message stamps
are, so the simulator and the plant node step through the same instants. Each step it admits the
commands (:meth:`PlantModel.admit`), audits the bound c M1 and checks collisions
(:meth:`PlantModel.advance`); it senses what each robot's range sensor sees
(:meth:`PlantModel.sensed`, the rule of ``core.maths.sensing``). Bodies beyond the paper (lag, an
acceleration limit, noisy or late sensing): ``core.model.dynamics`` and docs/equations.md (D1-D4).

Positions are rows: ``q`` (N, dim) in m; headings (N,) in rad; commands (N, dim) in m/s for
points, (N, 2) holding (v, w) in m/s and rad/s for unicycles.
"""

from collections import OrderedDict
from dataclasses import dataclass, field
import enum
from typing import Dict, List, Optional, Set, Tuple, TYPE_CHECKING

from formation_ros.core.maths.frames import from_frame_velocity, to_frame_velocity
from formation_ros.core.maths.law import LawParams
from formation_ros.core.maths.obstacle_tracking import feed_forward_change
from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.maths.pairs import pairs_within, row_differences, squared_norms
from formation_ros.core.maths.reference import Reference
from formation_ros.core.maths.sensing import neighbour_lists, sensed_pairs, sensor_radii
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import Bodies, PointBodies
from formation_ros.core.model.dynamics import IDEAL, Imperfections
import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

BOUND_TOLERANCE_FIXED = 1e-9
BOUND_TOLERANCE_MOVING = 1e-3
MAX_STATES_KEPT = 512
MAX_START_TRIES = 20000
GRID_FROM = 64
"""A random start compares a candidate with every point placed while there are fewer than this
many, with the points of the neighbouring grid cells after."""
PLANT_STATS_FILE = 'plant_stats.json'
AGE_BINS = 64
"""Command ages counted step by step in :attr:`PlantCounts.age_steps` (one more bin: none)."""
PAIR_SKIN = 0.25
"""With ``pair_radius`` the model searches the pairs within (1 + PAIR_SKIN) times it and keeps
them as candidates until some control point has moved half the difference since (a Verlet
list): each step's pairs are the candidates within ``pair_radius``, the very pairs a search of
its own would find, in the same order (``law.neighbour_pairs``), with fewer searches."""


class CommandStatus(enum.IntEnum):
    """What the plant made of a robot's latest command for one step."""

    APPLIED = 0
    MISSING = 1
    STALE = 2
    NON_FINITE = 3
    FUTURE = 4
    SATURATED = 5


@dataclass
class Commands:
    """
    The latest command of every robot, as received: what the plant node stores from cmd_vel.

    u: (N, dim) m/s; stamp_ns: (N,) the stamp of the state each command answers, ns;
    present: (N,) whether robot i has sent a command at all.
    """

    u: NDArray[np.float64]
    stamp_ns: NDArray[np.int64]
    present: NDArray[np.bool_]

    @classmethod
    def empty(cls, num_robots: int, dim: int) -> 'Commands':
        """No command from anyone yet."""
        return cls(np.zeros((num_robots, dim)), np.zeros(num_robots, dtype=np.int64),
                   np.zeros(num_robots, dtype=bool))

    def store(self, index: int, velocity: ArrayLike, stamp_ns: int) -> None:
        """Keep robot ``index``'s (0-based) newest command."""
        self.u[index] = velocity
        self.stamp_ns[index] = stamp_ns
        self.present[index] = True

    def store_all(self, u: ArrayLike, stamp_ns: int) -> None:
        """Keep one command per robot, all answering the state stamped ``stamp_ns``."""
        self.u[:] = u
        self.stamp_ns[:] = stamp_ns
        self.present[:] = True


@dataclass(frozen=True)
class Admission:
    """
    What counts for one step.

    u: (N, dim) commands held over the step, m/s ((N, 2) (v, w) for unicycles); status: (N,)
    :class:`CommandStatus` codes; largest_u_hat: (N,) largest |u_hat| component of each command
    as sent (0 where it did not count), m/s; velocity: (N, dim) the control-point velocity each
    held command stands for, world frame, m/s: ``u`` itself for points, R(th) (v, l w) at the
    heading of the state it answers for unicycles (what the robot's law asked for).
    """

    u: NDArray[np.float64]
    status: NDArray[np.int8]
    largest_u_hat: NDArray[np.float64]
    velocity: NDArray[np.float64]

    @property
    def counted(self) -> NDArray[np.bool_]:
        """(N,) whether each robot's command counted for the step (applied or saturated)."""
        counted: NDArray[np.bool_] = ((self.status == CommandStatus.APPLIED)
                                      | (self.status == CommandStatus.SATURATED))
        return counted


Saturation = Tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_],
                   NDArray[np.float64]]
"""(commands, velocities, saturated, largest |u_hat|) of ``PlantModel._saturate``."""


@dataclass(frozen=True)
class StepReport:
    """
    One step: the state it started from and what happened.

    t_ns, q: time and body positions (N, dim) before the step; admission: the commands held
    over it; violations: (robot index, largest |u_hat| component in m/s) of new commands above
    the bound; collisions: (i, j, distance in m) of pairs of bodies that came closer than the
    collision distance during the step (indices 0-based, i < j); points, heading: the control
    points (N, dim; q itself for points, the hand points of unicycles) and headings (N,) before
    the step.
    """

    t_ns: int
    q: NDArray[np.float64]
    admission: Admission
    violations: List[Tuple[int, float]]
    collisions: List[Tuple[int, int, float]]
    points: NDArray[np.float64]
    heading: NDArray[np.float64]
    velocity: Optional[NDArray[np.float64]] = None
    """The bodies' velocity at the end of the step, as the commands ((N, dim) world m/s for
    points, (N, 2) (v, w) for unicycles): the held command itself for ideal bodies."""


@dataclass(frozen=True)
class SensedState:
    """
    What the robots receive now: a state as measured, stamped with when it was measured.

    stamp_ns: measurement time (the present minus the delay), ns; q: (N, dim) sensed body
    positions, m; heading: (N,) headings, rad (exact: the noise is on positions); points:
    (N, dim) the control points of q and heading (what each robot's law computes from them).
    tree, body_tree, pairs: k-d trees of points and q and the pairs within the model's
    ``pair_radius``, when the model has them for this state (ideal sensing), else None.
    """

    stamp_ns: int
    q: NDArray[np.float64]
    heading: NDArray[np.float64]
    points: NDArray[np.float64]
    tree: Optional['cKDTree'] = None
    body_tree: Optional['cKDTree'] = None
    pairs: Optional[NDArray[np.intp]] = None


@dataclass
class PlantCounts:
    """What the model counted so far; per-robot arrays are (N,) and indexed from 0."""

    steps: int = 0
    collisions: int = 0
    bound_violations: int = 0
    oldest_counted_ns: int = 0
    """Age of the oldest command that counted for a step (how late commands arrive), ns."""
    status_steps: NDArray[np.int64] = field(default_factory=lambda: np.zeros((4, 0), np.int64))
    age_steps: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(AGE_BINS + 1, np.int64))
    """Steps by the age of the oldest command held over them, in steps: bin k counts the steps
    whose every robot held a command answering a state at most k steps old (and older than
    k - 1); the last bin the steps at which some robot's command was older than AGE_BINS - 1
    steps or did not count at all (missing, stale, future, non-finite)."""

    def fresh_steps(self, max_age_steps: int) -> int:
        """Return the steps at which every robot's command answered a state <= that old."""
        kept = int(np.clip(max_age_steps, -1, AGE_BINS - 1))
        return int(self.age_steps[:kept + 1].sum())

    def fresh_fraction(self, max_age_steps: int) -> float:
        """Fraction of steps at which every robot's command answered a state <= that old."""
        if self.steps == 0:
            return 0.0
        return self.fresh_steps(max_age_steps) / self.steps

    def steps_with(self, status: CommandStatus) -> int:
        """Robot-steps whose command had ``status`` (e.g. STALE), summed over robots."""
        return int(self.status_steps[status].sum())

    def totals(self) -> Dict[str, int]:
        """Return the counters by name (the keys of ``plant_stats.json``)."""
        return {'steps': self.steps, 'collisions': self.collisions,
                'bound_violations': self.bound_violations,
                'stale_command_steps': self.steps_with(CommandStatus.STALE),
                'bad_command_steps': self.steps_with(CommandStatus.NON_FINITE),
                'missing_command_steps': self.steps_with(CommandStatus.MISSING),
                'future_command_steps': self.steps_with(CommandStatus.FUTURE),
                'saturated_command_steps': self.steps_with(CommandStatus.SATURATED)}

    def by_robot(self, status: CommandStatus) -> Dict[int, int]:
        """Robot-steps with ``status`` per robot (1-based), for the robots that had any."""
        row = self.status_steps[status]
        return {int(i) + 1: int(row[i]) for i in np.flatnonzero(row)}


@dataclass(frozen=True)
class StartSpec:
    """
    Where the robots start: explicit positions (N, dim), or random in a disc/ball.

    With ``positions`` None: ``num_robots`` points uniform in the disc (ball in 3D) of
    ``random_radius`` m about the origin, pairwise at least ``min_separation`` m apart, from
    the random generator seeded with ``seed``.
    """

    num_robots: int
    dim: int
    positions: Optional[NDArray[np.float64]] = None
    random_radius: float = 0.0
    min_separation: float = 0.0
    seed: int = 0


def random_start(n: int, dim: int, radius: float, min_separation: float,
                 seed: int) -> Optional[NDArray[np.float64]]:
    """
    Uniform random positions in the disc/ball of ``radius`` about 0, pairwise >= separation.

    Returns (n, dim), or None when the points do not fit after many tries, or at once when
    they cannot fit at all (n balls of radius ``min_separation / 2`` about them would not fit,
    by volume, in the ball of radius ``radius + min_separation / 2``). Candidates are drawn
    one by one and kept when no point placed so far is closer than ``min_separation``; the
    placed points are kept in a grid of cells ``min_separation`` wide, so once there are
    :data:`GRID_FROM` or more a candidate is compared with the points of its own and the
    neighbouring cells only (the same decisions as comparing it with every point, in O(1)
    instead of O(n)).
    """
    if n * (0.5 * min_separation) ** dim > (radius + 0.5 * min_separation) ** dim:
        return None
    rng = np.random.default_rng(seed)
    placed = np.empty((n, dim))
    separation_sq = min_separation ** 2
    cell = min_separation if min_separation > 0.0 else 1.0
    grid: Dict[Tuple[int, ...], List[int]] = {}
    offsets = np.array(list(np.ndindex(*(3,) * dim))) - 1
    count = 0
    tries = 0
    while count < n:
        tries += 1
        if tries > MAX_START_TRIES * n:
            return None
        direction = rng.normal(size=dim)
        direction /= np.linalg.norm(direction)
        candidate = direction * radius * rng.random() ** (1.0 / dim)
        cells = (candidate // cell).astype(np.int64) if count >= GRID_FROM else None
        if cells is None:
            others = placed[:count]
        else:
            others = placed[[index for key in map(tuple, (cells + offsets).tolist())
                             for index in grid.get(key, ())]]
        if len(others) and np.min(np.sum((others - candidate) ** 2, axis=1)) < separation_sq:
            continue
        placed[count] = candidate
        if cells is None:
            cells = (candidate // cell).astype(np.int64)
        grid.setdefault(tuple(cells.tolist()), []).append(count)
        count += 1
    return placed


def start_positions(spec: StartSpec) -> Optional[NDArray[np.float64]]:
    """Return the start positions (N, dim) of ``spec``; None if random ones do not fit."""
    if spec.positions is not None:
        return np.array(spec.positions, dtype=float)
    return random_start(spec.num_robots, spec.dim, spec.random_radius, spec.min_separation,
                        spec.seed)


def _row_max(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """np.max(values, axis=1) of (N, width) values, a column at a time (faster for narrow rows)."""
    largest = values[:, 0].copy()
    for column in range(1, values.shape[1]):
        np.maximum(largest, values[:, column], out=largest)
    return largest


def _kd_tree(points: NDArray[np.float64]) -> 'cKDTree':
    """Build a k-d tree of ``points`` (scipy loads here: formation_sim --dt needs none)."""
    from scipy.spatial import cKDTree
    return cKDTree(points)


class PlantModel:
    """
    Every robot's body and range sensor, stepped with zero-order hold.

    start: (N, dim) positions, m; sensing_radii: (N,) R_i, m; step_ns: dt in ns; law: the
    control law constants (for the bound c M1); reference: the desired trajectory (to recover
    u_hat when auditing the bound); input_timeout_ns: the oldest state stamp a command may
    answer; collision_distance: m; max_speed: cap on every world command component, m/s (0:
    none beyond the law's own bound), for point bodies built here. bodies: the kind of body
    (``core.model.bodies``; default points with ``max_speed``); headings: (N,) start headings, rad
    (default 0). pair_radius: with a value > 0 (``formation_sim`` gives the law's b), the model
    keeps every pair of control points within it of each new state (:attr:`pairs`, for the law)
    and, for points when it is at least the collision distance, checks collisions among them
    instead of searching the tree a second time. imperfections: how the bodies and their
    sensing differ from the ideal (``core.model.dynamics``; default ideal): with ``pose_noise``
    each state is measured once (one draw per body), and every robot that sees body j gets the same
    measured position; with ``state_delay`` the robots get the state measured d ago (whole
    steps), stamped then, and the commands answering it are admitted against it. Collisions,
    distances and the recorded trajectory are always the true bodies'.

    Public state: ``q`` (N, dim) body positions, ``heading`` (N,), ``points`` (N, dim) the
    control points the law acts on, ``tree`` a k-d tree of ``points`` and ``body_tree`` one of
    ``q`` (the same object for points; both built when first asked for after a step), all true;
    ``velocity`` the bodies' velocity (None for ideal bodies, whose velocity is their command).
    """

    def __init__(self, start: ArrayLike, sensing_radii: ArrayLike, step_ns: int,
                 law: LawParams, reference: Reference, input_timeout_ns: int,
                 collision_distance: float, max_speed: float = 0.0,
                 bodies: Optional[Bodies] = None, headings: Optional[ArrayLike] = None,
                 pair_radius: float = 0.0, imperfections: Imperfections = IDEAL,
                 obstacles: Optional[Obstacles] = None):
        """Place the robots at ``start`` (and ``headings``) at time 0."""
        self.body: Bodies = PointBodies(max_speed) if bodies is None else bodies
        self.q = np.array(start, dtype=float)
        self.heading = (np.zeros(len(self.q)) if headings is None
                        else np.array(headings, dtype=float))
        self.radii = np.array(sensing_radii, dtype=float)
        self.num_robots, self.dim = self.q.shape
        if step_ns <= 0:
            raise ValueError(f'step_ns must be > 0, got {step_ns}')
        self.step_ns = int(step_ns)
        self.law = law
        self.reference = reference
        self.obstacles = obstacles
        self.input_timeout_ns = int(input_timeout_ns)
        self.collision_distance = float(collision_distance)
        self.contact_distance = max(self.collision_distance, self.body.contact_distance)
        self.sensor_radii = sensor_radii(self.radii, self.body.sensing_margin)
        self.pair_radius = float(pair_radius)
        self.pairs: Optional[NDArray[np.intp]] = None
        """(P, 2) pairs i < j of control points within ``pair_radius`` now (None without it),
        sorted by i, then j."""
        self._candidates: Optional[NDArray[np.intp]] = None
        self._searched_at: Optional[NDArray[np.float64]] = None
        self.max_speed = float(max_speed)
        self.bound_tolerance = (BOUND_TOLERANCE_FIXED if reference.is_stationary
                                else BOUND_TOLERANCE_MOVING)
        self.t_ns = 0
        self._tree: Optional['cKDTree'] = None
        self._body_tree: Optional['cKDTree'] = None
        self._moved()
        self.counts = PlantCounts(status_steps=np.zeros((len(CommandStatus), self.num_robots),
                                                        dtype=np.int64))
        self.imperfections = imperfections
        self.velocity: Optional[NDArray[np.float64]] = (
            None if imperfections.ideal_body
            else np.zeros((self.num_robots, self.body.command_width(self.dim))))
        self.delay_steps = imperfections.delay_steps(self.step_ns)
        self._noise = (imperfections.noise_generator() if imperfections.pose_noise > 0.0
                       else None)
        self._positions: 'Optional[OrderedDict[int, NDArray[np.float64]]]' = (
            None if imperfections.ideal_sensing else OrderedDict())
        """Sensed body positions of the kept states (None: ideal sensing, they are q)."""
        self._states: 'OrderedDict[int, NDArray[np.float64]]' = OrderedDict()
        self._headings: 'OrderedDict[int, NDArray[np.float64]]' = OrderedDict()
        self._keep_state()
        self._states_kept = max(min(MAX_STATES_KEPT, 2 + self.input_timeout_ns // self.step_ns),
                                2 + self.delay_steps)
        self._audited = np.full(self.num_robots, -1, dtype=np.int64)
        self._robots = np.arange(self.num_robots)
        self._colliding = self._close_pairs()

    def _keep_state(self) -> None:
        """Keep the present state as the robots are sent it (noisy with ``pose_noise``)."""
        points = self.points
        if self._positions is not None:
            q = self.q
            if self._noise is not None:
                q = q + self._noise.normal(0.0, self.imperfections.pose_noise, q.shape)
                points = self.body.control_points(q, self.heading)
            self._positions[self.t_ns] = q
        self._states[self.t_ns] = points
        self._headings[self.t_ns] = self.heading

    def _moved(self) -> None:
        """Update the control points after the bodies moved; the k-d trees are built anew."""
        self.points = self.body.control_points(self.q, self.heading)
        self._tree = None
        self._body_tree = None

    @property
    def tree(self) -> 'cKDTree':
        """Return a k-d tree of the control points now."""
        if self._tree is None:
            self._tree = _kd_tree(self.points)
        return self._tree

    @property
    def body_tree(self) -> 'cKDTree':
        """Return a k-d tree of the body positions now (:attr:`tree` itself for points)."""
        if self.points is self.q:
            return self.tree
        if self._body_tree is None:
            self._body_tree = _kd_tree(self.q)
        return self._body_tree

    @property
    def t(self) -> float:
        """Return the simulated time, s."""
        return self.t_ns / NS_PER_S

    @property
    def dt(self) -> float:
        """Return the step, s."""
        return self.step_ns / NS_PER_S

    def admit(self, commands: Commands) -> Admission:
        """
        Return the commands that count for the coming step, and why the others do not.

        A robot's latest command counts if there is one, it is finite, and it answers a state
        at most ``input_timeout`` old and not newer than the present one; otherwise the robot
        gets zero for the step. A command that counts but asks for more than the law can
        produce at the state it answers (a component of u_hat above c M1, eqs. (14), (25)), or
        a component above ``max_speed``, is saturated: u_hat clipped to c M1 and mapped back,
        then the world components clipped to ``max_speed``.
        """
        status = np.full(self.num_robots, CommandStatus.APPLIED, dtype=np.int8)
        age = self.t_ns - commands.stamp_ns
        status[age > self.input_timeout_ns] = CommandStatus.STALE
        status[age < 0] = CommandStatus.FUTURE
        finite = np.isfinite(commands.u)
        if not np.all(finite):
            status[~np.all(finite, axis=1)] = CommandStatus.NON_FINITE
        status[~commands.present] = CommandStatus.MISSING
        counted = status == CommandStatus.APPLIED
        u = (commands.u.copy() if np.all(counted)
             else np.where(counted[:, None], commands.u, 0.0))
        if np.any(counted):
            u, velocity, saturated, largest = self._saturate(u, commands.stamp_ns, counted)
            status[saturated] = CommandStatus.SATURATED
        else:
            largest = np.zeros(self.num_robots)
            velocity = self.body.world_velocity(u, self.heading)
        return Admission(u=u, status=status, largest_u_hat=largest, velocity=velocity)

    def _saturate(self, command: NDArray[np.float64], stamps: NDArray[np.int64],
                  counted: NDArray[np.bool_]) -> Saturation:
        """
        Return the counted commands clipped to the law's bound and to the actuator caps.

        The bound applies to the velocity a command gives the control point (the command itself
        for points; R(th) (v, l w) at the heading of the answered state for unicycles). Returns
        (commands, velocities, saturated, largest): the commands after clipping and the
        velocities they give the control points, (N, dim) each; which were clipped (N,); each
        counted robot's largest |u_hat| component before clipping (N,, 0 for the others).
        ``command`` is not changed.
        """
        body = self.body
        heading = self._answered_headings(stamps, counted) if body.has_heading else self.heading
        u = body.world_velocity(command, heading)
        same = u is command
        u, over, largest = self._clip_to_law(u, stamps, counted)
        if same:
            command = u
        elif np.any(over):
            command = np.array(command)
            command[over] = body.body_command(u[over], heading[over])
        command, capped = body.cap(command, counted)
        if same:
            u = command
        elif np.any(capped):
            u[capped] = body.world_velocity(command[capped], heading[capped])
        return command, u, over | capped, largest

    def _answered_headings(self, stamps: NDArray[np.int64],
                           counted: NDArray[np.bool_]) -> NDArray[np.float64]:
        """Return each robot's heading at the state its command answers (N,)."""
        heading = np.array(self.heading)
        for stamp in np.unique(stamps[counted]):
            rows = counted & (stamps == stamp)
            heading[rows] = self._headings[self._state_key(int(stamp))][rows]
        return heading

    def _clip_to_law(self, u: NDArray[np.float64], stamps: NDArray[np.int64],
                     counted: NDArray[np.bool_]
                     ) -> Tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.float64]]:
        """
        Return the control-point velocities ``u`` (N, dim) with u_hat clipped to c M1 (a copy).

        Also which were clipped (N,) and the largest |u_hat| component of each counted robot
        (N,, 0 for the others).
        """
        bound = self.law.u_bound
        limit = bound + self.bound_tolerance
        largest = np.zeros(self.num_robots)
        clipped = np.array(u)
        if self.reference.is_stationary:
            largest[counted] = _row_max(np.abs(u[counted]) if not np.all(counted) else np.abs(u))
            over = counted & (largest > limit)
            if np.any(over):
                clipped[over] = np.clip(u[over], -bound, bound)
        else:
            over = np.zeros(self.num_robots, dtype=bool)
            for stamp in np.unique(stamps[counted]):
                rows = counted & (stamps == stamp)
                state = self._state_at(int(stamp))[rows]
                frame = self.reference.sample(int(stamp) / NS_PER_S)
                change = feed_forward_change(state, frame, self.law, self.obstacles,
                                             self.radii[rows])
                sent = u[rows] if change is None else u[rows] - change
                u_hat = to_frame_velocity(sent, state, frame)
                largest[rows] = np.max(np.abs(u_hat), axis=1)
                clip = largest[rows] > limit
                if np.any(clip):
                    index = np.flatnonzero(rows)[clip]
                    clipped[index] = from_frame_velocity(np.clip(u_hat[clip], -bound, bound),
                                                         state[clip], frame)
                    if change is not None:
                        clipped[index] += change[clip]
                    over[index] = True
        return clipped, over, largest

    def _state_key(self, stamp_ns: int) -> int:
        """Return the time of the kept state a command stamped ``stamp_ns`` answers."""
        if stamp_ns in self._states:
            return stamp_ns
        earlier = [t for t in self._states if t <= stamp_ns]
        return max(earlier) if earlier else next(iter(self._states))

    def _state_at(self, stamp_ns: int) -> NDArray[np.float64]:
        """Return the control points of the state a command stamped ``stamp_ns`` answers."""
        return self._states[self._state_key(stamp_ns)]

    def advance(self, commands: Commands) -> StepReport:
        """Admit the commands, audit the bound, step the bodies over dt, check collisions."""
        admission = self.admit(commands)
        counted = admission.counted
        violations = self._audit(commands, admission, counted)
        t_ns, q, points, heading = self.t_ns, self.q, self.points, self.heading
        if self.velocity is None:
            self.q, self.heading = self.body.step(q, heading, admission.u, self.dt)
            velocity = admission.u
        else:
            self.q, self.heading, self.velocity = self.body.lagged_step(
                q, heading, self.velocity, admission.u, self.dt, self.imperfections)
            velocity = self.velocity
        self.t_ns += self.step_ns
        self._moved()
        self._keep_state()
        while len(self._states) > self._states_kept:
            self._states.popitem(last=False)
            self._headings.popitem(last=False)
            if self._positions is not None:
                self._positions.popitem(last=False)
        counts = self.counts
        counts.steps += 1
        counts.status_steps[admission.status, self._robots] += 1
        counts.bound_violations += len(violations)
        oldest = int(np.max(t_ns - commands.stamp_ns[counted])) if np.any(counted) else 0
        counts.oldest_counted_ns = max(counts.oldest_counted_ns, oldest)
        age_bin = min(-(-oldest // self.step_ns), AGE_BINS) if np.all(counted) else AGE_BINS
        counts.age_steps[age_bin] += 1
        collisions = self._new_collisions()
        counts.collisions += len(collisions)
        return StepReport(t_ns, q, admission, violations, collisions, points, heading, velocity)

    def sensed(self, trees: bool = True) -> SensedState:
        """
        Return what the robots receive now: the state measured ``delay_steps`` steps ago.

        Its stamp is when it was measured (0, the start, while the delay has not passed); its
        positions carry that state's noise. Ideal sensing: the present state itself, with the
        model's pairs and, unless ``trees`` is False (a caller that needs only the pairs), its
        trees.
        """
        if self._positions is None:
            if not trees:
                return SensedState(self.t_ns, self.q, self.heading, self.points,
                                   pairs=self.pairs)
            return SensedState(self.t_ns, self.q, self.heading, self.points, self.tree,
                               self.body_tree, self.pairs)
        stamp = max(self.t_ns - self.delay_steps * self.step_ns, 0)
        return SensedState(stamp, self._positions[stamp], self._headings[stamp],
                           self._states[stamp])

    def sensed_pairs(self) -> Tuple[NDArray[np.intp], NDArray[np.intp]]:
        """
        Every robot's range sensor now: (observer, seen) pairs (``core.maths.sensing``).

        A sensor sees bodies, strictly within R_i for points and R_i + 2 l for unicycles
        (``sensor_radii``), so that it sees every hand point within R_i of its own. The pairs
        are those of the sensed positions (:meth:`sensed`): the true ones with ideal sensing.
        """
        state = self.sensed()
        return sensed_pairs(state.q, self.sensor_radii, state.body_tree)

    def neighbours(self) -> List[NDArray[np.intp]]:
        """Robot i's range sensor: indices of the other bodies it sees, each sorted."""
        observer, seen = self.sensed_pairs()
        return neighbour_lists(observer, seen, self.num_robots)

    def closest_pair_distance(self) -> float:
        """Smallest distance between two control points now, m (inf for a single robot)."""
        if self.num_robots < 2:
            return float('inf')
        distance, _ = self.tree.query(self.points, k=2)
        return float(np.min(distance[:, 1]))

    def closest_body_distance(self) -> float:
        """Smallest distance between two body positions now, m (inf for a single robot)."""
        if self.num_robots < 2:
            return float('inf')
        distance, _ = self.body_tree.query(self.q, k=2)
        return float(np.min(distance[:, 1]))

    def _close_pairs(self) -> Set[Tuple[int, int]]:
        """
        Pairs of bodies within the contact distance now (and :attr:`pairs`, when they are kept).

        :attr:`pairs` are those of the control points (the law's); for points they are the
        bodies' too, so the collisions are found among them when ``pair_radius`` reaches the
        contact distance.
        """
        if self.pair_radius > 0.0:
            self.pairs, d2 = self._pairs_within_radius()
        if (self.pairs is not None and self.points is self.q
                and self.pair_radius >= self.contact_distance):
            close = np.compress(d2 <= self.contact_distance ** 2, self.pairs, axis=0).tolist()
        else:
            close = self.body_tree.query_pairs(self.contact_distance,
                                               output_type='ndarray').tolist()
        return {(int(i), int(j)) for i, j in close}

    def _pairs_within_radius(self) -> Tuple[NDArray[np.intp], NDArray[np.float64]]:
        """Return the pairs of control points within ``pair_radius`` now, and their d**2."""
        skin = PAIR_SKIN * self.pair_radius
        points = self.points
        if self._searched_at is not None:
            moved = points - self._searched_at
            if not float(np.max(np.einsum('kd,kd->k', moved, moved))) <= (0.5 * skin) ** 2:
                self._candidates = None
        if self._candidates is None:
            self._candidates = pairs_within(points, self.pair_radius + skin)
            self._searched_at = points.copy()
        candidates = self._candidates
        d2 = squared_norms(row_differences(points, candidates[:, 0], candidates[:, 1]))
        within = d2 <= self.pair_radius ** 2
        return np.compress(within, candidates, axis=0), d2[within]

    def _new_collisions(self) -> List[Tuple[int, int, float]]:
        pairs = self._close_pairs()
        new = sorted(pairs - self._colliding)
        self._colliding = pairs
        return [(i, j, float(np.linalg.norm(self.q[i] - self.q[j]))) for i, j in new]

    def _audit(self, commands: Commands, admission: Admission,
               counted: NDArray[np.bool_]) -> List[Tuple[int, float]]:
        """Return (robot, largest |u_hat| component) of new commands above c M1 (once each)."""
        fresh = counted & (commands.stamp_ns != self._audited)
        self._audited[fresh] = commands.stamp_ns[fresh]
        over = np.flatnonzero(fresh & (admission.largest_u_hat - self.law.u_bound
                                       > self.bound_tolerance))
        return [(int(i), float(admission.largest_u_hat[i])) for i in over]
