# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Write rosbag2 directories (metadata.yaml + MCAP): what the recorder stores.

Writing takes messages already serialized as CDR (what an rclpy subscription with ``raw=True``
hands over), so nothing is deserialized on the way. The ROS 2 message definitions are embedded
from rosbags' Jazzy type store, so ``ros2 bag info`` / ``ros2 bag play`` read the bag and so does
any MCAP tool. Every bag also carries its parameters as YAML text on ``/formation/params``
(std_msgs/String) and as ``params.yaml`` next to ``metadata.yaml``, so it describes itself.
Reading bags back is an offline tool's job (``formation_ros.tools.bag``).

``rosbags`` keeps the rosbag2 bookkeeping (connections, type hashes, QoS, metadata.yaml); the
MCAP file itself is written by the ``mcap`` library, because rosbags holds up to 1 MiB of
messages in memory before anything reaches the file and writes the schemas and channels only
with that first chunk. :meth:`BagWriter.flush` ends the chunk in progress and hands it to the
operating system, so a recorder killed with SIGKILL leaves an MCAP whose complete chunks (each
with its CRC) hold everything up to its last flush; ``formation_ros.tools.bag`` recovers them.
"""

from dataclasses import dataclass
import os
from pathlib import Path
import shutil
from typing import Any, BinaryIO, Dict, List, Optional, Tuple, Union

from formation_ros.core.params_file import dump_params_text
from formation_ros.ros import topics
from mcap import __version__ as MCAP_VERSION
from mcap.writer import CompressionType, Writer as McapWriter
from rosbags.interfaces import Connection, MessageDefinitionFormat, Qos, QosDurability
from rosbags.interfaces import QosHistory, QosLiveliness, QosReliability, QosTime
from rosbags.rosbag2 import CompressionMode, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores
import yaml

PARAMS_FILE = 'params.yaml'
TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
CHUNK_SIZE = 1 << 20
FLUSHES_PER_FILE = 300
"""Flushes after which the recorder starts a new MCAP file (5 minutes at one flush a second)."""
SCHEMA_ENCODINGS = {MessageDefinitionFormat.MSG: 'ros2msg',
                    MessageDefinitionFormat.IDL: 'ros2idl'}


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


@dataclass
class FileStats:
    """One MCAP file of a bag: its name and the messages in it (for metadata.yaml's ``files``)."""

    name: str
    first_ns: int = 0
    last_ns: int = 0
    count: int = 0

    def add(self, timestamp: int) -> None:
        """Count a message written at ``timestamp`` (ns)."""
        self.first_ns = timestamp if not self.count else min(self.first_ns, timestamp)
        self.last_ns = timestamp if not self.count else max(self.last_ns, timestamp)
        self.count += 1

    def entry(self) -> Dict[str, Any]:
        """Return this file's entry in metadata.yaml (rosbag2 format 9)."""
        return {'path': self.name,
                'starting_time': {'nanoseconds_since_epoch': self.first_ns},
                'duration': {'nanoseconds': self.last_ns - self.first_ns},
                'message_count': self.count}


class McapStorage:
    """
    rosbags storage plugin: the bag's MCAP files, written with the ``mcap`` library.

    The records are the ones rosbag2's own MCAP storage writes: profile ``ros2``, one schema
    (``ros2msg`` text) per message type, one channel per topic with ``offered_qos_profiles`` and
    ``topic_type_hash`` metadata, CDR messages in CRC-checked chunks, the ``rosbag2`` metadata
    record and a full summary (statistics, chunk and message indexes) when it is closed.

    The bag is split as rosbag2 splits by duration: after ``flushes_per_file`` flushes the file
    is finished (summary and footer written, its indexes freed) and the next message starts a
    new one, ``<name>_1.mcap``, ``<name>_2.mcap`` and so on, with every schema and channel
    again. The chunk indexes of one file stay in memory until it is finished: splitting keeps
    the writer's memory flat however long it records.
    """

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        """Create ``<path>/<path.name>.mcap`` (it must not exist) and write its header."""
        if compression != CompressionMode.NONE:
            raise BagError(f'{path}: only uncompressed bags are written here')
        self.folder = path
        self.path = path / f'{path.name}.mcap'
        self.flushes_per_file = 0
        self.files: List[FileStats] = []
        self._msgtypes: Dict[str, Connection] = {}
        self._connections: List[Tuple[Connection, str]] = []
        self._stream: Optional[BinaryIO] = None
        self._mcap: Optional[McapWriter] = None
        self._schemas: Dict[str, int] = {}
        self._channels: Dict[int, int] = {}
        self._flushes = 0
        self._open(self.path)

    def _open(self, path: Path) -> McapWriter:
        self._stream = path.open('xb')
        self._mcap = McapWriter(self._stream, chunk_size=CHUNK_SIZE,
                                compression=CompressionType.NONE)
        self._mcap.start(profile='ros2', library=f'formation_ros (mcap-python {MCAP_VERSION})')
        self.files.append(FileStats(path.name))
        self._schemas, self._channels, self._flushes = {}, {}, 0
        for connection in self._msgtypes.values():
            self._register_schema(self._mcap, connection)
        for connection, profiles in self._connections:
            self._register_channel(self._mcap, connection, profiles)
        return self._mcap

    def _writer(self) -> McapWriter:
        """Return the file being written; after a split, the next one, opened now."""
        if self._mcap is not None:
            return self._mcap
        return self._open(self.folder / f'{self.folder.name}_{len(self.files)}.mcap')

    def _register_schema(self, mcap: McapWriter, connection: Connection) -> None:
        self._schemas[connection.msgtype] = mcap.register_schema(
            connection.msgtype, SCHEMA_ENCODINGS[connection.msgdef.format],
            connection.msgdef.data.encode())

    def _register_channel(self, mcap: McapWriter, connection: Connection,
                          offered_qos_profiles: str) -> None:
        self._channels[connection.id] = mcap.register_channel(
            connection.topic, connection.ext.serialization_format,
            self._schemas[connection.msgtype],
            {'offered_qos_profiles': offered_qos_profiles, 'topic_type_hash': connection.digest})

    def add_msgtype(self, connection: Connection) -> None:
        """Store the message definition of ``connection``'s type as a schema."""
        self._msgtypes[connection.msgtype] = connection
        if self._mcap is not None:
            self._register_schema(self._mcap, connection)

    def add_connection(self, connection: Connection, offered_qos_profiles: str) -> None:
        """Store ``connection`` as a channel (topic, encoding, QoS and type hash)."""
        self._connections.append((connection, offered_qos_profiles))
        if self._mcap is not None:
            self._register_channel(self._mcap, connection, offered_qos_profiles)

    def write(self, connection: Connection, timestamp: int,
              data: Union[bytes, memoryview]) -> None:
        """Add one serialized message to the chunk in progress."""
        mcap = self._writer()
        mcap.add_message(self._channels[connection.id], timestamp, bytes(data), timestamp)
        self.files[-1].add(timestamp)

    def flush(self) -> None:
        """End the chunk in progress and hand it to the OS; finish the file when it is due."""
        if self._mcap is None:
            return
        self._mcap.flush()
        self._flushes += 1
        if self.flushes_per_file and self._flushes >= self.flushes_per_file \
                and self.files[-1].count:
            self._finish_file()

    def _finish_file(self, metadata: Optional[str] = None) -> None:
        assert self._mcap is not None and self._stream is not None
        self._mcap.flush()
        if metadata is not None:
            self._mcap.add_metadata('rosbag2', {'serialized_metadata': metadata})
        self._mcap.finish()
        self._stream.close()
        self._mcap = self._stream = None

    def list_files(self, information: Dict[str, Any]) -> None:
        """Set the file lists of a bag's metadata (``rosbag2_bagfile_information``) in place."""
        information['relative_file_paths'] = [stats.name for stats in self.files]
        information['files'] = [stats.entry() for stats in self.files]

    def close(self, version: int, metadata: str) -> None:
        """Finish the file being written, with the ``rosbag2`` metadata record (every file)."""
        if self._mcap is not None:
            information = yaml.safe_load(metadata)
            self.list_files(information)
            self._finish_file(yaml.safe_dump(information, default_flow_style=False,
                                             sort_keys=False).strip())

    def abort(self) -> None:
        """Close the file as it is (no summary)."""
        if self._stream is not None:
            self._stream.close()
        self._mcap = self._stream = None


class _Rosbag2Writer(Writer):
    """rosbags' rosbag2 writer with :class:`McapStorage` as its MCAP storage."""

    STORAGE_PLUGINS = {StoragePlugin.MCAP: McapStorage}

    def close(self) -> None:
        """Close as rosbags does, then list every MCAP file of the bag in metadata.yaml."""
        storage = self.storage
        assert isinstance(storage, McapStorage)
        super().close()
        if len(storage.files) == 1:
            return
        with self.metapath.open(encoding='utf-8') as stream:
            document = yaml.safe_load(stream)
        storage.list_files(document['rosbag2_bagfile_information'])
        temporary = self.metapath.with_suffix('.yaml.tmp')
        with temporary.open('w', encoding='utf-8') as stream:
            yaml.safe_dump(document, stream, default_flow_style=False, sort_keys=False)
        temporary.replace(self.metapath)


class BagWriter:
    """A rosbag2 (MCAP) being written; close it (or use ``with``) to write metadata.yaml."""

    def __init__(self, path, overwrite=False, flushes_per_file=0):
        """
        Open a new bag at ``path``; an existing bag there is replaced only with overwrite.

        flushes_per_file: start a new MCAP file after this many :meth:`flush` calls (0: one
        file); the recorder passes :data:`FLUSHES_PER_FILE`.
        """
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
        self._writer = _Rosbag2Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        storage = self._writer.storage
        assert isinstance(storage, McapStorage)
        self._storage = storage
        storage.flushes_per_file = flushes_per_file
        self._connections = {}
        self.counts = {}

    def add_topic(self, topic, msgtype, qos=None, definition=None):
        """
        Register ``topic`` with ROS type ``msgtype`` (e.g. 'geometry_msgs/msg/PoseStamped').

        qos: the offered QoS profile, or a list of them. definition: (message definition text,
        RIHS01 type hash) as another bag carried them; by default both come from the Jazzy type
        store.
        """
        profiles = [] if qos is None else list(qos) if isinstance(qos, list) else [qos]
        msgdef, rihs01 = definition if definition is not None else (None, None)
        self._connections[topic] = self._writer.add_connection(
            topic, msgtype, typestore=TYPESTORE, msgdef=msgdef, rihs01=rihs01,
            offered_qos_profiles=profiles)
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
        self.flush()

    def flush(self):
        """Put every message written so far into the file (one chunk); the recorder's timer."""
        if self._writer is not None:
            self._storage.flush()

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
