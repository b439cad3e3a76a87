# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Typed settings of a formation run, validated from flat parameter values.

The declarations (names, types, ranges) are in :mod:`formation_ros.core.settings.declarations`, the
file format in :mod:`formation_ros.core.settings.params_file`. :func:`validate` checks one
executable's parameters, then what no single value shows (array lengths, b against R_i and the
vertices, a reference that needs 3D...), and returns a :class:`FormationConfig` with a typed
settings object for the executable: :class:`PlantSettings`, :class:`RobotSettings`,
:class:`ReferenceSettings` or :class:`RecorderSettings`. Every problem is reported at once in
one :class:`ParamError`.
"""

from dataclasses import dataclass, field
import math
import re
import string
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from formation_ros.core.maths.frames import desired_positions, from_frame_velocity
from formation_ros.core.maths.jump import JumpKind
from formation_ros.core.maths.law import LawParams, make_law, PSI_FUNCTIONS, PsiKind
from formation_ros.core.maths.obstacle_tracking import FeedForwardGuard
from formation_ros.core.maths.obstacles import Obstacles
from formation_ros.core.maths.pairs import closest_pair
from formation_ros.core.maths.reference import dimension_problem, PERIODIC, Reference
from formation_ros.core.maths.reference import ReferenceKind
from formation_ros.core.maths.unicycle import command_bounds
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import (BodyKind, BodySettings, make_bodies, POINT_BODY,
                                             random_headings)
from formation_ros.core.model.dynamics import IDEAL, Imperfections
from formation_ros.core.model.plant import start_positions, StartSpec
from formation_ros.core.settings.declarations import (BY_NAME, check_values, CommandFrame,
                                                      CommandType, DEFAULT_WORLD_FRAME, Exe,
                                                      ObstacleSource, ParamError, PoseType,
                                                      range_problem,
                                                      SHAPE_NAME, shape_vertices_name, SourceType,
                                                      Transport, type_problem)
from formation_ros.core.settings.names import scan_frame
from formation_ros.core.settings.params_file import load_params_file, PathText
import numpy as np
from numpy.typing import NDArray

Problems = List[Tuple[str, str]]
TRACKING_SAMPLES = 721
HAND_POINTS_APART = 1e-9
"""Hand points closer than this at the start (m) are one point: the law has no direction."""
FRAME_ID = re.compile(r'[A-Za-z0-9_][A-Za-z0-9_./-]*')
"""A frame id as tf2 takes it: no leading slash, no spaces."""
SOURCE_FIELDS = ('i', 'name')


@dataclass(frozen=True)
class PlantSettings:
    """The plant node's own parameters (``plant.*``); rates in Hz, times in s."""

    rate: float
    input_timeout: float
    publish_rate: float
    realtime_factor: float
    collision_distance: float
    max_speed: float
    wait_for_robots: bool
    wait_for_subscribers: int
    marker_rate: float
    output_dir: str

    @property
    def step_ns(self) -> int:
        """Integration step 1 / rate, ns of simulated time."""
        return int(round(NS_PER_S / self.rate))

    @property
    def input_timeout_ns(self) -> int:
        """``input_timeout`` in ns."""
        return int(round(self.input_timeout * NS_PER_S))

    @property
    def steps_per_publish(self) -> int:
        """Return the number of steps between two published states (free-running)."""
        return steps_per_publish(self.rate, self.publish_rate)


def world_robot_rates(relay_rate: float) -> Tuple[Tuple[str, float], ...]:
    """
    Return the rates a robot on simulated time beside a world and its relay is given.

    relay_rate: ``relay.rate``, Hz of simulated time there. A robot reads ``plant.rate`` and
    ``plant.publish_rate`` only for the period of its states (``state_period``); beside a
    world they are the relay's, one state per step.
    """
    return (('plant.rate', relay_rate), ('plant.publish_rate', relay_rate))


def steps_per_publish(rate: float, publish_rate: float) -> int:
    """Return the plant's steps between two published states (free-running): rate in Hz."""
    return max(1, int(round(rate / publish_rate)))


def state_period(rate: float, publish_rate: float, lockstep: bool) -> float:
    """
    Return the simulated time between two states the plant publishes, s.

    rate: ``plant.rate``, publish_rate: ``plant.publish_rate`` (Hz); in lockstep every step.
    """
    return (1 if lockstep else steps_per_publish(rate, publish_rate)) / rate


@dataclass(frozen=True)
class ScanSettings:
    """
    How a robot with ``obstacles.source: scan`` reads its own scans (``obstacles.scan_*``).

    frame: the frame_id its scans must carry; mount: (x, y) of the scanner in the base's frame,
    m, and mount_yaw its rotation there, rad; margin: a return within body.radius plus this of
    a neighbour's position is that neighbour's, m; join: returns of neighbouring rays nearer
    each other than this are one obstacle, m (``core.maths.scan.nearest_by_object``); sectors:
    the sectors of directions about the robot that keep their nearest return each
    (``core.maths.scan.nearest_by_sector``).
    """

    frame: str
    mount: Tuple[float, float] = (0.0, 0.0)
    mount_yaw: float = 0.0
    margin: float = 0.05
    join: float = 0.2
    sectors: int = 72


@dataclass(frozen=True)
class RobotSettings:
    """
    A robot node's own parameters.

    plant_period: the simulated time between two states of the plant, s (``state_period``);
    relay_period: the time between two relay cycles, s (1 / ``relay.rate``: wall-clock time in
    a lab, simulated time beside a world);
    parameter_services: whether every robot node of a fleet offers the parameter services
    (``fleet.parameter_services``; the fleet's first robot always does); scan: how it reads its
    scans with ``obstacles.source: scan`` (None: its obstacles are told, ``map``).
    """

    robot_id: int
    control_rate: float
    input_timeout: float
    wait_for_subscribers: int
    pose_type: PoseType = PoseType.POSE_STAMPED
    plant_period: float = 0.02
    relay_period: float = 0.02
    parameter_services: bool = True
    scan: Optional[ScanSettings] = None

    def answer_period(self, sim_time: bool) -> float:
        """
        Return the time between two states the robot's answer budget expects, s.

        On the wall clock the states are a lab relay's: ``relay_period``. On simulated time
        they are stamped with it: ``plant_period``, the states' period that ``plant.rate``
        and ``plant.publish_rate`` give. Beside a world there is no plant, and the relay's
        cycles are on the world's /clock: the launcher and ``launch/world.launch.py`` give the
        robots both rates as ``relay.rate`` (:func:`world_robot_rates`), so that the budget
        expects a state every ``relay_period`` of simulated time.
        """
        return self.plant_period if sim_time else self.relay_period


