# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Reference node (executable ``reference``): the desired formation and what changes it (Section 6).

Publishes ``/formation/reference`` (the formation frame q_od, J, qdot_od and its angular
velocity at ``reference.rate``), ``/formation/shape`` and ``/formation/status`` (every change,
holding from its stamp on), and serves ``/formation/stop`` and ``/formation/start``. The
messages: docs/ros_interface.md, "Topics"; when samples go out (plant time, lockstep, a held
clock): docs/ros_interface.md, "Behaviour of the nodes"; changes at run time and the rules a new
shape or reference must keep: docs/changes.md. The frame itself is ``core.maths.reference``'s.
Start it beside a plant with ``use_sim_time:=true``::

    ros2 run formation_ros reference --ros-args --params-file config/square_4.yaml \\
        -p use_sim_time:=true
"""

import math
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.frames import frame_to_pose
from formation_ros.core.maths.reference import PERIODIC
from formation_ros.core.maths.reference import ReferenceKind
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.runs.timeline import Mode, ReferenceTimeline, Shape, TeamState, Timeline
from formation_ros.core.settings.declarations import Exe, ParamError
from formation_ros.core.settings.params import check_shape, tracking_problem
from formation_ros.core.settings.team import team_values
from formation_ros.ros import messages, qos, topics
from formation_ros.ros.cdr import encode_odometry
from formation_ros.ros.diagnostics import diagnostics, PERIOD
from formation_ros.ros.once import OnceLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from formation_ros.ros.team import announced, team_problems, TeamCheck
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType, JumpThreshold
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger

REFERENCE_STATUS = 'formation_ros/reference'
RUNTIME = ('formation.vertices', 'formation.name', 'reference.origin', 'reference.speed')
"""The parameters that can be set while the node runs."""
Change = Callable[[int], None]


class ReferenceNode(Node):
    """Publishes q_od(t), J(t), qdot_od(t), the frame's angular velocity, shapes and the mode."""

    def __init__(self) -> None:
        """Declare and check parameters, then start publishing."""
        super().__init__('reference')
        config = declare_parameters(self, Exe.REFERENCE, RUNTIME)
        settings = config.reference_node
        assert settings is not None
        self.config = config
        self.dim = config.dim
        self.world_frame = config.world_frame
        self.lockstep = config.lockstep
        self.step_ns = settings.step_ns
        self.sim_time = self.get_parameter('use_sim_time').value
        self.epoch_ns = 0 if self.sim_time else self.get_clock().now().nanoseconds
        self.last_stamp: Optional[int] = None
        self.once = OnceLog(self.get_logger())
        self.base = config.reference()
        self.shape = Shape(config.shape_name, config.vertices)
        self.shapes: Timeline[Shape] = Timeline(self.shape)
        self.state = TeamState.of(Mode.RUNNING, config.shape_name, self.base)
        self.states: Timeline[TeamState] = Timeline(self.state)
        self.reference = ReferenceTimeline(self.base, self.states)
        self.pending: List[Tuple[str, Change]] = []
        self.team = TeamCheck(self, REFERENCE_STATUS)
        self.pub = self.create_publisher(Odometry, topics.REFERENCE, qos.REFERENCE)
        self.shape_pub = self.create_publisher(PoseArray, topics.SHAPE, qos.CHANGES)
        self.status_pub = self.create_publisher(DiagnosticArray, topics.STATUS, qos.CHANGES)
        self.published = 0
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS,
                                                     qos.DIAGNOSTICS)
        self.diagnostics_timer = self.create_timer(
            PERIOD, self.on_diagnostics, clock=Clock(clock_type=ClockType.STEADY_TIME))
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.timer = self.create_timer(1.0 / settings.rate, self.on_timer, clock=steady)
        self.apply = Wake(self, self.on_changes, steady)
        self.create_service(Trigger, topics.STOP, self.on_stop)
        self.create_service(Trigger, topics.START, self.on_start)
        self.add_on_set_parameters_callback(self.on_set_parameters)
        if self.lockstep:
            self.clock_moved = Wake(self, self.on_timer, steady)
            self.jump_handle = self.get_clock().create_jump_callback(
                JumpThreshold(min_forward=Duration(nanoseconds=1), min_backward=None),
                post_callback=lambda jump: self.clock_moved.arm())
        self._publish_shape(0, self.shape)
        for time_s, name in config.schedule:
            since = self.epoch_ns + int(round(time_s * NS_PER_S))
            self.shapes.add(since, Shape(name, config.shapes[name]))
            self._publish_shape(since, self.shapes.at(since))
        self._publish_status(0, self.state)
        self.get_logger().info(
            f'reference: {self.base.kind} in {self.dim}D, '
            + ('lockstep' if self.lockstep else f'{settings.rate:g} Hz')
            + (', simulated time' if self.sim_time else ', wall-clock time from start')
            + (f', {len(config.schedule)} scheduled shape switches' if config.schedule else ''))
        if self.lockstep and not self.sim_time:
            self.get_logger().warning('lockstep without use_sim_time: samples will not match '
                                      'the plant state stamps')

    def on_timer(self) -> None:
        """
        Publish the sample of the current time.

        In lockstep: once per value of the clock, and the sample of the next step with it, so
        that it is with the robots before the state it belongs to (the plant's step is known).
        """
        now = self.get_clock().now().nanoseconds
        if not self.lockstep:
            self._publish(now)
            return
        for stamp in (now, now + self.step_ns):
            if self.last_stamp is None or stamp > self.last_stamp:
                self._publish(stamp)

    def _publish(self, stamp: int) -> None:
        self.last_stamp = stamp
        frame = self.reference.frame_at(stamp, self.epoch_ns)
        self.pub.publish(encode_odometry(stamp, self.world_frame, messages.FORMATION_FRAME,
                                         *frame_to_pose(frame, self.dim)))
        self.published += 1

    def _publish_shape(self, since_ns: int, shape: Shape) -> None:
        self.shape_pub.publish(messages.pose_array(shape.vertices, since_ns, self.dim,
                                                   self.world_frame))

    def _publish_status(self, since_ns: int, state: TeamState) -> None:
        self.status_pub.publish(messages.team_status(state.mode.value, since_ns, {
            'shape': state.shape or 'formation.vertices',
            'origin': ','.join(repr(v) for v in state.origin),
            'speed': repr(state.speed), 'phase': repr(state.phase)}))

    def _now_ns(self) -> int:
        return self.get_clock().now().nanoseconds

    def _reference_time(self, stamp_ns: int) -> float:
        return (stamp_ns - self.epoch_ns) / NS_PER_S

    def on_set_parameters(self, parameters: List[Parameter]) -> SetParametersResult:
        """
        Check a change of shape, origin or speed as the file's values are checked.

        A change that fails is refused with the reason (``ros2 param set`` prints it) and
        nothing changes; one that passes is applied by :meth:`on_changes` from now on.
        """
        changes: List[Tuple[str, Change]] = []
        for parameter in parameters:
            try:
                changes.append((parameter.name, self._change(parameter)))
            except ParamError as exc:
                reason = str(exc).replace('\n', '; ')
                self.get_logger().warning(f'refused {parameter.name}: {reason}')
                return SetParametersResult(successful=False, reason=reason)
        self.pending.extend(changes)
        self.apply.arm()
        return SetParametersResult(successful=True)

    def _change(self, parameter: Parameter) -> Change:
        """Return what applies a valid new value of ``parameter``; ParamError if it is not."""
        name, value = parameter.name, parameter.value
        if isinstance(value, Sequence) and not isinstance(value, str):
            value = list(value)
        if name == 'formation.vertices':
            vertices = check_shape(value, self.config.num_robots, self.dim,
                                   self.config.repulsion_radius)
            return lambda since: self._switch(since, Shape('', vertices))
        if name == 'formation.name':
            if value == '':
                flat = list(self.get_parameter('formation.vertices').value)
                vertices = check_shape(flat, self.config.num_robots, self.dim,
                                       self.config.repulsion_radius)
                return lambda since: self._switch(since, Shape('', vertices))
            if value not in self.config.shapes:
                known = ', '.join(self.config.shapes) or 'none'
                raise ParamError([(name, f'{value!r} is not a shape of formations.names '
                                         f'({known})')])
            return lambda since: self._switch(since, Shape(value, self.config.shapes[value]))
        if name == 'reference.origin':
            return self._origin_change(value)
        if name == 'reference.speed':
            return self._speed_change(value)
        raise ParamError([(name, 'cannot change while the node runs (only '
                                 f"{', '.join(RUNTIME)} can)")])

    def _origin_change(self, value: Any) -> Change:
        if self.base.kind is not ReferenceKind.FIXED:
            raise ParamError([('reference.origin', f'moves only a fixed reference; this one is '
                                                   f'a {self.base.kind} (change its speed)')])
        origin = value if isinstance(value, list) else []
        if len(origin) != self.dim or not all(isinstance(v, float) and math.isfinite(v)
                                              for v in origin):
            raise ParamError([('reference.origin', f'must hold dim = {self.dim} finite doubles, '
                                                   f'got {value!r}')])

        def move(since: int) -> None:
            state = self.states.at(since)
            self._set_state(since, TeamState(state.mode, state.shape, tuple(origin),
                                             state.speed, state.phase))
        return move

    def _speed_change(self, value: Any) -> Change:
        if self.base.kind not in PERIODIC:
            raise ParamError([('reference.speed', f'applies to circle, figure_eight and helix; '
                                                  f'this reference is a {self.base.kind}')])
        if not (isinstance(value, float) and math.isfinite(value) and value > 0.0):
            raise ParamError([('reference.speed', f'must be a finite double > 0, got {value!r}')])
        since = self._now_ns()
        faster = self.states.at(since).reference(self.base).with_speed(
            value, self._reference_time(since))
        problem = tracking_problem(self.config.body, self.shapes.at(since).vertices, faster,
                                   self.config.duration)
        if problem:
            raise ParamError([('reference.speed', problem)])

        def speed_up(at: int) -> None:
            reference = self.states.at(at).reference(self.base).with_speed(
                value, self._reference_time(at))
            state = self.states.at(at)
            self._set_state(at, TeamState(state.mode, state.shape,
                                          tuple(float(v) for v in reference.origin),
                                          reference.speed, reference.phase))
        return speed_up

    def on_changes(self) -> None:
        """
        Apply the changes accepted since the last call, from now on, and publish them.

        In lockstep from the first step whose reference sample is not sent yet (the sample of
        the next step goes out ahead), so that every node sees the change at the same state.
        """
        pending, self.pending = self.pending, []
        since = self._now_ns()
        if self.lockstep and self.last_stamp is not None:
            since = max(since, self.last_stamp + self.step_ns)
        for name, change in pending:
            change(since)
            self.get_logger().info(f'{name} changed at t = {self._reference_time(since):.3f} s')

    def _switch(self, since: int, shape: Shape) -> None:
        self.shapes.add(since, shape)
        self._publish_shape(since, shape)
        state = self.states.at(since)
        self._set_state(since, TeamState(state.mode, shape.name, state.origin, state.speed,
                                         state.phase))

    def _set_state(self, since: int, state: TeamState) -> None:
        self.states.add(since, state)
        self._publish_status(since, state)

    def _set_mode(self, mode: Mode, response: Trigger.Response) -> Trigger.Response:
        since = self._now_ns()
        state = self.states.at(since)
        was = state.mode
        self._set_state(since, TeamState(mode, state.shape, state.origin, state.speed,
                                         state.phase))
        at = self._reference_time(since)
        response.success = True
        response.message = (f'team {mode.value} from t = {at:.3f} s' if was is not mode
                            else f'team already {mode.value}')
        self.get_logger().info(response.message)
        return response

    def on_stop(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        """``/formation/stop``: every robot holds still (publishes zero) from now on."""
        return self._set_mode(Mode.STOPPED, response)

    def on_start(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        """``/formation/start``: the team moves again from now on."""
        return self._set_mode(Mode.RUNNING, response)

    def on_diagnostics(self) -> None:
        """Publish the reference node's status: kind, time, samples, shape and mode."""
        state = self.states.latest
        values: Dict[str, Any] = {
            'kind': self.base.kind, 'samples published': self.published,
            'time [s]': ('none yet' if self.last_stamp is None
                         else self._reference_time(self.last_stamp)),
            'team': state.mode.value, 'shape in force': state.shape or 'formation.vertices',
            'shape changes': len(self.shapes.changes())}
        shape = self.shapes.at(self.last_stamp if self.last_stamp is not None else 0).vertices
        values.update(announced(team_values(self.config, shape), self))
        others = team_problems(self.team, self.config, shape, self.once)
        if others:
            values['nodes with other team values'] = ' | '.join(others)
        level, message = ('ok', 'publishing') if self.published else ('warn', 'no sample yet')
        if state.mode is Mode.STOPPED:
            level, message = 'warn', 'team stopped'
        if others:
            level, message = 'error', f'{len(others)} nodes with other team values'
        if not self.sim_time and self.count_publishers(topics.CLOCK) > 0:
            level, message = 'error', 'on wall-clock time while /clock is published'
            self.once.start('clock', f'{topics.CLOCK} is published (a plant runs) but this node '
                                     'runs on wall-clock time: robots refuse its samples, '
                                     'stamped in another time base; restart it with '
                                     'use_sim_time:=true', 'error')
        self.diagnostics_pub.publish(diagnostics(REFERENCE_STATUS, level, message, values))


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros reference``."""
    return run(ReferenceNode, args, name='reference')
