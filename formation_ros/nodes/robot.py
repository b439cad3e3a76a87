# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Robot node (executable ``robot``): one robot's bounded formation controller.

It knows its own position (``pose``), the robots its range sensor sees (its neighbours, on
``neighbors``) and the desired formation frame (``/formation/reference``), and publishes
``cmd_vel`` with linear = u_i of eqs. (14), (25), computed by ``core.law.robot_command``. Run
one per robot, each in its namespace::

    ros2 run formation_ros robot --ros-args -r __ns:=/robot_1 -p robot_id:=1 \\
        --params-file config/paper_section5.yaml

A robot answers each state as soon as its pose and neighbours (same stamp) are both in: the
callbacks store them and arm a one-shot timer (``formation_ros.ros.wake``) that computes and
publishes; a pose whose neighbours are lost is answered one period of ``control_rate`` after
it. The watchdog, another one-shot timer, looks when the oldest input is due to turn stale
(states arriving keep it away: no wake-up per state) and then publishes zero at
``control_rate`` while the inputs stay stale. The command is stamped with the stamp of the
state it was computed from, so the plant can tell how old it is (and, in lockstep, which state
it answers). On simulated time (``use_sim_time:=true``, beside a plant) a robot's clock is set
from the stamps of the poses it accepts, which carry the plant's simulated time
(``formation_ros.ros.sim_clock.StateClock``; forward only while they come): no ``/clock``
subscription, one message less per state; its ``use_sim_time`` is then fixed while it runs.
There it also evaluates the reference frame at each state's stamp itself, from the reference's
parameters and the changes announced on ``/formation/status`` (the function the reference node
publishes from), and checks the reference node's samples against it: they show the reference
runs on the plant's time, but need not come with every state (``reference.rate`` below the
control rate costs nothing). On the wall clock it carries the newest sample to the state's
stamp.
Every input is read from its serialized bytes and the command written as bytes
(``formation_ros.ros.cdr``): rclpy's own conversions were most of a robot's time.