@dataclass(frozen=True)
class CommandSettings:
    """
    What a robot publishes on ``cmd_vel`` and the plant reads (``command.*``).

    message: TwistStamped or Twist (``command.type``); frame: world (u in ``world_frame``) or
    body (the robot's ``robot_<i>/base_link``: u rotated into it by the pose's orientation, and
    (v, w) for unicycles, which always command in their body frame).
    """

    message: CommandType = CommandType.TWIST_STAMPED
    frame: CommandFrame = CommandFrame.WORLD

    @property
    def stamped(self) -> bool:
        """Tell whether commands carry the stamp of the state they answer."""
        return self.message is CommandType.TWIST_STAMPED


@dataclass(frozen=True)
class RelaySettings:
    """
    The relay's own parameters (``relay.*``): where the measured poses come from, how often.

    source_topic: template with ``{i}`` (robot id) and ``{name}`` (its entry of
    ``source_names``); source_type: PoseStamped or Odometry; rate: cycles per second, Hz;
    max_age: a measurement older than this is stale, s.
    """

    source_topic: str
    source_names: Tuple[str, ...]
    source_type: SourceType
    rate: float
    max_age: float

    def source(self, robot_id: int) -> str:
        """Return robot ``robot_id``'s (1-based) measured-pose topic."""
        return fill_template(self.source_topic, robot_id, self.source_names)


@dataclass(frozen=True)
class ReferenceSettings:
    """The reference node's own parameters, and the plant's step (lockstep sends one ahead)."""

    rate: float
    step_ns: int


@dataclass(frozen=True)
class RecorderSettings:
    """The recorder's own parameters (``record.*``)."""

    path: str
    overwrite: bool
    markers: bool


@dataclass(frozen=True)
class WorldSettings:
    """
    The physics world's parameters (``world.*``; formation_ros/physics, beyond the paper).

    timestep: engine step, s (a whole number of ns: :attr:`timestep_ns`); realtime_factor:
    simulated s per wall s aimed at beside processes; pose_rate: measured poses, Hz;
    pose_noise: standard deviation of the measured positions' noise, m; seed: its generator's
    seed (``start.seed``); mass: each body, kg; wheel_radius, wheel_track: a differential-drive
    base's wheels, m; wheel_torque: each wheel motor's torque limit, N m; force_limit: a point
    body's servo force limit per axis, N; torque_limit: its heading servo's, N m;
    floor_friction: sliding friction coefficient of the floor; cmd_timeout: a command older
    than this stops the motors, s; obstacle_height: the height of 2D pillars and walls, m;
    scan_rate: each planar robot's laser scans, Hz (0 none); scan_rays: rays per scan;
    scan_range_min, scan_range_max: the returns a scan reports, m; scan_noise: standard
    deviation of their noise, m (seeded by ``seed`` too); output_dir: where world.xml and the
    results go ('' none).
    """

    timestep: float = 0.002
    realtime_factor: float = 1.0
    pose_rate: float = 50.0
    pose_noise: float = 0.0
    seed: int = 0
    mass: float = 1.0
    wheel_radius: float = 0.033
    wheel_track: float = 0.16
    wheel_torque: float = 0.2
    force_limit: float = 5.0
    torque_limit: float = 0.5
    floor_friction: float = 1.0
    cmd_timeout: float = 0.5
    obstacle_height: float = 0.5
    scan_rate: float = 5.0
    scan_rays: int = 360
    scan_range_min: float = 0.12
    scan_range_max: float = 3.5
    scan_noise: float = 0.0
    output_dir: str = ''

    @property
    def timestep_ns(self) -> int:
        """``timestep`` in ns."""
        return int(round(self.timestep * NS_PER_S))

    @property
    def cmd_timeout_ns(self) -> int:
        """``cmd_timeout`` in ns."""
        return int(round(self.cmd_timeout * NS_PER_S))

    @property
    def steps_per_pose(self) -> int:
        """Return the engine steps between two measured poses: timestep x pose_rate, rounded."""
        return max(1, int(round(1.0 / (self.pose_rate * self.timestep))))


WORLD_FIELDS = ('timestep', 'realtime_factor', 'pose_rate', 'pose_noise', 'mass',
                'wheel_radius', 'wheel_track', 'wheel_torque', 'force_limit', 'torque_limit',
                'floor_friction', 'cmd_timeout', 'obstacle_height', 'scan_rate', 'scan_rays',
                'scan_range_min', 'scan_range_max', 'scan_noise', 'output_dir')
"""The fields of :class:`WorldSettings` read from ``world.<field>``."""
WORLD_MAX_ROBOTS = 1000
"""The most robots the physics engine takes (the world node, ``formation_sim --engine
mujoco``): MuJoCo's compile time grows with the square of the bodies (1000: 8 s, 4000: out of
its memory); docs/physics.md ("What the world refuses")."""
TIMESTEP_NS_TOLERANCE = 1e-6
"""A timestep is a whole number of ns when within this many ns of one."""


def world_size_problem(num_robots: int) -> Optional[str]:
    """Return why the physics engine cannot take ``num_robots`` bodies, or None if it can."""
    if num_robots <= WORLD_MAX_ROBOTS:
        return None
    return (f'{num_robots} robots are more than the physics world takes ({WORLD_MAX_ROBOTS}: '
            "MuJoCo's compile time grows with the square of the bodies)")


