# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
World node (executable ``world``): the physics engine behind the topics a simulated lab has.

It steps :class:`formation_ros.physics.engine.Engine` (MuJoCo) on the steady clock at
``world.realtime_factor`` (``core.rules.pacing``) and gives the robots what a simulator and its
ROS bridge give a lab (Gazebo with ros_gz_bridge): ``/clock``, each robot's ground truth on
``/robot_<i>/measured_pose`` (the relay's default source), for wheeled bases wheel
odometry on ``/robot_<i>/odom`` and, for wheeled and planar bases, a laser scan on
``/robot_<i>/scan`` (``physics.scanner``, at ``world.scan_rate``); it drives the bodies from
``/robot_<i>/cmd_vel``, whose callbacks only store (``physics.intake``). It builds the
obstacle map (``obstacles.*``) as static geoms the bodies collide with, counts contacts between
robots and, apart, with obstacles, and, with ``world.output_dir``, writes ``world.xml``,
``trajectory.npz`` and ``world_stats.json`` (``core.runs.output``, ``core.runs.world_stats``).
Before its first step it looks at the domain through the plant's start gate
(``core.rules.plant_gate``, ``ros.clock_look``): beside another plant or world it refuses (exit 2).
How to start it, what it refuses and writes: docs/physics.md ("The world node"); its topics:
docs/ros_interface.md.
"""

import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.unicycle import headings_from_quaternions, quaternions_from_headings
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.model.commanded import (commanded_velocity, HeardPoses,
                                                needs_orientation)
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.pacing import Pacer
from formation_ros.core.rules.plant_gate import (leftover_line, Phase, StartGate, Verdict,
                                                 WORLD_LOOK_TIME)
from formation_ros.core.runs.output import FixedShape, RunOutput
from formation_ros.core.runs.trajectory import TRAJECTORY_FILE
from formation_ros.core.runs.world_stats import WORLD_STATS_FILE
from formation_ros.core.settings.declarations import CommandFrame, Exe
from formation_ros.core.settings.exits import ENGINE_FAILED, REFUSED
from formation_ros.core.settings.names import scan_frame
from formation_ros.core.settings.params import world_size_problem
from formation_ros.physics.engine import Engine, Unstable, unstable_line
from formation_ros.physics.intake import CommandInbox
from formation_ros.physics.obstacles import footprint_note
from formation_ros.physics.scanner import height_note, scan_period, steps_per_scan
from formation_ros.physics.scene import WORLD_FILE
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import (CdrError, encode_clock, encode_odometry, encode_pose_stamped,
                                   read_pose_stamped, read_twist, read_twist_stamped, TwistData)
from formation_ros.ros.clock_look import look_at_clock, refusal
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.once import OnceLog, RefusalLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.team import identity, PublisherWatch, TeamCheck
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
from numpy.typing import NDArray
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from sensor_msgs.msg import LaserScan

WORLD_STATUS = 'formation_ros/world'
MIN_TICK = 0.005
"""The shortest period of the step timer, s (wall clock): a fast world publishes several poses
per tick rather than waking more often."""
CATCH_UP = 0.2
"""The most wall-clock time a tick catches up when the world is behind, s (times the factor:
simulated); the rest is let go and counted (``core.rules.pacing``)."""
KEPT_UP = 0.9
"""A world whose real-time factor over the last second is below this share of the one asked
for is behind: WARN in /diagnostics, said once in the log."""
CONTACT_LINES = 50
"""Contacts logged one line each; further ones are counted only (in /diagnostics and the
stats)."""
CHUNK_PERIOD = 1.0
ODOMETRY_HEIGHT = 0.0
"""The height of an odometry pose, m: wheel odometry is planar."""
HEARD_KEPT = 256
"""States kept per robot to read a held command at the orientation it answered: 5 s at 50 Hz,
more than a command is ever held (``world.cmd_timeout``)."""
REFUSAL_WORDS = {Reason.MALFORMED: 'bytes that are not a whole {kind}',
                 Reason.FRAME: 'a frame other than its command frame',
                 Reason.NON_FINITE: 'non-finite values',
                 Reason.CLOCK: "a stamp after the world's time (another clock?)"}
"""How the world's log and /diagnostics name each reason a cmd_vel is refused for."""


class WorldNode(Node):
    """Steps the physics engine; publishes /clock, measured poses and odometry; takes cmd_vel."""

    def __init__(self) -> None:
        """Declare and check parameters, build the engine, set up topics and timers."""
        super().__init__('world')
        config = declare_parameters(self, Exe.WORLD)
        assert config.world is not None and config.start is not None
        self.config, self.world = config, config.world
        self.engine = Engine(config, config.world)
        self.n, self.dim = config.num_robots, config.dim
        self.unicycles = config.body.is_unicycle
        self.bodies = make_bodies(config.body)
        self.body_frame = config.command.frame is CommandFrame.BODY
        self.stamped = config.command.stamped
        self.once = OnceLog(self.get_logger())
        self.refusals: RefusalLog[int] = RefusalLog(self.once, self._refusal_line)
        self.command_frames = [messages.body_frame(i) if self.body_frame
                               else config.world_frame for i in range(1, self.n + 1)]
        self.inbox = CommandInbox(self.command_frames, self.dim, self.unicycles, self.stamped,
                                  self.world.cmd_timeout_ns)
        self.steps_per_pose = self.world.steps_per_pose
        self.pacer = Pacer(self.world.timestep_ns, self.world.realtime_factor,
                           int(CATCH_UP * self.world.realtime_factor * NS_PER_S))
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.contacts_logged = 0
        self.obstacle_contacts_logged = 0
        self.late = np.zeros(self.n, dtype=np.int64)
        """(N,) commands of each robot already stale when the step timer applied them."""
        self.rate_window = (time.monotonic_ns(), 0)
        self.output_dir = self.world.output_dir
        self.output = RunOutput(self.output_dir, 'world', 'the world goes on',
                                config.feed_forward_guard())
        self.gate = StartGate(time.monotonic(), False, self.get_fully_qualified_name(),
                              WORLD_LOOK_TIME)
        self.team_check = TeamCheck(self, WORLD_STATUS)
        self.graph = PublisherWatch(self, self.team_check)
        self.refusal: Optional[str] = None
        self.exit_code: Optional[int] = None
        self.clock_heard = 0
        self.clock_sub = self.create_subscription(ClockMsg, topics.CLOCK, self.on_clock,
                                                  qos.CLOCK, raw=True)

        self.clock_pub = self.create_publisher(ClockMsg, topics.CLOCK, qos.CLOCK)
        self.pose_pubs = [self.create_publisher(
            PoseStamped, topics.robot_topic(i, topics.MEASURED_POSE), qos.MEASUREMENT)
            for i in range(1, self.n + 1)]
        self.odometry_pubs = ([self.create_publisher(
            Odometry, topics.robot_topic(i, topics.ODOM), qos.MEASUREMENT)
            for i in range(1, self.n + 1)] if self.engine.odometer is not None else [])
        self.command_subs = [self.create_subscription(
            TwistStamped if self.stamped else Twist, topics.robot_topic(i, topics.CMD_VEL),
            lambda data, index=i - 1: self.on_command(index, data), qos.COMMAND_INPUT,
            raw=True) for i in range(1, self.n + 1)]
        scanner = self.engine.scanner
        self.steps_per_scan = 0 if scanner is None else steps_per_scan(self.world)
        self.scan_time = 0.0 if scanner is None else scan_period(self.world)
        self.scan_frames = [scan_frame(i) for i in range(1, self.n + 1)]
        self.scan_pubs = [] if scanner is None else [self.create_publisher(
            LaserScan, topics.robot_topic(i, topics.SCAN), qos.MEASUREMENT)
            for i in range(1, self.n + 1)]
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS,
                                                     qos.DIAGNOSTICS)
        self.heard: Optional[HeardPoses] = None
        """The states the robots heard (``pose``), to read what each commanded (``_sample``):
        at the orientation of the state it answered, if a command needs one, and at its
        position (eq. 25's feed-forward); only for stamped commands, recorded."""
        if self.output_dir and self.stamped:
            self.heard = HeardPoses(self.n, HEARD_KEPT)
            self.state_subs = [self.create_subscription(
                PoseStamped, topics.robot_topic(i, topics.POSE),
                lambda data, index=i - 1: self.on_state_heard(index, data),
                qos.recording(qos.STATE_INPUT), raw=True) for i in range(1, self.n + 1)]
        tick = max(MIN_TICK, 1.0 / (self.world.pose_rate * self.world.realtime_factor))
        self.timer = self.create_timer(tick, self.on_timer, clock=self.steady)
        self.diagnostics_timer = self.create_timer(PERIOD, self.on_diagnostics,
                                                   clock=self.steady)
        if self.output_dir:
            self.chunk_timer = self.create_timer(CHUNK_PERIOD, self.write_chunk,
                                                 clock=self.steady)
        self.get_logger().info(
            f'world: {self.n} {self.engine.model.kind.value} robots in {self.dim}D, timestep '
            f'{self.world.timestep:g} s, realtime factor {self.world.realtime_factor:g}, '
            f'poses at {self.world.pose_rate:g} Hz'
            + (f', scans of {self.world.scan_rays} rays at {1.0 / self.scan_time:g} Hz'
               if scanner is not None else ', no scanner')
            + (f', obstacles: {self.engine.obstacles.count}' if self.engine.obstacles.count
               else '')
            + (f', writing to {self.output_dir}' if self.output_dir else ''))

        note = footprint_note(self.engine.obstacles, config.body.radius,
                              self.engine.model.footprint)
        if note is not None:
            self.get_logger().warning(f'world: {note}')
        if scanner is not None:
            low = height_note(self.engine.obstacles.count, self.world.obstacle_height,
                              scanner.height)
            if low is not None:
                self.get_logger().warning(f'world: {low}')

    def _start_output(self) -> None:
        """
        With ``world.output_dir``: write world.xml now and start the trajectory's chunks.

        Once the domain is found free: a world that refuses writes nothing (another world may
        be writing there).
        """
        if not self.output_dir:
            return
        failed = self.output.start(self.engine.time_s, self.engine.scene.write)
        if failed is not None:
            self.get_logger().error(failed)

    def _refusal_line(self, index: int, reason: Reason, detail: str) -> str:
        kind = 'TwistStamped' if self.stamped else 'Twist'
        what = REFUSAL_WORDS.get(reason, reason.value).format(kind=kind)
        return (f'robot {index + 1}: ignoring cmd_vel with {what} ({detail}; logged once, '
                'counted in /diagnostics)')

    def on_clock(self, data: bytes) -> None:
        """While the world looks at the domain: count /clock messages, which only others send."""
        self.clock_heard += 1

    def _look_at_domain(self, now: float) -> bool:
        """
        Look up the other /clock publishers when the gate asks; return whether the domain is ours.

        The plant's gate decides (``core.rules.plant_gate``): refuse (exit REFUSED) beside another
        plant or world, take a silent one of this name for a killed world's, or go on looking.
        """
        if not self.gate.look_due(now):
            return False
        verdict, others = look_at_clock(self.graph, self.team_check, self.gate,
                                        self.clock_heard > 0, now)
        if self.gate.phase is Phase.REFUSED:
            self.refusal = refusal(self.graph, self.gate, self.context.get_domain_id(), now)
            self.get_logger().error(self.refusal)
            self.exit_code = REFUSED
            return False
        if not self.gate.looked:
            return False
        if verdict is Verdict.LEFTOVER and others:
            self.once.start('leftover-clock', leftover_line(others[0], now - self.gate.created))
        self.destroy_subscription(self.clock_sub)
        self._start_output()
        return True

    def on_command(self, index: int, data: bytes) -> None:
        """Keep robot ``index``'s command for the next step, or count its refusal (logged once)."""
        try:
            message = read_twist_stamped(data) if self.stamped else read_twist(data)
        except CdrError as exc:
            self.refusals.refuse(index, Reason.MALFORMED, str(exc))
            return
        reason = self.inbox.take(index, message.frame_id, message.linear, message.angular,
                                 message.stamp_ns, self.engine.time_ns)
        if reason is not None:
            self.refusals.refuse(index, reason, self._refusal_detail(index, reason, message))

    def _refusal_detail(self, index: int, reason: Reason, message: TwistData) -> str:
        """Say what was wrong with a refused command: its frame, its stamp or its values."""
        if reason is Reason.FRAME:
            return f'frame {message.frame_id!r}, expected {self.command_frames[index]!r}'
        if reason is Reason.CLOCK:
            return (f'stamp {message.stamp_ns / NS_PER_S:.9g} s, world at '
                    f'{self.engine.time_s:.9g} s')
        return f'linear {message.linear}, angular {message.angular}'

    def on_timer(self) -> None:
        """Apply the commands kept, run the steps due, publishing at every pose period."""
        if not self.gate.looked and not self._look_at_domain(time.monotonic()):
            return
        now = time.monotonic_ns()
        if self.pacer.started_ns is None:
            self.pacer.start(now, self.engine.steps)
            self.rate_window = (now, self.engine.steps)
            self._publish()
            self._publish_scans()
            return
        rows, commands, stamps = self.inbox.drain()
        if len(rows):
            self.engine.apply(commands, stamps, robots=rows)
            self._note_late(rows, stamps)
        due = self.pacer.due(now, self.engine.steps)
        try:
            while due > 0:
                steps = min(due, self.steps_per_pose - self.engine.steps % self.steps_per_pose)
                if self.steps_per_scan:
                    steps = min(steps, self.steps_per_scan
                                - self.engine.steps % self.steps_per_scan)
                self.engine.step(steps)
                due -= steps
                if self.engine.steps % self.steps_per_pose == 0:
                    self._publish()
                if self.steps_per_scan and self.engine.steps % self.steps_per_scan == 0:
                    self._publish_scans()
        except Unstable as exc:
            self._blew_up(exc)
        self._log_contacts()

    def _blew_up(self, exc: Unstable) -> None:
        """Stop at the step that made a pose absurd: say so in one line; exit ENGINE_FAILED."""
        self.timer.cancel()
        self.exit_code = ENGINE_FAILED
        self.get_logger().error(f'world: {unstable_line(exc, self.world, self.unicycles)}')

    def _note_late(self, rows: NDArray[np.intp], stamps: NDArray[np.int64]) -> None:
        """Count commands already older than ``world.cmd_timeout`` when applied; log once each."""
        ages = self.engine.time_ns - stamps
        late = ages > self.world.cmd_timeout_ns
        self.late[rows[late]] += 1
        for index, age in zip(rows[late].tolist(), ages[late].tolist()):
            self.once.start(f'late-{index}', (
                f'robot {index + 1}: cmd_vel stamped {age / NS_PER_S:.3g} s before the '
                "world's time, older than world.cmd_timeout: its motors stay stopped (a sender "
                'far behind, or on another clock?); counted in /diagnostics'), 'error')

    def _publish(self) -> None:
        """Publish /clock, then every robot's measured pose and odometry, all at one stamp."""
        t_ns = self.engine.time_ns
        self.clock_pub.publish(encode_clock(t_ns))
        measured = self.engine.measured_poses()
        frame = self.config.world_frame
        for pub, position, orientation in zip(self.pose_pubs, measured.positions,
                                              measured.orientations):
            pub.publish(encode_pose_stamped(t_ns, frame, position, orientation))
        if self.odometry_pubs:
            self._publish_odometry(t_ns)
        if self.output.running:
            self._sample(t_ns)

    def _publish_scans(self) -> None:
        """Publish every robot's laser scan, stamped now (simulated time), in its base_scan."""
        if not self.scan_pubs:
            return
        assert self.engine.scanner is not None
        t_ns = self.engine.time_ns
        shape = self.engine.scanner.shape
        for pub, frame, ranges in zip(self.scan_pubs, self.scan_frames, self.engine.scans()):
            pub.publish(messages.laser_scan(t_ns, frame, shape, ranges, self.scan_time))

    def _publish_odometry(self, t_ns: int) -> None:
        """Publish each base's wheel odometry: pose in world_frame, (v, w) in its base_link."""
        assert self.engine.odometer is not None
        positions, headings = self.engine.odometry()
        quaternions = quaternions_from_headings(headings)
        rates = self.engine.odometer.rates
        frame = self.config.world_frame
        for i, pub in enumerate(self.odometry_pubs):
            pub.publish(encode_odometry(
                t_ns, frame, self.command_frames[i],
                (positions[i, 0], positions[i, 1], ODOMETRY_HEIGHT), quaternions[i],
                (rates[i, 0], 0.0, 0.0), (0.0, 0.0, rates[i, 1])))

    def _held(self) -> NDArray[np.float64]:
        """Return the commands driving the motors now (N, width); zero for stale or none."""
        return np.where(self.engine.live()[:, None], self.engine.command, 0.0)

    def on_state_heard(self, index: int, data: bytes) -> None:
        """Keep the pose of a state robot ``index`` heard (its ``pose``), by its stamp."""
        assert self.heard is not None
        try:
            pose = read_pose_stamped(data, exact=True)
        except CdrError:
            return
        if pose.frame_id == self.config.world_frame:
            self.heard.hear(index, pose.stamp_ns, pose.position, pose.orientation)

    def _sample(self, t_ns: int) -> None:
        """
        Keep one trajectory sample as the plant writes it (hand points for unicycles).

        u: what each robot commanded, its held command read at the orientation of the state it
        answered (``core.model.commanded``; NaN where the world did not hear that state, or for
        unstamped commands, which do not say which state); u_held, for commands that need a
        heading: the held command read at the body's true heading now.
        """
        positions, headings = self.engine.planar_state()
        held = self._held()
        t = t_ns / NS_PER_S
        if not needs_orientation(self.unicycles, self.body_frame):
            if self.heard is None:
                self.output.append(t, positions, held)
            else:
                answered = self.heard.positions(self.engine.stamp_ns)[:, :self.dim]
                self.output.append(t, positions, held, q_answered=answered)
            return
        answered = (self.heard.rows(self.engine.stamp_ns) if self.heard is not None
                    else np.full((self.n, 4), np.nan))
        where = (self.heard.positions(self.engine.stamp_ns)[:, :self.dim]
                 if self.heard is not None else np.full((self.n, self.dim), np.nan))
        distance = self.config.body.hand_distance
        commanded, at_truth = (
            commanded_velocity(held, orientations, self.unicycles, distance, self.body_frame)
            for orientations in (answered, quaternions_from_headings(headings)))
        if self.unicycles:
            with np.errstate(invalid='ignore'):
                points = self.bodies.control_points(where, headings_from_quaternions(answered))
            self.output.append(t, self.bodies.control_points(positions, headings), commanded,
                               heading=headings, q_body=positions, body_command=held,
                               u_held=at_truth, q_answered=points)
            return
        self.output.append(t, positions, commanded, u_held=at_truth, q_answered=where)

    def _log_contacts(self) -> None:
        """Log each new contact (two robots; a robot and an obstacle) once, with its time."""
        labels = self.engine.labels
        self.contacts_logged = self._log_new(
            self.engine.contacts.events, self.contacts_logged, ('contact', 'contacts'),
            lambda event: f'robots {event.i} and {event.j} touched at t = {event.t:.3f} s')
        self.obstacle_contacts_logged = self._log_new(
            self.engine.obstacle_contacts.events, self.obstacle_contacts_logged,
            ('obstacle contact', 'contacts with obstacles'),
            lambda hit: f'robot {hit.robot} touched {labels[hit.obstacle]} at t = {hit.t:.3f} s')

    def _log_new(self, events: Sequence[Any], logged: int, names: Tuple[str, str],
                 line: Callable[[Any], str]) -> int:
        """
        Log the events after the first ``logged``, up to CONTACT_LINES; return how many there are.

        names: (one, the rest), e.g. ('contact', 'contacts'): how a line and the last line's
        note name them; line: the text of an event.
        """
        one, rest = names
        for number in range(logged + 1, min(len(events), CONTACT_LINES) + 1):
            last = (f'; further {rest} are counted in /diagnostics only'
                    if number == CONTACT_LINES else '')
            self.get_logger().error(f'{one} {number}: {line(events[number - 1])}{last}')
        return len(events)

    def on_diagnostics(self) -> None:
        """Publish the world's status: time, step rate, real-time factor, contacts, refusals."""
        now = time.monotonic_ns()
        since, steps = self.rate_window
        self.rate_window = (now, self.engine.steps)
        wall = (now - since) / NS_PER_S
        rate = (self.engine.steps - steps) / wall if wall > 0.0 else 0.0
        factor = rate * self.world.timestep
        target = self.world.realtime_factor
        running = self.pacer.started_ns is not None
        behind = running and wall >= PERIOD / 2 and factor < KEPT_UP * target
        if behind:
            self.once.start('behind', f'world: stepping at {factor:.2f} x real time of '
                                      f'{target:g} asked (too many robots for this machine, '
                                      'or a busy one); counted in /diagnostics')
        else:
            self.once.end('behind', 'world: keeping up with real time again')
        live = np.flatnonzero(self.engine.live()) + 1
        values: Dict[str, Any] = {
            'simulated time [s]': self.engine.time_s,
            'step rate achieved [Hz]': rate,
            'step rate target [Hz]': target / self.world.timestep,
            'realtime factor achieved': factor,
            'realtime factor target': target,
            'realtime factor since start': self.pacer.achieved(now, self.engine.steps),
            'ticks behind': self.pacer.falls,
            'simulated time let go [s]': self.pacer.dropped_s,
            'steps': self.engine.steps,
            'contacts': self.engine.contacts.count,
            'min body distance [m]': self.engine.closest.distance,
            **identity(self),
            'robots with live commands': ', '.join(map(str, live.tolist())) or 'none',
            'refused cmd_vel messages': self.refusals.refusals.count(),
            'robots with stale cmd_vel on arrival': ', '.join(
                f'{i + 1}: {count}' for i, count in enumerate(self.late.tolist()) if count)
            or 'none'}
        if self.engine.obstacles.count:
            values.update({'obstacle contacts': self.engine.obstacle_contacts.count,
                           'min obstacle gap [m]': self.engine.obstacle_approach.gap})
        values.update({f'robot {index + 1}: refused cmd_vel messages ({reason.name.lower()})':
                       count for (index, reason), count in self.refusals.refusals.items()})
        contacts = self.engine.contacts.count
        hits = self.engine.obstacle_contacts.count
        if contacts or hits or behind or self.refusals.refusals.count():
            level, message = 'warn', (f'{contacts} contacts, {hits} with obstacles, '
                                      f'{self.refusals.refusals.count()} refused commands, '
                                      f'{factor:.2f} x real time of {target:g}')
        elif self.refusal is not None:
            level, message = 'error', self.refusal
        else:
            level, message = 'ok', 'running' if running else (
                'starting' if self.gate.looked else self.gate.phase.value)
        self.diagnostics_pub.publish(diagnostics(WORLD_STATUS, level, message, values))

    def write_chunk(self) -> None:
        """Write the samples since the last chunk into ``world.output_dir`` (a failure: once)."""
        failed = self.output.flush(self.engine.time_s)
        if failed is not None:
            self.get_logger().error(failed)

    def finish(self) -> None:
        """Log a summary; with ``world.output_dir`` write world_stats.json and trajectory.npz."""
        if self.refusal is not None:
            return
        if self.pacer.started_ns is None:
            self.get_logger().info('world: stopped before the first step')
            return
        wall = self.pacer.wall_s(time.monotonic_ns())
        stats = self.engine.stats(
            wall, self.pacer,
            {i + 1: count for i, count in enumerate(self.late.tolist()) if count},
            {reason.name.lower(): {index + 1: count for (index, why), count
                                   in self.refusals.refusals.items() if why is reason}
             for reason in REFUSAL_WORDS})
        failure = self.output.failure
        self.get_logger().info(
            f'world: {stats.steps} steps ({stats.simulated_time:.2f} s simulated in '
            f'{wall:.1f} s, {stats.achieved_realtime_factor:.3g} x real time of '
            f'{self.world.realtime_factor:g}), {stats.contacts} contacts between robots, '
            f'min body distance {stats.min_body_distance:.4g} m, '
            + (f'{stats.obstacle_contacts} contacts with obstacles, min obstacle gap '
               f'{stats.min_obstacle_gap:.4g} m, ' if self.engine.obstacles.count else '')
            + f'{self.refusals.refusals.count()} cmd_vel messages refused'
            + (f'; output stopped early: {failure}' if failure else '')
            + ('; the engine blew up' if self.engine.failure is not None else ''))
        if not self.output.running:
            return
        failed = self.output.write(WORLD_STATS_FILE, stats.record(),
                                   self.config.reference().sample,
                                   FixedShape(self.config.vertices), self.unicycles,
                                   self.engine.time_s)
        if failed is not None:
            self.get_logger().error(failed)
            return
        written = [WORLD_FILE, WORLD_STATS_FILE] + (
            [TRAJECTORY_FILE] if self.output.trajectory_written else [])
        self.get_logger().info(f"world: wrote {', '.join(written)} to {self.output_dir}")


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros world``."""
    return run(WorldNode, args, name='world', robots_rule=world_size_problem)