A unicycle (``body.kind: unicycle``, docs/equations.md U1-U5) reads its heading from its pose's
orientation and its neighbours' from theirs, runs the law on its own hand point and the
neighbours' hand points within R_i, and publishes (v, w) in its body frame
(``robot_<i>/base_link``: linear.x = v, angular.z = w), as diff_drive_controller takes it. With
``pose_type: odometry`` the pose comes from a nav_msgs/Odometry (a real base's localisation)
instead of a PoseStamped.

A robot answers at most about one state per expected state period
(``formation_ros.core.answers``: the plant's, ``plant.publish_rate`` of simulated time, every
step in lockstep; on wall-clock time the relay's, ``relay.rate``), and a state once: a copy of
the state it answered last is not answered again. States beyond that (a flood of forged poses)
are counted in ``/diagnostics``, logged once, and not answered, so a flood on ``pose`` is never
one on ``cmd_vel``. A robot also looks up, once a second, who publishes ``/clock`` and
``/formation/reference``: more than one is an ERROR in its ``/diagnostics``, logged once,
naming them (two teams on one domain), and a robot refusing stamps from another clock says so
then instead of advising ``use_sim_time``.

With ``transport: team`` a robot hears no ``pose`` or ``neighbors``: its process reads the
team's ``/formation/states`` once for all its robots and answers with one
``/formation/commands`` message (:class:`TeamLink`); its ``cmd_vel`` carries its command only
while someone subscribes to it, and unless more subscribers than the plant are awaited
(``wait_for_subscribers`` > 1) its publisher is made only once a subscriber shows in the graph
(a thousand publishers nobody hears are a thousand endpoints for discovery). The process
evaluates the reference frame for each state's stamp itself from the reference's parameters
and the changes the reference node announced; the reference node's samples, heard by the
first robot of the process alone, are checked as always and against that frame, and in
lockstep a state is answered once its sample is in. Its robots' simulated clocks follow the
team states' stamps.

Every state and reference message must be in ``world_frame`` (default ``world``). Commands for
real bases: ``command.type: twist`` publishes a geometry_msgs/Twist (no stamp) instead of a
TwistStamped, and ``command.frame: body`` publishes a point robot's u in its
``robot_<i>/base_link`` (u turned by the inverse of its pose's orientation; a pose without a
unit-quaternion orientation is then refused), as holonomic (mecanum, omni-wheel) bases take it.
"""

from collections import deque
import enum
import math
import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, TypeVar

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.answers import AnswerBudget
from formation_ros.core.bodies import make_bodies
from formation_ros.core.declarations import CommandFrame, Exe, ParamError, PoseType
from formation_ros.core.frames import advance, FrameSample, to_body_frame, valid_quaternions
from formation_ros.core.law import Command, robot_command, robot_commands
from formation_ros.core.params import FormationConfig
from formation_ros.core.sensing import sensed_pairs, sensor_radii
from formation_ros.core.team import team_values
from formation_ros.core.timeline import Mode, Shape, TeamState
from formation_ros.core.transport import command_vectors, robot_name
from formation_ros.core.turns import Turns
from formation_ros.core.unicycle import (hand_points, headings_from_quaternions,
                                         unicycle_commands)
from formation_ros.core.units import NS_PER_S
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import (CdrError, encode_names, encode_team_commands, encode_twist,
                                   encode_twist_stamped, OdometryData, PoseArrayData, PoseData,
                                   read_odometry, read_pose_array, read_pose_stamped,
                                   StatusData, TooManyPoses)
from formation_ros.ros.changes import Changes
from formation_ros.ros.diagnostics import encode_statuses, make_status, PERIOD
from formation_ros.ros.once import OnceLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.sim_clock import sim_time_without_clock, StateClock, wall_clock_overrides
from formation_ros.ros.team import announced, PublisherWatch
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray, PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
from numpy.typing import NDArray
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.timer import Timer
from trajectory_msgs.msg import MultiDOFJointTrajectory

Read = TypeVar('Read')
REFERENCE_BUFFER = 64
LAST_WORD = 0.5
"""How long a stopping robot waits for its last (zero) command to be received, s."""
RATE_TOLERANCE = 1e-3
SAME_REFERENCE = 1e-6
"""How far (m, m/s, 1, 1/s) a heard reference sample may be from the frame a robot evaluates
for its stamp (float rounding in the message is ~1e-15)."""
INPUTS = ('pose', 'neighbour', 'reference')
OTHER_IN_ROW = 2
"""A sample unlike the frame a robot evaluates may only be ahead of the change announced with
it (the callbacks of the two topics run in either order): it is refused and counted, and the
refusal logged once so many in a row differ."""
COPY_GAP_NS = 25_000_000
"""A copy of the state answered last that arrives sooner than this after the previous state is
a fast copy (the plant sends a state again 0.05 s after the last while it waits, and once more
when it starts its clock); more than FAST_COPIES of them in a row count as flooding."""
FAST_COPIES = 3
STALE_MARGIN_NS = 1_000_000
"""How long after the oldest input is due to turn stale the watchdog looks, ns."""
LISTENERS_PERIOD = 0.5
"""Team transport: seconds between looks at who subscribes to the robots' cmd_vel."""
LISTENER_LOOKS = 10
"""Team transport: robots of a process without a cmd_vel publisher looked up in the graph per
look, in turn (each lookup costs more as the graph grows): a subscriber to one of K robots'
cmd_vel gets data within ceil(K / LISTENER_LOOKS) + 1 looks of its discovery, 2 s in a fleet
of 25. A robot with a publisher is looked at every look (its matched subscribers: no graph)."""
TEAM_VALUES = ('num_robots', 'dim', 'world_frame', 'repulsion_radius', 'controller.gain',
               'controller.kappa', 'controller.psi', 'jump.kind', 'jump.order', 'body.kind',
               'body.hand_distance', 'command.type', 'command.frame', 'plant.lockstep',
               'transport')
"""Parameters the robots of one team link share: it computes their commands in one call (the
watchdog and input timeout are the leader's)."""
REFERENCE_VALUES = ('num_robots', 'dim', 'world_frame', 'repulsion_radius')
REFERENCE_PREFIXES = ('reference.', 'formation.', 'formations.')
"""Parameters that decide how a robot checks the reference's samples and the changes (with
every ``reference.*``, ``formation.*`` and ``formations.*``): a fleet's robot that has the
first robot's values hears the reference and the changes through it."""


def reference_values(config: FormationConfig) -> Dict[str, Any]:
    """Return the values of ``config`` that decide how the reference and changes are checked."""
    return {name: value for name, value in config.values.items()
            if name in REFERENCE_VALUES or name.startswith(REFERENCE_PREFIXES)}


class Reason(enum.Enum):
    """Why a robot ignores a message it heard."""

    NON_FINITE = 'non-finite values'
    FRAME = 'a frame other than world_frame'
    ORIENTATION = 'an orientation that is not a unit quaternion'

    CLOCK = 'stamps from another clock'
    TOO_MANY = 'more neighbours than there are robots'
    MALFORMED = 'bytes that are not a whole message of its type'
    TOO_FAST = 'a speed or turn rate its reference kind cannot have'
    OTHER_REFERENCE = ('a frame other than the one its reference parameters and the announced '
                       'changes give')
    CHANGE = 'a shape or team status that cannot hold'


class RobotNode(Node):
    """One robot: stores what it hears in callbacks, computes and publishes in its timers."""

    def __init__(self, leader: Optional['RobotNode'] = None, reports: bool = True,
                 **kwargs) -> None:
        """
        Declare and check parameters, then set up topics and the control timer.

        ``leader``: the first robot of this process (a fleet's other robots); this robot then
        hears the reference and the changes through it (one subscription per process), with
        ``transport: team`` always, else if it has the leader's :func:`reference_values`.
        ``reports``: whether this node publishes on /diagnostics itself; a fleet's other robots
        do not, its first robot publishes their statuses with its own (:attr:`reported`).
        """
        given = list(kwargs.pop('parameter_overrides', None) or [])
        super().__init__('robot', parameter_overrides=wall_clock_overrides(given), **kwargs)
        self.sim_time = sim_time_without_clock(self, given)
        config = declare_parameters(self, Exe.ROBOT)
        settings = config.robot
        assert settings is not None
        self.dim = config.dim
        self.index = settings.robot_id - 1
        self.vertex = config.vertices[self.index]
        self.base_reference = config.reference()
        self.config = config
        self.sensing_radius = float(config.sensing_radii[self.index])
        self.law = config.law()
        self.lockstep = config.lockstep
        self.timeout_ns = int(settings.input_timeout * NS_PER_S)
        self.num_robots = config.num_robots
        self.speed_limit, self.turn_limit = config.reference().rate_limits()
        self.unicycle = config.body.is_unicycle
        self.hand_distance = config.body.hand_distance
        self.world_frame = config.world_frame
        self.stamped = config.command.stamped
        self.body_frame = config.command.frame is CommandFrame.BODY
        self.needs_orientation = self.body_frame
        self.command_frame = (messages.body_frame(settings.robot_id) if self.body_frame
                              else self.world_frame)
        self.last_body_command: Optional[NDArray[np.float64]] = None
        self.evaluates = config.team_transport or self.sim_time
        """Whether this robot evaluates the reference at each state's stamp itself (the team
        transport, and simulated time: the reference node's time is then the plant's) and
        checks the samples against it; else it carries the newest sample to the stamp."""
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)

        self.pose: Optional[PoseData] = None
        self.neighbours: Optional[PoseArrayData] = None
        self.references: deque = deque(maxlen=REFERENCE_BUFFER)
        self.received_ns = dict.fromkeys(INPUTS)
        self.pose_count = 0
        self.answered_count = 0
        self.rejected: Dict[Tuple[str, Reason], int] = {}
        self.others_in_row = 0
        """Reference samples in a row unlike the frame this robot evaluates (OTHER_IN_ROW)."""
        self.last: Optional[Command] = None
        self.waiting = True
        self.wait_subscribers = settings.wait_for_subscribers
        period = settings.plant_period if self.sim_time else settings.relay_period
        self.budget = AnswerBudget(max(1, int(round(period * NS_PER_S))))
        self.answered_stamp: Optional[int] = None
        self.flooded = 0
        self.flooded_reported = 0
        self.flood_stamp: Optional[int] = None
        self.copy_arrived_ns = 0
        self.fast_copies = 0
        self.last_message: Optional[bytes] = None
        self.resent_ns = 0
        self.graph = PublisherWatch(self)
        self.shared: Dict[str, str] = {}
        self.team: Optional[TeamLink] = None
        """The team link this robot leads (team transport: the first robot of its process)."""
        self.member_of: Optional[TeamLink] = None

        self.clock: Optional[StateClock] = None
        """Robot transport: this node's simulated clock, set from its own poses' stamps."""
        if not config.team_transport:
            self._subscribe_to_states(settings.pose_type)
            self.clock = StateClock([self])
        self.expected_publishers: Dict[str, Optional[str]] = {}
        self.first: RobotNode = self
        """The robot that hears the reference and the changes for this one (or itself)."""
        self.followers: List[RobotNode] = []
        """The robots that hear the reference and the changes through this one."""
        if leader is not None and (config.team_transport or reference_values(config)
                                   == reference_values(leader.config)):
            self.first = leader
            leader.followers.append(self)
            self.changes = leader.changes
            self.references = leader.references
            self.expected_publishers = leader.expected_publishers
        else:
            reference = self.create_subscription(Odometry, topics.REFERENCE, self.on_reference,
                                                 qos.REFERENCE, raw=True)
            self.expected_publishers[reference.topic_name] = None
            if self.sim_time:
                self.expected_publishers[topics.CLOCK] = None
            self.changes = Changes(self, config, self.steady, self._reject_change,
                                   self._new_state)
        self.lazy_cmd_vel = config.team_transport and self.wait_subscribers <= 1
        """Team transport with only the plant awaited: this robot's ``cmd_vel`` publisher is
        made once a subscriber shows in the graph (:meth:`TeamLink.look_at_listeners`)."""
        self.cmd_pub: Optional[Publisher] = None if self.lazy_cmd_vel else self.make_cmd_pub()
        self.reported: List[RobotNode] = [self]
        """The robots whose statuses this node publishes (a fleet's first robot: all of its)."""
        self.announcing: Optional[Tuple[Shape, Dict[str, str]]] = None
        self.diagnostics_pub: Optional[Publisher] = None
        self.diagnostics_timer: Optional[Timer] = None
        if reports:
            self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS,
                                                         qos.DIAGNOSTICS)
            self.diagnostics_timer = self.create_timer(PERIOD, self.on_diagnostics,
                                                       clock=self.steady)
        self.answer = Wake(self, self.on_state, self.steady)
        self.watch_period_ns = max(1, int(round(NS_PER_S / settings.control_rate)))
        self.awaiting_neighbours = False
        self.watchdog: Optional[Wake] = None
        if not self.lockstep:
            self.watchdog = Wake(self, self.on_timer, self.steady)
            self.watchdog.arm(self.watch_period_ns / NS_PER_S)
        self.get_logger().info(
            f'robot {self.index + 1}/{config.num_robots}: vertex {np.round(self.vertex, 4)}, '
            f'R_i = {self.sensing_radius:g} m, b = {config.repulsion_radius:g} m, '
            f'bound c*M1 = {self.law.u_bound:.4g} m/s, '
            + (f'unicycle, hand point {self.hand_distance:g} m ahead, ' if self.unicycle
               else '')
            + f"commands as {'TwistStamped' if self.stamped else 'Twist'} in "
              f'{self.command_frame}, '

            + ('lockstep' if self.lockstep else f'{settings.control_rate:g} Hz')
            + (', team transport' if config.team_transport else '')
            + (", simulated time from the states' stamps" if self.sim_time else ''))

    def make_cmd_pub(self) -> Publisher:
        """Create this robot's ``cmd_vel`` publisher (a team robot's offers no lease)."""
        return self.create_publisher(TwistStamped if self.stamped else Twist, topics.CMD_VEL,
                                     qos.TEAM_CMD_VEL if self.config.team_transport
                                     else qos.COMMAND)

    def cmd_vel_pub(self) -> Publisher:
        """Return this robot's ``cmd_vel`` publisher where it is published to (made then)."""
        assert self.cmd_pub is not None
        return self.cmd_pub

    def _subscribe_to_states(self, pose_type: PoseType) -> None:
        """Robot transport: hear this robot's ``pose`` and ``neighbors``."""
        if pose_type is PoseType.ODOMETRY:
            self.create_subscription(Odometry, topics.POSE, self.on_odometry, qos.STATE_INPUT,
                                     raw=True)
        else:
            self.create_subscription(PoseStamped, topics.POSE, self.on_pose, qos.STATE_INPUT,
                                     raw=True)
        self.create_subscription(PoseArray, topics.NEIGHBOURS, self.on_neighbours,
                                 qos.STATE_INPUT, raw=True)

    @staticmethod
    def _now_ns() -> int:
        """Steady time, ns: the clock of the timers (CLOCK_MONOTONIC), read without rclpy."""
        return time.monotonic_ns()

    def _reject(self, name: str, reason: Reason, detail: str = '', log: bool = True) -> bool:
        """Count and (once per input and reason; not yet without ``log``) log a message ignored."""
        key = (name, reason)
        self.rejected[key] = self.rejected.get(key, 0) + 1
        if log:
            self.once.start(f'{name}-{reason.name}', f'ignoring {name} messages with '
                                                     f'{reason.value}{detail} (logged once; '
                                                     'diagnostics count them)', 'error')
        return False

    def _clock_gap_s(self, stamp_ns: int) -> float:
        """
        Return how far a stamp (ns) is from this node's clock, s.

        0 on simulated time before it starts, and while the states that set it have stopped
        (:meth:`_states_stopped`): the next state's stamp is then the time.
        """
        now = self.get_clock().now().nanoseconds
        gap_ns = stamp_ns - now
        if self.sim_time and (now == 0 or (abs(gap_ns) > self.timeout_ns
                                           and self._states_stopped())):
            return 0.0
        return gap_ns / NS_PER_S

    def _states_stopped(self) -> bool:
        """
        Whether this robot's clock is set from its states and none came within input_timeout.

        Then the next state sets the clock whichever way it jumps: a link cut for a while (the
        plant's time went on), a plant started again (its time begins at 0). While states
        come, one stamped more than input_timeout from their time is refused as stamped on
        another clock (a second team, a forged message).
        """
        clock = self.clock if self.team is None else self.team.clock
        if clock is None or not clock.clocks:
            return False
        heard = self.received_ns['pose']
        return heard is None or self._now_ns() - heard > self.timeout_ns

    def _check(self, name: str, frame_id: str, stamp_ns: int, finite: bool,
               oriented: bool = True) -> bool:
        """Accept a state message only in the world frame, finite, oriented, on this clock."""
        if frame_id != self.world_frame:
            return self._reject(name, Reason.FRAME, f' (got {frame_id!r}, expected '
                                                    f'{self.world_frame!r})')
        if not finite:
            return self._reject(name, Reason.NON_FINITE)
        if not oriented:
            return self._reject(name, Reason.ORIENTATION, ' (its heading is needed: '
                                                          + ('a unicycle' if self.unicycle
                                                             else 'command.frame body') + ')')
        gap = self._clock_gap_s(stamp_ns)
        if abs(gap) * NS_PER_S > self.timeout_ns:
            clock = 'simulated' if self.sim_time else 'wall-clock'
            advice = self._clock_advice(name, 'the robots and the reference')
            return self._reject(name, Reason.CLOCK, f' ({gap:+.3g} s from the {clock} time '
                                                    f'of this node: {advice})',
                                log=advice is not None)
        self.once.end(f'{name}-{Reason.CLOCK.name}', f'{name} messages on this clock again')
        return True

    def _clock_advice(self, name: str, nodes: str) -> Optional[str]:
        """
        Say what to do about stamps from another clock: the graph's answer, else use_sim_time.

        Two publishers of /clock or of the reference are two teams on one domain (looked up
        here only when the refusal is about to be logged). None while the graph has not yet
        named every one (``PublisherWatch.named_publishers``): the line waits for the names.
        """
        if self.once.is_active(f'{name}-{Reason.CLOCK.name}'):
            return ''
        now = time.monotonic()
        found = {topic: self.graph.named_publishers(topic, now)
                 for topic in self.expected_publishers}
        if any(names is None for names in found.values()):
            return None
        doubled = {topic: names for topic, names in found.items() if names}
        if doubled:
            return ('; '.join(f"{topic} has {len(names)} publishers ({', '.join(names)})"
                              for topic, names in doubled.items())
                    + ': two teams on one domain? each needs a ROS_DOMAIN_ID of its own')
        return f'start {nodes} with use_sim_time:=true'

    def _read(self, name: str, reader: Callable[[bytes], Read], data: bytes) -> Optional[Read]:
        """Return ``reader(data)``; None, counted and logged once, if the bytes do not fit it."""
        try:
            return reader(data)
        except TooManyPoses as exc:
            self._reject(name, Reason.TOO_MANY, f' ({exc})')
        except CdrError as exc:
            self._reject(name, Reason.MALFORMED, f' ({exc})')
        return None

    def on_pose(self, data: bytes) -> None:
        """Store the latest own pose, read from the serialized PoseStamped."""
        pose = self._read('pose', read_pose_stamped, data)
        if pose is not None:
            self._store_pose(pose)

    def on_odometry(self, data: bytes) -> None:
        """Store the latest own pose, read from a serialized nav_msgs/Odometry."""
        odometry = self._read('pose', read_odometry, data)
        if odometry is not None:
            self._store_pose(odometry.pose)

    def _store_pose(self, pose: PoseData) -> None:
        oriented = not self.needs_orientation or bool(valid_quaternions(pose.orientation))
        stopped = self._states_stopped()
        if self._check('pose', pose.frame_id, pose.stamp_ns, pose.finite, oriented):
            if self.clock is not None:
                self.clock.advance(pose.stamp_ns, jump=stopped)
            self.pose = pose
            self.pose_count += 1
            self.received_ns['pose'] = self._now_ns()
            if self._paired():
                self.awaiting_neighbours = False
                self.answer.arm()
            elif not self.lockstep:
                self.awaiting_neighbours = True
                self.answer.arm(self.watch_period_ns / NS_PER_S)

    def _read_neighbours(self, data: bytes) -> PoseArrayData:
        return read_pose_array(data, self.num_robots - 1)

    def on_neighbours(self, data: bytes) -> None:
        """Store the latest sensed neighbour positions, read from the serialized PoseArray."""
        heard = self._read('neighbour', self._read_neighbours, data)
        if heard is None:
            return
        finite = bool(np.all(np.isfinite(heard.positions))
                      and (not self.unicycle or np.all(np.isfinite(heard.orientations))))
        oriented = not self.unicycle or bool(np.all(valid_quaternions(heard.orientations)))
        if self._check('neighbour', heard.frame_id, heard.stamp_ns, finite, oriented):
            self.neighbours = heard
            self.received_ns['neighbour'] = self._now_ns()
            if self._paired():
                self.awaiting_neighbours = False
                self.answer.arm()

    def _paired(self) -> bool:
        """Whether the pose and the neighbours stored are of one state (same stamp)."""
        return (self.pose is not None and self.neighbours is not None
                and self.neighbours.stamp_ns == self.pose.stamp_ns)

    def on_reference(self, data: bytes) -> None:
        """Store a reference sample (a few are kept to match state stamps in lockstep)."""
        msg = self._read('reference', read_odometry, data)
        if msg is None:
            return
        if msg.frame_id != self.world_frame:
            self._reject('reference', Reason.FRAME, f' (got {msg.frame_id!r}, expected '
                                                    f'{self.world_frame!r})')
        elif not msg.finite:
            self._reject('reference', Reason.NON_FINITE)
        elif not self._plausible(msg) and not (self.changes.take() and self._plausible(msg)):
            self._reject('reference', Reason.TOO_FAST)
        elif self.evaluates and not self._same_reference(msg):
            self.others_in_row += 1
            self._reject('reference', Reason.OTHER_REFERENCE, ' (another parameters file or '
                                                              'reference.* on one of them?)',
                         log=self.others_in_row >= OTHER_IN_ROW)
        else:
            self.others_in_row = 0
            if self.evaluates:
                self.once.end(f'reference-{Reason.OTHER_REFERENCE.name}',
                              'the reference is the one this robot evaluates again')
            self.references.append(msg)
            now = self._now_ns()
            for node in [self] + self.followers:
                node.received_ns['reference'] = now
                if node.lockstep and (node.member_of is None or node.team is not None):
                    node.answer.arm()

    def _reject_change(self, what: str, why: str) -> None:
        """Count and log once a shape or status refused (``ros.changes``)."""
        key = (what, Reason.CHANGE)
        self.rejected[key] = self.rejected.get(key, 0) + 1
        self.once.start(f'{what}-refused',
                        f'ignoring a {what} with {why} (logged once; diagnostics count them)',
                        'error')

    def _new_state(self, state: TeamState) -> None:
        """Accept reference samples as fast as the reference in force may be."""
        speed, turn = state.reference(self.base_reference).rate_limits()
        self.speed_limit = max(self.speed_limit, speed)
        self.turn_limit = max(self.turn_limit, turn)

    def _plausible(self, msg: OdometryData) -> bool:
        """Whether a reference sample's speed and turn rate fit the configured reference."""
        speed = math.hypot(*msg.linear)
        turn = math.hypot(*msg.angular)
        return (speed <= self.speed_limit * (1.0 + RATE_TOLERANCE) + RATE_TOLERANCE
                and turn <= self.turn_limit * (1.0 + RATE_TOLERANCE) + RATE_TOLERANCE)

    def _same_reference(self, msg: OdometryData) -> bool:
        """
        Whether a sample is the frame this robot evaluates for its stamp (:attr:`evaluates`).

        A sample far from this node's clock is let through (the states' clock check refuses
        it where it is used); a mismatch is looked at again after taking changes not yet taken.
        """
        if abs(self._clock_gap_s(msg.stamp_ns)) * NS_PER_S > self.timeout_ns:
            return True
        heard = msg.frame(self.dim)

        def close() -> bool:
            mine = self.changes.reference.frame_at(msg.stamp_ns)
            return all(bool(np.all(np.abs(a - b) <= SAME_REFERENCE))
                       for a, b in ((mine.q_od, heard.q_od), (mine.qdot_od, heard.qdot_od),
                                    (mine.J, heard.J), (mine.Jdot, heard.Jdot)))

        return close() or (bool(self.changes.take()) and close())

    def _reference_for(self, stamp_ns: int, exact: bool) -> Optional[FrameSample]:
        """
        Return the reference frame at ``stamp_ns``: that sample, else the newest carried on.

        Where this robot :attr:`evaluates` the reference: the frame at ``stamp_ns`` from the
        reference's parameters and the changes announced (``ReferenceTimeline.frame_at``, what
        the reference node publishes), once a sample of that stamp (``exact``: lockstep) or a
        recent sample on the states' clock shows the reference node runs on this team's time.
        """
        for msg in reversed(self.references):
            if msg.stamp_ns == stamp_ns:
                return (self.changes.reference.frame_at(stamp_ns) if self.evaluates
                        else msg.frame(self.dim))
        if exact or not self.references:
            return None
        newest = self.references[-1]
        ahead = (stamp_ns - newest.stamp_ns) / NS_PER_S
        if abs(ahead) * NS_PER_S > self.timeout_ns:
            advice = self._clock_advice('reference', 'the reference')
            self._reject('reference', Reason.CLOCK, f' ({-ahead:+.3g} s from the state: '
                                                    f'{advice})', log=advice is not None)
            return None
        self.once.end(f'reference-{Reason.CLOCK.name}', 'reference on the clock of the states')
        if self.evaluates:
            return self.changes.reference.frame_at(stamp_ns)
        return advance(newest.frame(self.dim), ahead)

    def _command(self, stamp_ns: int, exact: bool) -> Optional[np.ndarray]:
        """Return the command for the state stamped ``stamp_ns`` (zero while stopped), or None."""
        frame = self._reference_for(stamp_ns, exact)
        if frame is None:
            return None
        if self.changes.differs:
            self.once.start('other-shape', "following the reference's shape: it differs from "
                                           "this robot's formation.vertices (another "
                                           'parameters file?)', 'warning')
        if self.changes.states.at(stamp_ns).mode is Mode.STOPPED:
            self.once.start('stopped', 'team stopped: holding still', 'info')
            width = 2 if self.unicycle else self.dim
            return np.zeros(width if self.team is None else (len(self.team.nodes), width))
        self.once.end('stopped', 'team running again')
        if self.team is not None:
            return self.team.commands(stamp_ns, frame)
        self.vertex = self.changes.shapes.at(stamp_ns).vertices[self.index]
        self.last = robot_command(self._own_position(), self.vertex, self._neighbour_points(),
                                  self.sensing_radius, self.law, frame)
        if self.unicycle:
            self.last_body_command = unicycle_commands(self.last.u, self._own_heading(),
                                                       self.hand_distance)
        elif self.body_frame:
            assert self.pose is not None
            self.last_body_command = to_body_frame(self.last.u[None, :],
                                                   np.array([self.pose.orientation]))[0]
        else:
            return self.last.u
        return self.last_body_command

    def _own_heading(self) -> float:
        assert self.pose is not None
        return float(headings_from_quaternions(self.pose.orientation))

    def _own_position(self) -> NDArray[np.float64]:
        """Return the point the law acts on: own position, or own hand point (unicycles)."""
        assert self.pose is not None
        position = np.array(self.pose.position[:self.dim])
        if self.unicycle:
            return hand_points(position, self._own_heading(), self.hand_distance)
        return position

    def _neighbour_points(self) -> NDArray[np.float64]:
        """Return the neighbours' positions, or their hand points (unicycles): (K, dim)."""
        assert self.neighbours is not None
        positions = self.neighbours.positions[:, :self.dim]
        if self.unicycle:
            return hand_points(positions, headings_from_quaternions(self.neighbours.orientations),
                               self.hand_distance)
        return positions

    def _publish_command(self, u: Optional[NDArray[np.float64]], stamp_ns: int) -> None:
        """
        Publish a command answering the state stamped ``stamp_ns`` (None: zero).

        u: (dim,) m/s in the world frame or (``command.frame: body``) the body frame, or for a
        unicycle (v, w) in its body frame; as a TwistStamped in ``command_frame`` stamped
        ``stamp_ns``, or a Twist (``command.type: twist``). Team transport: u (K, width) of
        every robot of the link, as one team command (:meth:`TeamLink.publish`).
        """
        if self.team is not None:
            self.last_message = self.team.publish(u, stamp_ns)
            return
        if self.unicycle:
            v, w = (0.0, 0.0) if u is None else (float(u[0]), float(u[1]))
            linear, angular = (v, 0.0, 0.0), (0.0, 0.0, w)
        else:
            linear, angular = (np.zeros(self.dim) if u is None else u), (0.0, 0.0, 0.0)
        if self.stamped:
            message = encode_twist_stamped(stamp_ns, self.command_frame, linear, angular)
        else:
            message = encode_twist(linear, angular)
        self.cmd_vel_pub().publish(message)
        self.last_message = message

    def on_state(self) -> None:
        """
        Answer a state as soon as its pose and neighbours are both in (armed by the callbacks).

        In lockstep the reference sample of the state's stamp is needed too; otherwise the
        newest sample is carried forward to the state's time. A pose whose neighbours have not
        arrived one watchdog period (``control_rate``) after it (best effort: lost) is answered
        then with the latest neighbours.
        """
        if self.member_of is not None and self.team is None:
            return
        if self.team is not None:
            self.team.take()
        if self.lockstep:
            self._lockstep_answer()
        elif self._paired() or (self.awaiting_neighbours and self.neighbours is not None):
            self.awaiting_neighbours = False
            self._answer_newest()

    def on_timer(self) -> None:
        """
        Watchdog: zero when an input is stale, else answer a state left over; then re-armed.

        A one-shot timer, not a free-running one: it looks again one period of
        ``control_rate`` on while the robot waits for its first inputs, while its inputs are
        stale (it publishes zero at that rate) and while a state is left unanswered, else
        only when the oldest input is due to turn stale (states arriving keep it away). A look
        that finds no new pose since the last answer publishes nothing: the plant holds the
        last command until it is ``plant.input_timeout`` old.
        """
        if self.member_of is not None and self.team is None:
            return
        self._answer_newest()
        self._arm_watchdog()

    def _arm_watchdog(self) -> None:
        """Arm the watchdog for its next look (see :meth:`on_timer`)."""
        if self.watchdog is None:
            return
        delay_ns = self.watch_period_ns
        if not (self.waiting or self.once.is_active('stale')
                or self.pose_count != self.answered_count):
            oldest = min(ns for ns in self.received_ns.values() if ns is not None)
            delay_ns = max(delay_ns, oldest + self.timeout_ns + STALE_MARGIN_NS - self._now_ns())
        self.watchdog.arm(delay_ns / NS_PER_S)

    def _answer_newest(self) -> None:
        """Answer the newest state once: compute and publish its command (zero if stale)."""
        if self.waiting and not self._ready():
            return
        now = self._now_ns()
        stale = [name for name in INPUTS if self.received_ns[name] is None
                 or now - self.received_ns[name] > self.timeout_ns]
        if stale:
            self._publish_command(None, self.pose.stamp_ns)
            self.once.start('stale', f"no new {', '.join(stale)} for "
                                     f'{self.timeout_ns / NS_PER_S:g} s: publishing zero')
            return
        self.once.end('stale', 'inputs fresh again: controlling')
        if self.pose_count == self.answered_count:
            return
        stamp = self.pose.stamp_ns
        if not self._may_answer(stamp):
            if self.pose_count != self.answered_count:
                self._arm_watchdog()
            return
        self._publish_command(self._command(stamp, False), stamp)
        self.answered_count = self.pose_count
        self.answered_stamp = stamp

    def _may_answer(self, stamp: int) -> bool:
        """
        Whether the state stamped ``stamp`` is answered: a new one, within the answer budget.

        A copy of the state answered last is not computed again: the plant sends one when it
        has not heard the answer (which went, say, only to a recorder that subscribed first),
        so the answer already sent is sent again, at most once per state period (steady clock)
        whatever the copies' rate; more than FAST_COPIES copies in a row, each within
        COPY_GAP_NS of the one before, count as flooding. A new state beyond the budget counts
        as flooding.
        """
        now = self._now_ns()
        if stamp == self.answered_stamp:
            fast = now - self.copy_arrived_ns < COPY_GAP_NS
            self.fast_copies = self.fast_copies + 1 if fast else 0
            if self.fast_copies > FAST_COPIES:
                self._flooding(stamp)
            elif (self.last_message is not None
                  and now - self.resent_ns >= max(COPY_GAP_NS, self.budget.period_ns)):
                if self.team is None:
                    self.cmd_vel_pub().publish(self.last_message)
                else:
                    self.team.resend()
                self.resent_ns = now
            self.copy_arrived_ns = now
            self.answered_count = self.pose_count
            return False
        self.copy_arrived_ns = now
        if self.budget.take(self.get_clock().now().nanoseconds):
            return True
        if stamp != self.flood_stamp:
            self._flooding(stamp)
        return False

    def _flooding(self, stamp: int) -> None:
        self.flooded += 1
        self.flood_stamp = stamp
        period = self.budget.period_ns / NS_PER_S
        self.once.start('flooding', f'states arrive faster than one per {period:.3g} s (the '
                                    "plant's or relay's period): answering at most about one "
                                    'per period, the others are dropped (logged once; '
                                    'counted in diagnostics)', 'warning')

    def _ready(self) -> bool:
        """Start-up: every input heard once and cmd_vel has its subscribers (plant, recorder)."""
        never = [name for name in INPUTS if self.received_ns[name] is None]
        listeners = (self.cmd_vel_pub().get_subscription_count() if self.team is None
                     else self.team.listeners())
        if never or listeners < self.wait_subscribers:
            what = 'cmd_vel' if self.team is None else 'command (team topic and cmd_vel)'
            missing = never + ([f'{self.wait_subscribers} {what} subscribers (have '
                                f'{listeners})'] if listeners < self.wait_subscribers else [])
            self.once.start('waiting', f"waiting for {', '.join(missing)}", 'info')
            return False
        self.once.end('waiting')
        self.waiting = False
        if self.team is not None:
            self.team.look_at_listeners()
        return True

    def _lockstep_answer(self) -> None:
        """Answer each state the plant sends, once, with the reference sample of its stamp."""
        if self.pose is None or self.neighbours is None or self.pose_count == self.answered_count:
            return
        if self.waiting and not self._ready():
            return
        stamp = self.pose.stamp_ns
        if self.neighbours.stamp_ns != stamp:
            return
        if stamp != self.answered_stamp and self._reference_for(stamp, True) is None:
            return
        if not self._may_answer(stamp):
            return
        command = self._command(stamp, True)
        assert command is not None
        self._publish_command(command, stamp)
        self.answered_count = self.pose_count
        self.answered_stamp = stamp

    def finish(self) -> None:
        """
        On a clean stop, command zero, so that a base without a command timeout stops too.

        The zero answers the latest state (a base that drops old stamps still takes it), and
        the node waits up to :data:`LAST_WORD` s for its subscribers to have it.
        """
        if (self.pose is None or not rclpy.ok(context=self.context)
                or (self.member_of is not None and self.team is None)):
            return
        self._publish_command(None, self.pose.stamp_ns)
        (self.cmd_vel_pub() if self.team is None else self.team.pub).wait_for_all_acked(
            Duration(seconds=LAST_WORD))

    def on_diagnostics(self) -> None:
        """Publish one DiagnosticArray with the status of each robot this node reports."""
        if self.diagnostics_pub is not None:
            self.diagnostics_pub.publish(
                encode_statuses([node.status() for node in self.reported]))

    def _announcement(self, stamp_ns: int) -> Dict[str, str]:
        """Return the team values and identity this robot announces, made again on a new shape."""
        shape = self.changes.shapes.at(stamp_ns)
        if self.announcing is None or self.announcing[0] is not shape:
            self.announcing = (shape, announced(team_values(self.config, shape.vertices), self))
        return self.announcing[1]

    def status(self) -> StatusData:
        """
        Return this robot's status: input ages, neighbours in range, command size.

        Team transport: what the robot's link last gave it, and the link's state (waiting,
        stale, flooding, the look at who publishes /clock and the reference: its leader's,
        whose status comes first in its process's array).
        """
        if self.member_of is not None:
            self.member_of.give(self)
        leader = self if self.member_of is None else self.member_of.leader
        now = self._now_ns()
        values = {f'{name} message age [s]': ('never' if self.received_ns[name] is None
                                              else (now - self.received_ns[name]) / NS_PER_S)
                  for name in INPUTS}
        if self.neighbours is not None and self.pose is not None:
            gaps = np.linalg.norm(self._neighbour_points() - self._own_position(), axis=1)
            values['neighbours heard'] = len(gaps)
            values['neighbours within R_i'] = int(np.count_nonzero(gaps < self.sensing_radius))
            values['neighbours within b'] = int(np.count_nonzero(gaps < self.law.repulsion_radius))
        if self.last is not None:
            values['max |u| component [m/s]'] = float(np.max(np.abs(self.last.u)))
            values['max |u_hat| component [m/s]'] = float(np.max(np.abs(self.last.u_hat)))
        values['bound c*M1 [m/s]'] = self.law.u_bound
        now = self.pose.stamp_ns if self.pose is not None else 0
        values.update(self._announcement(now))
        if self.last_body_command is not None and self.unicycle:
            values['|v| [m/s]'] = abs(float(self.last_body_command[0]))
            values['|w| [rad/s]'] = abs(float(self.last_body_command[1]))
        elif self.last_body_command is not None:
            values['max |u| component in the body frame [m/s]'] = float(
                np.max(np.abs(self.last_body_command)))
        values.update({f'rejected {name} messages ({reason.value})': count
                       for (name, reason), count in self.rejected.items()})
        values['states not answered (flooding)'] = leader.flooded
        if self.member_of is not None:
            values['cmd_vel published'] = self.member_of.publishes_cmd_vel(self)
        flooding = leader.flooded > self.flooded_reported
        self.flooded_reported = leader.flooded
        shared = self._shared_topics() if self.first is self else self.first.shared
        if shared:
            values['topics with more than one publisher'] = ' | '.join(
                f'{topic}: {names}' for topic, names in sorted(shared.items()))
            level, message = 'error', (f"{', '.join(sorted(shared))}: more than one publisher "
                                       '(two teams on one domain?)')
        elif leader.waiting:
            level, message = 'warn', 'waiting for its first inputs'
        elif leader.once.is_active('stale'):
            level, message = 'warn', 'publishing zero: inputs stale'
        elif flooding:
            level, message = 'warn', 'flooding: states beyond the state rate dropped'
        else:
            level, message = 'ok', 'lockstep' if self.lockstep else 'controlling'
        return make_status(f'formation_ros/robot_{self.index + 1}', level, message, values)

    def _shared_topics(self) -> Dict[str, str]:
        """Return {topic: its publishers} of /clock and the reference with several; log once."""
        shared = self.graph.check(self.expected_publishers, time.monotonic())
        self.once.follow('publishers', {topic: f'{topic} has more than one publisher: {names} '
                                               '(two teams on one domain? each needs a '
                                               'ROS_DOMAIN_ID of its own)'
                                        for topic, names in shared.items()},
                         self.shared, lambda topic: f'{topic} has one publisher again')
        self.shared = shared
        return shared