def world_settings(values: Mapping[str, Any], problems: Problems) -> WorldSettings:
    """Build :class:`WorldSettings` from checked ``world.*`` values; add what does not fit."""
    world = WorldSettings(seed=values['start.seed'],
                          **{name: values[f'world.{name}'] for name in WORLD_FIELDS})
    exact_ns = world.timestep * NS_PER_S
    if abs(exact_ns - round(exact_ns)) > TIMESTEP_NS_TOLERANCE:
        problems.append(('world.timestep', f'{world.timestep!r} s is not a whole number of '
                                           'nanoseconds'))
    if world.pose_rate * world.timestep > 1.0:
        problems.append(('world.pose_rate', f'{world.pose_rate:g} Hz is faster than the '
                                            f'engine steps (1 / world.timestep = '
                                            f'{1.0 / world.timestep:g} Hz)'))
    if world.scan_rate * world.timestep > 1.0:
        problems.append(('world.scan_rate', f'{world.scan_rate:g} Hz is faster than the '
                                            f'engine steps (1 / world.timestep = '
                                            f'{1.0 / world.timestep:g} Hz)'))
    if world.scan_range_min >= world.scan_range_max:
        problems.append(('world.scan_range_min', f'{world.scan_range_min:g} m is not less than '
                                                 f'world.scan_range_max '
                                                 f'({world.scan_range_max:g} m)'))
    return world


@dataclass(frozen=True)
class FormationConfig:
    """
    Validated parameters of one formation run, for one executable.

    Arrays: sensing_radii (N,), vertices (N, dim), start (N, dim) (for ``formation_sim``, the
    plant, the recorder and the world; None for the others), reference_origin (dim,),
    reference_velocity (dim,). plant / robot / reference_node / recorder: the executable's own
    settings (None for the others). values: the flat checked values with defaults (to write
    back as a file).
    body: the robots' bodies (``body.*``); start_headings: (N,) start headings in rad of
    unicycles and of points with body-frame commands (for the executables that get a start;
    None otherwise). world_frame: the
    frame id of every formation message; shapes: the named shapes {name: (N, dim) vertices}
    (``formations.*``), shape_name: the one in force at the start ('' for
    ``formation.vertices``; ``vertices`` are then that shape's), schedule: (time in s, shape
    name) switches (``formation.schedule.*``); command: what cmd_vel carries (``command.*``);
    imperfections: how the bodies differ from q' = u (``plant.actuator_lag`` ...: ideal for
    the executables that do not step bodies); relay: the relay's settings (None for the others);
    transport: per-robot topics or team messages (``transport``; robot for the executables that
    do not read it); world: the physics world's settings (``world.*``; None for the
    executables that do not read them). obstacles: the static obstacles as they are
    (``obstacles.*``; None without any, and for the executables that do not read the map: a
    robot hears its obstacles); obstacle_clearance: b_o in m (``obstacles.clearance``, None if
    not given).
    """

    num_robots: int
    dim: int
    sensing_radii: NDArray[np.float64]
    repulsion_radius: float
    gain: float
    kappa: float
    psi: PsiKind
    jump_kind: JumpKind
    jump_order: int
    vertices: NDArray[np.float64]
    start: Optional[NDArray[np.float64]]
    reference_kind: ReferenceKind
    reference_origin: NDArray[np.float64]
    reference_velocity: NDArray[np.float64]
    reference_radius: float
    reference_speed: float
    reference_pitch: float
    duration: float
    lockstep: bool
    plant: Optional[PlantSettings] = None
    robot: Optional[RobotSettings] = None
    reference_node: Optional[ReferenceSettings] = None
    recorder: Optional[RecorderSettings] = None
    values: Dict[str, Any] = field(default_factory=dict, repr=False)
    body: BodySettings = POINT_BODY
    start_headings: Optional[NDArray[np.float64]] = None
    world_frame: str = DEFAULT_WORLD_FRAME
    shapes: Dict[str, NDArray[np.float64]] = field(default_factory=dict, repr=False)
    shape_name: str = ''
    schedule: Tuple[Tuple[float, str], ...] = ()
    command: CommandSettings = CommandSettings()
    imperfections: Imperfections = IDEAL
    relay: Optional[RelaySettings] = None
    transport: Transport = Transport.ROBOT
    world: Optional[WorldSettings] = None
    obstacles: Optional[Obstacles] = None
    obstacle_clearance: Optional[float] = None

    @property
    def team_transport(self) -> bool:
        """Tell whether states and commands travel as team messages (``transport: team``)."""
        return self.transport is Transport.TEAM

    def law(self) -> LawParams:
        """Return the control law constants (``core.maths.law.LawParams``)."""
        return make_law(self.gain, self.kappa, self.psi, self.jump_kind,
                        self.jump_order, self.repulsion_radius)

    def law_obstacles(self) -> Optional[Obstacles]:
        """
        Return the obstacles as the law sees them: grown by the bodies' footprint, or None.

        The law keeps a robot's control point off the obstacles grown by
        ``body.footprint`` (``Obstacles.grown``), which keeps its whole body off the real ones.
        """
        if self.obstacles is None:
            return None
        return self.obstacles.grown(self.body.footprint)

    def feed_forward_guard(self) -> Optional[FeedForwardGuard]:
        """
        Return the obstacles' feed-forward rule the robots' commands are given under, or None.

        With obstacles, a moving reference's feed-forward near them is guarded
        (``core.maths.obstacle_tracking``): whoever reads u_hat back from a command takes that
        change off first. None without obstacles.
        """
        obstacles = self.law_obstacles()
        if obstacles is None:
            return None
        return FeedForwardGuard(self.law(), obstacles, self.sensing_radii)

    def reference(self) -> Reference:
        """Build the moving desired trajectory (``core.maths.reference.Reference``)."""
        return Reference(self.reference_kind.value, self.dim, self.reference_origin,
                         self.reference_velocity, self.reference_radius, self.reference_speed,
                         self.reference_pitch)


def _points(values: Mapping[str, Any], name: str, n: int, dim: int,
            problems: Problems) -> Optional[NDArray[np.float64]]:
    flat = values.get(name)
    if flat is None:
        return None
    if len(flat) != n * dim:
        problems.append((name, f'must hold num_robots x dim = {n} x {dim} = {n * dim} values '
                               f'(robot after robot), got {len(flat)}'))
        return None
    return np.array(flat, dtype=float).reshape(n, dim)


def _closest_pair(points: NDArray[np.float64]) -> Tuple[float, int, int]:
    """Return (distance, i, j) of the closest pair, 1-based i < j."""
    distance, i, j = closest_pair(points)
    return distance, i + 1, j + 1


