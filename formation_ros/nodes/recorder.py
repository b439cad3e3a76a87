# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

r"""
Recorder node (executable ``record``): every formation topic into a rosbag2 (MCAP) directory.

It stores the serialized bytes in its callbacks and writes them from a timer, a whole MCAP
chunk a second (``ros.bag_writer``), so a killed recorder loses at most the last second; a
robot's ``cmd_vel`` is subscribed once its states are. What it records, how a failed write or a
kill ends, and ``formation_report --repair``: docs/recording.md, "Recording a run"::

    ros2 run formation_ros record --ros-args --params-file config/paper_section5.yaml \\
        -p record.path:=runs/section5_bag
"""

from dataclasses import replace
import os
from typing import Any, Dict, List, Optional, Tuple

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.settings.declarations import Exe, ParamError, RECORDER_ONLY
from formation_ros.core.settings.exits import RECORDING_FAILED
from formation_ros.ros import qos, topics
from formation_ros.ros.bag_writer import (BagError, BagWriteError, BagWriter, FLUSHES_PER_FILE,
                                          qos_of)
from formation_ros.ros.once import OnceLog
from formation_ros.ros.parameters import declare_parameters
from formation_ros.ros.runner import run
from geometry_msgs.msg import PoseArray, PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rosgraph_msgs.msg import Clock as ClockMsg
from visualization_msgs.msg import MarkerArray

FLUSH_PERIOD = 1.0
"""Seconds between chunks. Each chunk's index stays in memory until its MCAP file is finished
(about 3 KB with every topic in it); a new file is started every FLUSHES_PER_FILE flushes."""
MATCH_PERIOD = 0.02
MESSAGE_CLASSES = {
    'geometry_msgs/msg/PoseStamped': PoseStamped,
    'geometry_msgs/msg/PoseArray': PoseArray,
    'geometry_msgs/msg/TwistStamped': TwistStamped,
    'geometry_msgs/msg/Twist': Twist,
    'nav_msgs/msg/Odometry': Odometry,
    'rosgraph_msgs/msg/Clock': ClockMsg,
    'diagnostic_msgs/msg/DiagnosticArray': DiagnosticArray,
    'visualization_msgs/msg/MarkerArray': MarkerArray,
}


def _bag_qos(profile: QoSProfile) -> Any:
    return qos_of(reliable=profile.reliability == qos.COMMAND.reliability,
                  transient_local=profile.durability == qos.REFERENCE.durability,
                  depth=profile.depth)


