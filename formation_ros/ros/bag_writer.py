# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Write rosbag2 directories (metadata.yaml + MCAP) with ``rosbags``: what the recorder stores.

Writing takes messages already serialized as CDR (what an rclpy subscription with ``raw=True``
hands over), so nothing is deserialized on the way. The ROS 2 message definitions are embedded
from rosbags' Jazzy type store, so ``ros2 bag info`` / ``ros2 bag play`` read the bag and so does
any MCAP tool. Every bag also carries its parameters as YAML text on ``/formation/params``
(std_msgs/String) and as ``params.yaml`` next to ``metadata.yaml``, so it describes itself.
Reading bags back is an offline tool's job (``formation_ros.tools.bag``).
"""

import os
import shutil

from formation_ros.core.params_file import dump_params_text
from formation_ros.ros import topics
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability
from rosbags.interfaces import QosTime
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

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
        text = dump_params_text(values)
        if topics.PARAMS not in self._connections:
            self.add_topic(topics.PARAMS, 'std_msgs/msg/String',
                           qos_of(reliable=True, transient_local=True, depth=1))
        message = TYPESTORE.types['std_msgs/msg/String'](data=text)
        self.write(topics.PARAMS, timestamp_ns,
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