def _start(values: Mapping[str, Any], n: int, dim: int,
           problems: Problems) -> Optional[NDArray[np.float64]]:
    given = _points(values, 'start.positions', n, dim, problems)
    random_given = [values.get(key) is not None
                    for key in ('start.random_radius', 'start.min_separation')]
    if values.get('start.positions') is not None:
        if any(random_given):
            problems.append(('start.positions', 'give either start.positions or '
                                                'start.random_radius + start.min_separation, '
                                                'not both'))
        return given
    if not all(random_given):
        problems.append(('start.positions', 'is required (or start.random_radius and '
                                            'start.min_separation for a random start)'))
        return None
    radius, separation = values['start.random_radius'], values['start.min_separation']
    start = start_positions(StartSpec(n, dim, None, radius, separation, values['start.seed']))
    if start is None:
        problems.append(('start.min_separation', f'{n} robots {separation:g} m apart do not fit '
                                                 f'in start.random_radius = {radius:g} m'))
    return start


def _vector(values: Dict[str, Any], name: str, dim: int,
            problems: Problems) -> NDArray[np.float64]:
    vec = values.get(name)
    if vec is None:
        return np.zeros(dim)
    if len(vec) != dim:
        problems.append((name, f'must hold dim = {dim} values, got {len(vec)}'))
        return np.zeros(dim)
    return np.array(vec, dtype=float)


def shape_problem(vertices: NDArray[np.float64], repulsion_radius: float) -> Optional[str]:
    """
    Return why a shape cannot be the formation, or None: two vertices closer than b.

    vertices: (N, dim) finite, m. Eq. (11) needs b_ij <= eps_2, the smallest distance between
    two vertices, so that the collision term vanishes at the formation.
    """
    if len(vertices) < 2:
        return None
    gap, i, j = _closest_pair(vertices)
    if gap == 0.0:
        return f'robots {i} and {j} have the same vertex'
    if repulsion_radius > gap:
        return (f'b = {repulsion_radius:g} m must not exceed the distance between the closest '
                f'vertices ({i} and {j}: {gap:g} m): eq. (11) needs b_ij <= eps_2')
    return None


def check_shape(flat: Any, n: int, dim: int, repulsion_radius: float) -> NDArray[np.float64]:
    """
    Check a shape given at runtime as the file's would be; return its vertices (N, dim).

    flat: num_robots x dim finite doubles, robot after robot. Raises :class:`ParamError` (one
    problem, named ``formation.vertices``) otherwise.
    """
    problems: Problems = []
    param = BY_NAME['formation.vertices']
    problem = type_problem(param, flat) or range_problem(param, flat)
    vertices = None
    if problem:
        problems.append(('formation.vertices', problem))
    else:
        vertices = _points({'v': list(flat)}, 'v', n, dim, problems)
    if vertices is not None:
        problem = shape_problem(vertices, repulsion_radius)
        if problem:
            problems.append(('formation.vertices', problem))
    if problems or vertices is None:
        raise ParamError([('formation.vertices', text.replace("'v'", 'formation.vertices'))
                          for _, text in problems])
    return vertices


def _geometry(values: Mapping[str, Any], radii: NDArray[np.float64],
              vertices: Optional[NDArray[np.float64]],
              start: Optional[NDArray[np.float64]], problems: Problems) -> None:
    b = values['repulsion_radius']
    smallest = float(np.min(radii))
    if b > smallest:
        problems.append(('repulsion_radius', f'b = {b:g} m must not exceed any sensing radius '
                                             f'(smallest R_i = {smallest:g} m): eq. (11) needs '
                                             'b_ij <= min(R_i, R_j)'))
    if vertices is not None:
        problem = shape_problem(vertices, b)
        if problem:
            name = 'repulsion_radius' if problem.startswith('b =') else 'formation.vertices'
            problems.append((name, problem))
    if start is not None:
        gap, i, j = _closest_pair(start)
        if gap == 0.0:
            problems.append(('start.positions', f'robots {i} and {j} start at the same point'))


def _reference_problems(values: Mapping[str, Any], dim: int, problems: Problems) -> None:
    kind = ReferenceKind(values['reference.kind'])
    problem = dimension_problem(kind, dim)
    if problem:
        problems.append(('reference.kind', problem))
    if kind is ReferenceKind.LINE and values.get('reference.velocity') is None:
        problems.append(('reference.velocity', f'is required for a line (dim = {dim} values)'))
    if kind in PERIODIC and values['reference.speed'] <= 0.0:
        problems.append(('reference.speed', f'must be > 0 for a {kind.value}'))


def _down(value: float) -> float:
    """Round down to 4 significant digits (a gain suggested as fitting must fit)."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 3)
    return math.floor(value / scale) * scale


def _up(value: float) -> float:
    """Round up to 4 significant digits."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 3)
    return math.ceil(value / scale) * scale


def _body(values: Mapping[str, Any], dim: int, problems: Problems) -> BodySettings:
    """Check ``body.*`` and build the :class:`BodySettings` (docs/equations.md, U5)."""
    kind = BodyKind(values['body.kind'])
    l_value = values.get('body.hand_distance')
    if kind is BodyKind.POINT:
        for name in ('body.hand_distance', 'body.max_linear', 'body.max_angular'):
            if values.get(name) is not None:
                problems.append((name, 'applies only to body.kind unicycle'))
        if values.get('start.headings') is not None and not _body_frame_points(values):
            problems.append(('start.headings', 'applies to unicycles and to points with '
                                               'command.frame body'))
        return BodySettings(radius=values.get('body.radius', 0.0))
    if dim != 2:
        problems.append(('body.kind', f'unicycle needs dim 2 (a differential-drive robot moves '
                                      f'in the plane), got dim {dim}'))
    if values.get('plant.max_speed', 0.0) > 0.0:
        problems.append(('plant.max_speed', 'is for point bodies; give unicycles '
                                            'body.max_linear and body.max_angular'))
    if l_value is None:
        problems.append(('body.hand_distance', 'is required for body.kind unicycle (l > 0, m)'))
        return BodySettings(kind=kind, hand_distance=1.0)
    psi_bound = PSI_FUNCTIONS[PsiKind(values['controller.psi'])][1]
    v_bound, w_bound = command_bounds(values['controller.gain'] * psi_bound, l_value)
    v_per_gain = command_bounds(psi_bound, l_value)[0]
    max_linear, max_angular = values.get('body.max_linear'), values.get('body.max_angular')
    if max_linear is not None and v_bound > max_linear:
        problems.append(('body.max_linear', f'the law bound sqrt(2) c M1 = {v_bound:.4g} m/s '
                                            f'exceeds body.max_linear = {max_linear:g} m/s: '
                                            'controller.gain <= '
                                            f'{_down(max_linear / v_per_gain):g} would fit'))
    if max_angular is not None and w_bound > max_angular:
        fit_gain = _down(max_angular * l_value / v_per_gain)
        problems.append(('body.max_angular', 'the law bound sqrt(2) c M1 / l = '
                                             f'{w_bound:.4g} rad/s exceeds '
                                             f'body.max_angular = {max_angular:g} rad/s: '
                                             f'controller.gain <= {fit_gain:g} or '
                                             'body.hand_distance >= '
                                             f'{_up(v_bound / max_angular):g} m would fit'))
    return BodySettings(kind=kind, hand_distance=l_value, radius=values.get('body.radius', 0.0),
                        max_linear=max_linear, max_angular=max_angular)


