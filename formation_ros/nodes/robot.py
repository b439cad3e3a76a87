# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Robot node (executable ``robot``): one robot's bounded formation controller.

:class:`RobotNode` adapts messages and timers to the robot's rules, which hold no ROS: what it
takes of its states and their clock (``core.rules.robot_intake``), the reference it follows
(``core.rules.reference_track``), which states it answers and when its watchdog looks
(``core.rules.answers``), and its commands (``core.rules.control``). Callbacks read the bytes
(``ros.cdr``), store and arm a one-shot timer (``ros.wake``) that answers; the command goes out
through one output: the robot's ``cmd_vel`` (:class:`CmdVelOutput`), or with ``transport:
team`` its process's link (``nodes.robots_link``). Topics, parameters and behaviour:
docs/ros_interface.md ("Nodes", "Behaviour of the nodes", "Transports"); faults:
docs/faults.md. One per robot::

    ros2 run formation_ros robot --ros-args -r __ns:=/robot_1 -p robot_id:=1 \\
        --params-file config/paper_section5.yaml -p use_sim_time:=true
"""

import time
from typing import Any, Callable, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.frames import FrameSample
from formation_ros.core.maths.law import Command
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.answers import Act, AnswerPolicy
from formation_ros.core.rules.control import Commands, Control, Sensed
from formation_ros.core.rules.reference_track import ReferenceTrack
from formation_ros.core.rules.robot_intake import Refused, StateIntake
from formation_ros.core.rules.robot_status import startup_line, status_level, status_values
from formation_ros.core.runs.timeline import Mode, Shape, TeamState
from formation_ros.core.settings.declarations import CommandFrame, Exe, PoseType
from formation_ros.core.settings.names import robot_name
from formation_ros.core.settings.team import reference_values, team_values
from formation_ros.nodes.robots_link import RobotsLink
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import (PoseArrayData, PoseData, read_odometry, read_pose_array,
                                   read_pose_stamped, StatusData)
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
from numpy.typing import NDArray
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.publisher import Publisher

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
        self.needs_orientation = body_frame
        self.command_frame = (messages.body_frame(settings.robot_id) if body_frame
                              else config.world_frame)
        self.control = Control(self.law, [self.sensing_radius], self.dim, self.unicycle,
                               config.body.hand_distance, body_frame)
        """The law of the robots whose commands this node computes (a link's: all of them)."""
        self.evaluates = config.team_transport or self.sim_time
        """Whether this robot evaluates the reference at each state's stamp itself."""
        self.once = OnceLog(self.get_logger())
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.state_clock = StateClock(self)
        shares = leader is not None and (config.team_transport or reference_values(config.values)
                                         == reference_values(leader.config.values))
        self.inputs = InputGate(self, StateIntake(
            config.world_frame, self.timeout_ns, self.sim_time, self.state_clock.follows_states,
            'a unicycle' if self.unicycle else 'command.frame body'), self.state_clock,
            self.once, leader.inputs.expected if shares and leader is not None else {})
        period = settings.answer_period(self.sim_time)
        self.watch_ns = max(1, int(round(NS_PER_S / settings.control_rate)))
        self.policy = AnswerPolicy(max(1, int(round(period * NS_PER_S))), self.timeout_ns,
                                   self.watch_ns, settings.wait_for_subscribers)
        self.pose: Optional[PoseData] = None
        self.neighbours: Optional[PoseArrayData] = None
        self.awaiting_neighbours = False
        self.latest: Optional[Commands] = None
        """The commands computed last (K rows: this robot's, or every robot's of its link)."""
        self.last: Optional[Tuple[Command, Optional[NDArray[np.float64]]]] = None
        """This robot's latest command and its published form (diagnostics)."""
        self.flooded_reported = 0
        self.first: RobotNode = self
        """The robot that hears the reference and the changes for this one (or itself)."""
        self.followers: List[RobotNode] = []
        self.link: Optional[RobotsLink] = None
        """The process's link to its robots (team transport), once :meth:`join` ed."""
        self.answering: RobotNode = self
        """The robot that answers for this one (its link's leader, or itself)."""
        if not config.team_transport:
            self._subscribe_to_states(settings.pose_type)
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
        self.output: Optional[Output] = (None if config.team_transport
                                         else CmdVelOutput(self.cmd_vel, self.control))
        """Where this robot's commands go (None: a link's robot its leader answers for)."""
        self.senses: Callable[[], Sensed] = self._sensed_alone
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
        if not self.lockstep:
            self.watchdog = Wake(self, self.on_watchdog, self.steady)
            self.watchdog.arm(self.watch_ns / NS_PER_S)
        self.get_logger().info(startup_line(config, self.index, self.command_frame,
                                            self.sim_time))

    def join(self, link: 'RobotsLink', output: Optional[Output], control: Control,
             senses: Callable[[], Sensed], leader: 'RobotNode') -> None:
        """Be one of ``link``'s robots; its ``leader`` answers with ``output`` for all."""
        self.link, self.output, self.answering = link, output, leader
        self.control, self.senses = control, senses

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
            self.policy.heard(['pose'], self.now_ns(), state=True)
            if self._paired():
                self.awaiting_neighbours = False
                self.answer.arm()
            elif not self.lockstep:
                self.awaiting_neighbours = True
                self.answer.arm(self.watch_ns / NS_PER_S)

    def on_neighbours(self, data: bytes) -> None:
        """Store the latest sensed neighbour positions, read from the serialized PoseArray."""
        most = self.config.num_robots - 1
        heard = self.inputs.read('neighbour', lambda raw: read_pose_array(raw, most), data)
        if heard is not None and self.admit_state('neighbour', heard, self.unicycle):
            self.neighbours = heard
            self.policy.heard(['neighbour'], self.now_ns())
            if self._paired():
                self.awaiting_neighbours = False
                self.answer.arm()

    def see(self, pose: PoseData, neighbours: PoseArrayData, heard_ns: int, new: bool,
            last: Optional[Tuple[Command, Optional[NDArray[np.float64]]]] = None) -> None:
        """
        Take this robot's pose and neighbours in a state its link read, heard at ``heard_ns``.

        new: a state to answer (the link's leader); last: the robot's latest command and its
        published form (diagnostics), if one was computed.
        """
        self.pose, self.neighbours = pose, neighbours
        self.policy.heard(['pose', 'neighbour'], heard_ns, state=new)
        if last is not None:
            self.last = last

    def _paired(self) -> bool:
        """Whether the pose and the neighbours stored are of one state (same stamp)."""
        return (self.pose is not None and self.neighbours is not None
                and self.neighbours.stamp_ns == self.pose.stamp_ns)

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
        self.policy.heard(['reference'], now_ns)
        if self.lockstep and self.output is not None:
            self.answer.arm()

    def _refuse_change(self, what: str, why: str) -> None:
        """Count and log once a shape or status refused (``ros.changes``)."""
        self.inputs.refused.add(what, Reason.CHANGE)
        self.once.start(f'{what}-refused', f'ignoring a {what} with {why} (logged once; '
                                           'diagnostics count them)', 'error')

    def _new_state(self, state: TeamState) -> None:
        """Admit reference samples as fast as the reference in force may be."""
        self.track.widen(state.reference(self.config.reference()).rate_limits())

    def _frame_at(self, stamp_ns: int, exact: bool) -> Optional[FrameSample]:
        """Return the reference frame at ``stamp_ns`` (``ReferenceTrack.frame_at``), or None."""
        frame, gap = self.track.frame_at(stamp_ns, exact, self.evaluates, self.timeout_ns)
        if gap is not None:
            self.inputs.refuse('reference', Refused(Reason.CLOCK, gap_s=gap))
        elif frame is not None:
            self.inputs.on_clock('reference', 'reference on the clock of the states')
        return frame

    def _sensed_alone(self) -> Sensed:
        """Return what this robot knows of the state stored (``Control.alone``)."""
        assert self.pose is not None and self.neighbours is not None
        return self.control.alone(self.index, self.pose.position, self.pose.orientation,
                                  self.neighbours.positions, self.neighbours.orientations)

    def _commands(self, stamp_ns: int, exact: bool) -> Optional[NDArray[np.float64]]:
        """Return the commands (K, width) answering the state ``stamp_ns``; None: zero."""
        frame = self._frame_at(stamp_ns, exact)
        if frame is None:
            return None
        if self.changes.differs:
            self.once.start('other-shape', "following the reference's shape: it differs from "
                                           "this robot's formation.vertices (another "
                                           'parameters file?)', 'warning')
        if self.changes.states.at(stamp_ns).mode is Mode.STOPPED:
            self.once.start('stopped', 'team stopped: holding still', 'info')
            return None
        self.once.end('stopped', 'team running again')
        sensed = self.senses()
        vertices = self.changes.shapes.at(stamp_ns).vertices[sensed.indices]
        self.latest = self.control.commands(sensed, vertices, frame)
        return self.latest.published

    def on_state(self) -> None:
        """Answer a state as soon as its pose and neighbours are in (armed by the callbacks)."""
        if self.output is None:
            return
        if self.lockstep:
            self._answer_lockstep()
        elif self._paired() or (self.awaiting_neighbours and self.neighbours is not None):
            self.awaiting_neighbours = False
            self._answer_newest()

    def on_watchdog(self) -> None:
        """Watchdog: zero while an input is stale, else answer a state left over; re-armed."""
        if self.output is None:
            return
        self._answer_newest()
        self._arm_watchdog()

    def _arm_watchdog(self) -> None:
        if self.watchdog is not None:
            self.watchdog.arm(self.policy.watchdog_delay_ns(self.now_ns()) / NS_PER_S)

    def _ready(self, output: Output) -> bool:
        """Start-up (``AnswerPolicy.missing``): say once what the robot waits for."""
        missing = self.policy.missing(output.listeners(), output.what)
        if missing:
            self.once.start('waiting', f"waiting for {', '.join(missing)}", 'info')
            return False
        self.once.end('waiting')
        output.started()
        return True

    def _answer_newest(self) -> None:
        """Answer the newest state once: compute and publish its command (zero if stale)."""
        output = self.output
        if output is None or (self.policy.waiting and not self._ready(output)):
            return
        assert self.pose is not None
        stamp = self.pose.stamp_ns
        act = self.policy.newest(stamp, self.now_ns(), self.get_clock().now().nanoseconds)
        if act is Act.ZERO:
            output.publish(None, stamp)
            self.once.start('stale', f"no new {', '.join(self.policy.stale)} for "
                                     f'{self.timeout_ns / NS_PER_S:g} s: publishing zero')
            return
        self.once.end('stale', 'inputs fresh again: controlling')
        self._act(output, act, stamp, False)

    def _answer_lockstep(self) -> None:
        """Answer each state the plant sends, once, with the reference sample of its stamp."""
        output = self.output
        if output is None or self.pose is None or not self.policy.unanswered:
            return
        if (self.policy.waiting and not self._ready(output)) or not self._paired():
            return
        stamp = self.pose.stamp_ns
        if stamp != self.policy.answered_stamp and self._frame_at(stamp, True) is None:
            return
        act = self.policy.admit(stamp, self.now_ns(), self.get_clock().now().nanoseconds)
        self._act(output, act, stamp, True)

    def _act(self, output: Output, act: Act, stamp: int, exact: bool) -> None:
        """Do what the policy decided for the state stamped ``stamp``."""
        if act is Act.ANSWER:
            output.publish(self._commands(stamp, exact), stamp)
            self.policy.answered_state(stamp)
            return
        if act is Act.RESEND:
            output.resend()
        elif act is Act.FLOOD:
            period = self.policy.budget.period_ns / NS_PER_S
            self.once.start('flooding', f'states arrive faster than one per {period:.3g} s '
                                        "(the plant's or relay's period): answering at most "
                                        'about one per period, the others are dropped (logged '
                                        'once; counted in diagnostics)', 'warning')
        if self.policy.unanswered:
            self._arm_watchdog()

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
        return None if self.latest is None else self.latest.row(k)

    def diagnostic_status(self) -> StatusData:
        """Return this robot's status (``core.rules.robot_status``) with its team values."""
        if self.link is not None:
            self.link.report_to(self)
        else:
            self.last = self.command_of(0)
        policy, now = self.answering.policy, self.now_ns()
        points = None
        if self.neighbours is not None and self.pose is not None:
            sensed = self._sensed_alone()
            points = np.vstack([sensed.points, sensed.neighbours])
        values = status_values({name: None if heard is None else (now - heard) / NS_PER_S
                                for name, heard in self.policy.received_ns.items()}, points,
                               self.sensing_radius, self.law.repulsion_radius, self.last,
                               self.unicycle)
        values['bound c*M1 [m/s]'] = self.law.u_bound
        values.update(self._announcement(self.pose.stamp_ns if self.pose is not None else 0))
        values.update({f'rejected {name} messages ({reason.value})': count
                       for (name, reason), count in self.inputs.refused.items()})
        values['states not answered (flooding)'] = policy.flooded
        if self.link is not None:
            values['cmd_vel published'] = self.link.publishes_cmd_vel(self.index)
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
