r"""
Recorder node (executable ``record``): every formation topic into a rosbag2 (MCAP) directory.

Subscribes with ``raw=True`` (the serialized CDR bytes, no deserialise/serialise round trip) and
with the reliability and durability of each publisher (best effort for poses and neighbours,
transient local for the reference) but a deep history, stores the bytes in its callbacks and
writes them to the bag from a timer. Robot i's ``cmd_vel`` is subscribed only once the
recorder's own readers of its ``pose`` and ``neighbors`` have matched a publisher: a robot that
waits for the recorder on ``cmd_vel`` (``wait_for_subscribers``) then cannot start before its
states are recorded, whichever side of the DDS discovery finishes first. The bag is finished
(metadata.yaml written) when the node stops, on Ctrl-C or SIGTERM too. It carries the run's
parameters on /formation/params and in params.yaml, for ``formation_report``::

    ros2 run formation_ros record --ros-args --params-file config/paper_section5.yaml \\
        -p record.path:=runs/section5_bag
"""

import os

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.ros import qos
from formation_ros.tools.bag import BagError, BagWriter, qos_of
from formation_ros.core.params import ParamError
from formation_ros.nodes.common import declare_and_validate, OnceLog, run
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from visualization_msgs.msg import MarkerArray

FLUSH_PERIOD = 0.2
MATCH_PERIOD = 0.02
RECORD_ONLY = ('record.path', 'record.overwrite', 'record.markers')


def _bag_qos(profile):
    return qos_of(reliable=profile.reliability == qos.COMMAND.reliability,
                  transient_local=profile.durability == qos.REFERENCE.durability,
                  depth=profile.depth)


def robot_topics(i):
    """Return [(topic, message class, ROS type name, QoS profile)] of robot i (1-based)."""
    return [
        (f'/robot_{i}/pose', PoseStamped, 'geometry_msgs/msg/PoseStamped', qos.STATE),
        (f'/robot_{i}/neighbors', PoseArray, 'geometry_msgs/msg/PoseArray', qos.STATE),
        (f'/robot_{i}/cmd_vel', TwistStamped, 'geometry_msgs/msg/TwistStamped', qos.COMMAND),
    ]


def formation_topics(num_robots, markers):
    """Return [(topic, message class, ROS type name, QoS profile)] the recorder subscribes to."""
    topics = [topic for i in range(1, num_robots + 1) for topic in robot_topics(i)]
    topics += [
        ('/formation/reference', Odometry, 'nav_msgs/msg/Odometry', qos.REFERENCE),
        ('/clock', ClockMsg, 'rosgraph_msgs/msg/Clock', qos.CLOCK),
        ('/diagnostics', DiagnosticArray, 'diagnostic_msgs/msg/DiagnosticArray',
         qos.DIAGNOSTICS),
    ]
    if markers:
        topics.append(('/formation/markers', MarkerArray, 'visualization_msgs/msg/MarkerArray',
                       qos.MARKERS))
    return topics


class RecorderNode(Node):
    """Buffers serialized messages in callbacks; a timer writes them to the bag."""

    def __init__(self, **kwargs):
        """Declare and check parameters, open the bag, subscribe to every formation topic."""
        super().__init__('record', **kwargs)
        config = declare_and_validate(self, 'record')
        values = config.values
        self.path = os.path.abspath(values['record.path'])
        try:
            self.bag = BagWriter(self.path, overwrite=values['record.overwrite'])
        except BagError as exc:
            raise ParamError([('record.path', str(exc))]) from None
        self.pending = []
        self.once = OnceLog(self.get_logger())
        self.subscriptions_by_topic = {}
        topics = formation_topics(config.num_robots, values['record.markers'])
        self.commands_to_subscribe = {topic[0]: topic for topic in topics
                                      if topic[0].endswith('/cmd_vel')}
        for topic in topics:
            self.bag.add_topic(topic[0], topic[2], _bag_qos(topic[3]))
            if topic[0] not in self.commands_to_subscribe:
                self._subscribe(topic)
        self.bag.write_params({k: v for k, v in values.items() if k not in RECORD_ONLY},
                              self.get_clock().now().nanoseconds)
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.timer = self.create_timer(FLUSH_PERIOD, self.flush, clock=steady)
        self.match_timer = self.create_timer(MATCH_PERIOD, self.subscribe_commands,
                                             clock=steady)
        self.get_logger().info(f'recording {len(topics)} topics and the parameters '
                               f'(/formation/params) to {self.path}')

    def _subscribe(self, topic):
        name, msg_class, _, profile = topic
        self.subscriptions_by_topic[name] = self.create_subscription(
            msg_class, name, lambda data: self.on_message(name, data), qos.recording(profile),
            raw=True)

    def subscribe_commands(self):
        """Subscribe to robot i's cmd_vel once its pose and neighbours reach this recorder."""
        waiting = []
        for name in list(self.commands_to_subscribe):
            robot = name[:-len('/cmd_vel')]
            if all(self.subscriptions_by_topic[f'{robot}/{state}'].get_publisher_count() > 0
                   for state in ('pose', 'neighbors')):
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

    def on_message(self, topic, data):
        """Keep a serialized message with its receive time until the next flush."""
        self.pending.append((topic, self.get_clock().now().nanoseconds, data))

    def flush(self):
        """Write the buffered messages to the bag."""
        pending, self.pending = self.pending, []
        for topic, stamp, data in pending:
            self.bag.write(topic, stamp, data)

    def finish(self):
        """Write what is left and finish the bag (metadata.yaml)."""
        self.flush()
        self.bag.close()
        total = sum(self.bag.counts.values())
        self.get_logger().info(f'wrote {total} messages on '
                               f'{sum(1 for c in self.bag.counts.values() if c)} topics to '
                               f'{self.path}')


def main(args=None):
    """Entry point of ``ros2 run formation_ros record``."""
    return run(RecorderNode, args, name='record')