def tracking_problem(body: BodySettings, vertices: NDArray[np.float64], reference: Reference,
                     duration: float) -> Optional[str]:
    """Return why unicycles cannot follow ``reference`` with ``vertices`` (speed), or None."""
    problems: Problems = []
    _tracking_problems(body, vertices, reference, duration, problems)
    return problems[0][1] if problems else None


def _tracking_problems(body: BodySettings, vertices: NDArray[np.float64],
                       reference: Reference, duration: float, problems: Problems) -> None:
    """
    Refuse a moving formation whose vertices need more speed than ``body.max_linear``.

    At the formation each hand point moves with its vertex, at the feed-forward of eq. (25)
    (``from_frame_velocity`` with u_hat = 0); |v| is at least that speed, so no gain can make a
    unicycle slower than its vertex. Sampled at 721 times over the run.
    """
    if body.max_linear is None or reference.is_stationary:
        return
    fastest = 0.0
    for t in np.linspace(0.0, duration, TRACKING_SAMPLES):
        frame = reference.sample(float(t))
        speeds = np.linalg.norm(from_frame_velocity(np.zeros_like(vertices),
                                                    desired_positions(vertices, frame), frame),
                                axis=1)
        fastest = max(fastest, float(np.max(speeds)))
    if fastest > body.max_linear:
        problems.append(('body.max_linear', f'the formation moves its vertices at up to '
                                            f'{fastest:.4g} m/s along this reference, more '
                                            f'than body.max_linear = {body.max_linear:g} m/s: '
                                            'a reference '
                                            f'{_up(fastest / body.max_linear):g} times slower '
                                            '(or vertices nearer its path) would fit'))


def _body_frame_points(values: Mapping[str, Any]) -> bool:
    """Tell whether point bodies take body-frame commands (and so have headings)."""
    return (values['body.kind'] == BodyKind.POINT.value
            and values.get('command.frame') == CommandFrame.BODY.value)


def _headings(values: Mapping[str, Any], body: BodySettings, n: int,
              problems: Problems) -> Optional[NDArray[np.float64]]:
    """Start headings of unicycles and body-frame points: given, random (random start), or 0."""
    if not body.is_unicycle and not _body_frame_points(values):
        return None
    given = values.get('start.headings')
    if given is not None:
        if len(given) != n:
            problems.append(('start.headings', f'must hold num_robots = {n} values, '
                                               f'got {len(given)}'))
            return np.zeros(n)
        return np.array(given, dtype=float)
    if values.get('start.positions') is None:
        return random_headings(n, values['start.seed'])
    return np.zeros(n)


def _body_geometry(body: BodySettings, start: NDArray[np.float64],
                   headings: Optional[NDArray[np.float64]], problems: Problems) -> None:
    """Bodies must not overlap at the start, nor two hand points coincide."""
    if len(start) < 2:
        return
    gap, i, j = _closest_pair(start)
    if body.radius > 0.0 and gap < 2.0 * body.radius:
        problems.append(('body.radius', f'bodies of radius {body.radius:g} m overlap at the '
                                        f'start: robots {i} and {j} are {gap:g} m apart '
                                        f'(< 2 x {body.radius:g} m)'))
    if headings is not None and body.is_unicycle:
        gap, i, j = _closest_pair(make_bodies(body).control_points(start, headings))
        if gap < HAND_POINTS_APART:
            problems.append(('start.headings', f'robots {i} and {j} start with their hand '
                                               f'points at the same point ({gap:.3g} m apart)'))


def _scan_settings(values: Mapping[str, Any], robot_id: int,
                   problems: Problems) -> Optional[ScanSettings]:
    """``obstacles.source`` and ``obstacles.scan_*`` of robot ``robot_id``; None: ``map``."""
    if ObstacleSource(values['obstacles.source']) is ObstacleSource.MAP:
        return None
    if values.get('obstacles.clearance') is None:
        problems.append(('obstacles.source', 'scan needs obstacles.clearance: b_o > 0, m, the '
                                             "distance from an obstacle's surface within which "
                                             'it repels'))
    if values['dim'] != 2:
        problems.append(('obstacles.source', f"scan is a planar scanner's: dim must be 2, got "
                                             f"{values['dim']}"))
    mount = values.get('obstacles.scan_mount') or [0.0, 0.0, 0.0]
    if len(mount) != 3:
        problems.append(('obstacles.scan_mount', f'takes [x, y, yaw], got {len(mount)} numbers'))
        mount = [0.0, 0.0, 0.0]
    frame = values['obstacles.scan_frame'] or scan_frame(robot_id)
    if not FRAME_ID.fullmatch(frame):
        problems.append(('obstacles.scan_frame', f'{frame!r} is not a frame id (no leading '
                                                 'slash, no spaces)'))
    return ScanSettings(frame, (float(mount[0]), float(mount[1])), float(mount[2]),
                        values['obstacles.scan_margin'], values['obstacles.scan_join'],
                        values['obstacles.scan_sectors'])


OBSTACLE_LISTS = ('obstacles.circles', 'obstacles.walls', 'obstacles.spheres')


