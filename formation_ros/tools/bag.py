"""
rosbag2 directories (metadata.yaml + MCAP) of formation runs, written and read with ``rosbags``.

Writing takes messages already serialized as CDR (what an rclpy subscription with ``raw=True``
hands over), so nothing is deserialized on the way. The ROS 2 message definitions are embedded
from rosbags' Jazzy type store, so ``ros2 bag info`` / ``ros2 bag play`` read the bag and so does
any MCAP tool. Every bag also carries its parameters as YAML text on ``/formation/params``
(std_msgs/String) and as ``params.yaml`` next to ``metadata.yaml``, so it describes itself.

Reading rebuilds a :class:`formation_ros.trajectory.Trajectory` from the recorded poses,
commands and reference samples (header stamps, i.e. simulated time).
"""

import os
import shutil

from formation_ros.core.frames import advance
from formation_ros.ros.fields import frame_of, NS_PER_S, position_of, stamp_to_ns, velocity_of
from formation_ros.core.trajectory import Trajectory
import numpy as np
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability
from rosbags.interfaces import QosTime
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores
import yaml

PARAMS_TOPIC = '/formation/params'
PARAMS_FILE = 'params.yaml'
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


class BagError(Exception):
    """A bag cannot be written or read; the message says why."""


def qos_of(reliable, transient_local, depth):
    """Return an offered QoS profile for metadata.yaml (what ``ros2 bag play`` republishes)."""
    return Qos(history=QosHistory.KEEP_LAST, depth=depth,
               reliability=QosReliability.RELIABLE if reliable else QosReliability.BEST_EFFORT,
               durability=(QosDurability.TRANSIENT_LOCAL if transient_local
                           else QosDurability.VOLATILE),
               deadline=QosTime(sec=0, nsec=0), lifespan=QosTime(sec=0, nsec=0),
               liveliness=QosLiveliness.AUTOMATIC,
               liveliness_lease_duration=QosTime(sec=0, nsec=0),
               avoid_ros_namespace_conventions=False)


def _looks_like_bag(path):
    names = os.listdir(path)
    return 'metadata.yaml' in names or any(name.endswith('.mcap') for name in names)


def params_yaml(values):
    """Return the ROS 2 parameters YAML (``/**: ros__parameters:``) of flat dotted values."""
    tree = {}
    for name, value in sorted(values.items()):
        if value is None:
            continue
        node = tree
        parts = name.split('.')
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = list(value) if isinstance(value, (list, tuple)) else value
    return yaml.safe_dump({'/**': {'ros__parameters': tree}}, sort_keys=True)


