# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Plant node (executable ``plant``): the robots' bodies and range sensors on the ROS graph.

The physics is :class:`formation_ros.core.plant.PlantModel`, the same model ``formation_sim
--dt`` steps: q_i' = u_i (eq. 1) with zero-order hold at ``plant.rate`` (simulated time),
command admission (a missing, non-finite or stale command counts as zero), the bound audit and
the collision check. This node only moves messages in and out:

* it stores each robot's latest ``robot_<i>/cmd_vel`` in its callback: a TwistStamped in the
  robot's command frame (``world_frame``; ``robot_<i>/base_link`` for unicycles and
  ``command.frame: body``), or with ``command.type: twist`` a Twist, taken to answer the latest
  state published; it is the stand-in for every base the robots can drive;
* its timer steps the model and publishes ``robot_<i>/pose`` (PoseStamped) and
  ``robot_<i>/neighbors`` (PoseArray: what robot i's range sensor sees), in ``world_frame``, at
  ``plant.publish_rate``, each time after ``/clock`` (the simulated time, from 0): the clock
  advances with the states, so nodes on simulated time wake once per state, not per step;
* it logs what the model reports (once per condition), publishes ``/diagnostics`` and
  ``/formation/markers``, and with ``plant.output_dir`` writes ``trajectory.npz`` and
  ``plant_stats.json`` when it stops. Its output is not what it is for: when a write there
  fails (a full disk) it says so in one line, keeps what was written (whole trajectory chunks,
  which ``formation_report`` reads), writes nothing more and goes on controlling.

With ``plant.lockstep`` it steps only when every robot has answered the latest state, which
makes a run reproduce ``formation_sim --dt 1/plant.rate``.

With ``transport: team`` (``core.transport``) it publishes each state once for every robot on
``/formation/states`` and reads the commands from ``/formation/commands`` (one message per robot
process or fleet, bytes checked before any element is read, malformed ones counted and dropped),
admitted as every ``cmd_vel`` is; robot i's ``pose`` and ``neighbors`` are published only while
someone subscribes to them, and ``cmd_vel`` is not subscribed to. Which robots are gone it tells
from when their latest command arrived.

One team per domain: before its first state the plant looks for :data:`LOOK_TIME` s (up to
:data:`LOOK_LIMIT` s to hear the other's host) for another ``/clock`` publisher. If there is
one, another plant or anything else, that sends ``/clock`` or announces itself on
``/diagnostics`` from another process, the plant refuses to start: one line naming it and its
host, exit 2. A silent one with the plant's own name is taken for a killed plant's leftover (DDS
forgets it within about 20 s): said once, and the plant starts. Until its first step (while
its clock waits for the robots) it goes on looking every :data:`LOOK_PERIOD` s, since discovery
on a busy machine can take longer than the look. While running, it looks up the
graph once a second (:class:`formation_ros.ros.team.PublisherWatch`) for a second publisher on
``/clock``, a robot's ``pose``, ``neighbors`` or ``cmd_vel``: ERROR in ``/diagnostics`` and
one log line per topic, naming the other publisher.

Unicycles (``body.kind: unicycle``): each pose carries the robot's heading as its orientation,
and so does every neighbour in ``neighbors``, which lists the bodies within R_i + 2 l (so that a
robot sees every hand point within R_i of its own); a command is read in the robot's body frame
(``robot_<i>/base_link``: linear.x = v, angular.z = w, as diff_drive_controller takes it) and
admitted by the model like any other.
"""

from collections import OrderedDict
from dataclasses import replace
import json
import os
import shutil
import time
from typing import Any, Dict, List, Optional, Set

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.bodies import make_bodies
from formation_ros.core.declarations import CommandFrame, Exe
from formation_ros.core.events import event_records, timeline_events
from formation_ros.core.exits import REFUSED
from formation_ros.core.frames import desired_positions
from formation_ros.core.plant import (Commands, CommandStatus, DurationHistogram,
                                      PLANT_STATS_FILE, PlantModel, StepReport)
from formation_ros.core.team import team_values
from formation_ros.core.timeline import Mode
from formation_ros.core.trajectory import (CHUNKS_DIR, ChunkWriter, read_body_chunks,
                                           read_chunks, save_atomically, Trajectory,
                                           TRAJECTORY_FILE)
from formation_ros.core.transport import commands_of
from formation_ros.core.turns import Turns
from formation_ros.core.units import NS_PER_S
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import (CdrError, encode_clock, read_twist, read_twist_stamped,
                                   StateEncoder, TeamCommandReader)
from formation_ros.ros.changes import Changes
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.liveliness import PeerLiveliness
from formation_ros.ros.markers import formation_markers, Paths
from formation_ros.ros.once import OnceLog, robots_named
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.team import announced, PublisherWatch, team_problems, TeamCheck
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray, PoseStamped, Twist, TwistStamped
import numpy as np
from numpy.typing import NDArray
from rclpy.clock import Clock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.publisher import Publisher
from rosgraph_msgs.msg import Clock as ClockMsg
from trajectory_msgs.msg import MultiDOFJointTrajectory
from visualization_msgs.msg import MarkerArray

PLANT_STATUS = 'formation_ros/plant'
RESEND_AFTER = 0.05
PUBLISHES_TIMED = 256
"""States whose first publish time is kept for the answer latency; answers to older states are
not timed."""
GRAPH_LOOKS = 100
"""Topics looked up in the graph per diagnostics period for a second publisher (of 3N + 2,
in turn: ``ros.team.PublisherWatch``)."""
PATH_LENGTH = 100
CHUNK_PERIOD = 1.0
LOOK_TIME = 2.0
"""How long the plant looks for another /clock publisher before its first state, s (steady
clock). Fast DDS finds a participant on this host within its five initial announcements
(0.1 s apart) and its endpoints a moment later; a running plant sends /clock at least every
0.05 s and its status every second (diagnostics.PERIOD), so 2 s leave room for a busy machine
at no cost: the robots take longer than that to start."""
LOOK_LIMIT = 5.0
"""With another /clock publisher found, how long the plant waits to hear its host on
/diagnostics before refusing without it, s."""
LOOK_PERIOD = 0.5
"""Seconds between looks at the graph while the clock waits for the robots."""
REFUSAL_HEARD = 2.0
"""How long a refusing plant waits for its last status to be acknowledged, s."""
CLOCK_MATCH_WAIT = 5.0
"""Once every robot is up, how long the clock waits at most for each /clock subscriber the
graph shows (the reference node) to be matched to its publisher, s: one not yet matched when
the clock starts stamps its samples on the old time for as long as discovery takes (seen:
1.3 s on a busy machine, the robots refusing the samples meanwhile). One that never matches
(a subscriber asking for a QoS /clock does not offer) does not hold the team for ever."""
FRESH_PERIODS = 2
"""A command is fresh (diagnostics' ``steps with fresh commands``) while the state it answers
is at most this many state periods old (as bench_capacity's fresh share)."""
LISTENERS_PERIOD = 0.5
"""Team transport: seconds between looks at who subscribes to each robot's pose and neighbors
(published only while someone does)."""
DOUBLED_WITHIN = 1.5
"""Team transport: two processes that announced one robot node within this many seconds (their
statuses come once a second) both run it."""
LISTENER_LOOKS = 50
"""Team transport: robots whose pose and neighbors subscribers are looked up in the graph per
LISTENERS_PERIOD while the plant has no publishers of theirs (two lookups each)."""


class PlantNode(Node):
    """Steps the plant model, publishes states, sensor readings and the simulated clock."""

    def __init__(self) -> None:
        """Declare and check parameters, then set up topics and the step timer."""
        super().__init__('plant')
        config = declare_parameters(self, Exe.PLANT)
        settings = config.plant
        assert settings is not None and config.start is not None
        self.config, self.settings = config, settings
        self.law = config.law()
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.refused_changes: Dict[str, int] = {}
        self.changes = Changes(self, config, self.steady, self._reject_change)
        self.reference = self.changes.reference
        self.held_steps = 0
        self.team = TeamCheck(self, PLANT_STATUS)
        self.refusal: Optional[str] = None
        self.exit_code: Optional[int] = None
        self.looked = False
        self.next_look = 0.0
        self.created_wall = time.monotonic()
        self.clock_heard = 0
        self.graph = PublisherWatch(self, self.team, GRAPH_LOOKS)
        self.own_name = self.get_fully_qualified_name()
        self.n, self.dim = config.num_robots, config.dim
        self.unicycles = config.body.is_unicycle
        self.body_frame = config.command.frame is CommandFrame.BODY
        self.bodies = make_bodies(config.body, settings.max_speed,
                                  body_frame=self.body_frame and not self.unicycles)
        self.model = PlantModel(config.start, config.sensing_radii, settings.step_ns, self.law,
                                self.reference, settings.input_timeout_ns,
                                settings.collision_distance, settings.max_speed,
                                bodies=self.bodies, headings=config.start_headings,
                                imperfections=config.imperfections)
        self.commands = Commands.empty(self.n, self.bodies.command_width(self.dim))
        self.stamped = config.command.stamped
        self.command_frames = [messages.body_frame(i) if self.body_frame else config.world_frame
                               for i in range(1, self.n + 1)]
        self.state_stamp_ns = 0
        self.wrong_frame = np.zeros(self.n, dtype=np.int64)
        self.closest_body = self.model.closest_body_distance()
        self.status = np.full(self.n, CommandStatus.MISSING, dtype=np.int8)
        self.lockstep = config.lockstep
        self.publish_every = 1 if self.lockstep else settings.steps_per_publish
        self.chunks = (ChunkWriter(os.path.join(settings.output_dir, CHUNKS_DIR))
                       if settings.output_dir else None)
        self.output_failure: Optional[str] = None
        self.closest = self.model.closest_pair_distance()
        self.largest_u_hat = 0.0
        self.command_subs = []
        self.shared: Dict[str, str] = {}
        self.shared_by: Set[str] = set()
        """The publishers (names without hosts) of each line on :attr:`shared` logged."""
        self.last_publish_wall = 0.0
        self.started_wall: Optional[float] = None
        self.waiting = settings.wait_for_robots or self.lockstep
        self.clock_match_since: Optional[float] = None
        self.paths = Paths(self.n, PATH_LENGTH)
        self.published_ns: 'OrderedDict[int, int]' = OrderedDict()
        self.arrived_ns = np.zeros(self.n, dtype=np.int64)
        self.timed_stamp = np.full(self.n, -1, dtype=np.int64)
        self.latency = DurationHistogram()
        self.rate_window = (time.monotonic(), 0)

        self.state_encoder = StateEncoder(self.n, self.dim, config.world_frame)
        self.malformed = np.zeros(self.n, dtype=np.int64)
        self.command_liveliness: List[PeerLiveliness] = []
        self.team_transport = config.team_transport
        self.listened = np.ones(self.n, dtype=bool)
        self.pose_topics = [topics.robot_topic(i, topics.POSE) for i in range(1, self.n + 1)]
        self.neighbour_topics = [topics.robot_topic(i, topics.NEIGHBOURS)
                                 for i in range(1, self.n + 1)]
        self.pose_pubs: List[Optional[Publisher]] = [None] * self.n
        self.neighbour_pubs: List[Optional[Publisher]] = [None] * self.n
        self.lazy_robot_topics = (self.team_transport
                                  and self.settings.wait_for_subscribers <= 1)
        """Team transport with nobody else awaited: a robot's pose and neighbors publishers
        are made once someone subscribes to either (looked up in the graph in turn)."""
        self.listener_turns = Turns(LISTENER_LOOKS)
        for i in range(1, self.n + 1):
            if not self.lazy_robot_topics:
                self._make_robot_publishers(i - 1)
            if self.team_transport:
                continue
            self.command_liveliness.append(PeerLiveliness())
            self.command_subs.append(self.create_subscription(
                TwistStamped if self.stamped else Twist, topics.robot_topic(i, topics.CMD_VEL),
                lambda data, index=i - 1: self.on_command(index, data), qos.COMMAND_INPUT,
                raw=True,
                event_callbacks=self.command_liveliness[-1].callbacks()))
        self.malformed_team = 0
        self.wrong_frame_team = 0
        if self.team_transport:
            self._team_topics()
        self.clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, qos.CLOCK)
        self.clock_sub = self.create_subscription(ClockMsg, topics.CLOCK, self.on_clock,
                                                  qos.CLOCK, raw=True)
        self.expected_publishers: Dict[str, Optional[str]] = {self.clock_pub.topic_name:
                                                              self.own_name}
        for pose, neighbours in zip(self.pose_topics, self.neighbour_topics):
            self.expected_publishers[pose] = self.own_name
            self.expected_publishers[neighbours] = self.own_name
        if self.team_transport:
            self.expected_publishers[self.states_pub.topic_name] = self.own_name
        self.command_index = {sub.topic_name: i for i, sub in enumerate(self.command_subs)}
        self.expected_publishers.update(dict.fromkeys(self.command_index))
        self.robot_nodes = [topics.robot_node_name(i) for i in range(1, self.n + 1)]
        self.doubled: Dict[str, str] = {}
        """Team transport: {robot node: its processes} for robots that two processes run."""
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, topics.DIAGNOSTICS, qos.DIAGNOSTICS)
        period = RESEND_AFTER if self.lockstep else self.model.dt / settings.realtime_factor
        self.timer = self.create_timer(period, self.on_timer, clock=self.steady)
        self.step_wake = Wake(self, self.on_timer, self.steady)
        self.diagnostics_timer = self.create_timer(PERIOD, self.on_diagnostics,
                                                   clock=self.steady)
        if self.chunks is not None:
            self.chunk_timer = self.create_timer(CHUNK_PERIOD, self.write_chunk,
                                                 clock=self.steady)
        if settings.marker_rate > 0.0:
            self.marker_pub = self.create_publisher(MarkerArray, topics.MARKERS, qos.MARKERS)
            self.marker_timer = self.create_timer(1.0 / settings.marker_rate, self.on_markers,
                                                  clock=self.steady)
        self.get_logger().info(
            f'plant: {self.n} robots in {self.dim}D, dt = {self.model.dt:g} s, '
            f'reference {self.reference.kind}, '
            + ('lockstep' if self.lockstep
               else f'realtime factor {settings.realtime_factor:g}')
            + (', team transport' if self.team_transport else '')
            + ('' if config.imperfections.is_ideal else ', bodies beyond the paper: ' + ', '.join(
                f'{name} = {value:g}' for name, value in config.imperfections.as_dict().items()
                if value)))

    def _team_topics(self) -> None:
        """
        Team transport: publish /formation/states, hear /formation/commands.

        The robots' pose and neighbors are published only while someone subscribes (looked up
        every :data:`LISTENERS_PERIOD` s); cmd_vel is not subscribed to (a robot publishes it
        while something else does).
        """
        self.states_pub = self.create_publisher(PoseArray, topics.STATES, qos.STATE)
        self.team_reader = TeamCommandReader(self.n)
        self.team_liveliness = PeerLiveliness()
        self.team_sub = self.create_subscription(
            MultiDOFJointTrajectory, topics.TEAM_COMMANDS, self.on_team_command,
            qos.team_commands_input(self.n), raw=True,
            event_callbacks=self.team_liveliness.callbacks())
        self.listeners_timer = self.create_timer(LISTENERS_PERIOD, self._look_at_listeners,
                                                 clock=self.steady)
        self._look_at_listeners()

    def _make_robot_publishers(self, index: int) -> None:
        """Create the ``pose`` and ``neighbors`` publishers of robot ``index`` (0-based)."""
        self.pose_pubs[index] = self.create_publisher(PoseStamped, self.pose_topics[index],
                                                      qos.STATE)
        self.neighbour_pubs[index] = self.create_publisher(
            PoseArray, self.neighbour_topics[index], qos.STATE)

    def _look_at_listeners(self) -> None:
        """
        Team transport: note which robots' pose or neighbors someone subscribes to.

        With lazy robot topics, LISTENER_LOOKS robots a call (in turn) without publishers are
        looked up in the graph, and get theirs once a subscriber shows: a ``ros2 topic echo``
        of one of N robots is served within about N / LISTENER_LOOKS calls.
        """
        if self.lazy_robot_topics:
            for i in self.listener_turns.due(self.n):
                if self.pose_pubs[i] is None and (
                        self.count_subscribers(self.pose_topics[i]) > 0
                        or self.count_subscribers(self.neighbour_topics[i]) > 0):
                    self._make_robot_publishers(i)
        self.listened = np.array([pose is not None and neighbours is not None
                                  and (pose.get_subscription_count() > 0
                                       or neighbours.get_subscription_count() > 0)
                                  for pose, neighbours in zip(self.pose_pubs,
                                                              self.neighbour_pubs)], dtype=bool)

    def on_team_command(self, data: bytes) -> None:
        """
        Team transport: store the commands of one team message, as :meth:`on_command` does.

        Its header is in ``world_frame`` and stamped with the state its commands answer; each
        velocity is in its robot's command frame (``core.transport``). Malformed or oversized
        bytes (checked before any element is read) are counted and dropped, logged once.
        """
        try:
            message = self.team_reader.read(data)
        except CdrError as exc:
            self.malformed_team += 1
            self.once.start('malformed-team', 'ignoring /formation/commands bytes that are not '
                                              f'a team command ({exc}; logged once, counted in '
                                              'diagnostics)', 'error')
            return
        if message.frame_id != self.config.world_frame:
            self.wrong_frame_team += 1
            self.once.start('frame-team', 'ignoring /formation/commands in frame '
                                          f'{message.frame_id!r}: its header is in '
                                          f'{self.config.world_frame!r} (logged once, counted '
                                          'in diagnostics)', 'error')
            return
        indices = message.indices
        self.commands.u[indices] = commands_of(message.linear, message.angular, self.dim,
                                               self.unicycles)
        self.commands.stamp_ns[indices] = message.stamp_ns
        self.commands.present[indices] = True
        self.arrived_ns[indices] = time.monotonic_ns()
        if self.lockstep:
            self.step_wake.arm()

    def on_clock(self, data: bytes) -> None:
        """Before the first state: count /clock messages, which only another node sends."""
        self.clock_heard += 1

    def on_command(self, index: int, data: bytes) -> None:
        """
        Store robot ``index``'s latest command and when it arrived (lockstep: wake the step).

        A TwistStamped must be in the robot's command frame (``world_frame``, or its
        ``robot_<i>/base_link`` for unicycles and ``command.frame: body``) and answers the state
        of its stamp; a Twist (``command.type: twist``) has neither, and answers the latest
        state published when it arrives.
        """
        try:
            command = read_twist_stamped(data) if self.stamped else read_twist(data)
        except CdrError as exc:
            self.malformed[index] += 1
            kind = 'TwistStamped' if self.stamped else 'Twist'
            self.once.start(f'malformed-{index}', f'robot {index + 1}: ignoring cmd_vel bytes '
                                                  f'that are not a {kind} ({exc}; logged '
                                                  'once, counted in diagnostics)', 'error')
            return
        frame = self.command_frames[index]
        if self.stamped and command.frame_id != frame:
            self.wrong_frame[index] += 1
            self.once.start(f'frame-{index}', f'robot {index + 1}: ignoring cmd_vel in frame '
                                              f'{command.frame_id!r}: its commands are in '
                                              f'{frame!r} (logged once, counted in '
                                              'diagnostics)', 'error')
            return
        stamp_ns = command.stamp_ns if self.stamped else self.state_stamp_ns
        if self.unicycles:
            self.commands.store(index, (command.linear[0], command.angular[2]), stamp_ns)
        else:
            self.commands.store(index, command.linear[:self.dim], stamp_ns)
        self.arrived_ns[index] = time.monotonic_ns()
        if self.lockstep:
            self.step_wake.arm()

    def _reject_change(self, what: str, why: str) -> None:
        """Count and log once a shape or status refused (``ros.changes``)."""
        self.refused_changes[what] = self.refused_changes.get(what, 0) + 1
        self.once.start(f'{what}-refused', f'ignoring a {what} with {why} (logged once; '
                                           'counted in diagnostics)', 'error')

    def _vertices_at(self, t_ns: int) -> np.ndarray:
        """Return the shape in force at ``t_ns`` (N, dim), m."""
        return self.changes.shapes.at(t_ns).vertices

    def _time_answers(self) -> None:
        """Count how long each new command took: from its state's publish to its arrival."""
        stamps = self.commands.stamp_ns
        new = np.flatnonzero(self.commands.present & (stamps != self.timed_stamp))
        sent = [self.published_ns.get(int(stamps[i]), -1) for i in new]
        known = [k for k, when in enumerate(sent) if when >= 0]
        self.latency.add(self.arrived_ns[new[known]] - np.array(sent, dtype=np.int64)[known])
        self.timed_stamp[new] = stamps[new]

    def on_timer(self) -> None:
        """
        Free-running: one step per tick. Lockstep: step when every robot has answered.

        In lockstep this runs when a command arrives (:class:`Wake`) and every
        ``RESEND_AFTER`` s, to send a state again that was not answered.
        """
        if not self.looked and not self._look():
            return
        if self.started_wall is None:
            self.started_wall = time.monotonic()
            self._publish()
            return
        if self.waiting and not self._all_robots_up():
            self._look_while_waiting()
            return
        if self.lockstep:
            self._lockstep_tick()
            return
        self._step()
        if self.model.counts.steps % self.publish_every == 0:
            self._publish()

    def _look(self) -> bool:
        """
        Before the first state: True once the domain is known to hold no other /clock sender.

        Sets :attr:`refusal` (logged; the runner then exits REFUSED) for a /clock publisher other
        than this node that sends /clock, announces itself from another process, or has
        another name than this node's.
        """
        now = time.monotonic()
        waited = now - self.created_wall
        if waited < LOOK_TIME or self.refusal:
            return False
        others = self._other_clock_publishers(now)
        if others is None:
            return False
        if not others:
            return self._looked()
        running = any(self.team.running(name, now) for name in others)
        ours = all(name == self.own_name for name in others)
        if ours and not running and not self.clock_heard:
            self.once.start('leftover-clock', f'{others[0]} is listed as a /clock publisher '
                                              f'but sent nothing for {waited:.1f} s: taken '
                                              'for what is left of a plant that was killed '
                                              '(DDS forgets it within about 20 s); starting')
            return self._looked()
        if not running and waited < LOOK_LIMIT:
            return False
        self._refuse(others, now)
        return False

    def _other_clock_publishers(self, now: float) -> Optional[List[str]]:
        """
        Return the /clock publishers of the graph other than this node (one per writer).

        None while the graph has not named them all yet (at most ``ros.team.NAMES_WAIT`` s).
        """
        others = self.graph.named_publishers(self.clock_pub.topic_name, now)
        if others is None:
            return None
        if self.own_name in others:
            others.remove(self.own_name)
        return others

    def _look_while_waiting(self, at_once: bool = False) -> None:
        """
        While the clock waits for the robots: refuse another team's /clock publisher found late.

        Every LOOK_PERIOD s (``at_once``: now). Discovery on a busy machine can take longer
        than LOOK_TIME; until the first step a publisher with another name, or one that
        announces itself from another process, still means another team, and this plant has
        not moved a body yet.
        """
        now = time.monotonic()
        if (now < self.next_look and not at_once) or self.refusal:
            return
        self.next_look = now + LOOK_PERIOD
        others = self._other_clock_publishers(now)
        if others is not None and any(name != self.own_name or self.team.running(name, now)
                                      for name in others):
            self._refuse(others, now)

    def _refuse(self, others: List[str], now: float) -> None:
        """Log once why this plant will not start (``others`` publish /clock) and exit REFUSED."""
        plants = [name for name in others if name.rsplit('/', 1)[-1] == 'plant']
        what = 'plant' if plants else '/clock publisher'
        self.refusal = (f'refusing to start: another {what} is on ROS_DOMAIN_ID '
                        f'{self.context.get_domain_id()}: '
                        f'{self.graph.name_others(others, None, now)} publishes /clock (another '
                        'team? stop it, or run this team on a domain of its own: export '
                        'ROS_DOMAIN_ID=N, or the launcher without ROS_DOMAIN_ID set)')
        self.get_logger().error(self.refusal)
        self.exit_code = REFUSED

    def _announce_refusal(self) -> None:
        """
        Publish this plant's refusal as its last status, and wait a moment for it to be heard.

        The other plant names this one from its status; one that refuses within its first
        seconds may not have sent a status the other has heard yet (discovery on a busy
        machine), so the last one is waited for (reliable: acknowledged, at most
        REFUSAL_HEARD s).
        """
        shape = self._vertices_at(self.model.t_ns)
        self.diagnostics_pub.publish(diagnostics(
            PLANT_STATUS, 'error', self.refusal,
            announced(team_values(self.config, shape), self)))
        self.diagnostics_pub.wait_for_all_acked(Duration(seconds=REFUSAL_HEARD))

    def _looked(self) -> bool:
        self.looked = True
        self.destroy_subscription(self.clock_sub)
        return True

    def _lockstep_tick(self) -> None:
        answered = bool(np.all(self.commands.present
                               & (self.commands.stamp_ns == self.model.t_ns)))
        assert self.started_wall is not None
        ahead_s = self.model.t / self.settings.realtime_factor - (time.monotonic()
                                                                  - self.started_wall)
        if answered and ahead_s <= 0.0:
            self._step()
            self._publish()
        elif answered:
            self.step_wake.arm(ahead_s)
        else:
            self._resend_if_due()

    def _step(self) -> None:
        self._time_answers()
        if self.changes.states.at(self.model.t_ns).mode is Mode.STOPPED:
            self.held_steps += 1
        report = self.model.advance(self.commands)
        self.largest_u_hat = max(self.largest_u_hat,
                                 float(np.max(report.admission.largest_u_hat)))
        if (self.model.counts.steps - 1) % self.publish_every == 0:
            self.closest = min(self.closest, self.model.closest_pair_distance())
            self.closest_body = min(self.closest_body, self.model.closest_body_distance())
            if self.chunks is not None and self.unicycles:
                self.chunks.append(report.t_ns / NS_PER_S, report.points,
                                   report.admission.velocity,
                                   heading=report.heading, q_body=report.q,
                                   body_command=report.admission.u)
            elif self.chunks is not None:
                self.chunks.append(report.t_ns / NS_PER_S, report.q, report.admission.velocity)
        self._log(report)

    def _log(self, report: StepReport) -> None:
        """Say once what changed: a robot's command status, a bound violation, a collision."""
        status = report.admission.status
        changed = np.flatnonzero(status != self.status)
        if changed.size:
            self._log_staleness(changed, status, report.t_ns)
            for i in changed[status[changed] != CommandStatus.STALE].tolist():
                self._log_status(i, CommandStatus(status[i]), report.t_ns)
        self.status = status
        for robot, value in report.violations:
            self.get_logger().error(
                f'robot {robot + 1}: command component {value:.6g} m/s above the bound '
                f'c*M1 = {self.law.u_bound:.6g} m/s '
                f'({self.model.counts.bound_violations} so far)', throttle_duration_sec=1.0)
        limit = ('2 x body.radius or plant.collision_distance'
                 if self.model.body.contact_distance > 0.0 else 'plant.collision_distance')
        for i, j, distance in report.collisions:
            self.get_logger().error(
                f'collision: robots {i + 1} and {j + 1} are {distance:.3g} m apart at t = '
                f'{self.model.t:.3f} s (< {limit})')

    def _log_staleness(self, changed: NDArray[np.intp], status: NDArray[np.int_],
                       t_ns: int) -> None:
        """
        Say in one line which robots' commands went stale this step, and which are fresh again.

        A stall of a process (or of the machine) makes many robots' commands late at once: one
        line names them all (the first few and how many more), not a line per robot.
        """
        stale = {f'stale-{i}': i
                 for i in changed[status[changed] == CommandStatus.STALE].tolist()}
        ages = {key: (t_ns - int(self.commands.stamp_ns[i])) / NS_PER_S
                for key, i in stale.items()}
        self.once.start_group(list(stale), lambda keys: (
            f'{robots_named([stale[key] for key in keys])}: latest '
            f"command{'' if len(keys) == 1 else 's'} {max(ages[key] for key in keys):.3g} s old"
            f"{'' if len(keys) == 1 else ' at most'}; using zero"))
        fresh = {f'stale-{i}': i for i in changed[
            (status[changed] == CommandStatus.APPLIED)
            | (status[changed] == CommandStatus.SATURATED)].tolist()}
        self.once.end_group(list(fresh), lambda keys: (
            f'{robots_named([fresh[key] for key in keys])}: commands fresh again'))

    def _log_status(self, i: int, status: CommandStatus, t_ns: int) -> None:
        age = (t_ns - int(self.commands.stamp_ns[i])) / NS_PER_S
        if status is CommandStatus.FUTURE:
            self.once.start(f'future-{i}', f'robot {i + 1}: command stamped {-age:.3g} s after '
                                           'the present state (a sender on another clock? '
                                           'check use_sim_time); using zero', 'error')
        elif status is CommandStatus.NON_FINITE:
            self.once.start(f'bad-{i}', f'robot {i + 1} sent a non-finite command; using zero '
                                        '(logged once; counted in bad command steps)', 'error')
        elif status is CommandStatus.SATURATED:
            self.once.start(f'saturated-{i}', f'robot {i + 1}: command beyond what the law '
                                              'allows; saturating it (counted in saturated '
                                              'command steps)', 'error')
        if status in (CommandStatus.APPLIED, CommandStatus.SATURATED):
            self.once.end(f'future-{i}', f'robot {i + 1}: commands answer present states again')
        if status is CommandStatus.APPLIED:
            self.once.end(f'saturated-{i}')

    def _publish_clock(self) -> None:
        self.clock_pub.publish(encode_clock(self.model.t_ns))

    def _publish(self) -> None:
        """
        Publish /clock, then what the robots sense: every pose and each range sensor's bodies.

        Team transport: one /formation/states message, and robot i's pose and neighbors only
        while someone subscribes to them.

        That is the model's sensed state (``PlantModel.sensed``): the present one for ideal
        sensing; with ``plant.pose_noise`` / ``plant.state_delay`` the noisy state measured the
        delay ago, stamped with its measurement time (the clock stays the present).
        """
        self._publish_clock()
        state = self.model.sensed()
        self.state_stamp_ns = state.stamp_ns
        self.published_ns.setdefault(state.stamp_ns, time.monotonic_ns())
        while len(self.published_ns) > PUBLISHES_TIMED:
            self.published_ns.popitem(last=False)
        headings = state.heading if self.unicycles or self.body_frame else None
        if self.team_transport:
            self.state_encoder.set_rows(state.q, headings)
            self.states_pub.publish(self.state_encoder.team(state.stamp_ns))
        if not self.team_transport or np.any(self.listened):
            observer, seen = self.model.sensed_pairs()
            poses, arrays = self.state_encoder.encode(state.q, observer, seen, state.stamp_ns,
                                                      headings)
            for i in np.flatnonzero(self.listened).tolist():
                pose, neighbours = self.pose_pubs[i], self.neighbour_pubs[i]
                assert pose is not None and neighbours is not None
                pose.publish(poses[i])
                neighbours.publish(arrays[i])
        self.last_publish_wall = time.monotonic()

    def _resend_if_due(self) -> None:
        if time.monotonic() - self.last_publish_wall > RESEND_AFTER:
            self._publish()

    def _clock_unmatched(self) -> bool:
        """
        Whether a /clock subscriber the graph shows is not matched to this plant's publisher.

        For at most CLOCK_MATCH_WAIT s from the first call (steady clock), then False; the
        plant's own subscription, while it looks, counts on both sides.
        """
        now = time.monotonic()
        if self.clock_match_since is None:
            self.clock_match_since = now
        unmatched = (self.clock_pub.get_subscription_count()
                     < self.count_subscribers(topics.CLOCK))
        if unmatched and now - self.clock_match_since >= CLOCK_MATCH_WAIT:
            self.get_logger().warning(
                f'a /clock subscriber is still not matched after {CLOCK_MATCH_WAIT:g} s '
                '(a QoS /clock does not offer?): starting the clock all the same')
            return False
        return unmatched

    def _all_robots_up(self) -> bool:
        """While waiting: start the clock once every robot has sent a command."""
        missing = (np.flatnonzero(~self.commands.present) + 1).tolist()
        wanted = self.settings.wait_for_subscribers - (1 if self.team_transport else 0)
        unheard = ([pub for pub in self.pose_pubs
                    if pub is None or pub.get_subscription_count() < wanted]
                   if wanted > 0 else [])
        if self.team_transport and self.states_pub.get_subscription_count() < 1:
            unheard.append(self.states_pub)
        clock_unmatched = not missing and not unheard and self._clock_unmatched()
        if missing or unheard or clock_unmatched:
            more = '...' if len(missing) > 10 else ''
            listeners = f'{wanted} subscribers on every pose topic'
            if self.team_transport:
                listeners = (f'a subscriber of {topics.STATES}'
                             + (f' and {listeners}' if wanted > 0 else ''))
            if clock_unmatched:
                self.once.start('clock-match', 'every robot is up: waiting for /clock to reach '
                                               'its subscribers', 'info')
            else:
                self.once.start('waiting', f'waiting for {len(missing)} of {self.n} robots to '
                                           f'send a command (robots {missing[:10]}{more}) and '
                                           f'for {listeners}', 'info')
            self._resend_if_due()
            return False
        self.waiting = False
        if self.team_transport:
            self._look_at_listeners()
        self.started_wall = time.monotonic()
        self.rate_window = (self.started_wall, self.model.counts.steps)
        started = f'all {self.n} robots are up: starting the clock'
        self.once.end('clock-match')
        if self.once.is_active('waiting'):
            self.once.end('waiting', started)
        else:
            self.get_logger().info(started)
        self._publish()
        return True

    def on_diagnostics(self) -> None:
        """
        Publish the plant's status: step rate, counters, closest pair, bound.

        Before the first step another team is the look's to refuse, in one line: the look runs
        first, and a refusing plant names no shared topic or other plant besides.
        """
        if self.waiting and self.looked:
            self._look_while_waiting(at_once=True)
        now = time.monotonic()
        since, steps = self.rate_window
        counts = self.model.counts
        rate = (counts.steps - steps) / (now - since) if now > since else 0.0
        self.rate_window = (now, counts.steps)
        target = self.settings.realtime_factor / self.model.dt
        values = {'simulated time [s]': self.model.t,
                  'step rate achieved [Hz]': rate,
                  'step rate target [Hz]': 'lockstep' if self.lockstep else target,
                  'min pair distance [m]': self.model.closest_pair_distance(),
                  **({'min body distance [m]': self.model.closest_body_distance()}
                     if self.unicycles else {}),
                  'bound c*M1 [m/s]': self.law.u_bound,
                  'oldest command counted [s]': counts.oldest_counted_ns / NS_PER_S,
                  'steps with fresh commands': counts.fresh_steps(
                      FRESH_PERIODS * self.publish_every)}
        values.update({name.replace('_', ' '): count for name, count in counts.totals().items()})
        if np.any(self.wrong_frame):
            values['robots with cmd_vel in a frame other than their command frame'] = ', '.join(
                f'{i + 1}: {count}' for i, count in enumerate(self.wrong_frame.tolist()) if count)
        values['team'] = self.changes.states.at(self.model.t_ns).mode.value
        values['held steps'] = self.held_steps
        values.update({f'refused {what} messages': count
                       for what, count in self.refused_changes.items()})
        if np.any(self.malformed):
            values['robots with malformed cmd_vel messages'] = ', '.join(
                f'{i + 1}: {count}' for i, count in enumerate(self.malformed.tolist()) if count)
        if self.team_transport:
            values['transport'] = 'team'
            values['malformed team command messages'] = self.malformed_team
            values['team command messages in another frame'] = self.wrong_frame_team
            values['team command publishers alive'] = self.team_liveliness.alive
            values['robots with pose and neighbors published'] = ', '.join(
                str(i + 1) for i in np.flatnonzero(self.listened).tolist()) or 'none'
        for status in (CommandStatus.STALE, CommandStatus.FUTURE, CommandStatus.NON_FINITE,
                       CommandStatus.SATURATED):
            robots = counts.by_robot(status)
            if robots:
                values[f'robots with {status.name.lower().replace("_", "-")} commands'] = \
                    ', '.join(f'{robot}: {steps}' for robot, steps in robots.items())
        states = self._command_states()
        for state in ('alive', 'lost'):
            robots = [str(i + 1) for i, s in enumerate(states) if s == state]
            values[f'robots with {state} cmd_vel'] = ', '.join(robots) or 'none'
        shape = self._vertices_at(self.model.t_ns)
        values.update(announced(team_values(self.config, shape), self))
        others = team_problems(self.team, self.config, shape, self.once)
        if others:
            values['nodes with other team values'] = ' | '.join(others)
        shared = self._shared_topics(now)
        doubled = self._doubled_robots(now)
        if doubled:
            values['robot nodes in more than one process'] = ' | '.join(
                f'{name}: {processes}' for name, processes in sorted(doubled.items()))
        plants = (self.team.running(self.own_name, now) if self.looked and not self.refusal
                  else [])
        if plants:
            self.once.start('other-plant', 'another plant runs on this domain: '
                                           f'{self.team.describe(self.own_name, now)} (another '
                                           'team? each needs a ROS_DOMAIN_ID of its own)', 'error')
            values['other plants'] = self.team.describe(self.own_name, now)
        else:
            self.once.end('other-plant', 'the other plant is gone')
        if shared:
            values['topics with more than one publisher'] = ' | '.join(
                f'{topic}: {names}' for topic, names in sorted(shared.items()))
        if (counts.collisions or counts.bound_violations or shared or doubled or others
                or plants):
            level, message = 'error', (f'{counts.collisions} collisions, '
                                       f'{counts.bound_violations} commands above the bound, '
                                       f'{len(shared)} topics with several publishers, '
                                       f'{len(doubled)} robots in several processes, '
                                       f'{len(others)} nodes with other team values')
        elif not self.looked:
            level, message = 'ok', 'looking for another plant on this domain'
        elif self.waiting:
            level, message = 'ok', 'waiting for the robots'
        elif 'lost' in states:
            level, message = 'warn', (f"{states.count('lost')} robots gone "
                                      '(cmd_vel liveliness lost)')
        elif not self.lockstep and rate < 0.9 * target:
            level, message = 'warn', f'stepping at {rate:.1f} Hz of {target:.1f} Hz'
        else:
            level, message = 'ok', 'running'
        self.diagnostics_pub.publish(diagnostics(PLANT_STATUS, level, message, values))

    def _command_states(self) -> List[str]:
        """
        Return each robot's 'alive', 'lost' or 'unknown', as its commands show it.

        Robot transport: its cmd_vel's DDS liveliness. Team transport: whether its latest
        command arrived within the liveliness lease or two state periods, whichever is longer
        (wall clock; 'unknown' before the first),
        so that the robots of a fleet that died show as lost within about a second, as the
        robots of one that is alive do not (a robot process or fleet answers every state).
        """
        if not self.team_transport:
            return [peer.state() for peer in self.command_liveliness]
        state_period = self.publish_every * self.model.dt / self.settings.realtime_factor
        lease_ns = int(max(qos.LIVELINESS_LEASE, 2.0 * state_period) * NS_PER_S)
        recent = time.monotonic_ns() - self.arrived_ns <= lease_ns
        return ['unknown' if not present else 'alive' if fresh else 'lost'
                for present, fresh in zip(self.commands.present.tolist(), recent.tolist())]

    def _shared_topics(self, now: float) -> Dict[str, str]:
        """
        Return {topic: its other publishers} of /clock and the robots' topics; log each once.

        Only once the plant has looked, and /clock only once the clock runs: before, a second
        /clock publisher is the look's to refuse (:meth:`_look_while_waiting`), in one line.
        A second publisher with the expected name runs for sure when it announces itself
        from another process, or (cmd_vel) when DDS liveliness counts two alive.
        """
        if not self.looked or self.refusal:
            return {}
        expected = self.expected_publishers
        if self.waiting:
            expected = {topic: name for topic, name in expected.items()
                        if topic != self.clock_pub.topic_name}
        shared = self.graph.check(expected, now, self._alive)
        by_names: Dict[str, List[str]] = {}
        for topic in shared:
            by_names.setdefault(self.graph.others(topic, expected[topic]), []).append(topic)
        lines = {names: f'{_some(listed)} more than one publisher: {shared[listed[0]]} ('
                 + ('a second node with this robot_id?' if listed[0] in self.command_index
                    else 'another team on this domain, or a node forging them?') + ')'
                 for names, listed in by_names.items()}
        self.once.follow('publishers', lines, self.shared_by,
                         lambda names: f'{names}: no longer publishing here')
        self.shared = shared
        self.shared_by = set(lines)
        return shared

    def _doubled_robots(self, now: float) -> Dict[str, str]:
        """
        Team transport: return {robot node: its processes} run by two processes; log each once.

        Two processes that claim one robot both answer for it on the team topic, where the
        plant cannot tell them apart; each announces its robots' nodes, host and process in
        its ``/diagnostics`` once a second (``ros.team.TeamCheck``), which shows them: both
        within DOUBLED_WITHIN s (a restarted process announces its first more than that after
        the one it replaces announced its last).
        """
        if not self.team_transport or not self.looked:
            return {}
        doubled = {name: self.team.describe(name, now) for name in self.robot_nodes
                   if len(self.team.running(name, now, DOUBLED_WITHIN)) >= 2}
        self.once.follow('doubled', {name: f'{name} runs in more than one process: {processes}'
                                           ' (a second node with this robot_id?)'
                                     for name, processes in doubled.items()},
                         self.doubled, lambda name: f'{name} runs in one process again')
        self.doubled = doubled
        return doubled

    def _alive(self, topic: str, names: List[str]) -> bool:
        """Whether a same-named second publisher of ``topic`` is known to run."""
        now = time.monotonic()
        index = self.command_index.get(topic)
        if index is None:
            return bool(self.team.running(self.own_name, now))
        return (self.command_liveliness[index].alive >= 2
                or len(self.team.running(names[0], now)) >= 2)

    def on_markers(self) -> None:
        """
        Publish the RViz picture: robots, sensing and repulsion zones, formation, paths.

        Only while someone subscribes (RViz, a recorder with ``record.markers``): building the
        MarkerArray was a quarter of a lockstep plant's time. The paths are kept regardless.
        """
        self.paths.append(self.model.q)
        if self.marker_pub.get_subscription_count() == 0:
            return
        desired = desired_positions(self._vertices_at(self.model.t_ns),
                                    self.reference.sample(self.model.t))
        self.marker_pub.publish(formation_markers(
            self.model.q, self.config.sensing_radii, self.law.repulsion_radius, desired,
            self.paths, self.model.t_ns, self.config.world_frame,
            self.model.heading if self.unicycles else None))

    def write_chunk(self) -> None:
        """Write the samples since the last chunk into ``plant.output_dir`` (a failure: once)."""
        assert self.chunks is not None
        try:
            self.chunks.flush()
        except OSError as exc:
            self._output_failed(exc, self.chunks.folder)

    def _output_failed(self, exc: OSError, where: str) -> None:
        """Say in one line that the output stopped, where and why; write nothing more."""
        assert self.chunks is not None
        until = self.chunks.written_until
        kept = ('nothing of the trajectory' if until is None else
                f'the trajectory up to t = {until:.2f} s in {self.chunks.count} chunks '
                f'({CHUNKS_DIR}/, which formation_report reads)')
        reason = exc.strerror or ' '.join(str(exc).split()) or type(exc).__name__
        self.output_failure = f'cannot write to {where} ({reason})'
        self.get_logger().error(
            f'plant: output stopped at t = {self.model.t:.2f} s: {self.output_failure}; '
            f'{self.settings.output_dir} keeps {kept}; the plant goes on controlling and '
            'writes nothing more there')

    def trajectory(self) -> Optional[Trajectory]:
        """Return the run written so far (``plant.output_dir``): a sample per published state."""
        if self.chunks is None:
            return None
        self.write_chunk()
        try:
            t, q, u = read_chunks(self.chunks.folder)
        except ValueError:
            return None
        frames = [self.reference.sample(time_s) for time_s in t]
        shapes = [self._vertices_at(int(round(time_s * NS_PER_S))) for time_s in t]
        trajectory = Trajectory.from_frames(t, q, u, frames, shapes)
        body = read_body_chunks(self.chunks.folder) if self.unicycles else None
        return trajectory if body is None else replace(trajectory, **body)

    def finish(self) -> None:
        """Log a summary of the run; with ``plant.output_dir`` write trajectory and counters."""
        if self.refusal:
            self._announce_refusal()
            return
        if self.started_wall is None or self.model.counts.steps == 0:
            self.get_logger().info('plant: stopped before the first step')
            return
        wall = time.monotonic() - self.started_wall
        counts = self.model.counts
        totals = counts.totals()
        desired = desired_positions(self._vertices_at(self.model.t_ns),
                                    self.reference.sample(self.model.t))
        error = float(np.max(np.linalg.norm(self.model.points - desired, axis=1)))
        bodies = f', min body distance {self.closest_body:.4g} m' if self.unicycles else ''
        self.get_logger().info(
            f"plant: {totals['steps']} steps ({self.model.t:.2f} s simulated in {wall:.1f} s), "
            f'final max error {error:.3g} m, min pair distance {self.closest:.4g} m{bodies}, '
            f'max |u_hat| {self.largest_u_hat:.4g} m/s (bound {self.law.u_bound:.4g}), '
            f"{totals['collisions']} collisions, {totals['bound_violations']} commands above "
            f"the bound, {totals['stale_command_steps']} stale commands"
            + (f'; output stopped early: {self.output_failure}' if self.output_failure else ''))
        output_dir = self.settings.output_dir
        if not output_dir or self.output_failure is not None:
            return
        self.write_chunk()
        if self.output_failure is not None:
            return
        stats: Dict[str, Any] = {
            'integrator': f'plant, zero-order hold, dt = {self.model.dt:g} s'
                          + (', lockstep' if self.lockstep else ''),
            'simulated_time': self.model.t, 'wall_time': wall,
            'achieved_step_rate': totals['steps'] / wall if wall > 0 else None}
        stats.update(totals)
        stats['held_steps'] = self.held_steps
        stats['shape_changes'] = len(self.changes.shapes.changes())
        stats['events'] = event_records(timeline_events(self.changes.shapes,
                                                        self.changes.states))
        stats['imperfections'] = self.config.imperfections.as_dict()
        stats['state_delay_steps'] = self.model.delay_steps
        stats['oldest_command_counted'] = counts.oldest_counted_ns / NS_PER_S
        stats['command_age_steps'] = counts.age_steps.tolist()
        stats['answer_latency'] = {
            'count': self.latency.count,
            **{f'p{p}_ms': (None if self.latency.percentile_ns(p) is None
                            else self.latency.percentile_ns(p) / 1e6) for p in (50, 99)},
            'max_ms': self.latency.largest_ns / 1e6}
        stats['by_robot'] = {status.name.lower(): counts.by_robot(status)
                             for status in CommandStatus if status is not CommandStatus.APPLIED}
        if self.unicycles:
            stats['min_body_distance'] = self.closest_body
        stats['wrong_frame_command_messages'] = {
            i + 1: count for i, count in enumerate(self.wrong_frame.tolist()) if count}
        stats['malformed_command_messages'] = {
            i + 1: count for i, count in enumerate(self.malformed.tolist()) if count}
        stats['transport'] = self.config.transport.value
        if self.team_transport:
            stats['malformed_team_command_messages'] = self.malformed_team
        text = (json.dumps(stats, indent=2) + '\n').encode()
        where = os.path.join(output_dir, PLANT_STATS_FILE)
        try:
            save_atomically(where, lambda stream: stream.write(text))
            trajectory = self.trajectory()
            where = os.path.join(output_dir, TRAJECTORY_FILE)
            if trajectory is not None:
                trajectory.save(where)
        except OSError as exc:
            self._output_failed(exc, where)
            return
        if trajectory is not None:
            assert self.chunks is not None
            shutil.rmtree(self.chunks.folder, ignore_errors=True)
        self.get_logger().info(f'plant: wrote {TRAJECTORY_FILE} and {PLANT_STATS_FILE} to '
                               f'{output_dir}')


def _some(topics: List[str], shown: int = 3) -> str:
    """Return '/clock has' or '/clock, /robot_1/pose and 99 more topics have'."""
    if len(topics) == 1:
        return f'{topics[0]} has'
    more = f' and {len(topics) - shown} more topics' if len(topics) > shown else ''
    return f"{', '.join(topics[:shown])}{more} have"


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros plant``."""
    return run(PlantNode, args, name='plant')