class TeamLink:
    """
    The team transport of one robot process or fleet: its robots' states in, their commands out.

    One subscription to ``/formation/states`` and one publisher on ``/formation/commands``, on
    the first robot node (the leader), for all robots of the process. The callback stores the
    bytes and wakes the leader, whose timer (:meth:`RobotNode.on_state`) reads and checks the
    state (:meth:`take`), senses each robot's neighbours within its R_i with the plant's
    sensing function (``core.sensing.sensed_pairs``), gives the leader its pose and neighbours
    (each other robot node gets its own when it reports them: :meth:`give`), and answers the
    state as a robot answers one (the leader's answer budget, watchdog and lockstep rules):
    every robot's command from one call of the law (``core.law.robot_commands``,
    :meth:`commands`), in one team command message (:meth:`publish`). Robot i's own
    ``cmd_vel`` carries its command too while something subscribes to it
    (:meth:`look_at_listeners`). The reference frame
    is evaluated in the process for each state's stamp (:meth:`RobotNode._reference_for`); the
    leader alone hears the reference node (its samples checked: on this clock, plausible, the
    frame evaluated here) and the changes. The nodes' simulated clocks follow the states'
    stamps (``ros.sim_clock.StateClock``): no ``/clock`` subscription. Each robot stays its own
    node: namespace, parameters, diagnostics.
    """

    def __init__(self, nodes: Sequence[RobotNode]) -> None:
        """
        Link ``nodes`` (team transport, sharing :data:`TEAM_VALUES`; ParamError if not).

        The first is the leader; the rows of the link's arrays are the robots in id order.
        """
        leader = self.leader = nodes[0]
        self.nodes = sorted(nodes, key=lambda node: node.index)
        config = leader.config
        differing = [name for name in TEAM_VALUES for node in self.nodes[1:]
                     if node.config.values.get(name) != config.values.get(name)]
        if differing:
            raise ParamError([(differing[0], 'must be the same for every robot of a process '
                                             'with transport team (one call of the law '
                                             'computes their commands)')])
        self.n, self.dim = config.num_robots, config.dim
        self.unicycle, self.body_frame = leader.unicycle, leader.body_frame
        self.width = 2 if self.unicycle else self.dim
        self.indices = np.array([node.index for node in self.nodes], dtype=np.intp)
        self.radii = np.array([node.sensing_radius for node in self.nodes])
        self.reach = np.zeros(self.n)
        self.reach[self.indices] = sensor_radii(self.radii,
                                                make_bodies(config.body).sensing_margin)
        self.local = np.full(self.n, -1, dtype=np.intp)
        self.local[self.indices] = np.arange(len(self.nodes))
        self.names = encode_names([robot_name(int(i) + 1) for i in self.indices])
        self.heard: Optional[bytes] = None
        self.taken: Optional[bytes] = None
        """The bytes of the state taken last: a copy of them is not read and sensed again."""
        self.state: Optional[PoseArrayData] = None
        self.taken_ns = 0
        self.bounds = np.zeros(len(self.nodes) + 1, dtype=np.intp)
        self.command: Optional[Command] = None
        self.body: Optional[NDArray[np.float64]] = None
        self.vertices = np.zeros((len(self.nodes), self.dim))
        self.points = np.zeros((self.n, self.dim))
        self.headings = np.zeros(self.n)
        self.orientations = np.zeros((self.n, 4))
        self.observer = np.zeros(0, dtype=np.intp)
        self.seen = np.zeros(0, dtype=np.intp)
        self.listening = np.zeros(len(self.nodes), dtype=bool)
        self.turns = Turns(LISTENER_LOOKS)
        self.last_sent: Optional[bytes] = None
        self.sent: List[Tuple[RobotNode, bytes]] = []
        """The cmd_vel messages that went with the latest team command, by robot."""
        for node in self.nodes:
            node.member_of = self
        leader.team = self
        self.clock = StateClock(self.nodes)
        self.pub = leader.create_publisher(MultiDOFJointTrajectory, topics.TEAM_COMMANDS,
                                           qos.COMMAND)
        leader.create_subscription(PoseArray, topics.STATES, self.on_states, qos.STATE_INPUT,
                                   raw=True)
        self.listeners_timer = leader.create_timer(LISTENERS_PERIOD, self.look_at_listeners,
                                                   clock=leader.steady)

    def on_states(self, data: bytes) -> None:
        """Store the latest team state's bytes and wake the leader."""
        self.heard = data
        self.leader.answer.arm()

    def look_at_listeners(self) -> None:
        """
        Note which robots' cmd_vel someone subscribes to (published only then).

        A robot without a publisher (``RobotNode.lazy_cmd_vel``) gets one when its turn
        (LISTENER_LOOKS robots a look) finds a subscriber in the graph; it is published to
        from the look after, once the subscriber has matched it.
        """
        lazy = [k for k in self.turns.due(len(self.nodes)) if self.nodes[k].cmd_pub is None]
        for k in lazy:
            node = self.nodes[k]
            if node.count_subscribers(topics.CMD_VEL) > 0:
                node.cmd_pub = node.make_cmd_pub()
        self.listening = np.array([node.cmd_pub is not None
                                   and node.cmd_pub.get_subscription_count() > 0
                                   for node in self.nodes], dtype=bool)

    def publishes_cmd_vel(self, node: RobotNode) -> str:
        """Return 'yes' while robot ``node``'s own cmd_vel is published (someone listens)."""
        return 'yes' if self.listening[self.local[node.index]] else 'no'

    def listeners(self) -> int:
        """
        Return the command subscribers every robot has: team topic plus its fewest cmd_vel.

        Those of the team topic alone with lazy cmd_vel publishers (only the plant awaited).
        """
        return self.pub.get_subscription_count() + min(
            0 if node.cmd_pub is None else node.cmd_pub.get_subscription_count()
            for node in self.nodes)

    def take(self) -> None:
        """
        Read the team state heard (if any), check it as a robot checks a pose, sense, store.

        A state must hold exactly ``num_robots`` finite poses (and unit quaternions where the
        headings are needed) in ``world_frame``, on this node's clock; others are counted and
        logged once in the leader's diagnostics (``rejected states messages``). A copy of the
        state taken last (the plant sends one again while it waits for answers: 20 a second
        while a thousand robots start) is not read again: it is heard anew, and answered as a
        copy is (:meth:`RobotNode._may_answer`).
        """
        data, self.heard = self.heard, None
        if data is None or (data != self.taken and not self._sense(data)):
            return
        self.taken, self.taken_ns = data, self.leader._now_ns()
        self.give(self.leader)
        self.leader.pose_count += 1

    def _sense(self, data: bytes) -> bool:
        """Read and check a new state's bytes, set the clocks, sense; False if refused."""
        leader = self.leader
        state = leader._read('states', lambda raw: read_pose_array(raw, self.n), data)
        if state is None:
            return False
        if len(state.positions) != self.n:
            leader._reject('states', Reason.MALFORMED, f' ({len(state.positions)} poses for '
                                                       f'{self.n} robots)')
            return False
        positions, orientations = state.positions[:, :self.dim], state.orientations
        needs_orientation = self.unicycle or self.body_frame
        finite = bool(np.all(np.isfinite(positions))
                      and (not needs_orientation or np.all(np.isfinite(orientations))))
        oriented = not needs_orientation or bool(np.all(valid_quaternions(orientations)))
        stopped = leader._states_stopped()
        if not leader._check('states', state.frame_id, state.stamp_ns, finite, oriented):
            return False
        self.clock.advance(state.stamp_ns, jump=stopped)
        observer, self.seen = sensed_pairs(positions, self.reach, observers=self.indices)
        self.observer = self.local[observer]
        if self.unicycle:
            self.headings = headings_from_quaternions(orientations)
            self.points = hand_points(positions, self.headings, leader.hand_distance)
        else:
            self.points = positions
        self.orientations = orientations
        self.bounds = np.searchsorted(self.observer, np.arange(len(self.nodes) + 1))
        self.state = state
        return True

    def give(self, node: RobotNode) -> None:
        """
        Give robot ``node`` what it would have heard and computed, as of the state taken last.

        Its pose and neighbours in that state and its latest command: what its diagnostics
        report (and the leader's answers use).
        """
        state = self.state
        if state is None:
            return
        k = int(self.local[node.index])
        seen = self.seen[self.bounds[k]:self.bounds[k + 1]]
        node.pose = PoseData(state.stamp_ns, state.frame_id,
                             tuple(state.positions[node.index].tolist()),
                             tuple(state.orientations[node.index].tolist()))
        node.neighbours = PoseArrayData(state.stamp_ns, state.frame_id, state.positions[seen],
                                        state.orientations[seen])
        node.received_ns['pose'] = node.received_ns['neighbour'] = self.taken_ns
        if self.command is not None:
            node.vertex = self.vertices[k]
            node.last = Command(u=self.command.u[k], u_hat=self.command.u_hat[k],
                                omega=self.command.omega[k])
            node.last_body_command = None if self.body is None else self.body[k]

    def commands(self, stamp_ns: int, frame: FrameSample) -> NDArray[np.float64]:
        """
        Return every robot's command for the state taken: (K, width), in their command frames.

        u of eqs. (14), (25) from ``core.law.robot_commands`` (what each robot's
        ``robot_command`` gives), then (v, w) for unicycles or the body frame's u.
        """
        leader = self.leader
        self.vertices = leader.changes.shapes.at(stamp_ns).vertices[self.indices]
        command = robot_commands(self.points[self.indices], self.vertices, self.observer,
                                 self.points[self.seen], self.radii, leader.law, frame)
        if self.unicycle:
            body: Optional[NDArray[np.float64]] = unicycle_commands(
                command.u, self.headings[self.indices], leader.hand_distance)
        elif self.body_frame:
            body = to_body_frame(command.u, self.orientations[self.indices])
        else:
            body = None
        self.command, self.body = command, body
        return command.u if body is None else body

    def publish(self, u: Optional[NDArray[np.float64]], stamp_ns: int) -> bytes:
        """
        Publish one team command answering the state ``stamp_ns``: u (K, width), None for zero.

        Robot i's own cmd_vel carries its row too while someone subscribes to it. Returns the
        team message's bytes.
        """
        if u is None:
            u = np.zeros((len(self.nodes), self.width))
        linear, angular = command_vectors(u, self.unicycle)
        message = encode_team_commands(stamp_ns, self.leader.world_frame, self.names, linear,
                                       angular)
        self.pub.publish(message)
        self.sent = [(self.nodes[k], encode_twist_stamped(stamp_ns, self.nodes[k].command_frame,
                                                          linear[k], angular[k])
                      if self.nodes[k].stamped else encode_twist(linear[k], angular[k]))
                     for k in np.flatnonzero(self.listening).tolist()]
        for node, own in self.sent:
            node.cmd_vel_pub().publish(own)
        self.last_sent = message
        return message

    def resend(self) -> None:
        """Publish the latest team command again, and each listened robot's cmd_vel with it."""
        if self.last_sent is None:
            return
        self.pub.publish(self.last_sent)
        for node, own in self.sent:
            node.cmd_vel_pub().publish(own)


def make_robot() -> RobotNode:
    """Build the robot node, linked to the team topics with ``transport: team``."""
    node = RobotNode()
    if node.config.team_transport:
        TeamLink([node])
    return node


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros robot``."""
    return run(make_robot, args, name='robot')
