# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
One declaration per parameter: name, type, allowed range, description, who reads it.

This is the only list of parameters. ``core.settings.params`` checks values against it and builds
the typed settings; the ROS adapter declares each node's parameters from it (with the same
descriptions and ranges); the docs' parameter reference is generated from it (a declaration
without a description fails the docs build). Adding a parameter means adding its
:class:`Param` here and using it in ``core.settings.params``.

A range bound is inclusive or exclusive and says so in messages: ``> 0`` for a strictly
positive value, ``>= 2`` for an inclusive one.
"""

from dataclasses import dataclass
import difflib
import enum
import math
import re
from typing import Any, Dict, FrozenSet, Iterable, Mapping, Optional, Tuple, Type

from formation_ros.core.maths.choice import Choice
from formation_ros.core.maths.jump import JumpKind
from formation_ros.core.maths.law import GAIN_MAX, KAPPA_MAX, PsiKind, REPULSION_RANGE
from formation_ros.core.maths.reference import ReferenceKind
from formation_ros.core.model.bodies import BodyKind

DEFAULT_COLLISION_DISTANCE = 1e-3
LENGTH_LIMIT = 1e6
SPEED_LIMIT = 1e6
"""Lengths within +-1000 km and speeds within 1000 km/s (the law's own limits: core.maths.law)."""


class Kind(enum.Enum):
    """ROS 2 parameter type of a declaration."""

    INT = 'int'
    DOUBLE = 'double'
    STRING = 'string'
    BOOL = 'bool'
    DOUBLE_ARRAY = 'double_array'
    STRING_ARRAY = 'string_array'


ARRAYS = (Kind.DOUBLE_ARRAY, Kind.STRING_ARRAY)


class Exe(enum.Enum):
    """The executables that read parameters."""

    SIM = 'formation_sim'
    ROBOT = 'robot'
    PLANT = 'plant'
    REFERENCE = 'reference'
    RECORD = 'record'
    RELAY = 'relay'
    WORLD = 'world'


class PoseType(Choice):
    """The message a robot reads its own pose from: ``pose_type``."""

    POSE_STAMPED = 'pose_stamped'
    ODOMETRY = 'odometry'


class CommandType(Choice):
    """The message a robot publishes its command as: ``command.type``."""

    TWIST_STAMPED = 'twist_stamped'
    TWIST = 'twist'


class CommandFrame(Choice):
    """The frame of a robot's command: ``command.frame``."""

    WORLD = 'world'
    BODY = 'body'


class Transport(Choice):
    """How states and commands travel between the plant and the robots: ``transport``."""

    ROBOT = 'robot'
    TEAM = 'team'


class ObstacleSource(Choice):
    """Where a robot takes its obstacles from: ``obstacles.source``."""

    MAP = 'map'
    SCAN = 'scan'


class SourceType(Choice):
    """The message the relay reads a measured pose from: ``relay.source_type``."""

    POSE = 'pose'
    ODOMETRY = 'odometry'


@dataclass(frozen=True)
class Bound:
    """One end of a numeric range: ``value``, inclusive (``>=``/``<=``) or not (``>``/``<``)."""

    value: float
    inclusive: bool = True


def at_least(value: float) -> Bound:
    """Return the inclusive bound ``>= value`` (or ``<= value`` as an upper end)."""
    return Bound(value, True)


def above(value: float) -> Bound:
    """Return the exclusive bound ``> value`` (or ``< value`` as an upper end)."""
    return Bound(value, False)


class Required:
    """Marker default: the parameter must be given."""

    def __repr__(self) -> str:
        """Show as REQUIRED."""
        return 'REQUIRED'


REQUIRED = Required()
ALL = frozenset(Exe)
START = frozenset({Exe.SIM, Exe.PLANT, Exe.RECORD})
PLACED = START | {Exe.WORLD}
"""The readers of the start and the bodies' size and limits: START and the physics world."""
PLANT = frozenset({Exe.PLANT, Exe.RECORD})
ROBOT = frozenset({Exe.ROBOT, Exe.RECORD})
COMMAND = frozenset({Exe.SIM, Exe.ROBOT, Exe.PLANT, Exe.RECORD, Exe.WORLD})
RELAY = frozenset({Exe.RELAY})
SCHEDULE = frozenset({Exe.SIM, Exe.REFERENCE, Exe.RECORD})
PHYSICS = frozenset({Exe.SIM, Exe.WORLD})
"""The readers of ``world.*``: ``formation_sim --engine mujoco`` and the ``world`` node
(formation_ros/physics)."""
MAPPED = frozenset({Exe.SIM, Exe.PLANT, Exe.RECORD, Exe.RELAY, Exe.WORLD})
"""The readers of the obstacle map (``obstacles.*``): whoever places bodies or tells robots
their obstacles; a robot hears its obstacles (and reads only ``obstacles.clearance``)."""
SHAPE_VERTICES = 'formations.<name>.vertices'
"""The declaration of every named shape's vertices: ``formations.line.vertices`` and so on."""
SHAPE_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*')
DEFAULT_WORLD_FRAME = 'world'


@dataclass(frozen=True)
class Param:
    """
    One parameter.

    default: its value when absent; ``None`` for an optional parameter without a value (it is
    then declared on a node only when it applies, see ``ros.parameters``); :data:`REQUIRED`.
    low / high: range of the value (of each element for arrays); choices: allowed strings
    (from an enum); users: the executables that read it.
    """

    name: str
    kind: Kind
    default: object
    description: str
    low: Optional[Bound] = None
    high: Optional[Bound] = None
    choices: Tuple[str, ...] = ()
    users: FrozenSet[Exe] = ALL

    def range_text(self) -> str:
        """Describe the allowed values, e.g. ``> 0``, ``2 to 3``, ``arctan, tanh``."""
        if self.choices:
            return ', '.join(self.choices)
        parts = []
        if self.low is not None:
            parts.append(f"{'>=' if self.low.inclusive else '>'} {self.low.value:g}")
        if self.high is not None:
            parts.append(f"{'<=' if self.high.inclusive else '<'} {self.high.value:g}")
        return ', '.join(parts)


def _choices(kind: Type[enum.Enum]) -> Tuple[str, ...]:
    return tuple(str(member.value) for member in kind)


DECLARATIONS = (
    Param('num_robots', Kind.INT, REQUIRED, 'Number of robots N (robots are numbered 1..N).',
          low=at_least(2), high=at_least(100000)),
    Param('dim', Kind.INT, 2, 'Dimension n of the workspace: 2 or 3.', low=at_least(2),
          high=at_least(3)),
    Param('world_frame', Kind.STRING, DEFAULT_WORLD_FRAME,
          'Frame id of every formation message (poses, neighbours, reference, world-frame '
          "commands); messages in another frame are refused. A mocap system's frame, e.g. "
          "'map' or 'mocap'."),
    Param('sensing_radius', Kind.DOUBLE, REQUIRED, 'Sensing radius R_i of every robot, m.',
          low=above(0.0), high=at_least(LENGTH_LIMIT)),
    Param('sensing_radii', Kind.DOUBLE_ARRAY, None,
          'Optional sensing radius per robot (num_robots values, m); overrides sensing_radius.',
          low=above(0.0), high=at_least(LENGTH_LIMIT)),
    Param('repulsion_radius', Kind.DOUBLE, REQUIRED,
          'Repulsion radius b_ij of eq. (11), m; at most every R_i and the closest vertex pair.',
          low=at_least(REPULSION_RANGE[0]), high=at_least(REPULSION_RANGE[1])),
    Param('controller.gain', Kind.DOUBLE, 2.0, 'Gain c of eq. (14), m/s.', low=above(0.0),
          high=at_least(GAIN_MAX)),
    Param('controller.kappa', Kind.DOUBLE, 1.0,
          'Weight kappa of the collision term, eqs. (8), (13).', low=above(0.0),
          high=at_least(KAPPA_MAX)),
    Param('controller.psi', Kind.STRING, PsiKind.ARCTAN.value,
          'Bounded function psi of eq. (14).', choices=_choices(PsiKind)),
    Param('jump.kind', Kind.STRING, JumpKind.POLY.value,
          "Jump function of Lemma 1: 'poly' (g = y^p) or 'smooth' (g = exp(-1/y)).",
          choices=_choices(JumpKind)),
    Param('jump.order', Kind.INT, 2, "Order p of g(y) = y^p (kind 'poly').", low=at_least(1),
          high=at_least(50)),
    Param('formation.vertices', Kind.DOUBLE_ARRAY, REQUIRED,
          "Flat list of num_robots x dim values: robot i's place in the formation frame, m.",
          low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT)),
    Param('formation.name', Kind.STRING, '',
          "Name of the shape in force: one of formations.names, or '' for formation.vertices. "
          'Settable on the running reference node.'),
    Param('formations.names', Kind.STRING_ARRAY, None,
          'Names of the shapes the team can switch between; shape N has its vertices in '
          'formations.N.vertices.'),
    Param(SHAPE_VERTICES, Kind.DOUBLE_ARRAY, None,
          'Vertices of the shape named <name> (one of formations.names), as formation.vertices.',
          low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT)),
    Param('formation.schedule.times', Kind.DOUBLE_ARRAY, None,
          'Times at which the shape changes, s, increasing (with formation.schedule.names): a '
          'scripted switch that formation_sim and a lockstep run reproduce alike.',
          low=at_least(0.0), high=at_least(1e7), users=SCHEDULE),
    Param('formation.schedule.names', Kind.STRING_ARRAY, None,
          'The shape (a name of formations.names) in force from each of formation.schedule.times '
          'on.', users=SCHEDULE),
    Param('body.kind', Kind.STRING, BodyKind.POINT.value,
          "The robots' bodies: 'point' (q' = u, eq. 1) or 'unicycle' (differential drive, "
          'commanded with (v, w) through a hand point; dim 2 only).', choices=_choices(BodyKind)),
    Param('body.hand_distance', Kind.DOUBLE, None,
          'Unicycles: distance l of the hand point ahead of the axle centre, m (the law acts '
          'on the hand points).', low=above(0.0), high=at_least(LENGTH_LIMIT)),
    Param('body.radius', Kind.DOUBLE, 0.0,
          'Radius of a body about its position (the axle centre of a unicycle), m: two bodies '
          'closer than twice this are logged as a collision; with obstacles, part of the '
          'footprint the law keeps off them.', low=at_least(0.0), high=at_least(LENGTH_LIMIT),
          users=PLACED | {Exe.ROBOT, Exe.RELAY}),
    Param('body.max_linear', Kind.DOUBLE, None,
          'Unicycles: actuator limit on |v|, m/s; a file whose bound sqrt(2) c M1 '
          'exceeds it is refused, and the plant clips |v| to it; the reference refuses a '
          'speed whose vertices it cannot carry.', low=above(0.0),
          high=at_least(SPEED_LIMIT), users=PLACED | {Exe.REFERENCE}),
    Param('body.max_angular', Kind.DOUBLE, None,
          'Unicycles: actuator limit on |w|, rad/s; a file whose bound '
          'sqrt(2) c M1 / l exceeds it is refused, and the plant clips |w| to it.',
          low=above(0.0), high=at_least(SPEED_LIMIT), users=PLACED),
    Param('start.positions', Kind.DOUBLE_ARRAY, None,
          'Flat list of num_robots x dim start positions, m (or use start.random_*).',
          low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT), users=PLACED),
    Param('start.random_radius', Kind.DOUBLE, None,
          'Random start: radius of the disc (ball in 3D) about the origin, m.', low=above(0.0),
          high=at_least(LENGTH_LIMIT), users=PLACED),
    Param('start.min_separation', Kind.DOUBLE, None,
          'Random start: smallest distance between two robots, m.', low=above(0.0),
          high=at_least(LENGTH_LIMIT), users=PLACED),
    Param('start.headings', Kind.DOUBLE_ARRAY, None,
          'Unicycles: num_robots start headings, rad, counter-clockwise from +x (default: random '
          'with a random start, else 0).', low=at_least(-LENGTH_LIMIT),
          high=at_least(LENGTH_LIMIT), users=PLACED),
    Param('start.seed', Kind.INT, 0, 'Random start: seed of the random generator.',
          low=at_least(0), high=at_least(2 ** 31 - 1), users=PLACED),
    Param('reference.kind', Kind.STRING, ReferenceKind.FIXED.value,
          'Desired formation trajectory q_od(t).', choices=_choices(ReferenceKind)),
    Param('reference.origin', Kind.DOUBLE_ARRAY, None,
          'dim values: fixed point, start of a line, centre of a circle/figure eight/helix, m '
          '(default: the origin).', low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT)),
    Param('reference.velocity', Kind.DOUBLE_ARRAY, None,
          "dim values: velocity of a 'line', m/s (default: zero).", low=at_least(-SPEED_LIMIT),
          high=at_least(SPEED_LIMIT)),
    Param('reference.radius', Kind.DOUBLE, 1.0, 'Radius of circle, figure eight and helix, m.',
          low=above(0.0), high=at_least(LENGTH_LIMIT)),
    Param('reference.speed', Kind.DOUBLE, 0.5,
          'Path speed of circle and helix (mean speed of the figure eight), m/s.',
          low=at_least(0.0), high=at_least(SPEED_LIMIT)),
    Param('reference.pitch', Kind.DOUBLE, 1.0, 'Helix rise per turn along +z, m.',
          low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT)),
    Param('reference.rate', Kind.DOUBLE, 50.0,
          'Publication rate of /formation/reference, Hz (wall clock).', low=above(0.0),
          high=at_least(10000.0), users=frozenset({Exe.REFERENCE, Exe.RECORD})),
    Param('duration', Kind.DOUBLE, 20.0, 'Length of a run, s.', low=above(0.0),
          high=at_least(1e7)),
    Param('obstacles.circles', Kind.DOUBLE_ARRAY, None,
          'Static obstacles: flat list [x, y, r, ...] in world_frame, m: discs in 2D, vertical '
          'pillars of radius r (unbounded in z) in 3D (beyond the paper: docs/equations.md, '
          '"Obstacles").', low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT),
          users=MAPPED),
    Param('obstacles.walls', Kind.DOUBLE_ARRAY, None,
          'Static obstacles: flat list [x1, y1, x2, y2, t, ...] in world_frame, m: the points '
          'within t of the segment from (x1, y1) to (x2, y2); in 3D vertical walls, unbounded '
          'in z.', low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT), users=MAPPED),
    Param('obstacles.spheres', Kind.DOUBLE_ARRAY, None,
          'Static obstacles, 3D only: flat list [x, y, z, r, ...] in world_frame, m.',
          low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT), users=MAPPED),
    Param('obstacles.clearance', Kind.DOUBLE, None,
          'b_o, m: an obstacle repels a robot whose footprint is nearer than this to its '
          'surface; required with obstacles, at most every R_i.', low=above(0.0),
          high=at_least(LENGTH_LIMIT), users=MAPPED | {Exe.ROBOT}),
    Param('obstacles.source', Kind.STRING, ObstacleSource.MAP.value,
          "Where a robot takes its obstacles from: 'map' (the points the plant or relay tells "
          "it on obstacles, from their obstacles.* map) or 'scan' (its own laser scan, "
          "sensor_msgs/LaserScan on the relative topic scan: remap it onto a lab robot's "
          '/scan). Beyond the paper: docs/equations.md, "Obstacles from a scan". formation_sim '
          'has no scanner: it says so and gives the law the map.',
          choices=_choices(ObstacleSource), users=ROBOT | {Exe.SIM}),
    Param('obstacles.scan_frame', Kind.STRING, '',
          "frame_id a robot's scans must carry (others are refused); empty: "
          "robot_<i>/base_scan, the world's (a TurtleBot3 driver's: 'base_scan').",
          users=ROBOT),
    Param('obstacles.scan_mount', Kind.DOUBLE_ARRAY, None,
          "[x, y, yaw]: the scanner's place in the base's frame, m, m, rad (a TurtleBot3 "
          "Burger's LDS: [-0.032, 0.0, 0.0]); absent: at the pose's position, facing +x (the "
          "world's).", low=at_least(-LENGTH_LIMIT), high=at_least(LENGTH_LIMIT), users=ROBOT),
    Param('obstacles.scan_margin', Kind.DOUBLE, 0.05,
          "A scan return within body.radius plus this of a neighbour's position is that "
          "neighbour (left to the pair terms), m: the pose's age and noise.",
          low=at_least(0.0), high=at_least(LENGTH_LIMIT), users=ROBOT),
    Param('obstacles.scan_join', Kind.DOUBLE, 0.2,
          'Returns of neighbouring rays (a dropout between allowed) nearer each other than this '
          "are one obstacle, m: its nearest return within R_i repels, as a mapped obstacle's "
          'closest point does, and so does the nearest of each of its faces (a minimum from '
          'which the distance rises by this much on both sides: the walls of a room); 0: '
          'every return repels.', low=at_least(0.0), high=at_least(LENGTH_LIMIT),
          users=ROBOT),
    Param('obstacles.scan_sectors', Kind.INT, 72,
          'A robot keeps the nearest scan return of each of this many equal sectors of '
          "directions about it (72: 5 degrees) as its obstacle points: the law's cost stays "
          'bounded whatever the scanner.', low=at_least(4), high=at_least(3600), users=ROBOT),
    Param('robot_id', Kind.INT, REQUIRED, 'This robot: 1..num_robots (robot node only).',
          low=at_least(1), users=frozenset({Exe.ROBOT})),
    Param('control_rate', Kind.DOUBLE, 50.0,
          'Rate of the robot watchdog, Hz (wall clock): it publishes zero at this rate while '
          'an input is stale, and answers a pose whose neighbours were lost one period after '
          'it (states are answered as they arrive).',
          low=above(0.0), high=at_least(10000.0), users=ROBOT),
    Param('input_timeout', Kind.DOUBLE, 0.5,
          'A robot publishes zero when no new pose, neighbours or reference arrived for this '
          'long, s (wall clock; not in lockstep).', low=above(0.0), users=ROBOT),
    Param('pose_type', Kind.STRING, PoseType.POSE_STAMPED.value,
          "Message type of a robot's 'pose' topic: 'pose_stamped' (geometry_msgs/PoseStamped, "
          "what the plant publishes) or 'odometry' (nav_msgs/Odometry, e.g. a real base's "
          'localisation, remapped onto pose).', choices=_choices(PoseType),
          users=frozenset({Exe.ROBOT})),
    Param('command.type', Kind.STRING, CommandType.TWIST_STAMPED.value,
          "Message a robot publishes on cmd_vel: 'twist_stamped' (geometry_msgs/TwistStamped, "
          "stamped with the state it answers) or 'twist' (geometry_msgs/Twist, for bases that "
          'take no stamp); the plant subscribes with the same type.',
          choices=_choices(CommandType), users=COMMAND),
    Param('command.frame', Kind.STRING, None,
          "Frame of a robot's command: 'world' (default for points: u in world_frame) or "
          "'body' (robot_<i>/base_link, rotated by the pose's orientation: holonomic bases "
          'that take body-frame velocities; unicycles always command (v, w) in their body '
          'frame).', choices=_choices(CommandFrame), users=COMMAND),
    Param('transport', Kind.STRING, Transport.ROBOT.value,
          "How states and commands travel: 'robot' (each robot's pose, neighbors and cmd_vel "
          "topics, what real robots and the relay use) or 'team' (one /formation/states "
          'message per state for every robot, one /formation/commands message per robot '
          'process or fleet per state; the per-robot topics only while something subscribes '
          'to them).', choices=_choices(Transport),
          users=frozenset({Exe.PLANT, Exe.ROBOT})),
    Param('fleet.parameter_services', Kind.BOOL, True,
          'In a fleet process, whether every robot node offers the parameter services (ros2 '
          'param list, get, set, dump on /robot_<i>/robot) and the type description '
          "service, and publishes on /rosout. False: the fleet's first robot alone does (the "
          "others' log lines still reach the console), and each other robot node has 15 DDS "
          'endpoints fewer (its parameters '
          'are still declared and checked, its team values announced on /diagnostics); '
          'discovery, start-up and memory grow with the endpoints of every process, which is '
          'what limits a team of a thousand robots. A robot process of its own always offers '
          'them.',
          users=ROBOT),
    Param('wait_for_subscribers', Kind.INT, 1,
          'A robot sends its first command only once cmd_vel has this many subscribers (the '
          'plant; 2 when a recorder listens too).', low=at_least(0), high=at_least(1000),
          users=ROBOT),
    Param('plant.rate', Kind.DOUBLE, 100.0,
          'Integration rate of the plant, Hz of simulated time: step dt = 1 / rate.',
          low=above(0.0), high=at_least(100000.0),
          users=frozenset({Exe.PLANT, Exe.REFERENCE, Exe.ROBOT})),
    Param('plant.input_timeout', Kind.DOUBLE, 0.5,
          'A command whose state stamp is older than this counts as zero, s (simulated time).',
          low=above(0.0), users=PLANT),
    Param('plant.publish_rate', Kind.DOUBLE, 50.0,
          'Rate of /robot_<i>/pose, /robot_<i>/neighbors (or /formation/states with transport '
          'team) and /clock, Hz of simulated time '
          '(at most plant.rate; every step in lockstep). Robots answer at most about one state '
          'per period.', low=above(0.0), high=at_least(100000.0), users=PLANT | {Exe.ROBOT}),
    Param('plant.realtime_factor', Kind.DOUBLE, 1.0,
          'Simulated seconds per wall-clock second (an upper bound in lockstep).',
          low=above(0.0), high=at_least(1000.0), users=PLANT),
    Param('plant.lockstep', Kind.BOOL, False,
          'Deterministic mode: the plant steps only when every robot answered the latest state.',
          users=frozenset({Exe.PLANT, Exe.ROBOT, Exe.REFERENCE, Exe.RECORD})),
    Param('plant.max_speed', Kind.DOUBLE, 0.0,
          'Cap on every component of an applied command, m/s (world frame); 0: no cap beyond '
          "the law's own bound (u_hat within c*M1 at the state a command answers).",
          low=at_least(0.0), users=PLANT),
    Param('plant.actuator_lag', Kind.DOUBLE, 0.0,
          "Time constant of a first-order lag between a robot's admitted command and its "
          "body's velocity, s (0: the body moves at once, as eq. (1) assumes; beyond the "
          'paper).', low=at_least(0.0), high=at_least(1000.0), users=START),
    Param('plant.max_acceleration', Kind.DOUBLE, 0.0,
          "Limit on the rate of change of the body's velocity, m/s^2, per world component "
          'for points, on v (m/s^2) and w (rad/s^2) for unicycles (0: none; beyond the '
          'paper).', low=at_least(0.0), high=at_least(SPEED_LIMIT), users=START),
    Param('plant.pose_noise', Kind.DOUBLE, 0.0,
          'Standard deviation of Gaussian noise on every sensed position (own pose and '
          'neighbours), m, seeded by start.seed (0: exact; beyond the paper).',
          low=at_least(0.0), high=at_least(LENGTH_LIMIT), users=START),
    Param('plant.state_delay', Kind.DOUBLE, 0.0,
          'A state reaches the robots this much later than it happened, s (0: at once; beyond '
          'the paper); less than plant.input_timeout and than input_timeout (robots).',
          low=at_least(0.0), high=at_least(1000.0), users=START | {Exe.ROBOT}),
    Param('plant.collision_distance', Kind.DOUBLE, DEFAULT_COLLISION_DISTANCE,
          'Two robots closer than this are logged as a collision, m.', low=at_least(0.0),
          users=PLANT),
    Param('plant.wait_for_robots', Kind.BOOL, True,
          'Hold the clock at 0 (resending the start state) until every robot has sent a '
          'command, so that all robots start together.', users=PLANT),
    Param('plant.wait_for_subscribers', Kind.INT, 1,
          'While waiting for the robots, also wait until every robot_<i>/pose topic has this '
          'many subscribers (2 when a recorder listens too).', low=at_least(0),
          high=at_least(1000), users=PLANT),
    Param('plant.marker_rate', Kind.DOUBLE, 5.0,
          'Rate of /formation/markers for RViz, Hz (wall clock); 0 publishes none.',
          low=at_least(0.0), high=at_least(100.0), users=PLANT),
    Param('plant.output_dir', Kind.STRING, '',
          'If set, the plant writes trajectory.npz and plant_stats.json there when it stops.',
          users=PLANT),
    Param('record.path', Kind.STRING, REQUIRED,
          'Directory of the rosbag2 (MCAP) the recorder writes; must not exist yet.',
          users=frozenset({Exe.RECORD})),
    Param('record.overwrite', Kind.BOOL, False,
          'Let the recorder replace an existing bag directory at record.path.',
          users=frozenset({Exe.RECORD})),
    Param('record.markers', Kind.BOOL, False, 'Also record /formation/markers.',
          users=frozenset({Exe.RECORD})),
    Param('relay.source_topic', Kind.STRING, '/robot_{i}/measured_pose',
          "Topic of robot i's measured pose: '{i}' is the robot id, '{name}' its entry of "
          "relay.source_names (e.g. '/vrpn_mocap/{name}/pose').", users=RELAY),
    Param('relay.source_names', Kind.STRING_ARRAY, None,
          "One name per robot (num_robots values), for '{name}' in relay.source_topic (e.g. "
          'mocap rigid bodies [tb1, tb2, ...]).', users=RELAY),
    Param('relay.source_type', Kind.STRING, SourceType.POSE.value,
          "Message type of the measured poses: 'pose' (geometry_msgs/PoseStamped) or "
          "'odometry' (nav_msgs/Odometry).", choices=_choices(SourceType), users=RELAY),
    Param('relay.rate', Kind.DOUBLE, 50.0,
          'Cycles per second of the relay, Hz (of wall-clock time in a lab, of simulated '
          'time beside a world): each publishes every pose and neighbour list with one '
          'stamp; robots answer at most about one state per cycle.', low=above(0.0),
          high=at_least(10000.0), users=RELAY | {Exe.ROBOT}),
    Param('relay.max_age', Kind.DOUBLE, 0.2,
          'A robot whose latest measurement is older than this is stale, s: it gets no pose '
          "(its watchdog stops it) but stays in the others' neighbour lists at its last "
          'measured position.', low=above(0.0), high=at_least(1000.0), users=RELAY),
    Param('world.timestep', Kind.DOUBLE, 0.002,
          'Step of the physics engine (MuJoCo), s of simulated time; a whole number of '
          'nanoseconds.', low=at_least(1e-5), high=at_least(0.05), users=PHYSICS),
    Param('world.realtime_factor', Kind.DOUBLE, 1.0,
          'Simulated seconds per wall-clock second the world aims at when it runs beside '
          'processes (offline, formation_sim --engine mujoco runs as fast as it can).',
          low=above(0.0), high=at_least(1000.0), users=PHYSICS),
    Param('world.pose_rate', Kind.DOUBLE, 50.0,
          "Rate of the world's measured poses, Hz of simulated time (at most 1 / "
          'world.timestep).', low=above(0.0), high=at_least(100000.0), users=PHYSICS),
    Param('world.pose_noise', Kind.DOUBLE, 0.0,
          'Standard deviation of Gaussian noise on every measured position, m, seeded by '
          'start.seed (0: the ground truth).', low=at_least(0.0), high=at_least(LENGTH_LIMIT),
          users=PHYSICS),
    Param('world.mass', Kind.DOUBLE, 1.0,
          "Mass of each robot's body, kg (a TurtleBot3 Burger: about 1 kg).", low=above(0.0),
          high=at_least(1e4), users=PHYSICS),
    Param('world.wheel_radius', Kind.DOUBLE, 0.033,
          "Unicycles: radius of a differential-drive base's two wheels, m (TurtleBot3 Burger: "
          '0.033 m).', low=above(0.0), high=at_least(10.0), users=PHYSICS),
    Param('world.wheel_track', Kind.DOUBLE, 0.16,
          'Unicycles: distance between the two wheels, m (TurtleBot3 Burger: 0.160 m); a '
          "base's footprint is body.radius, or wider if the wheels need it.", low=above(0.0),
          high=at_least(100.0), users=PHYSICS),
    Param('world.wheel_torque', Kind.DOUBLE, 0.2,
          "Unicycles: torque limit of each wheel's velocity servo, N m: with the mass it sets "
          'how fast a base can speed up or brake.', low=above(0.0), high=at_least(1e4),
          users=PHYSICS),
    Param('world.force_limit', Kind.DOUBLE, 5.0,
          'Points: force limit of the velocity servo on each axis, N (in 2D at most '
          'world.floor_friction x the weight: what the floor lets the wheels push); the thrust '
          'that holds a 3D body against gravity comes on top.', low=above(0.0),
          high=at_least(1e6), users=PHYSICS),
    Param('world.torque_limit', Kind.DOUBLE, 0.5,
          "Points: torque limit of the servo that holds a body's heading, N m.",
          low=above(0.0), high=at_least(1e6), users=PHYSICS),
    Param('world.floor_friction', Kind.DOUBLE, 1.0,
          'Sliding friction coefficient between the floor and the wheels (unicycles) or the '
          'traction of a holonomic base (2D points); below 0.01 (no real floor) MuJoCo loses '
          'the bases.', low=at_least(0.01), high=at_least(10.0),
          users=PHYSICS),
    Param('world.cmd_timeout', Kind.DOUBLE, 0.5,
          "A robot's command older than this (by its stamp), or none for this long, stops its "
          "motors, s of simulated time (diff_drive_controller's cmd_vel_timeout).",
          low=above(0.0), high=at_least(1e7), users=PHYSICS),
    Param('world.obstacle_height', Kind.DOUBLE, 0.5,
          'Height of the pillars (obstacles.circles) and walls (obstacles.walls) the world '
          'builds in 2D, m: they stand on the floor and must rise above the bodies (the law '
          'treats them as unbounded in z). In 3D they span the flight volume instead.',
          low=above(0.0), high=at_least(LENGTH_LIMIT), users=PHYSICS),
    Param('world.scan_rate', Kind.DOUBLE, 5.0,
          "Rate of each planar robot's laser scan (/robot_<i>/scan), Hz of simulated time "
          '(a TurtleBot3 LDS: 5 Hz; at most 1 / world.timestep); 0: no scanner. 3D flyers '
          'have none.', low=at_least(0.0), high=at_least(100000.0), users=PHYSICS),
    Param('world.scan_rays', Kind.INT, 360,
          'Rays of each scan, evenly spaced over a full turn counter-clockwise from the '
          "base's +x (LDS: 360, one a degree).", low=at_least(1), high=at_least(100000),
          users=PHYSICS),
    Param('world.scan_range_min', Kind.DOUBLE, 0.12,
          'Nearest return a scan reports, m (LDS: 0.12 m); a nearer one reads +inf; less '
          'than world.scan_range_max.', low=at_least(0.0), high=at_least(LENGTH_LIMIT),
          users=PHYSICS),
    Param('world.scan_range_max', Kind.DOUBLE, 3.5,
          'Farthest return a scan reports, m (LDS: 3.5 m); nothing within it reads +inf.',
          low=above(0.0), high=at_least(LENGTH_LIMIT), users=PHYSICS),
    Param('world.scan_noise', Kind.DOUBLE, 0.0,
          'Standard deviation of Gaussian noise on every scan return, m, seeded by start.seed '
          '(0: exact ranges).', low=at_least(0.0), high=at_least(LENGTH_LIMIT), users=PHYSICS),
    Param('world.output_dir', Kind.STRING, '',
          'If set, the world writes world.xml (and its results) there.', users=PHYSICS),
)
BY_NAME = {param.name: param for param in DECLARATIONS}
ROS_OWN = ('use_sim_time', 'start_type_description_service', 'qos_overrides.')
ROS_OWN_BOOLS = ('use_sim_time', 'start_type_description_service')
"""rclpy's own parameters that it declares as bools as a node is made."""
RECORDER_ONLY = ('record.path', 'record.overwrite', 'record.markers')