def _obstacle_map(values: Mapping[str, Any], dim: int, radii: NDArray[np.float64],
                  problems: Problems) -> Optional[Obstacles]:
    """``obstacles.*``: the map, b_o within every R_i; None when no obstacle is given."""
    clearance = values.get('obstacles.clearance')
    smallest = float(np.min(radii))
    if clearance is not None and clearance > smallest:
        problems.append(('obstacles.clearance', f'b_o = {clearance:g} m must not exceed any '
                                                f'sensing radius (smallest R_i = {smallest:g} '
                                                'm): a robot must sense every obstacle that '
                                                'repels it'))
        return None
    given = [values.get(name) or [] for name in OBSTACLE_LISTS]
    if not any(given):
        return None
    if clearance is None:
        problems.append(('obstacles.clearance', 'is required with obstacles: b_o > 0, m, the '
                                                "distance from an obstacle's surface within "
                                                'which it repels'))
        return None
    for name, flat, columns in zip(OBSTACLE_LISTS, given, (3, 5, 4)):
        if len(flat) % columns:
            problems.append((name, f'takes {columns} numbers an obstacle, got {len(flat)} '
                                   f'(not a multiple of {columns})'))
    if len(given[2]) and dim != 3:
        problems.append(('obstacles.spheres', f'spheres are 3D obstacles; dim is {dim} (use '
                                              'obstacles.circles)'))
    for name, flat, columns in zip(OBSTACLE_LISTS, given, (3, 5, 4)):
        sizes = flat[columns - 1::columns]
        if any(size <= 0.0 for size in sizes):
            what = 'half-thickness t' if columns == 5 else 'radius r'
            problems.append((name, f'every {what} must be > 0, got {min(sizes):g}'))
    if problems:
        return None
    circles, walls, spheres = given
    return Obstacles(np.asarray(circles, dtype=float), np.asarray(walls, dtype=float),
                     np.asarray(spheres, dtype=float), clearance=clearance, dim=dim)


def _obstacle_places(obstacles: Obstacles, body: BodySettings,
                     start: Optional[NDArray[np.float64]],
                     headings: Optional[NDArray[np.float64]],
                     rest: Optional[NDArray[np.float64]], problems: Problems) -> None:
    """
    Refuse a start that touches an obstacle and a resting place within b_o of one.

    start: (N, dim) body positions; rest: (N, dim) the desired positions where the formation
    comes to rest (a fixed reference, or a moving one at the end of the run), or None. A body
    touches an obstacle when its footprint does (``BodySettings.footprint`` about the control
    point, ``FormationConfig.law_obstacles``): the law is not defined there.
    """
    grown = obstacles.grown(body.footprint)
    labels = obstacles.labels()
    where = (f'its footprint, {body.footprint:g} m about its control point,'
             if body.footprint > 0.0 else 'its position')
    if start is not None:
        points = start
        if body.is_unicycle and headings is not None:
            points = make_bodies(body).control_points(start, headings)
        distances = grown.distances(points)
        i, o = np.unravel_index(int(np.argmin(distances)), distances.shape)
        if distances[i, o] <= 0.0:
            problems.append(('start.positions', f'robot {i + 1} starts touching {labels[o]} '
                                                f'({where} {distances[i, o]:.4g} m from its '
                                                'surface)'))
    if rest is not None:
        distances = grown.distances(rest)
        i, o = np.unravel_index(int(np.argmin(distances)), distances.shape)
        if distances[i, o] < obstacles.clearance:
            problems.append(('obstacles.clearance', f"robot {i + 1}'s place in the formation "
                                                    f'comes within b_o = '
                                                    f'{obstacles.clearance:g} m of {labels[o]} '
                                                    f'({where} {distances[i, o]:.4g} m from '
                                                    'its surface): '
                                                    'the formation could never be reached'))


def _own_settings(values: Mapping[str, Any], exe: Exe, n: int,
                  problems: Problems) -> Dict[str, Any]:
    """Build the executable's own settings object, as keyword arguments of FormationConfig."""
    if exe is Exe.PLANT:
        if values['plant.publish_rate'] > values['plant.rate']:
            problems.append(('plant.publish_rate', 'must not exceed plant.rate = '
                                                   f"{values['plant.rate']:g} Hz"))
        return {'plant': PlantSettings(
            rate=values['plant.rate'], input_timeout=values['plant.input_timeout'],
            publish_rate=values['plant.publish_rate'],
            realtime_factor=values['plant.realtime_factor'],
            collision_distance=values['plant.collision_distance'],
            max_speed=values['plant.max_speed'],
            wait_for_robots=values['plant.wait_for_robots'],
            wait_for_subscribers=values['plant.wait_for_subscribers'],
            marker_rate=values['plant.marker_rate'], output_dir=values['plant.output_dir'])}
    if exe is Exe.ROBOT:
        if values['robot_id'] > n:
            problems.append(('robot_id', f'must be between 1 and num_robots = {n}, '
                                         f"got {values['robot_id']}"))
        return {'robot': RobotSettings(
            robot_id=values['robot_id'], control_rate=values['control_rate'],
            input_timeout=values['input_timeout'],
            wait_for_subscribers=values['wait_for_subscribers'],
            pose_type=PoseType(values['pose_type']),
            plant_period=state_period(values['plant.rate'], values['plant.publish_rate'],
                                      values.get('plant.lockstep', False)),
            relay_period=1.0 / values['relay.rate'],
            parameter_services=values['fleet.parameter_services'],
            scan=_scan_settings(values, values['robot_id'], problems))}
    if exe is Exe.REFERENCE:
        step_ns = NS_PER_S / values['plant.rate']
        if not math.isfinite(step_ns):
            problems.append(('plant.rate', f"{values['plant.rate']:g} Hz is too slow for a step "
                                           'in nanoseconds'))
            step_ns = NS_PER_S
        return {'reference_node': ReferenceSettings(rate=values['reference.rate'],
                                                    step_ns=int(round(step_ns)))}
    if exe is Exe.RECORD:
        return {'recorder': RecorderSettings(path=values['record.path'],
                                             overwrite=values['record.overwrite'],
                                             markers=values['record.markers'])}
    if exe in (Exe.SIM, Exe.WORLD):
        return {'world': world_settings(values, problems)}
    return {}


