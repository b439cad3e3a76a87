# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Robot node (executable ``robot``): one robot's bounded formation controller.

:class:`RobotNode` adapts messages and timers to the robot's rules, which hold no ROS: what it
takes of its states and their clock (``core.rules.robot_intake``), the reference it follows
(``core.rules.reference_track``), and what it answers, when, and with which commands
(``core.rules.robot_core.RobotCore``). Callbacks read the bytes (``ros.cdr``), admit and note
them in the core and arm a one-shot timer (``ros.wake``) that asks the core and does what it
answers through one output: the robot's ``cmd_vel`` (:class:`CmdVelOutput`), or with
``transport: team`` its process's link (``nodes.robots_link``), which serves the first robot
with a core of all its robots. Topics, parameters and behaviour:
docs/ros_interface.md ("Nodes", "Behaviour of the nodes", "Transports"); faults:
docs/faults.md. One per robot::

    ros2 run formation_ros robot --ros-args -r __ns:=/robot_1 -p robot_id:=1 \\
        --params-file config/paper_section5.yaml -p use_sim_time:=true
"""

import dataclasses
import time
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.law import Command
from formation_ros.core.maths.obstacles import MAX_TOLD, quaternion_normals
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.answers import AnswerPolicy
from formation_ros.core.rules.control import Control, Sensed
from formation_ros.core.rules.reference_track import ReferenceTrack
from formation_ros.core.rules.robot_core import Answer, Note, RobotCore, Said, Wake as Due
from formation_ros.core.rules.robot_intake import Refused, StateIntake
from formation_ros.core.rules.robot_status import startup_line, status_level, status_values
from formation_ros.core.rules.scan_obstacles import MAX_RAYS, ScanObstacles
from formation_ros.core.runs.timeline import Shape, TeamState
from formation_ros.core.settings.declarations import CommandFrame, Exe, PoseType
from formation_ros.core.settings.names import robot_name
from formation_ros.core.settings.team import reference_values, team_values
from formation_ros.nodes.robots_link import Linked, RobotsLink
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import (PoseArrayData, PoseData, read_laser_scan, read_odometry,
                                   read_pose_array, read_pose_stamped, StatusData)
from formation_ros.ros.changes import Changes
from formation_ros.ros.command_output import CmdVel, CmdVelOutput, Output
from formation_ros.ros.diagnostics import encode_statuses, make_status, PERIOD
from formation_ros.ros.once import OnceLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.robot_inputs import InputGate
from formation_ros.ros.runner import run
from formation_ros.ros.sim_clock import sim_time_without_clock, StateClock, wall_clock_overrides
from formation_ros.ros.team import announced
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray, PoseStamped
from nav_msgs.msg import Odometry
import numpy as np
from numpy.typing import ArrayLike, NDArray
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.publisher import Publisher
from sensor_msgs.msg import LaserScan

LAST_WORD = 0.5
"""How long a stopping robot waits for its last (zero) command to be received, s."""


class RobotNode(Node):
    """One robot: stores what it hears in callbacks, computes and publishes in its timers."""

    def __init__(self, leader: Optional['RobotNode'] = None, reports: bool = True,
                 **kwargs: Any) -> None:
        """
        Declare and check parameters, then set up topics and timers.

        ``leader``: the first robot of this process (a fleet's other robots); this robot then
        hears the reference and the changes through it, with ``transport: team`` always, else
        if it has the leader's ``core.settings.team.reference_values``. ``reports``:
        whether it publishes on /diagnostics itself (a fleet's first robot publishes the others'
        statuses, :attr:`reported`).
        """
        given = list(kwargs.pop('parameter_overrides', None) or [])
        super().__init__('robot', parameter_overrides=wall_clock_overrides(given), **kwargs)
        self.sim_time = sim_time_without_clock(self, given)
        config = self.config = declare_parameters(self, Exe.ROBOT)
        settings = config.robot
        assert settings is not None
        self.dim, self.index, self.lockstep = config.dim, settings.robot_id - 1, config.lockstep
        self.vertex = config.vertices[self.index]
        self.sensing_radius = float(config.sensing_radii[self.index])
        self.law = config.law()
        self.timeout_ns = int(settings.input_timeout * NS_PER_S)
        self.unicycle = config.body.is_unicycle
        body_frame = config.command.frame is CommandFrame.BODY
        self.scan = (None if settings.scan is None else
                     ScanObstacles(settings.scan, self.sensing_radius, config.body.radius))
        """This robot's obstacles from its own scans (``obstacles.source: scan``), or None."""
        self.needs_orientation = body_frame or self.scan is not None
        """Whether its pose's orientation is needed besides a unicycle's heading: a body-frame
        command, or a scan to place."""
        self.command_frame = (messages.body_frame(settings.robot_id) if body_frame
                              else config.world_frame)
        self.control = Control(self.law, [self.sensing_radius], self.dim, self.unicycle,
                               config.body.hand_distance, body_frame, config.body.footprint,
                               config.obstacle_clearance)
        """This robot's law and command frame (what it senses, its diagnostics)."""
        self.evaluates = config.team_transport or self.sim_time
        """Whether this robot evaluates the reference at each state's stamp itself."""
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.state_clock = StateClock(self)
        shares = leader is not None and (config.team_transport or reference_values(config.values)
                                         == reference_values(leader.config.values))
        self.inputs = InputGate(self, StateIntake(
            config.world_frame, self.timeout_ns, self.sim_time, self.state_clock.follows_states,
            'a unicycle' if self.unicycle else
            'command.frame body' if body_frame else 'obstacles.source scan'), self.state_clock,
            self.once, leader.inputs.expected if shares and leader is not None else {})
        period = settings.answer_period(self.sim_time)
        self.watch_ns = max(1, int(round(NS_PER_S / settings.control_rate)))
        self.policy = AnswerPolicy(max(1, int(round(period * NS_PER_S))), self.timeout_ns,
                                   self.watch_ns, settings.wait_for_subscribers)
        self.pose: Optional[PoseData] = None
        self.neighbours: Optional[PoseArrayData] = None
        self.obstacles: Optional[PoseArrayData] = None
        """The latest obstacles admitted (None: none heard: the law as without obstacles)."""
        self.unplaced_stamp: Optional[int] = None
        """The stamp of the latest scan counted as unplaced (counted once)."""
        self.core: Optional[RobotCore] = None
        """What decides this robot's answers (a link's first robot: all of its robots'); None
        for a link's other robots, answered by the first."""
        self.last: Optional[Tuple[Command, Optional[NDArray[np.float64]]]] = None
        """This robot's latest command and its published form (diagnostics)."""
        self.flooded_reported = 0
        self.first: RobotNode = self
        """The robot that hears the reference and the changes for this one (or itself)."""
        self.followers: List[RobotNode] = []
        self.linked: Optional[Linked] = None
        """What this robot's link tells of it (team transport), once :meth:`join` ed."""
        self.answering = self.policy
        """The policy of the robot that answers for this one (its link's leader, or itself)."""
        if not config.team_transport:
            self._subscribe_to_states(settings.pose_type)
        if self.scan is not None:
            self.create_subscription(LaserScan, topics.SCAN, self.on_scan, qos.MEASUREMENT,
                                     raw=True)
        if shares and leader is not None:
            self.first = leader
            leader.followers.append(self)
            self.changes, self.track = leader.changes, leader.track
        else:
            reference = self.create_subscription(Odometry, topics.REFERENCE, self.on_reference,
                                                 qos.REFERENCE, raw=True)
            self.inputs.expected[reference.topic_name] = None
            if self.sim_time:
                self.inputs.expected[topics.CLOCK] = None
            self.changes = Changes(self, config, self.steady, self._refuse_change,
                                   self._new_state)
            self.track = ReferenceTrack(self.changes.reference, self.dim, config.world_frame,
                                        config.reference().rate_limits(), self.evaluates,
                                        self.timeout_ns)
        self.cmd_vel = CmdVel(self, config.command.stamped, self.command_frame,
                              config.team_transport,
                              config.team_transport and settings.wait_for_subscribers <= 1)
        self.output: Optional[Output] = None
        """Where this robot's commands go (None: a link's robot its leader answers for)."""
        self.reported: List[RobotNode] = [self]
        """The robots whose statuses this node publishes (a fleet's first robot: all of its)."""
        self.announcing: Optional[Tuple[Shape, Dict[str, str]]] = None
        self.diagnostics_pub: Optional[Publisher] = None
        if reports:
            self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS,
                                                         qos.DIAGNOSTICS)
            self.create_timer(PERIOD, self.on_diagnostics, clock=self.steady)
        self.answer = Wake(self, self.on_state, self.steady)
        self.watchdog: Optional[Wake] = None
        if not config.team_transport:
            self.serve(CmdVelOutput(self.cmd_vel, self.control), self.control, self._sensed_alone)
        self.get_logger().info(startup_line(config, self.index, self.command_frame,
                                            self.sim_time))

    def serve(self, output: Output, control: Control,
              senses: Callable[[], Sensed]) -> RobotCore:
        """
        Answer, through ``output``, the states of the robots ``control`` commands (once).

        senses: what they know of the state heard last; a robot alone serves itself, a link's
        first robot all of the link's robots. Out of lockstep its watchdog starts. Return the
        core that decides.
        """
        assert self.core is None
        self.output = output
        self.core = RobotCore(control, senses, self.policy, self.track, self.changes,
                              output.listeners, output.what, self.lockstep, self.evaluates,
                              self.timeout_ns)
        if not self.lockstep:
            self.watchdog = Wake(self, self.on_watchdog, self.steady)
            self.watchdog.arm(self.watch_ns / NS_PER_S)
        return self.core

    def join(self, linked: Linked, answering: AnswerPolicy) -> None:
        """Be one of a link's robots: ``linked`` tells of it, ``answering`` answers for all."""
        self.linked, self.answering = linked, answering

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
        if self.config.obstacle_clearance is not None and self.scan is None:
            self.create_subscription(PoseArray, topics.OBSTACLES, self.on_obstacles,
                                     qos.STATE_INPUT, raw=True)

    @staticmethod
    def now_ns() -> int:
        """Steady time, ns: the clock of the timers (CLOCK_MONOTONIC), read without rclpy."""
        return time.monotonic_ns()

    def admit_state(self, name: str, state: PoseArrayData, needs_orientation: bool,
                    finite: Optional[bool] = None) -> bool:
        """Admit a state of input ``name`` (``InputGate.admit_state``) as of now."""
        return self.inputs.admit_state(name, state, needs_orientation,
                                       self.policy.received_ns['pose'], self.now_ns(), finite)

    def on_pose(self, data: bytes) -> None:
        """Store the latest own pose, read from the serialized PoseStamped."""
        pose = self.inputs.read('pose', read_pose_stamped, data)
        if pose is not None:
            self._store_pose(pose)

    def on_odometry(self, data: bytes) -> None:
        """Store the latest own pose, read from a serialized nav_msgs/Odometry."""
        odometry = self.inputs.read('pose', read_odometry, data)
        if odometry is not None:
            self._store_pose(odometry.pose)

    def _store_pose(self, pose: PoseData) -> None:
        state = PoseArrayData(pose.stamp_ns, pose.frame_id, np.array([pose.position]),
                              np.array([pose.orientation]))
        if self.admit_state('pose', state, self.needs_orientation, pose.finite):
            self.pose = pose
            if self.scan is not None:
                self.scan.pose_heard(pose.stamp_ns, pose.position, pose.orientation)
            assert self.core is not None
            self._arm(self.core.pose_heard(pose.stamp_ns, self.now_ns()))

    def on_neighbours(self, data: bytes) -> None:
        """Store the latest sensed neighbour positions, read from the serialized PoseArray."""
        most = self.config.num_robots - 1
        heard = self.inputs.read('neighbour', lambda raw: read_pose_array(raw, most), data)
        if heard is not None and self.admit_state('neighbour', heard, self.unicycle):
            self.neighbours = heard
            assert self.core is not None
            self._arm(self.core.neighbours_heard(heard.stamp_ns, self.now_ns()))

    def on_obstacles(self, data: bytes) -> None:
        """
        Store the latest obstacles heard, read from the serialized PoseArray (untrusted).

        Admitted as a state (world_frame, finite, unit quaternions, its stamp on this robot's
        clock), at most MAX_TOLD points, each normal with a direction in the team's space;
        then the state of that stamp waits for them (``RobotCore.obstacles_heard``).
        """
        heard = self.inputs.read('obstacles', lambda raw: read_pose_array(raw, MAX_TOLD), data,
                                 Reason.TOO_MANY_POINTS)
        if heard is None or not self.admit_state('obstacles', heard, True):
            return
        normals = quaternion_normals(heard.orientations, self.dim)
        if not np.all(np.any(normals != 0.0, axis=1)):
            self.inputs.refuse('obstacles', Refused(Reason.NO_NORMAL))
            return
        self.obstacles = heard
        assert self.core is not None
        self._arm(self.core.obstacles_heard(heard.stamp_ns, self.now_ns()))

    def on_scan(self, data: bytes) -> None:
        """
        Keep the latest scan, read from the serialized LaserScan (untrusted).

        Admitted in ``obstacles.scan_frame``, with at most MAX_RAYS rays, readable fields, not
        mostly NaN ranges and a stamp on this robot's clock (within input_timeout); placed in
        the world frame when a state is answered, if at most input_timeout older than it
        (``core.rules.scan_obstacles``).
        """
        scan = self.inputs.read('scan', lambda raw: read_laser_scan(raw, MAX_RAYS), data)
        if scan is None or self.scan is None:
            return
        refused = self.scan.refusal(scan)
        clock_ns = self.get_clock().now().nanoseconds
        gap = self.inputs.intake.gap_ns(scan.stamp_ns, clock_ns, False)
        if refused is None and abs(gap) > self.timeout_ns:
            refused = Refused(Reason.CLOCK, gap_s=gap / NS_PER_S)
        if refused is not None:
            self.inputs.refuse('scan', refused)
            return
        self.inputs.on_clock('scan', 'scan messages on this clock again')
        self.scan.scan_heard(scan)

    def _arm(self, due: Due) -> None:
        """Arm the answer when the core says it is due."""
        if due.now:
            self.answer.arm()
        elif due.after_ns is not None:
            self.answer.arm(due.after_ns / NS_PER_S)

    def see(self, pose: PoseData, neighbours: PoseArrayData, heard_ns: int, new: bool,
            last: Optional[Tuple[Command, Optional[NDArray[np.float64]]]] = None,
            obstacles: bool = False) -> None:
        """
        Take this robot's pose and neighbours in a state its link read, heard at ``heard_ns``.

        new: a state to answer (the link's leader); last: the robot's latest command and its
        published form (diagnostics), if one was computed; obstacles: the state's obstacles
        came with it.
        """
        self.pose, self.neighbours = pose, neighbours
        if self.core is not None:
            self.core.state_heard(pose.stamp_ns, heard_ns, new, obstacles)
        else:
            self.policy.heard(['pose', 'neighbour'], heard_ns, state=new)
        if last is not None:
            self.last = last

    def on_reference(self, data: bytes) -> None:
        """Keep a reference sample the track admits; wake the robots in lockstep."""
        sample = self.inputs.read('reference', read_odometry, data)
        if sample is None:
            return
        time_ns = (self.get_clock().now().nanoseconds if self.pose is None
                   else self.pose.stamp_ns)
        refused = self.track.refusal(sample, time_ns, lambda: bool(self.changes.take()))
        if refused is not None:
            self.inputs.refuse('reference', refused)
            return
        self.inputs.refusals.admitted('reference', Reason.OTHER_REFERENCE,
                                      'the reference is the one this robot evaluates again')
        now = self.now_ns()
        for node in [self] + self.followers:
            node.reference_heard(now)

    def reference_heard(self, now_ns: int) -> None:
        """Note a reference sample heard at ``now_ns`` (steady); answer it in lockstep."""
        if self.core is None:
            self.policy.heard(['reference'], now_ns)
        else:
            self._arm(self.core.reference_heard(now_ns))

    def _refuse_change(self, what: str, why: str) -> None:
        """Count and log once a shape or status refused (``ros.changes``)."""
        self.inputs.refused.add(what, Reason.CHANGE)
        self.once.start(f'{what}-refused', f'ignoring a {what} with {why} (logged once; '
                                           'diagnostics count them)', 'error')

    def _new_state(self, state: TeamState) -> None:
        """Admit reference samples as fast as the reference in force may be."""
        self.track.widen(state.reference(self.config.reference()).rate_limits())

    def _alone(self) -> Sensed:
        """Return this robot's own point and its neighbours' of the state stored."""
        assert self.pose is not None and self.neighbours is not None
        return self.control.alone(self.index, self.pose.position, self.pose.orientation,
                                  self.neighbours.positions, self.neighbours.orientations)

    def _sensed_alone(self) -> Sensed:
        """Return what this robot knows of the state stored, its obstacles with it."""
        sensed = self._alone()
        if self.scan is not None:
            return self._scanned(sensed)
        if self.obstacles is None:
            return sensed
        heard = self.control.heard_obstacles([(self.obstacles.positions,
                                               self.obstacles.orientations)])
        return dataclasses.replace(sensed, obstacles=heard)

    def _scanned(self, sensed: Sensed) -> Sensed:
        """Give ``sensed`` the obstacles of the latest scan; unseen if it cannot tell them."""
        assert self.pose is not None and self.neighbours is not None
        seen = self.scanned(self.pose.stamp_ns, self.pose.position, sensed.points[0],
                            self.neighbours.positions)
        if isinstance(seen, str):
            return dataclasses.replace(sensed, unseen=seen)
        return dataclasses.replace(sensed, obstacles=self.control.scanned_obstacles([seen]))

    def scanned(self, stamp_ns: int, position: ArrayLike, control_point: ArrayLike,
                neighbours: ArrayLike) -> Union[str, Tuple[NDArray[np.float64],
                                                           NDArray[np.float64]]]:
        """
        Return this robot's obstacles from its scan at the state ``stamp_ns``, or why none.

        position: (>= 2,) its pose's position and control_point (2,) its law's point, m;
        neighbours: (M, >= 2) the positions of the neighbours it sensed, m. Returns (points,
        normals) (``ScanObstacles.obstacles``), or the reason it cannot tell them
        (``ScanObstacles.unseen``; a scan it cannot place is counted once).
        """
        assert self.scan is not None
        unseen = self.scan.unseen(stamp_ns, self.timeout_ns)
        if unseen is not None:
            return unseen
        placed = self.scan.place(self.timeout_ns)
        if placed is None:
            stamp = None if self.scan.scan is None else self.scan.scan.stamp_ns
            if stamp is not None and stamp != self.unplaced_stamp:
                self.unplaced_stamp = stamp
                self.inputs.refuse('scan', Refused(Reason.UNPLACED))
            return 'its scan cannot be placed'
        return self.scan.obstacles(placed, position, control_point, neighbours)

    def on_state(self) -> None:
        """Answer a state as soon as its pose and neighbours are in (armed by the callbacks)."""
        if self.core is not None:
            self._do(self.core.on_state(self.now_ns(), self.get_clock().now().nanoseconds))

    def on_watchdog(self) -> None:
        """Watchdog: zero while an input is stale, else answer a state left over; re-armed."""
        if self.core is not None:
            self._do(self.core.on_watchdog(self.now_ns(), self.get_clock().now().nanoseconds))

    def _do(self, answer: Answer) -> None:
        """Do what the core answered: start, log, publish or send again, look again."""
        output, core = self.output, self.core
        assert output is not None and core is not None
        if answer.started:
            output.started()
        for note in answer.notes:
            self._say(note)
        if answer.publish:
            output.publish(answer.commands, answer.stamp_ns)
        elif answer.resend:
            output.resend()
        if answer.watchdog and self.watchdog is not None:
            self.watchdog.arm(core.watchdog_delay_ns(self.now_ns()) / NS_PER_S)

    def _say(self, note: Note) -> None:
        """Log a core's note once (``ros.once``), or count a reference refused (``InputGate``)."""
        if note.said is Said.START:
            assert note.text is not None
            self.once.start(note.key, note.text, note.level)
        elif note.said is Said.END:
            self.once.end(note.key, note.text or '')
        elif note.said is Said.REFERENCE_CLOCK:
            self.inputs.refuse('reference', Refused(Reason.CLOCK, gap_s=note.gap_s))
        else:
            self.inputs.on_clock('reference', 'reference on the clock of the states')

    def finish(self) -> None:
        """On a clean stop, command zero for the latest state and wait up to LAST_WORD s."""
        if self.pose is None or self.output is None or not rclpy.ok(context=self.context):
            return
        self.output.publish(None, self.pose.stamp_ns)
        self.output.flush(LAST_WORD)

    def on_diagnostics(self) -> None:
        """Publish one DiagnosticArray with the status of each robot this node reports."""
        if self.diagnostics_pub is not None:
            self.diagnostics_pub.publish(
                encode_statuses([node.diagnostic_status() for node in self.reported]))

    def _announcement(self, stamp_ns: int) -> Dict[str, str]:
        """Return the team values and identity this robot announces, made again on a new shape."""
        shape = self.changes.shapes.at(stamp_ns)
        if self.announcing is None or self.announcing[0] is not shape:
            self.announcing = (shape, announced(team_values(self.config, shape.vertices), self))
        return self.announcing[1]

    def command_of(self, k: int) -> Optional[Tuple[Command, Optional[NDArray[np.float64]]]]:
        """Return row ``k`` of the commands computed last (``Commands.row``), None before."""
        latest = None if self.core is None else self.core.latest
        return None if latest is None else latest.row(k)

    def diagnostic_status(self) -> StatusData:
        """Return this robot's status (``core.rules.robot_status``) with its team values."""
        if self.linked is not None:
            self.linked.report()
        else:
            self.last = self.command_of(0)
        policy, now = self.answering, self.now_ns()
        points = None
        if self.neighbours is not None and self.pose is not None:
            sensed = self._alone()
            points = np.vstack([sensed.points, sensed.neighbours])
        values = status_values({name: None if heard is None else (now - heard) / NS_PER_S
                                for name, heard in self.policy.received_ns.items()}, points,
                               self.sensing_radius, self.law.repulsion_radius, self.last,
                               self.unicycle)
        values['bound c*M1 [m/s]'] = self.law.u_bound
        if self.scan is not None:
            values['obstacle points from the scan'] = self.scan.kept
            if self.scan.scan is not None and self.pose is not None:
                values['scan age at the latest state [s]'] = (
                    (self.pose.stamp_ns - self.scan.scan.stamp_ns) / NS_PER_S)
        values.update(self._announcement(self.pose.stamp_ns if self.pose is not None else 0))
        values.update({f'rejected {name} messages ({reason.value})': count
                       for (name, reason), count in self.inputs.refused.items()})
        values['states not answered (flooding)'] = policy.flooded
        if self.linked is not None:
            values['cmd_vel published'] = self.linked.publishes_cmd_vel()
        flooding, self.flooded_reported = policy.flooded > self.flooded_reported, policy.flooded
        shared = self.inputs.shared_topics() if self.first is self else self.first.inputs.shared
        if shared:
            values['topics with more than one publisher'] = ' | '.join(
                f'{topic}: {names}' for topic, names in sorted(shared.items()))
        level, message = status_level(shared, policy.waiting, bool(policy.stale), flooding,
                                      self.lockstep)
        return make_status(f'formation_ros/{robot_name(self.index + 1)}', level, message,
                           values)


def make_robot() -> RobotNode:
    """Build the robot node, linked to the team topics with ``transport: team``."""
    node = RobotNode()
    if node.config.team_transport:
        RobotsLink([node])
    return node


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros robot``."""
    return run(make_robot, args, name='robot')
