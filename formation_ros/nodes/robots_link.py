# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot process's link to its robots with ``transport: team``: states in, commands out.

:class:`RobotsLink` reads ``/formation/states`` once for every robot of a process (or fleet),
admits it through its first robot (the leader, a :class:`LinkedRobot`: ``nodes.robot``'s node),
senses each robot's neighbours with the plant's sensing rule (``core.maths.sensing``) and is the
output the leader serves (``core.rules.robot_core``): every robot's command from one call of
``core.rules.control.Control``, in one
``/formation/commands`` message, and on a robot's own ``cmd_vel`` while someone subscribes to
it (``ros.on_demand``). With ``obstacles.clearance`` it hears ``/formation/obstacles`` too
and takes a state once the obstacles of its stamp are in (after the first obstacles heard).
The message layouts and rules: docs/ros_interface.md ("Transports", "Obstacles").
"""

import dataclasses
from typing import Callable, List, Optional, Protocol, Sequence, Tuple, Union

from formation_ros.core.maths.law import Command, LawParams
from formation_ros.core.maths.obstacles import HeardObstacles, MAX_TOLD, quaternion_normals
from formation_ros.core.maths.sensing import sensed_pairs, sensor_radii
from formation_ros.core.model.bodies import make_bodies
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.answers import AnswerPolicy
from formation_ros.core.rules.control import Control, Sensed
from formation_ros.core.rules.robot_core import RobotCore
from formation_ros.core.rules.robot_intake import Refused
from formation_ros.core.rules.scan_obstacles import ScanObstacles
from formation_ros.core.rules.transport import command_vectors
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.names import robot_name
from formation_ros.core.settings.params import FormationConfig
from formation_ros.core.settings.team import LINK_VALUES
from formation_ros.ros import qos, topics
from formation_ros.ros.cdr import (encode_names, encode_team_commands, PoseArrayData, PoseData,
                                   read_pose_array, read_team_obstacles, TeamObstaclesData)
from formation_ros.ros.command_output import CmdVel, Output
from formation_ros.ros.on_demand import LISTENERS_PERIOD, OnDemand
from formation_ros.ros.robot_inputs import InputGate
from formation_ros.ros.sim_clock import StateClock
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray
import numpy as np
from numpy.typing import ArrayLike, NDArray
from rclpy.clock import Clock
from rclpy.duration import Duration
from rclpy.node import Node
from trajectory_msgs.msg import MultiDOFJointTrajectory

LISTENER_LOOKS = 10
"""Robots without a cmd_vel publisher looked up in the graph per look, in turn."""


class LinkedRobot(Protocol):
    """What the link uses of one of its robots (``nodes.robot.RobotNode``)."""

    index: int
    sensing_radius: float
    config: FormationConfig
    scan: Optional[ScanObstacles]
    needs_orientation: bool
    law: LawParams
    control: Control
    cmd_vel: CmdVel
    state_clock: StateClock
    steady: Clock
    inputs: InputGate
    policy: AnswerPolicy

    def count_subscribers(self, topic_name: str) -> int:
        """Return the subscribers of a topic in the graph."""

    def now_ns(self) -> int:
        """Return steady time, ns."""

    def admit_state(self, name: str, state: PoseArrayData, needs_orientation: bool,
                    finite: Optional[bool] = None) -> bool:
        """Admit a state of input ``name`` as of now."""

    def see(self, pose: PoseData, neighbours: PoseArrayData, heard_ns: int, new: bool,
            last: Optional[Tuple[Command, Optional[NDArray[np.float64]]]] = None,
            obstacles: bool = False) -> None:
        """Take the robot's pose and neighbours (and obstacles) in a state the link read."""

    def serve(self, output: Output, control: Control,
              senses: Callable[[], Sensed]) -> RobotCore:
        """Answer through ``output`` the states of the robots ``control`` commands."""

    def join(self, linked: 'Linked', answering: AnswerPolicy) -> None:
        """Be one of a link's robots: ``linked`` tells of it, ``answering`` answers for all."""

    def on_state(self) -> None:
        """Answer the state taken."""

    def scanned(self, stamp_ns: int, position: ArrayLike, control_point: ArrayLike,
                neighbours: ArrayLike) -> Union[str, Tuple[NDArray[np.float64],
                                                           NDArray[np.float64]]]:
        """Return the robot's obstacles from its scan at a state, or why none."""


class Linked:
    """What a link tells one of its robots (its diagnostics), without the robot holding it."""

    def __init__(self, link: 'RobotsLink', node: LinkedRobot) -> None:
        """Tell ``node`` of ``link``."""
        self._link, self._node = link, node

    def report(self) -> None:
        """Give the robot what it would have heard and computed (``RobotsLink.report_to``)."""
        self._link.report_to(self._node)

    def publishes_cmd_vel(self) -> str:
        """Return 'yes' while the robot's own cmd_vel is published (someone listens)."""
        return self._link.publishes_cmd_vel(self._node.index)


class RobotsLink:
    """The team transport of one robot process or fleet, on its first robot node (the leader)."""

    what = 'command (team topic and cmd_vel)'

    def __init__(self, nodes: Sequence[LinkedRobot]) -> None:
        """
        Link ``nodes`` (team transport, sharing :data:`LINK_VALUES`; ParamError if not).

        The first is the leader; the link's rows are the robots in id order.
        """
        leader = self.leader = nodes[0]
        assert isinstance(leader, Node)
        self.nodes = sorted(nodes, key=lambda node: node.index)
        config = leader.config
        differing = [name for name in LINK_VALUES for node in self.nodes[1:]
                     if node.config.values.get(name) != config.values.get(name)]
        if differing:
            raise ParamError([(differing[0], 'must be the same for every robot of a process '
                                             'with transport team (one call of the law '
                                             'computes their commands)')])
        self.n, self.dim = config.num_robots, config.dim
        self.indices = np.array([node.index for node in self.nodes], dtype=np.intp)
        radii = np.array([node.sensing_radius for node in self.nodes])
        self.control = Control(leader.law, radii, self.dim, leader.control.unicycle,
                               leader.control.hand_distance, leader.control.body_frame,
                               leader.control.footprint, leader.control.obstacle_clearance)
        self.needs_orientation = leader.control.unicycle or leader.needs_orientation
        self.reach = np.zeros(self.n)
        self.reach[self.indices] = sensor_radii(radii, make_bodies(config.body).sensing_margin)
        self.local = np.full(self.n, -1, dtype=np.intp)
        self.local[self.indices] = np.arange(len(self.nodes))
        self.names = encode_names([robot_name(int(i) + 1) for i in self.indices])
        self.heard: Optional[bytes] = None
        self.taken: Optional[bytes] = None
        """The bytes of the state taken last: a copy of them is not read and sensed again."""
        self.taken_ns = 0
        self.state: Optional[PoseArrayData] = None
        self.sensed_now: Optional[Sensed] = None
        self.seen = np.zeros(0, dtype=np.intp)
        self.bounds = np.zeros(len(self.nodes) + 1, dtype=np.intp)
        self.heard_obstacles: Optional[bytes] = None
        self.obstacles: Optional[TeamObstaclesData] = None
        """The latest obstacles admitted (None: none heard yet: the law as without them)."""
        self.pending = False
        """Whether the state taken waits for its obstacles."""
        self.last_sent: Optional[bytes] = None
        self.sent: List[Tuple[CmdVel, bytes]] = []
        """The cmd_vel messages that went with the latest team command, by robot."""
        self.on_demand = OnDemand(
            len(self.nodes), LISTENER_LOOKS, lambda k: self.nodes[k].cmd_vel.pub is not None,
            lambda k: self.nodes[k].count_subscribers(topics.CMD_VEL) > 0,
            lambda k: self.nodes[k].cmd_vel.make(),
            lambda k: self.nodes[k].cmd_vel.listeners() > 0)
        for node in self.nodes:
            if node is not leader:
                leader.state_clock.join(node.state_clock)
            node.join(Linked(self, node), leader.policy)
        self.core = leader.serve(self, self.control, self.sensed)
        self.pub = leader.create_publisher(MultiDOFJointTrajectory, topics.TEAM_COMMANDS,
                                           qos.COMMAND)
        self.wake = Wake(leader, self.on_wake, leader.steady)
        leader.create_subscription(PoseArray, topics.STATES, self.on_states, qos.STATE_INPUT,
                                   raw=True)
        if leader.control.obstacle_clearance is not None and leader.scan is None:
            leader.create_subscription(MultiDOFJointTrajectory, topics.TEAM_OBSTACLES,
                                       self.on_obstacles, qos.STATE_INPUT, raw=True)
        self.listeners_timer = leader.create_timer(LISTENERS_PERIOD, self.on_demand.look,
                                                   clock=leader.steady)

    def on_states(self, data: bytes) -> None:
        """Store the latest team state's bytes and wake the link."""
        self.heard = data
        self.wake.arm()

    def on_wake(self) -> None:
        """Take the state heard, then let the leader answer it."""
        self.take_state()
        self.leader.on_state()

    def on_obstacles(self, data: bytes) -> None:
        """Store the latest team obstacles' bytes and wake the link."""
        self.heard_obstacles = data
        self.wake.arm()

    def take_state(self) -> None:
        """
        Read and admit the team state heard (if any), sense, and give the leader its part.

        A copy of the state taken last (the plant sends one again while it waits for answers)
        is not read again: it is heard anew and answered as a copy (``core.rules.answers``).
        Once obstacles were heard, a state is given with the obstacles of its stamp, when
        they are in.
        """
        data, self.heard = self.heard, None
        if data is not None:
            if data != self.taken and not self._sense(data):
                return
            self.taken, self.taken_ns = data, self.leader.now_ns()
            self.pending = True
        self._take_obstacles()
        if not self.pending or self.state is None or not (
                self.obstacles is None or self.obstacles.stamp_ns == self.state.stamp_ns):
            return
        self.pending = False
        if self.obstacles is not None and self.sensed_now is not None:
            self.sensed_now = dataclasses.replace(self.sensed_now,
                                                  obstacles=self._heard(self.obstacles))
        self._give(self.leader, new=True)

    def _take_obstacles(self) -> None:
        """Read and admit the team obstacles heard (untrusted: ``read_team_obstacles``)."""
        data, self.heard_obstacles = self.heard_obstacles, None
        if data is None:
            return
        leader = self.leader
        heard = leader.inputs.read('obstacles', lambda raw: read_team_obstacles(
            raw, self.n, MAX_TOLD * self.n), data, Reason.TOO_MANY_POINTS)
        if heard is None or not leader.admit_state('obstacles', PoseArrayData(
                heard.stamp_ns, heard.frame_id, heard.positions, heard.orientations), True):
            return
        if not np.all(np.any(quaternion_normals(heard.orientations, self.dim) != 0.0, axis=1)):
            leader.inputs.refuse('obstacles', Refused(Reason.NO_NORMAL))
            return
        self.obstacles = heard

    def _heard(self, heard: TeamObstaclesData) -> Optional[HeardObstacles]:
        """Return the obstacles of this link's robots in ``heard`` (``Control``)."""
        local = self.local[heard.robots]
        order = np.argsort(local, kind='stable')
        bounds = np.searchsorted(local[order], np.arange(len(self.nodes) + 1))
        rows = [order[bounds[k]:bounds[k + 1]] for k in range(len(self.nodes))]
        return self.control.heard_obstacles([(heard.positions[r], heard.orientations[r])
                                             for r in rows])

    def _sense(self, data: bytes) -> bool:
        """Read and admit a new state's bytes, sense; False if refused."""
        leader = self.leader
        state = leader.inputs.read('states', lambda raw: read_pose_array(raw, self.n), data)
        if state is None:
            return False
        if len(state.positions) != self.n:
            leader.inputs.refuse('states', Refused(
                Reason.MALFORMED, f' ({len(state.positions)} poses for {self.n} robots)'))
            return False
        positions = state.positions[:, :self.dim]
        checked = PoseArrayData(state.stamp_ns, state.frame_id, positions, state.orientations)
        if not leader.admit_state('states', checked, self.needs_orientation):
            return False
        observer, self.seen = sensed_pairs(positions, self.reach, observers=self.indices)
        points, headings = self.control.points(positions, state.orientations)
        indices = self.indices
        self.sensed_now = Sensed(indices, points[indices], headings[indices],
                                 state.orientations[indices], self.local[observer],
                                 points[self.seen])
        self.bounds = np.searchsorted(self.sensed_now.observer, np.arange(len(self.nodes) + 1))
        self.state = state
        for node in self.nodes:
            if node.scan is not None:
                node.scan.pose_heard(state.stamp_ns, tuple(state.positions[node.index]),
                                     tuple(state.orientations[node.index]))
        return True

    def sensed(self) -> Sensed:
        """
        Return what the robots know of the state taken last (``core.rules.control.Sensed``).

        Robots on their scanners (``obstacles.source: scan``) take their obstacles from them
        (``RobotNode.scanned``); while one of them cannot tell its own, all hold still.
        """
        assert self.sensed_now is not None
        if self.leader.scan is None or self.state is None:
            return self.sensed_now
        state, seen = self.state, []
        for k, node in enumerate(self.nodes):
            near = self.seen[self.bounds[k]:self.bounds[k + 1]]
            view = node.scanned(state.stamp_ns, state.positions[node.index],
                                self.sensed_now.points[k], state.positions[near])
            if isinstance(view, str):
                return dataclasses.replace(self.sensed_now,
                                           unseen=f'{robot_name(node.index + 1)}: {view}')
            seen.append(view)
        return dataclasses.replace(self.sensed_now,
                                   obstacles=self.control.scanned_obstacles(seen))

    def _give(self, node: LinkedRobot, new: bool) -> None:
        """Give robot ``node`` its pose, neighbours and latest command as of the state taken."""
        state = self.state
        if state is None:
            return
        k = int(self.local[node.index])
        seen = self.seen[self.bounds[k]:self.bounds[k + 1]]
        latest = self.core.latest
        node.see(PoseData(state.stamp_ns, state.frame_id,
                          tuple(state.positions[node.index].tolist()),
                          tuple(state.orientations[node.index].tolist())),
                 PoseArrayData(state.stamp_ns, state.frame_id, state.positions[seen],
                               state.orientations[seen]),
                 self.taken_ns, new, None if latest is None else latest.row(k),
                 self.obstacles is not None and self.obstacles.stamp_ns == state.stamp_ns)

    def report_to(self, node: LinkedRobot) -> None:
        """Give robot ``node`` what it would have heard and computed (its diagnostics)."""
        self._give(node, new=False)

    def publishes_cmd_vel(self, index: int) -> str:
        """Return 'yes' while robot ``index``'s own cmd_vel is published (someone listens)."""
        return 'yes' if self.on_demand.listening[self.local[index]] else 'no'

    def listeners(self) -> int:
        """Return the command subscribers every robot has: team topic plus its fewest cmd_vel."""
        return self.pub.get_subscription_count() + min(node.cmd_vel.listeners()
                                                       for node in self.nodes)

    def started(self) -> None:
        """Look at who subscribes to the robots' cmd_vel as the robots start answering."""
        self.on_demand.look()

    def publish(self, u: Optional[NDArray[np.float64]], stamp_ns: int) -> None:
        """
        Publish one team command answering the state ``stamp_ns``: u (K, width), None for zero.

        Robot i's own cmd_vel carries its row too while someone subscribes to it.
        """
        linear, angular = command_vectors(self.control.zero() if u is None else u,
                                          self.control.unicycle)
        message = encode_team_commands(stamp_ns, self.leader.config.world_frame, self.names,
                                       linear, angular)
        self.pub.publish(message)
        self.sent = [(self.nodes[k].cmd_vel, self.nodes[k].cmd_vel.encode(stamp_ns, linear[k],
                                                                          angular[k]))
                     for k in np.flatnonzero(self.on_demand.listening).tolist()]
        for cmd_vel, own in self.sent:
            cmd_vel.publish(own)
        self.last_sent = message

    def resend(self) -> None:
        """Publish the latest team command again, and each listened robot's cmd_vel with it."""
        if self.last_sent is None:
            return
        self.pub.publish(self.last_sent)
        for cmd_vel, own in self.sent:
            cmd_vel.publish(own)

    def flush(self, seconds: float) -> None:
        """Wait up to ``seconds`` for the team topic's subscribers to have the last command."""
        self.pub.wait_for_all_acked(Duration(seconds=seconds))