class RecorderNode(Node):
    """Buffers serialized messages in callbacks; a timer writes them to the bag."""

    def __init__(self) -> None:
        """Declare and check parameters, open the bag, subscribe to every formation topic."""
        super().__init__('record')
        config = declare_parameters(self, Exe.RECORD)
        settings = config.recorder
        assert settings is not None
        self.path = os.path.abspath(settings.path)
        self.exit_code: Optional[int] = None
        """Set when the recording failed: the process then ends with it (ros.runner)."""
        self.pending: List[Tuple[str, int, bytes]] = []
        try:
            self.bag = BagWriter(self.path, overwrite=settings.overwrite,
                                 flushes_per_file=FLUSHES_PER_FILE)
        except BagWriteError as exc:
            self._stop_recording(exc)
            return
        except BagError as exc:
            raise ParamError([('record.path', str(exc))]) from None
        self.once = OnceLog(self.get_logger())
        self.subscriptions_by_topic: Dict[str, Any] = {}
        recorded = topics.recorded_topics(config.num_robots, settings.markers,
                                          config.command.stamped, config.obstacles is not None)
        command_names = {topics.robot_topic(i, topics.CMD_VEL)
                         for i in range(1, config.num_robots + 1)}
        self.commands_to_subscribe = {topic.name: topic for topic in recorded
                                      if topic.name in command_names}
        for topic in recorded:
            self.bag.add_topic(topic.name, topic.type_name, _bag_qos(qos.BY_KIND[topic.qos]))
            if topic.name not in self.commands_to_subscribe:
                self._subscribe(topic)
        try:
            self.bag.write_params({k: v for k, v in config.values.items()
                                   if k not in RECORDER_ONLY},
                                  self.get_clock().now().nanoseconds)
        except BagWriteError as exc:
            self._stop_recording(exc)
            return
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.timer = self.create_timer(FLUSH_PERIOD, self.flush, clock=steady)
        self.match_timer = self.create_timer(MATCH_PERIOD, self.subscribe_commands,
                                             clock=steady)
        self.get_logger().info(f'recording {len(recorded)} topics and the parameters '
                               f'({topics.PARAMS}) to {self.path}')

    def _subscribe(self, topic: topics.Topic) -> None:
        name = topic.name
        self.subscriptions_by_topic[name] = self.create_subscription(
            MESSAGE_CLASSES[topic.type_name], name, lambda data: self.on_message(name, data),
            qos.recording(qos.BY_KIND[topic.qos]), raw=True)

    def subscribe_commands(self) -> None:
        """Subscribe to robot i's cmd_vel once its pose and neighbours reach this recorder."""
        waiting = []
        for name in list(self.commands_to_subscribe):
            robot = name[:-len(topics.CMD_VEL) - 1]
            if all(self.subscriptions_by_topic[f'{robot}/{state}'].get_publisher_count() > 0
                   for state in (topics.POSE, topics.NEIGHBOURS)):
                self._subscribe(self.commands_to_subscribe.pop(name))
            else:
                waiting.append(robot)
        if waiting:
            shown = ', '.join(waiting[:5]) + ('...' if len(waiting) > 5 else '')
            self.once.start('commands', f'cmd_vel of {len(waiting)} robots is recorded once '
                                        f'their pose and neighbours are (waiting for {shown})',
                            'info')
            return
        self.once.end('commands', 'the pose and neighbours of every robot reach the recorder: '
                                  'recording every cmd_vel')
        self.match_timer.cancel()

    def on_message(self, topic: str, data: bytes) -> None:
        """Keep a serialized message with its receive time until the next flush."""
        self.pending.append((topic, self.get_clock().now().nanoseconds, data))

    def flush(self) -> None:
        """Write the buffered messages to the bag and the bag's file (one MCAP chunk)."""
        pending, self.pending = self.pending, []
        if self.exit_code is not None:
            return
        handed = 0
        try:
            for topic, stamp, data in pending:
                handed += 1
                self.bag.write(topic, stamp, data)
            self.bag.flush()
        except BagWriteError as exc:
            self._stop_recording(exc, len(pending) - handed)

    def _stop_recording(self, exc: BagWriteError, unwritten: int = 0) -> None:
        """Say once what the bag holds after a failed write; end the process (exit code)."""
        failure = exc.failure
        if failure is None:
            self.get_logger().error(f'recording stopped before it began: {exc}')
        else:
            failure = replace(failure, lost=failure.lost + unwritten)
            self.get_logger().error(f'recording stopped: cannot write {self.path} '
                                    f'({failure.reason}); {failure.describe()}')
        self.pending = []
        self.exit_code = RECORDING_FAILED

    def finish(self) -> None:
        """Write what is left and finish the bag (metadata.yaml); nothing after a failure."""
        self.flush()
        if self.exit_code is not None:
            return
        try:
            self.bag.close()
        except BagWriteError as exc:
            self._stop_recording(exc)
            return
        total = sum(self.bag.counts.values())
        self.get_logger().info(f'wrote {total} messages on '
                               f'{sum(1 for c in self.bag.counts.values() if c)} topics to '
                               f'{self.path}')


def main(args: Optional[List[str]] = None) -> int:
    """Entry point of ``ros2 run formation_ros record``."""
    return run(RecorderNode, args, name='record')
