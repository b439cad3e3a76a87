r"""
Recorder node (executable ``record``): every formation topic into a rosbag2 (MCAP) directory.

Subscribes with ``raw=True`` (the serialized CDR bytes, no deserialise/serialise round trip) and
with the QoS of each publisher (best effort for poses and neighbours, transient local for the
reference), stores the bytes in its callbacks and writes them to the bag from a timer. The bag
is finished (metadata.yaml written) when the node stops, on Ctrl-C or SIGTERM too. It carries
the run's parameters on /formation/params and in params.yaml, for ``formation_report``::

    ros2 run formation_ros record --ros-args --params-file config/paper_section5.yaml \\
        -p record.path:=runs/section5_bag
"""

import os

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros import qos
from formation_ros.bag import BagError, BagWriter, qos_of
from formation_ros.core.params import ParamError
from formation_ros.nodes.common import declare_and_validate, run
from geometry_msgs.msg import PoseArray, PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock as ClockMsg
from visualization_msgs.msg import MarkerArray

FLUSH_PERIOD = 0.2
RECORD_ONLY = ('record.path', 'record.overwrite', 'record.markers')


def _bag_qos(profile):
    return qos_of(reliable=profile.reliability == qos.COMMAND.reliability,
                  transient_local=profile.durability == qos.REFERENCE.durability,
                  depth=profile.depth)


def formation_topics(num_robots, markers):
    """Return [(topic, message class, ROS type name, QoS profile)] the recorder subscribes to."""
    topics = []
    for i in range(1, num_robots + 1):
        topics += [
            (f'/robot_{i}/pose', PoseStamped, 'geometry_msgs/msg/PoseStamped', qos.STATE),
            (f'/robot_{i}/neighbors', PoseArray, 'geometry_msgs/msg/PoseArray', qos.STATE),
            (f'/robot_{i}/cmd_vel', TwistStamped, 'geometry_msgs/msg/TwistStamped', qos.COMMAND),
        ]
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
        topics = formation_topics(config.num_robots, values['record.markers'])
        for topic, msg_class, type_name, profile in topics:
            self.bag.add_topic(topic, type_name, _bag_qos(profile))
            self.create_subscription(msg_class, topic,
                                     lambda data, topic=topic: self.on_message(topic, data),
                                     profile, raw=True)
        self.bag.write_params({k: v for k, v in values.items() if k not in RECORD_ONLY},
                              self.get_clock().now().nanoseconds)
        self.timer = self.create_timer(FLUSH_PERIOD, self.flush,
                                       clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(f'recording {len(topics)} topics to {self.path}')

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
