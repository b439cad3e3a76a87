# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Plant node (executable ``plant``): the robots' bodies and range sensors on the ROS graph.

It steps :class:`formation_ros.core.model.plant.PlantModel` (the model ``formation_sim --dt``
steps) with the commands it hears and publishes ``/clock``, what each robot senses,
``/diagnostics`` and ``/formation/markers``; with ``plant.output_dir`` it writes ``trajectory.npz``
and ``plant_stats.json``. Topics, transports, start-up and lockstep: docs/ros_interface.md; faults
and another team on the domain: docs/faults.md. Its rules are core objects it feeds with what
it read: the start gate (``core.rules.plant_gate``), the intake of commands
(``core.rules.plant_intake``), the pace (``core.rules.pacing``), the run statistics
(``core.rules.plant_stats``), the output (``core.runs.output``) and the status
(``core.rules.plant_status``). Callbacks store, timers act.
"""

import time
from typing import List, Optional

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.frames import desired_positions
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.model.plant import PLANT_STATS_FILE, PlantModel, StepReport
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.lockstep import AnswerWait
from formation_ros.core.rules.obstacle_watch import ObstacleWatch
from formation_ros.core.rules.pacing import Pacer
from formation_ros.core.rules.plant_gate import (CLOCK_MATCH_LINE, ClockMatch, GAVE_UP_LINE,
                                                 leftover_line, Phase, StartGate, Verdict,
                                                 waiting_line)
from formation_ros.core.rules.plant_intake import CommandIntake, Source, TEAM
from formation_ros.core.rules.plant_stats import RunStats, trajectory_sample
from formation_ros.core.rules.plant_status import (collision_lines, CommandWatch, Heard, Note,
                                                   PlantStatus, start_line, violation_lines)
from formation_ros.core.runs.events import event_records, timeline_events
from formation_ros.core.runs.output import RunOutput
from formation_ros.core.runs.timeline import Mode
from formation_ros.core.runs.trajectory import TRAJECTORY_FILE
from formation_ros.core.settings.declarations import CommandFrame, Exe
from formation_ros.core.settings.exits import REFUSED
from formation_ros.core.settings.team import team_values
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import CdrError, read_twist, read_twist_stamped, TeamCommandReader
from formation_ros.ros.changes import Changes
from formation_ros.ros.clock_look import look_at_clock, refusal
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.markers import formation_markers, Paths
from formation_ros.ros.once import OnceLog, RefusalLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.plant_topics import PlantTopics
from formation_ros.ros.runner import run
from formation_ros.ros.team import announced, DomainWatch, team_problems, TeamCheck
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import Twist, TwistStamped
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from trajectory_msgs.msg import MultiDOFJointTrajectory
from visualization_msgs.msg import MarkerArray

PLANT_STATUS = 'formation_ros/plant'
RESEND_AFTER = 0.05
"""Lockstep: seconds after which a state not answered is sent again."""
PATH_LENGTH = 100
CHUNK_PERIOD = 1.0
REFUSAL_HEARD = 2.0
"""How long a refusing plant waits for its last status to be acknowledged, s."""


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
        self.n, self.dim = config.num_robots, config.dim
        self.unicycles = config.body.is_unicycle
        body_frame = config.command.frame is CommandFrame.BODY
        self.intake = CommandIntake(
            [messages.body_frame(i) if body_frame else config.world_frame
             for i in range(1, self.n + 1)], config.world_frame, self.dim, self.unicycles,
            config.command.stamped)
        self.refusals = RefusalLog(self.once, self.intake.line)
        self.changes = Changes(self, config, self.steady,
                               lambda what, why: self.refusals.refuse(what, Reason.CHANGE, why))
        self.reference = self.changes.reference
        self.model = PlantModel(config.start, config.sensing_radii, settings.step_ns, self.law,
                                self.reference, settings.input_timeout_ns,
                                settings.collision_distance, settings.max_speed,
                                bodies=make_bodies(config.body, settings.max_speed,
                                                   body_frame=body_frame and not self.unicycles),
                                headings=config.start_headings,
                                imperfections=config.imperfections,
                                obstacles=config.law_obstacles())
        self.lockstep, self.team_transport = config.lockstep, config.team_transport
        self.answer_wait = AnswerWait()
        self.publish_every = 1 if self.lockstep else settings.steps_per_publish
        self.own_name = self.get_fully_qualified_name()
        self.gate = StartGate(time.monotonic(), settings.wait_for_robots or self.lockstep,
                              self.own_name)
        self.stats = RunStats(self.model, self.publish_every, self.lockstep, self.unicycles)
        self.pacer = Pacer(settings.step_ns, settings.realtime_factor, settings.step_ns)
        self.watch = CommandWatch(self.n)
        self.status_report = PlantStatus(
            self.lockstep, self.unicycles, self.team_transport,
            settings.realtime_factor / self.model.dt, self.publish_every, self.law.u_bound,
            time.monotonic())
        self.team_check = TeamCheck(self, PLANT_STATUS)
        self.refusal: Optional[str] = None
        self.exit_code: Optional[int] = None
        self.clock_heard = 0
        self.output = RunOutput(settings.output_dir, 'plant', 'the plant goes on controlling',
                                config.feed_forward_guard())
        if settings.output_dir:
            failed = self.output.start(self.model.t)
            if failed is not None:
                self.get_logger().error(failed)
        self.paths = Paths(self.n, PATH_LENGTH)
        self.last_publish_wall = 0.0
        self.state_topics = PlantTopics(
            self, self.n, self.dim, config.world_frame, self.team_transport,
            self.team_transport and settings.wait_for_subscribers <= 1,
            self.unicycles or body_frame, self.steady, config.obstacles, config.sensing_radii)
        self.obstacle_watch = (None if config.obstacles is None
                               else ObstacleWatch(config.obstacles, config.body.radius))
        """The bodies against the real obstacles (``core.rules.obstacle_watch``), with a map."""
        self.command_topics: List[str] = []
        if self.team_transport:
            self.team_reader = TeamCommandReader(self.n)
            self.team_sub = self.create_subscription(
                MultiDOFJointTrajectory, topics.TEAM_COMMANDS, self.on_team_command,
                qos.team_commands_input(self.n), raw=True)
        else:
            self._command_topics()
        self.clock_sub = self.create_subscription(ClockMsg, topics.CLOCK, self.on_clock,
                                                  qos.CLOCK, raw=True)
        self.domain = DomainWatch(
            self, self.team_check, self.once,
            {**dict.fromkeys(self.state_topics.published_topics(), self.own_name),
             **dict.fromkeys(self.command_topics)}, self.command_topics,
            [topics.robot_node_name(i) for i in range(1, self.n + 1)]
            if self.team_transport else [])
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, topics.DIAGNOSTICS, qos.DIAGNOSTICS)
        period = RESEND_AFTER if self.lockstep else self.pacer.step_period_s
        self.step_timer = self.create_timer(period, self.advance_run, clock=self.steady)
        self.step_wake = Wake(self, self.advance_run, self.steady)
        self.diagnostics_timer = self.create_timer(PERIOD, self.on_diagnostics,
                                                   clock=self.steady)
        if settings.output_dir:
            self.chunk_timer = self.create_timer(CHUNK_PERIOD, self.write_chunk,
                                                 clock=self.steady)
        if settings.marker_rate > 0.0:
            self.marker_pub = self.create_publisher(MarkerArray, topics.MARKERS, qos.MARKERS)
            self.marker_timer = self.create_timer(1.0 / settings.marker_rate, self.on_markers,
                                                  clock=self.steady)
        self.get_logger().info(start_line(config, self.model.dt))

    def _command_topics(self) -> None:
        """Robot transport: hear each robot's cmd_vel, from any publisher (``COMMAND_INPUT``)."""
        for i in range(self.n):
            sub = self.create_subscription(
                TwistStamped if self.intake.stamped else Twist,
                topics.robot_topic(i + 1, topics.CMD_VEL),
                lambda data, index=i: self.on_command(index, data), qos.COMMAND_INPUT,
                raw=True)
            self.command_topics.append(sub.topic_name)

    def on_command(self, index: int, data: bytes) -> None:
        """Store robot ``index``'s command (``rules.plant_intake``); lockstep: wake the step."""
        try:
            command = read_twist_stamped(data) if self.intake.stamped else read_twist(data)
        except CdrError as exc:
            self.refusals.refuse(index, Reason.MALFORMED, str(exc))
            return
        reason = self.intake.take(index, command.frame_id, command.linear, command.angular,
                                  command.stamp_ns, time.monotonic_ns())
        self._took(index, reason, command.frame_id if reason is not Reason.NON_FINITE
                   else f'linear {command.linear}, angular {command.angular}')

    def on_team_command(self, data: bytes) -> None:
        """Team transport: store the commands of one team message, as :meth:`on_command`."""
        try:
            message = self.team_reader.read(data)
        except CdrError as exc:
            self.refusals.refuse(TEAM, Reason.MALFORMED, str(exc))
            return
        self._took(TEAM, self.intake.take_team(message.indices, message.frame_id,
                                               message.linear, message.angular,
                                               message.stamp_ns, time.monotonic_ns()),
                   message.frame_id)

    def _took(self, source: Source, reason: Optional[Reason], detail: str) -> None:
        """Count a refusal (logged once while it lasts), or in lockstep wake the step."""
        if reason is not None:
            self.refusals.refuse(source, reason, detail)
        elif self.lockstep:
            self.step_wake.arm()

    def on_clock(self, data: bytes) -> None:
        """While the plant looks at the domain: count /clock messages, which only others send."""
        self.clock_heard += 1

    def _vertices_at(self, t_ns: int) -> np.ndarray:
        """Return the shape in force at ``t_ns`` (N, dim), m."""
        return self.changes.shapes.at(t_ns).vertices

    def advance_run(self) -> None:
        """
        Start the run through the gate, then step.

        Free-running: a step a tick. Lockstep: once every robot has answered (woken by a
        command, and every RESEND_AFTER s to resend a state not answered).
        """
        now = time.monotonic()
        if not self.gate.looked and not self._look_at_domain(now):
            return
        if self.pacer.started_ns is None:
            self.pacer.start(time.monotonic_ns(), self.model.counts.steps)
            self._publish()
            return
        if self.gate.phase is Phase.WAITING and not self._start_clock(now):
            self._look_at_domain(now)
            return
        if self.lockstep:
            self._lockstep_tick(now)
            return
        self._step()
        if self.model.counts.steps % self.publish_every == 0:
            self._publish()

    def _look_at_domain(self, now: float, at_once: bool = False) -> bool:
        """
        Look up the other /clock publishers when the gate asks; return whether the domain is ours.

        The gate (``core.rules.plant_gate``) decides: refuse (exit REFUSED), end the look or go on.
        """
        if not self.gate.look_due(now, at_once):
            return self.gate.looked
        looking = self.gate.phase is Phase.LOOKING
        verdict, others = look_at_clock(self.domain.graph, self.team_check, self.gate,
                                        self.clock_heard > 0, now)
        if self.gate.phase is Phase.REFUSED:
            self.refusal = refusal(self.domain.graph, self.gate, self.context.get_domain_id(),
                                   now)
            self.get_logger().error(self.refusal)
            self.exit_code = REFUSED
        elif looking and self.gate.looked:
            if verdict is Verdict.LEFTOVER and others:
                self.once.start('leftover-clock', leftover_line(others[0],
                                                                now - self.gate.created))
            self.destroy_subscription(self.clock_sub)
        return self.gate.looked

    def _start_clock(self, now: float) -> bool:
        """While the clock waits: start it once every robot is up and /clock reaches them."""
        missing = self.intake.missing()
        wanted = self.settings.wait_for_subscribers - (1 if self.team_transport else 0)
        if missing or self.state_topics.unheard(wanted):
            self.once.start('waiting', waiting_line(
                missing, self.n, wanted, topics.STATES if self.team_transport else None), 'info')
            self._resend_if_due()
            return False
        match = self.gate.clock_match(self.state_topics.clock_unmatched(), now)
        if match is ClockMatch.WAIT:
            self.once.start('clock-match', CLOCK_MATCH_LINE, 'info')
            self._resend_if_due()
            return False
        if match is ClockMatch.GAVE_UP:
            self.get_logger().warning(GAVE_UP_LINE)
        self.gate.start()
        if self.team_transport:
            self.state_topics.look_at_listeners()
        self.pacer.start(time.monotonic_ns(), self.model.counts.steps)
        self.status_report.restart(now, self.model.counts.steps)
        self.once.end('clock-match')
        self.once.end('waiting')
        self.get_logger().info(f'all {self.n} robots are up: starting the clock')
        self._publish()
        return True

    def _lockstep_tick(self, now: float) -> None:
        """Lockstep: step once every robot answered and the run is not ahead; else resend."""
        ahead_s = self.pacer.ahead_ns(time.monotonic_ns(), self.model.counts.steps) / NS_PER_S
        answered = self.intake.answered(self.model.t_ns)
        line = self.answer_wait.look([] if answered else self.intake.silent(self.model.t_ns),
                                     now)
        if line is not None:
            if answered:
                self.get_logger().info(line)
            else:
                self.get_logger().warning(line)
        if answered and ahead_s <= 0.0:
            self._step()
            self._publish()
        elif answered:
            self.step_wake.arm(ahead_s)
        else:
            self._resend_if_due()

    def _step(self) -> None:
        """Step the model with the commands held; keep a sample and say what changed."""
        self.stats.answers.time(self.intake.commands, self.intake.arrived_ns)
        held = self.changes.states.at(self.model.t_ns).mode is Mode.STOPPED
        report = self.model.advance(self.intake.commands)
        if self.stats.stepped(self.model, report, held) and self.output.running:
            t, q, u, extras = trajectory_sample(report, self.unicycles)
            self.output.append(t, q, u, **extras)
        self._log(report)
        if self.obstacle_watch is not None:
            for line in self.obstacle_watch.step(self.model.q, self.model.t):
                self.get_logger().error(line)

    def _log(self, report: StepReport) -> None:
        """Say once what changed: a robot's command status, a bound violation, a collision."""
        for note in self.watch.update(report.admission.status, self.intake.commands.stamp_ns,
                                      report.t_ns):
            self._say(note)
        for line in violation_lines(report, self.law.u_bound,
                                    self.model.counts.bound_violations):
            self.get_logger().error(line, throttle_duration_sec=1.0)
        for line in collision_lines(report, self.model.t,
                                    self.model.body.contact_distance > 0.0):
            self.get_logger().error(line)

    def _say(self, note: Note) -> None:
        """Log a condition's start or end once (``core.rules.plant_status.Note``)."""
        if note.starts:
            self.once.start_group(list(note.keys), note.line, note.level)
        elif note.line is not None:
            self.once.end_group(list(note.keys), note.line)
        else:
            for key in note.keys:
                self.once.end(key)

    def _publish(self) -> None:
        """Publish /clock and the state (``ros.plant_topics``); note when, for the latency."""
        stamp_ns = self.state_topics.publish(self.model)
        self.intake.state_stamp_ns = stamp_ns
        self.stats.answers.published(stamp_ns, time.monotonic_ns())
        self.last_publish_wall = time.monotonic()
        if self.lockstep and self.gate.phase is Phase.RUNNING:
            self.answer_wait.published(stamp_ns, self.last_publish_wall)

    def _resend_if_due(self) -> None:
        if time.monotonic() - self.last_publish_wall > RESEND_AFTER:
            self._publish()

    def on_diagnostics(self) -> None:
        """
        Publish the plant's status (``core.rules.plant_status``).

        While the clock waits for the robots the domain is looked at first: another team is
        the gate's to refuse, in one line.
        """
        if self.gate.phase is Phase.WAITING:
            self._look_at_domain(time.monotonic(), at_once=True)
        now = time.monotonic()
        shape = self._vertices_at(self.model.t_ns)
        heard = Heard(self._command_states(),
                      announced=announced(team_values(self.config, shape), self),
                      disagreeing=team_problems(self.team_check, self.config, shape, self.once))
        if self.gate.looked:
            heard.shared = self.domain.shared_topics(now, topics.CLOCK,
                                                     self.gate.phase is Phase.RUNNING)
            heard.doubled, heard.plants = (self.domain.doubled_robots(now),
                                           self.domain.other_plants(now))
        heard.waiting = self.answer_wait.values(now)
        if self.team_transport:
            heard.team_publishers = self.team_sub.get_publisher_count()
            heard.listened = self.state_topics.listened
        level, message, values = self.status_report.report(
            now, self.model, self.gate.phase, self.changes.states.at(self.model.t_ns).mode.value,
            self.stats.held_steps, self.refusals.refusals, heard)
        if self.obstacle_watch is not None:
            values.update(self.obstacle_watch.values())
            if self.obstacle_watch.contacts:
                level, message = 'error', (f'{self.obstacle_watch.contacts} obstacle contacts; '
                                           + message)
        self.diagnostics_pub.publish(diagnostics(PLANT_STATUS, level, message, values))

    def _command_states(self) -> List[str]:
        """
        Return each robot's 'alive', 'lost' or 'unknown', as its commands show it.

        Whether its latest command came within the liveliness lease or two state periods,
        whichever is longer: a robot answers every state, whoever publishes its commands.
        """
        state_period = self.publish_every * self.model.dt / self.settings.realtime_factor
        lease = max(qos.LIVELINESS_LEASE, 2.0 * state_period)
        return self.intake.arrival_states(time.monotonic_ns(), int(lease * NS_PER_S))

    def on_markers(self) -> None:
        """Keep the paths; publish the RViz picture only while someone subscribes."""
        self.paths.append(self.model.q)
        if self.marker_pub.get_subscription_count() == 0:
            return
        desired = desired_positions(self._vertices_at(self.model.t_ns),
                                    self.reference.sample(self.model.t))
        self.marker_pub.publish(formation_markers(
            self.model.q, self.config.sensing_radii, self.law.repulsion_radius, desired,
            self.paths, self.model.t_ns, self.config.world_frame,
            self.model.heading if self.unicycles else None, self.config.obstacles))

    def write_chunk(self) -> None:
        """Write the samples since the last chunk into ``plant.output_dir`` (a failure: once)."""
        failed = self.output.flush(self.model.t)
        if failed is not None:
            self.get_logger().error(failed)

    def finish(self) -> None:
        """Log a summary of the run; with ``plant.output_dir`` write trajectory and counters."""
        if self.refusal:
            self._announce_refusal()
            return
        if self.pacer.started_ns is None or self.model.counts.steps == 0:
            self.get_logger().info('plant: stopped before the first step')
            return
        wall = self.pacer.wall_s(time.monotonic_ns())
        desired = desired_positions(self._vertices_at(self.model.t_ns),
                                    self.reference.sample(self.model.t))
        failure = self.output.failure
        obstacles = ('' if self.obstacle_watch is None
                     else f', {self.obstacle_watch.summary()}')
        self.get_logger().info(self.stats.summary(self.model, wall, desired, self.law.u_bound)
                               + obstacles
                               + (f'; output stopped early: {failure}' if failure else ''))
        if not self.output.running:
            return
        record = self.stats.record(
            self.model, wall, self.refusals.refusals, len(self.changes.shapes.changes()),
            event_records(timeline_events(self.changes.shapes, self.changes.states)),
            self.config.imperfections.as_dict(), self.config.transport.value)
        if self.obstacle_watch is not None:
            record.update(self.obstacle_watch.record())
        failed = self.output.write(PLANT_STATS_FILE, record, self.reference.sample,
                                   self._vertices_at, self.unicycles, self.model.t)
        if failed is not None:
            self.get_logger().error(failed)
            return
        self.get_logger().info(f'plant: wrote {TRAJECTORY_FILE} and {PLANT_STATS_FILE} to '
                               f'{self.settings.output_dir}')

    def _announce_refusal(self) -> None:
        """Publish the refusal as the last status (the other plant names this one from it)."""
        shape = self._vertices_at(self.model.t_ns)
        self.diagnostics_pub.publish(diagnostics(
            PLANT_STATUS, 'error', self.refusal,
            announced(team_values(self.config, shape), self)))
        self.diagnostics_pub.wait_for_all_acked(Duration(seconds=REFUSAL_HEARD))


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros plant``."""
    return run(PlantNode, args, name='plant')
