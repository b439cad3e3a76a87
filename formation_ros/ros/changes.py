# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Follow the formation's changes: ``/formation/shape`` and ``/formation/status`` into timelines.

Robots and the plant hear the reference node's shapes and team states (``nodes/reference.py``),
check each as the parameters file's values are checked, and keep it in a
:class:`formation_ros.core.runs.timeline.Timeline` from its stamp on. Subscription callbacks only
store the message and arm a one-shot timer (:class:`formation_ros.ros.wake.Wake`), which calls
:meth:`Changes.take`.
"""

from collections import deque
from typing import Any, Callable, List

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.maths.reference import ReferenceKind
from formation_ros.core.runs.timeline import (Mode, named_shape, ReferenceTimeline, Shape,
                                              TeamState, Timeline)
from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.params import check_shape, FormationConfig
from formation_ros.ros import fields, qos, topics
from formation_ros.ros.messages import team_state_of
from formation_ros.ros.wake import Wake
from geometry_msgs.msg import PoseArray
from rclpy.clock import Clock
from rclpy.node import Node

Reject = Callable[[str, str], None]
"""Called with (what: 'shape' or 'status', why) for a message that is refused."""


class Changes:
    """
    The shapes and team states in force, as the reference node announced them.

    shapes: ``Timeline[Shape]`` (the file's shape until the reference's arrives); states:
    ``Timeline[TeamState]``; reference: the reference in force at each time
    (``ReferenceTimeline``); ``on_state`` is called with each new state taken.
    """

    def __init__(self, node: Node, config: FormationConfig, clock: Clock, reject: Reject,
                 on_state: Callable[[TeamState], None] = lambda state: None) -> None:
        """Subscribe ``node`` to both topics; refused messages are reported to ``reject``."""
        self.config = config
        self.reject = reject
        self.on_state = on_state
        self.own = Shape(config.shape_name, config.vertices)
        self.shapes: Timeline[Shape] = Timeline(self.own)
        base = config.reference()
        self.states: Timeline[TeamState] = Timeline(
            TeamState.of(Mode.RUNNING, config.shape_name, base))
        self.reference = ReferenceTimeline(base, self.states)
        self.differs = False
        self.heard: deque = deque(maxlen=2 * qos.CHANGES_KEPT)
        self.wake = Wake(node, self.take, clock)
        node.create_subscription(PoseArray, topics.SHAPE, self.store, qos.CHANGES)
        node.create_subscription(DiagnosticArray, topics.STATUS, self.store, qos.CHANGES)

    def store(self, msg: Any) -> None:
        """Keep a shape or status heard; the timer takes it."""
        self.heard.append(msg)
        self.wake.arm()

    def take(self) -> List[Any]:
        """Check the messages heard and let each hold from its stamp on; return those taken."""
        taken = []
        while self.heard:
            msg = self.heard.popleft()
            change = self._shape(msg) if isinstance(msg, PoseArray) else self._state(msg)
            if change is not None:
                taken.append(change)
        return taken

    def _shape(self, msg: PoseArray) -> Any:
        frame = msg.header.frame_id
        if frame != self.config.world_frame:
            self.reject('shape', f'a frame other than world_frame (got {frame!r}, expected '
                                 f'{self.config.world_frame!r})')
            return None
        flat = [float(v) for row in fields.points_of(msg, self.config.dim) for v in row]
        try:
            vertices = check_shape(flat, self.config.num_robots, self.config.dim,
                                   self.config.repulsion_radius)
        except ParamError as exc:
            self.reject('shape', f'a shape the law cannot hold ({exc})')
            return None
        since = fields.stamp_to_ns(msg.header.stamp)
        shape = named_shape(vertices, self.config.shapes)
        if since == 0 and not shape.same_as(self.own):
            self.differs = True
        self.shapes.add(since, shape)
        return shape

    def _state(self, msg: DiagnosticArray) -> Any:
        try:
            state = team_state_of(msg, self.config.dim)
        except ValueError as exc:
            self.reject('status', f'bytes that are not a team status ({exc})')
            return None
        if state.speed < 0.0 or (state.speed == 0.0 and not self.reference.base.is_stationary
                                 and self.reference.base.kind is not ReferenceKind.LINE):
            self.reject('status', f'a path speed this reference cannot have ({state.speed!r} '
                                  'm/s)')
            return None
        self.states.add(fields.stamp_to_ns(msg.header.stamp), state)
        self.on_state(state)
        return state