def _named_shapes(values: Mapping[str, Any], n: int, dim: int,
                  problems: Problems) -> Dict[str, NDArray[np.float64]]:
    """``formations.names`` and each ``formations.<name>.vertices``, checked as the file's."""
    names = list(values.get('formations.names') or ())
    shapes: Dict[str, NDArray[np.float64]] = {}
    for name in names:
        key = shape_vertices_name(name)
        if not SHAPE_NAME.fullmatch(name):
            problems.append(('formations.names', f'{name!r} is not a shape name (a letter, then '
                                                 'letters, digits or _)'))
        elif name in shapes:
            problems.append(('formations.names', f'{name!r} is named twice'))
        elif values.get(key) is None:
            problems.append((key, f'is required: formations.names lists {name!r}'))
        else:
            points = _points(values, key, n, dim, problems)
            problem = None if points is None else shape_problem(points, values['repulsion_radius'])
            if problem:
                problems.append((key, problem))
            elif points is not None:
                shapes[name] = points
    for key in values:
        shape = key.split('.')[1] if key.startswith('formations.') and key.count('.') == 2 \
            else None
        if shape is not None and key.endswith('.vertices') and shape not in names:
            problems.append((key, f'{shape!r} is not in formations.names'))
    given = values.get('formation.name', '')
    if given and given not in names:
        problems.append(('formation.name', f'{given!r} is not a shape of formations.names '
                                           f"({', '.join(names) or 'none'})"))
    return shapes


def _schedule(values: Mapping[str, Any], shapes: Mapping[str, NDArray[np.float64]],
              problems: Problems) -> Tuple[Tuple[float, str], ...]:
    """``formation.schedule.*``: (time in s, shape name) pairs, times increasing."""
    times = list(values.get('formation.schedule.times') or ())
    names = list(values.get('formation.schedule.names') or ())
    if len(times) != len(names):
        problems.append(('formation.schedule.names', f'must hold one name per time: {len(times)} '
                                                     f'times, {len(names)} names'))
        return ()
    if any(later <= earlier for earlier, later in zip(times, times[1:])):
        problems.append(('formation.schedule.times', f'must increase, got {times}'))
    unknown = [name for name in names if name not in shapes]
    if unknown:
        problems.append(('formation.schedule.names', f"{', '.join(map(repr, unknown))} not in "
                                                     'formations.names'))
    return tuple(zip(times, names))


def _world_frame(values: Mapping[str, Any], problems: Problems) -> str:
    frame = values['world_frame']
    if not FRAME_ID.fullmatch(frame):
        problems.append(('world_frame', f'must be a frame id without a leading slash or '
                                        f"spaces (e.g. 'world', 'map'), got {frame!r}"))
    return str(frame)


def _command(values: Mapping[str, Any], body: BodySettings,
             problems: Problems) -> CommandSettings:
    """``command.*``: unicycles command (v, w) in their body frame, points either frame."""
    kind = CommandType(values.get('command.type', CommandType.TWIST_STAMPED.value))
    given = values.get('command.frame')
    if body.is_unicycle:
        if given is not None and CommandFrame(given) is not CommandFrame.BODY:
            problems.append(('command.frame', 'unicycles command (v, w) in their body frame: '
                                              "leave command.frame out or set it to 'body'"))
        return CommandSettings(kind, CommandFrame.BODY)
    if kind is CommandType.TWIST and values.get('plant.lockstep', False):
        problems.append(('command.type', 'plant.lockstep needs twist_stamped: a Twist carries no '
                                         'stamp to tell which state it answers'))
    return CommandSettings(kind, CommandFrame.WORLD if given is None else CommandFrame(given))


def _imperfections(values: Mapping[str, Any], exe: Exe, problems: Problems) -> Imperfections:
    """``plant.actuator_lag`` ...: the non-ideal bodies of the executables that step them."""
    delay = values.get('plant.state_delay', 0.0)
    if exe is Exe.ROBOT and delay >= values['input_timeout']:
        problems.append(('plant.state_delay', f'{delay:g} s would make every state stale for '
                                              'the robots: it must be less than input_timeout '
                                              f"= {values['input_timeout']:g} s"))
    if exe not in (Exe.SIM, Exe.PLANT, Exe.RECORD):
        return IDEAL
    imperfections = Imperfections(
        actuator_lag=values['plant.actuator_lag'],
        max_acceleration=values['plant.max_acceleration'],
        pose_noise=values['plant.pose_noise'], state_delay=values['plant.state_delay'],
        seed=values['start.seed'])
    timeout = values.get('plant.input_timeout')
    if exe is Exe.PLANT and timeout is not None and imperfections.state_delay >= timeout:
        problems.append(('plant.state_delay', f'{imperfections.state_delay:g} s would make '
                                              'every command stale: it must be less than '
                                              f'plant.input_timeout = {timeout:g} s'))
    if exe is Exe.PLANT and values.get('plant.lockstep') and imperfections.state_delay > 0.0:
        problems.append(('plant.state_delay', 'cannot be used with plant.lockstep: a lockstep '
                                              'plant steps once every robot has answered the '
                                              'present state, and with a delay the robots '
                                              'only ever receive older ones; run free (no '
                                              'lockstep), or use formation_sim --dt'))
    return imperfections


def fill_template(template: str, robot_id: int, names: Sequence[str] = ()) -> str:
    """Return robot ``robot_id``'s (1-based) topic: ``{i}`` its id, ``{name}`` its entry."""
    name = names[robot_id - 1] if names else ''
    return template.format(i=robot_id, name=name)


def template_problems(template: str, names: Sequence[str], n: int,
                      template_key: str = 'relay.source_topic',
                      names_key: str = 'relay.source_names') -> Problems:
    """
    Return what is wrong with a per-robot topic template and its names (empty: nothing).

    The template may use ``{i}`` (the robot id) and ``{name}`` (its entry of ``names``, which
    then holds n distinct, non-empty names) and must tell the n robots' topics apart. Problems
    are (key, message) with the keys given (the relay's parameters, or a launcher option).
    """
    problems: Problems = []
    try:
        fields = [name for _, name, spec, conv in string.Formatter().parse(template)
                  if name is not None]
    except ValueError as exc:
        problems.append((template_key, f'is not a topic template ({exc}): {template!r}'))
        fields = []
    unknown = sorted(set(fields) - set(SOURCE_FIELDS))
    if unknown:
        problems.append((template_key, 'may use only {i} and {name}, got '
                                       f"{', '.join('{' + f + '}' for f in unknown)} in "
                                       f'{template!r}'))
    if names and len(names) != n:
        problems.append((names_key, f'must hold num_robots = {n} names, got {len(names)}'))
    elif 'name' in fields and not names:
        problems.append((names_key, f'is required: {template_key} {template!r} uses {{name}}'))
    elif names and len(set(names)) != len(names):
        problems.append((names_key, 'names must differ (two robots would read one topic)'))
    elif names and not all(names):
        problems.append((names_key, 'names must not be empty'))
    elif not unknown and fields.count('i') + fields.count('name') == 0 and n > 1:
        problems.append((template_key, f'{template!r} names no robot: use {{i}} or {{name}}, '
                                       'or every robot would have one and the same topic'))
    return problems