class BagWriter:
    """A rosbag2 (MCAP) being written; close it (or use ``with``) to write metadata.yaml."""

    def __init__(self, path, overwrite=False):
        """Open a new bag at ``path``; an existing bag there is replaced only with overwrite."""
        self.path = os.path.abspath(path)
        if os.path.exists(self.path):
            if not os.path.isdir(self.path):
                raise BagError(f'{self.path} exists and is not a directory')
            if os.listdir(self.path) and not overwrite:
                raise BagError(f'{self.path} exists already; refusing to overwrite it '
                               '(choose a new directory, or allow overwriting)')
            if os.listdir(self.path) and not _looks_like_bag(self.path):
                raise BagError(f'{self.path} is not a bag directory; not replacing it')
            shutil.rmtree(self.path)
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections = {}
        self.counts = {}

    def add_topic(self, topic, msgtype, qos=None):
        """Register ``topic`` with ROS type ``msgtype`` (e.g. 'geometry_msgs/msg/PoseStamped')."""
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=TYPESTORE, offered_qos_profiles=[qos] if qos else [])
        self.counts[topic] = 0

    def write(self, topic, timestamp_ns, data):
        """Write one serialized (CDR) message received at ``timestamp_ns``."""
        self._writer.write(self._connections[topic], int(timestamp_ns), data)
        self.counts[topic] += 1

    def write_params(self, values, timestamp_ns):
        """Store the run's parameters on /formation/params and as params.yaml."""
        text = params_yaml(values)
        if PARAMS_TOPIC not in self._connections:
            self.add_topic(PARAMS_TOPIC, 'std_msgs/msg/String',
                           qos_of(reliable=True, transient_local=True, depth=1))
        message = TYPESTORE.types['std_msgs/msg/String'](data=text)
        self.write(PARAMS_TOPIC, timestamp_ns,
                   TYPESTORE.serialize_cdr(message, 'std_msgs/msg/String'))
        with open(os.path.join(self.path, PARAMS_FILE), 'w', encoding='utf-8') as stream:
            stream.write(text)

    def close(self):
        """Finish the MCAP file and write metadata.yaml."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def __enter__(self):
        """Use as a context manager."""
        return self

    def __exit__(self, *exc):
        """Close on leaving the ``with`` block."""
        self.close()


def read_messages(path):
    """Return ({topic: [(timestamp_ns, message), ...]}, {topic: count in metadata.yaml})."""
    if not os.path.isfile(os.path.join(path, 'metadata.yaml')):
        raise BagError(f'{path}: no metadata.yaml, not a rosbag2 directory')
    topics, counts = {}, {}
    with Reader(path) as reader:
        for connection in reader.connections:
            counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
        for connection, timestamp, raw in reader.messages():
            message = TYPESTORE.deserialize_cdr(raw, connection.msgtype)
            topics.setdefault(connection.topic, []).append((timestamp, message))
    return topics, counts


def bag_params_text(path, topics):
    """Return the parameters YAML stored with a bag (topic, else params.yaml), or None."""
    if topics.get(PARAMS_TOPIC):
        return topics[PARAMS_TOPIC][-1][1].data
    file_path = os.path.join(path, PARAMS_FILE)
    if os.path.isfile(file_path):
        with open(file_path, encoding='utf-8') as stream:
            return stream.read()
    return None


def _frames_at(stamps, reference_messages, config):
    """
    Return the reference frame at each stamp and where it came from.

    The recorded sample with that stamp, else the last earlier one carried on; before the first
    recorded sample (or with none recorded) the reference in the parameters.
    """
    dim = config.dim
    reference = config.reference()
    if not reference_messages:
        return [reference.sample(s / NS_PER_S) for s in stamps], 'parameters'
    by_stamp = {}
    for _, message in reference_messages:
        by_stamp[stamp_to_ns(message.header.stamp)] = message
    known = np.array(sorted(by_stamp))
    frames = []
    for stamp in stamps:
        if stamp in by_stamp:
            frames.append(frame_of(by_stamp[stamp], dim))
            continue
        index = int(np.searchsorted(known, stamp, side='right')) - 1
        if index < 0:
            frames.append(reference.sample(stamp / NS_PER_S))
            continue
        base = frame_of(by_stamp[int(known[index])], dim)
        frames.append(advance(base, (stamp - int(known[index])) / NS_PER_S))
    return frames, 'recorded'


def trajectory_from_topics(topics, config):
    """
    Rebuild the run from recorded messages.

    Samples are the state stamps at which every robot's pose was recorded; u_i at a sample is
    the command robot i sent for that state (or its latest earlier one, zero before its first);
    desired positions come from the recorded reference samples (or, if none were recorded, from
    the reference in the parameters) and the formation vertices. Returns (Trajectory, info).
    """
    n, dim = config.num_robots, config.dim
    poses = {}
    for i in range(1, n + 1):
        for _, message in topics.get(f'/robot_{i}/pose', []):
            poses.setdefault(stamp_to_ns(message.header.stamp), {})[i - 1] = \
                position_of(message, dim)
    stamps = sorted(stamp for stamp, seen in poses.items() if len(seen) == n)
    if len(stamps) < 2:
        raise BagError('fewer than two moments with the poses of all robots recorded')
    q = np.array([[poses[stamp][i] for i in range(n)] for stamp in stamps])
    u = np.zeros((len(stamps), n, dim))
    for i in range(1, n + 1):
        commands = {}
        for _, message in topics.get(f'/robot_{i}/cmd_vel', []):
            commands[stamp_to_ns(message.header.stamp)] = velocity_of(message, dim)
        if not commands:
            continue
        known = np.array(sorted(commands))
        index = np.searchsorted(known, stamps, side='right') - 1
        values = np.array([commands[int(k)] for k in known])
        u[:, i - 1] = np.where((index >= 0)[:, None], values[np.maximum(index, 0)], 0.0)
    frames, source = _frames_at(stamps, topics.get('/formation/reference', []), config)
    trajectory = Trajectory.from_frames(np.array(stamps) / NS_PER_S, q, u, frames,
                                        config.vertices)
    return trajectory, {'reference_source': source}


def plant_status(topics):
    """Return the counters of the plant's last /diagnostics status (collisions, ...), or {}."""
    wanted = ('collisions', 'bound_violations', 'stale_command_steps', 'bad_command_steps',
              'steps')
    for _, message in reversed(topics.get('/diagnostics', [])):
        for status in message.status:
            if status.name == 'formation_ros/plant':
                return {kv.key: int(kv.value) for kv in status.values if kv.key in wanted}
    return {}