class ParamError(ValueError):
    """One or more invalid parameters; ``str()`` names each parameter and what is allowed."""

    def __init__(self, problems: Iterable[Tuple[str, str]]):
        """Keep the list of (parameter name, message) pairs."""
        self.problems = list(problems)
        super().__init__('\n'.join(f"parameter '{name}': {msg}" for name, msg in self.problems))


def used_by(exe: Exe) -> Tuple[Param, ...]:
    """Return the declarations that ``exe`` reads, in declaration order."""
    return tuple(param for param in DECLARATIONS if exe in param.users)


def shape_vertices_name(shape: str) -> str:
    """Return the parameter of a named shape's vertices: 'line' gives formations.line.vertices."""
    return f'formations.{shape}.vertices'


def shape_of_parameter(name: str) -> Optional[str]:
    """Return the shape a ``formations.<name>.vertices`` parameter names, else None."""
    parts = name.split('.')
    if len(parts) == 3 and parts[0] == 'formations' and parts[2] == 'vertices' \
            and SHAPE_NAME.fullmatch(parts[1]):
        return parts[1]
    return None


def is_known(name: str) -> bool:
    """Tell whether ``name`` is a formation parameter or one that rclpy itself declares."""
    return name in BY_NAME or name.startswith(ROS_OWN) or shape_of_parameter(name) is not None