def _relay(values: Mapping[str, Any], n: int, problems: Problems) -> RelaySettings:
    """``relay.*``: the topic template may name {i} and {name} (with one name per robot)."""
    template = values['relay.source_topic']
    names = tuple(values.get('relay.source_names') or ())
    problems.extend(template_problems(template, names, n))
    return RelaySettings(source_topic=template, source_names=names,
                         source_type=SourceType(values['relay.source_type']),
                         rate=values['relay.rate'], max_age=values['relay.max_age'])


def validate(raw: Mapping[str, Any], executable: Union[Exe, str] = Exe.SIM) -> FormationConfig:
    """
    Check flat parameter values for one executable and build its :class:`FormationConfig`.

    executable: an :class:`Exe` (or its name, e.g. 'plant'); only the parameters it reads are
    required (a robot needs no start positions). Raises :class:`ParamError` naming every
    problem.
    """
    exe = Exe(executable)
    values = check_values(raw, exe)
    problems: Problems = []
    n, dim = values['num_robots'], values['dim']
    too_many = world_size_problem(n) if exe is Exe.WORLD else None
    if too_many:
        raise ParamError([('num_robots', too_many)])
    radii = np.full(n, values['sensing_radius'], dtype=float)
    if values.get('sensing_radii') is not None:
        if len(values['sensing_radii']) != n:
            problems.append(('sensing_radii', f'must hold num_robots = {n} values, '
                                              f"got {len(values['sensing_radii'])}"))
        else:
            radii = np.array(values['sensing_radii'], dtype=float)
    vertices = _points(values, 'formation.vertices', n, dim, problems)
    shapes = _named_shapes(values, n, dim, problems)
    if values.get('formation.name') and vertices is not None:
        vertices = shapes.get(values['formation.name'], vertices)
    schedule = _schedule(values, shapes, problems)
    start = (_start(values, n, dim, problems)
             if exe in (Exe.SIM, Exe.PLANT, Exe.RECORD, Exe.WORLD) else None)
    _geometry(values, radii, vertices, start, problems)
    _reference_problems(values, dim, problems)
    origin = _vector(values, 'reference.origin', dim, problems)
    velocity = _vector(values, 'reference.velocity', dim, problems)
    own = _own_settings(values, exe, n, problems)
    body = _body(values, dim, problems)
    world_frame = _world_frame(values, problems)
    command = _command(values, body, problems)
    imperfections = _imperfections(values, exe, problems)
    relay = _relay(values, n, problems) if exe is Exe.RELAY else None
    headings = _headings(values, body, n, problems) if start is not None else None
    if start is not None and not problems:
        _body_geometry(body, start, headings, problems)
    mapped = _obstacle_map(values, dim, radii, problems)
    if mapped is not None and mapped.count and vertices is not None and not problems:
        reference = Reference(values['reference.kind'], dim, origin, velocity,
                              values['reference.radius'], values['reference.speed'],
                              values['reference.pitch'])
        rest = desired_positions(vertices, reference.sample(
            0.0 if reference.is_stationary else values['duration']))
        _obstacle_places(mapped, body, start, headings, rest, problems)
    if body.is_unicycle and vertices is not None and not problems:
        _tracking_problems(body, vertices, Reference(
            values['reference.kind'], dim, origin, velocity, values['reference.radius'],
            values['reference.speed'], values['reference.pitch']), values['duration'], problems)
    if problems or vertices is None:
        raise ParamError(problems)
    return FormationConfig(
        num_robots=n, dim=dim, sensing_radii=radii, repulsion_radius=values['repulsion_radius'],
        gain=values['controller.gain'], kappa=values['controller.kappa'],
        psi=PsiKind(values['controller.psi']), jump_kind=JumpKind(values['jump.kind']),
        jump_order=values['jump.order'], vertices=vertices, start=start,
        reference_kind=ReferenceKind(values['reference.kind']), reference_origin=origin,
        reference_velocity=velocity, reference_radius=values['reference.radius'],
        reference_speed=values['reference.speed'], reference_pitch=values['reference.pitch'],
        duration=values['duration'], lockstep=values.get('plant.lockstep', False),
        values=values, body=body, start_headings=headings, world_frame=world_frame,
        shapes=shapes, shape_name=values.get('formation.name', ''), schedule=schedule,
        command=command, imperfections=imperfections, relay=relay,
        transport=Transport(values.get('transport', Transport.ROBOT.value)), obstacles=mapped,
        obstacle_clearance=values.get('obstacles.clearance'), **own)


def load_config(path: PathText,
                executable: Union[Exe, str] = Exe.SIM) -> FormationConfig:
    """Load and validate a parameters file: ``load_params_file`` then :func:`validate`."""
    return validate(load_params_file(path), executable)


def validate_for_every_executable(raw: Mapping[str, Any]) -> Dict[Exe, FormationConfig]:
    """
    Validate one parameters file as every executable of a run reads it.

    The robot is checked as robot 1 (each robot's ``robot_id`` is given on its command line).
    Raises the first :class:`ParamError`.
    """
    checked = {}
    for exe in (Exe.SIM, Exe.PLANT, Exe.REFERENCE, Exe.ROBOT, Exe.RELAY):
        given = {**raw, 'robot_id': raw.get('robot_id', 1)} if exe is Exe.ROBOT else raw
        checked[exe] = validate(given, exe)
    return checked


__all__ = ['CommandSettings', 'fill_template', 'FormationConfig', 'load_config', 'ParamError',
           'PlantSettings', 'RecorderSettings', 'ReferenceSettings', 'RelaySettings',
           'RobotSettings', 'ScanSettings', 'template_problems', 'validate',
           'validate_for_every_executable', 'world_settings', 'WorldSettings']