def did_you_mean(name: str) -> str:
    """Return " (did you mean 'x'?)" with the closest known name, or '' when none is close."""
    close = difflib.get_close_matches(name, list(BY_NAME), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ''


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def type_problem(param: Param, value: object) -> Optional[str]:
    """Return what is wrong with the type of ``value`` for ``param``, or None."""
    if param.kind is Kind.INT:
        return None if _is_int(value) else f'must be an integer, got {value!r}'
    if param.kind is Kind.DOUBLE:
        if _is_int(value):
            return f'must be a double: write {value}.0, not {value} (ROS 2 parameters are typed)'
        ok = isinstance(value, float) and math.isfinite(value)
        return None if ok else f'must be a finite double, got {value!r}'
    if param.kind is Kind.STRING:
        return None if isinstance(value, str) else f'must be a string, got {value!r}'
    if param.kind is Kind.BOOL:
        return None if isinstance(value, bool) else f'must be true or false, got {value!r}'
    if param.kind is Kind.STRING_ARRAY:
        ok = (isinstance(value, (list, tuple)) and bool(value)
              and all(isinstance(item, str) for item in value))
        return None if ok else f'must be a non-empty list of strings, got {value!r}'
    if not isinstance(value, (list, tuple)) or not value:
        return f'must be a non-empty list of doubles, got {value!r}'
    for item in value:
        if _is_int(item):
            return (f'must be a list of doubles: write {item}.0, not {item} '
                    '(ROS 2 parameters are typed)')
        if not (isinstance(item, float) and math.isfinite(item)):
            return f'must be a list of finite doubles, got element {item!r}'
    return None


def _outside(value: float, bound: Bound, lower: bool) -> bool:
    if lower:
        return value < bound.value if bound.inclusive else value <= bound.value
    return value > bound.value if bound.inclusive else value >= bound.value


def range_problem(param: Param, value: object) -> Optional[str]:
    """Return what is wrong with the (well-typed) ``value`` for ``param``'s range, or None."""
    if param.choices:
        ok = value in param.choices
        return None if ok else f"must be one of {', '.join(param.choices)}; got {value!r}"
    if param.kind not in (Kind.INT, Kind.DOUBLE, Kind.DOUBLE_ARRAY):
        return None
    items: Any = value if param.kind is Kind.DOUBLE_ARRAY else [value]
    for item in items:
        for bound, lower in ((param.low, True), (param.high, False)):
            if bound is not None and _outside(item, bound, lower):
                sign = ('>' if lower else '<') + ('=' if bound.inclusive else '')
                return f'must be {sign} {bound.value:g}, got {item!r}'
    return None


def check_values(raw: Mapping[str, Any], exe: Exe) -> Dict[str, Any]:
    """
    Check names, types and ranges; return {name: value} with the static defaults filled in.

    raw: flat {dotted name: value}, as given. Only the parameters ``exe`` reads are checked and
    returned; unknown names are errors. Raises :class:`ParamError` listing every problem.
    """
    problems = [(name, f'unknown parameter{did_you_mean(name)}') for name in raw
                if not is_known(name)]
    problems += [(name, f'must be true or false, got {raw[name]!r}') for name in ROS_OWN_BOOLS
                 if name in raw and not isinstance(raw[name], bool)]
    values: Dict[str, Any] = {}
    shapes = BY_NAME[SHAPE_VERTICES]
    for name in raw:
        if shape_of_parameter(name) is not None and exe in shapes.users:
            value = raw[name]
            problem = type_problem(shapes, value) or range_problem(shapes, value)
            if problem:
                problems.append((name, problem))
            else:
                values[name] = list(value)
    for param in used_by(exe):
        if param is shapes:
            continue
        value = raw.get(param.name)
        if value is None:
            if param.default is REQUIRED:
                problems.append((param.name, f'is required: {param.description}'))
            elif param.default is not None:
                values[param.name] = param.default
            continue
        problem = type_problem(param, value) or range_problem(param, value)
        if problem:
            problems.append((param.name, problem))
        else:
            values[param.name] = list(value) if param.kind in ARRAYS else value
    if problems:
        raise ParamError(problems)
    return values
