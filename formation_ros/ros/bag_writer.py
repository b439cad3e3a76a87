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

A write that fails (a full disk: ``ENOSPC``, or any other OSError on a write, flush or close)
ends the writing at once: the MCAP file is cut back to its last whole chunk and ended there
(data end and footer, no summary: readers scan such a file), metadata.yaml is written for
what the files hold, and :class:`BagWriteError` says how much that is (:class:`WriteFailure`).
The files are written unbuffered (:class:`FileSink`), so nothing is left in a buffer to be
written after the failure.
"""

from dataclasses import dataclass
import errno
import os
from pathlib import Path
import shutil
from typing import Any, BinaryIO, Callable, Dict, List, Optional, Tuple, Union

from formation_ros.core.settings.params_file import dump_params_text
from formation_ros.ros import topics
from formation_ros.ros.cdr import CdrError, read_clock
from formation_ros.ros.fields import NS_PER_S
from mcap import __version__ as MCAP_VERSION
from mcap.data_stream import RecordBuilder
from mcap.records import DataEnd, Footer
from mcap.writer import CompressionType, MCAP0_MAGIC, Writer as McapWriter
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
NO_SPACE = (errno.ENOSPC, errno.EDQUOT)
ROOM_BASE = 16 << 10
ROOM_PER_TOPIC = 2 << 10
"""Bytes that closing a bag on a full disk may give up (complete chunks, newest first) to make
room for the end of its MCAP file and metadata.yaml: ROOM_BASE plus ROOM_PER_TOPIC per topic
(metadata.yaml takes about 0.7 KB per topic, and a filesystem counts whole blocks)."""


def _tail() -> bytes:
    """Return the end of an MCAP file without summary: data end, footer, magic."""
    builder = RecordBuilder()
    DataEnd(0).write(builder)
    Footer(summary_start=0, summary_offset_start=0, summary_crc=0).write(builder)
    return bytes(builder.end()) + MCAP0_MAGIC


_TAIL = _tail()


class BagError(Exception):
    """A bag cannot be written or read; the message says why."""


@dataclass(frozen=True)
class WriteFailure:
    """
    How a bag whose writing failed was closed: the error and what the bag holds.

    messages: messages in the bag (in chunks that reached its files whole); size: bytes of its
    MCAP files; first_ns, last_ns: receive times of its first and last message; clock_ns: the
    last /clock it holds (simulated time), None without any; metadata: metadata.yaml was
    written (else the bag is left for ``formation_report``'s recovery); lost: messages handed
    to the writer that are not in the bag.
    """

    reason: str
    messages: int
    size: int
    first_ns: int
    last_ns: int
    clock_ns: Optional[int]
    metadata: bool
    lost: int

    def describe(self) -> str:
        """Say in one clause how much the bag holds, up to when, and how it was left."""
        if self.clock_ns is not None:
            until = f'up to simulated time {self.clock_ns / NS_PER_S:.2f} s'
        else:
            until = f'{(self.last_ns - self.first_ns) / NS_PER_S:.1f} s of recording'
        state = ('closed, readable (metadata.yaml written)' if self.metadata else
                 'left without metadata.yaml (formation_report recovers it)')
        lost = f'; {self.lost} messages received after that are not in it' if self.lost else ''
        return (f'the bag holds {self.messages} messages ({self.size / 1e6:.2f} MB) {until}, '
                f'{state}{lost}')


class BagWriteError(BagError):
    """Writing a bag failed; :attr:`failure` says how it was closed (None: nothing written)."""

    def __init__(self, message: str, failure: Optional[WriteFailure] = None) -> None:
        """Keep the one-line message and the failure."""
        super().__init__(message)
        self.failure = failure


def reason_of(exc: OSError) -> str:
    """Return an OSError as one short clause: its strerror ('No space left on device')."""
    return exc.strerror or ' '.join(str(exc).split()) or type(exc).__name__


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


class FileSink:
    """
    One MCAP file as the mcap writer sees it: every write reaches the OS whole, or raises.

    ``raw`` is an unbuffered binary file (``open(path, 'xb', buffering=0)``): nothing waits in a
    buffer that a failed write would leave behind, a short write is continued (a full disk
    first takes what still fits, then refuses), and the file can be cut back to a known size.
    """

    def __init__(self, raw: BinaryIO) -> None:
        """Write into ``raw`` from its start."""
        self.raw = raw
        self.offset = 0

    def write(self, data: Union[bytes, bytearray, memoryview]) -> int:
        """Write all of ``data``; OSError (nothing said about how much arrived) if it fails."""
        view = memoryview(data).cast('B')
        while view:
            written = self.raw.write(view)
            if not written:
                raise OSError(errno.EIO, 'the file took no bytes')
            self.offset += written
            view = view[written:]
        return len(data)

    def tell(self) -> int:
        """Return the bytes written so far."""
        return self.offset

    def flush(self) -> None:
        """Nothing is buffered here."""

    def cut(self, offset: int) -> None:
        """Cut the file back to ``offset`` bytes and write on from there."""
        self.raw.truncate(offset)
        self.raw.seek(offset)
        self.offset = offset

    def close(self) -> None:
        """Close the file."""
        self.raw.close()


def open_new(path: Path) -> BinaryIO:
    """Create ``path`` (it must not exist) for unbuffered writing: how MCAP files are opened."""
    return path.open('xb', buffering=0)


@dataclass
class _Commit:
    """One chunk that reached the file whole: where it ends, its messages, its last clock."""

    offset: int
    counts: Dict[int, int]
    first_ns: int
    last_ns: int
    clock: Optional[bytes]


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

    Each flush that reaches the file whole is a commit: the file's size then and the messages
    in it. Only committed messages count (:attr:`on_disk`, :attr:`files`); after a failed write
    :meth:`salvage` cuts the file back to its last commit and :meth:`close` ends it with a
    data-end record and a footer without summary, which readers scan (rosbags, ``ros2 bag``).
    """

    OPENER: Callable[[Path], BinaryIO] = staticmethod(open_new)  # type: ignore[assignment]
    """How the MCAP files are opened (a test replaces it in a subclass)."""

    def __init__(self, path: Path, compression: CompressionMode) -> None:
        """Create ``<path>/<path.name>.mcap`` (it must not exist) and write its header."""
        if compression != CompressionMode.NONE:
            raise BagError(f'{path}: only uncompressed bags are written here')
        self.folder = path
        self.path = path / f'{path.name}.mcap'
        self.flushes_per_file = 0
        self.files: List[FileStats] = []
        self.on_disk: Dict[int, int] = {}
        """Committed messages per connection id, in every file of the bag."""
        self._clock_at_open: Optional[bytes] = None
        self.failed = False
        self._msgtypes: Dict[str, Connection] = {}
        self._connections: List[Tuple[Connection, str]] = []
        self._sink: Optional[FileSink] = None
        self._mcap: Optional[McapWriter] = None
        self._schemas: Dict[str, int] = {}
        self._channels: Dict[int, int] = {}
        self._flushes = 0
        self._base: Optional[int] = None
        self._commits: List[_Commit] = []
        self._pending: Dict[int, int] = {}
        self._pending_times: List[int] = []
        self._pending_clock: Optional[bytes] = None
        self._open(self.path)

    def _open(self, path: Path) -> McapWriter:
        self._clock_at_open = self.last_clock
        self.files.append(FileStats(path.name))
        self._base, self._commits = None, []
        self._sink = FileSink(self.OPENER(path))
        self._mcap = McapWriter(self._sink, chunk_size=CHUNK_SIZE,
                                compression=CompressionType.NONE)
        self._mcap.start(profile='ros2', library=f'formation_ros (mcap-python {MCAP_VERSION})')
        self._base = self._sink.offset
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
        self._pending[connection.id] = self._pending.get(connection.id, 0) + 1
        self._pending_times.append(timestamp)
        if connection.topic == topics.CLOCK:
            self._pending_clock = bytes(data)

    def flush(self) -> None:
        """End the chunk in progress and hand it to the OS; finish the file when it is due."""
        if self._mcap is None:
            return
        self._mcap.flush()
        self._commit()
        self._flushes += 1
        if self.flushes_per_file and self._flushes >= self.flushes_per_file \
                and self.files[-1].count:
            self._finish_file()

    def _commit(self) -> None:
        """Count the messages written since the last commit: they are in the file now."""
        assert self._sink is not None
        if not self._pending:
            return
        commit = _Commit(self._sink.offset, self._pending, min(self._pending_times),
                         max(self._pending_times), self._pending_clock or self.last_clock)
        self._commits.append(commit)
        self._pending, self._pending_times, self._pending_clock = {}, [], None
        self._count(commit, 1)

    def _count(self, commit: _Commit, sign: int) -> None:
        """Add (sign 1) or take away (-1) a commit's messages in the counts of the bag."""
        for key, number in commit.counts.items():
            self.on_disk[key] = self.on_disk.get(key, 0) + sign * number
        stats = self.files[-1]
        stats.count = sum(sum(kept.counts.values()) for kept in self._commits)
        stats.first_ns = min((kept.first_ns for kept in self._commits), default=0)
        stats.last_ns = max((kept.last_ns for kept in self._commits), default=0)

    @property
    def last_clock(self) -> Optional[bytes]:
        """Return the last committed message on /clock (CDR), None before any."""
        return self._commits[-1].clock if self._commits else self._clock_at_open

    def _finish_file(self, metadata: Optional[str] = None) -> None:
        assert self._mcap is not None and self._sink is not None
        self._mcap.flush()
        self._commit()
        if metadata is not None:
            self._mcap.add_metadata('rosbag2', {'serialized_metadata': metadata})
        self._mcap.finish()
        self._sink.close()
        self._mcap = self._sink = None

    def list_files(self, information: Dict[str, Any]) -> None:
        """Set the file lists of a bag's metadata (``rosbag2_bagfile_information``) in place."""
        information['relative_file_paths'] = [stats.name for stats in self.files]
        information['files'] = [stats.entry() for stats in self.files]

    def close(self, version: int, metadata: str) -> None:
        """
        Finish the file being written, with the ``rosbag2`` metadata record (every file).

        After :meth:`salvage`: cut the file back to its last commit and end it there (data
        end, footer); the file stays open, so that it can be cut again (:meth:`release`).
        """
        if self.failed:
            if self._sink is not None:
                self._sink.cut(self._end())
                self._sink.write(_TAIL)
            return
        if self._mcap is not None:
            information = yaml.safe_load(metadata)
            self.list_files(information)
            self._finish_file(yaml.safe_dump(information, default_flow_style=False,
                                             sort_keys=False).strip())

    def _end(self) -> int:
        """Return the size of the current file at its last commit."""
        assert self._base is not None
        return self._commits[-1].offset if self._commits else self._base

    def salvage(self) -> None:
        """
        After a failed write: keep only what the files hold whole, write nothing more.

        The current file is cut back to its last commit; a file whose header did not reach
        the disk is removed (the bag's earlier files are complete).
        """
        self.failed = True
        self._mcap = None
        self._pending, self._pending_times, self._pending_clock = {}, [], None
        if self._sink is None:
            return
        if self._base is None:
            self._sink.close()
            self._sink = None
            (self.folder / self.files.pop().name).unlink()
            return
        self._sink.cut(self._end())

    def drop_last_commit(self) -> int:
        """Give up the current file's last chunk (to make room); return its bytes, 0 if none."""
        if self._sink is None or not self._commits:
            return 0
        end = self._end()
        dropped = self._commits.pop()
        self._count(dropped, -1)
        self._sink.cut(self._end())
        return end - self._end()

    def size(self) -> int:
        """Return the bytes of the bag's MCAP files (the current one up to its last commit)."""
        current = self._end() + len(_TAIL) if self._sink is not None else 0
        finished = self.files if self._sink is None else self.files[:-1]
        return current + sum(os.path.getsize(self.folder / stats.name) for stats in finished)

    def release(self) -> None:
        """Close the current file as it is."""
        if self._sink is not None:
            self._sink.close()
        self._mcap = self._sink = None

    def abort(self) -> None:
        """Close the file as it is (no summary)."""
        self.release()


class _Rosbag2Writer(Writer):
    """rosbags' rosbag2 writer with :class:`McapStorage` as its MCAP storage."""

    STORAGE_PLUGINS = {StoragePlugin.MCAP: McapStorage}

    mcap: McapStorage
    """The storage, kept once rosbags has dropped it (set by :class:`BagWriter`)."""

    def close(self) -> None:
        """Close as rosbags does, then list every MCAP file of the bag in metadata.yaml."""
        storage = self.mcap
        if storage.failed:
            self.storage = storage
            self.counts = {key: storage.on_disk.get(key, 0) for key in self.counts}
            kept = [stats for stats in storage.files if stats.count]
            self.min_timestamp = min((stats.first_ns for stats in kept), default=0)
            self.max_timestamp = max((stats.last_ns for stats in kept), default=0)
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
    """
    A rosbag2 (MCAP) being written; close it (or use ``with``) to write metadata.yaml.

    The first OSError of a write, flush or close (a full disk) ends the writing: the bag is
    closed as it is, readable (:meth:`_close_after_failure`), and :class:`BagWriteError` is
    raised with a :class:`WriteFailure` saying what it holds; the writer takes nothing more.
    """

    def __init__(self, path, overwrite=False, flushes_per_file=0, storage=McapStorage):
        """
        Open a new bag at ``path``; an existing bag there is replaced only with overwrite.

        flushes_per_file: start a new MCAP file after this many :meth:`flush` calls (0: one
        file); the recorder passes :data:`FLUSHES_PER_FILE`. storage: the storage class (a
        test passes one whose files fail). Raises BagWriteError when the bag cannot be created.
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
        self._writer: Optional[_Rosbag2Writer] = _Rosbag2Writer(
            self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.STORAGE_PLUGINS = {StoragePlugin.MCAP: storage}
        try:
            self._writer.open()
        except OSError as exc:
            shutil.rmtree(self.path, ignore_errors=True)
            raise BagWriteError(f'cannot create {self.path}: {reason_of(exc)}') from None
        storage = self._writer.storage
        assert isinstance(storage, McapStorage)
        self._writer.mcap = self._storage = storage
        self._storage.flushes_per_file = flushes_per_file
        self._connections: Dict[str, Connection] = {}
        self._written = 0
        self.failure: Optional[WriteFailure] = None

    @property
    def counts(self) -> Dict[str, int]:
        """Return the messages per topic that reached the bag's files whole (so far)."""
        return {topic: self._storage.on_disk.get(connection.id, 0)
                for topic, connection in self._connections.items()}

    def add_topic(self, topic, msgtype, qos=None, definition=None):
        """
        Register ``topic`` with ROS type ``msgtype`` (e.g. 'geometry_msgs/msg/PoseStamped').

        qos: the offered QoS profile, or a list of them. definition: (message definition text,
        RIHS01 type hash) as another bag carried them; by default both come from the Jazzy type
        store.
        """
        profiles = [] if qos is None else list(qos) if isinstance(qos, list) else [qos]
        msgdef, rihs01 = definition if definition is not None else (None, None)
        self._guard(lambda writer: self._connections.__setitem__(topic, writer.add_connection(
            topic, msgtype, typestore=TYPESTORE, msgdef=msgdef, rihs01=rihs01,
            offered_qos_profiles=profiles)))

    def write(self, topic, timestamp_ns, data):
        """Write one serialized (CDR) message received at ``timestamp_ns``."""
        self._written += 1
        self._guard(lambda writer: writer.write(self._connections[topic], int(timestamp_ns),
                                                data))

    def write_params(self, values, timestamp_ns):
        """Store the run's parameters on /formation/params and as params.yaml."""
        text = dump_params_text(values)
        if topics.PARAMS not in self._connections:
            self.add_topic(topics.PARAMS, 'std_msgs/msg/String',
                           qos_of(reliable=True, transient_local=True, depth=1))
        message = TYPESTORE.types['std_msgs/msg/String'](data=text)
        self.write(topics.PARAMS, timestamp_ns,
                   TYPESTORE.serialize_cdr(message, 'std_msgs/msg/String'))
        self._guard(lambda writer: _write_text(os.path.join(self.path, PARAMS_FILE), text))
        self.flush()

    def flush(self):
        """Put every message written so far into the file (one chunk); the recorder's timer."""
        self._guard(lambda writer: self._storage.flush())

    def close(self):
        """Finish the MCAP file and write metadata.yaml (after a failure: nothing to do)."""
        if self._writer is not None and self.failure is None:
            self._guard(lambda writer: writer.close())
            self._writer = None

    def _guard(self, action: Callable[[_Rosbag2Writer], Any]) -> None:
        """Run ``action`` on the open writer; its first OSError closes the bag as it is."""
        if self.failure is not None or self._writer is None:
            raise BagWriteError(f'{self.path}: the bag is closed', self.failure)
        try:
            action(self._writer)
        except OSError as exc:
            failure = self._close_after_failure(exc)
            raise BagWriteError(f'cannot write {self.path}: {failure.reason}', failure) from None

    def _close_after_failure(self, exc: OSError) -> WriteFailure:
        """
        Close the bag as its files hold it after ``exc``: every chunk that reached them whole.

        The current MCAP file is cut back to its last whole chunk and ended there; then
        metadata.yaml is written for what is on disk. When that does not fit on the disk, the
        newest chunks are given up to make room (see :data:`ROOM_PER_TOPIC`) and it is tried
        once more; if it still fails, the bag is left as ``formation_report`` recovers it
        (complete chunks, no metadata.yaml).
        """
        writer, storage = self._writer, self._storage
        assert writer is not None
        metadata = False
        try:
            storage.salvage()
            for attempt in range(2):
                try:
                    writer.close()
                    metadata = True
                    break
                except OSError as again:
                    for name in ('metadata.yaml.tmp', 'metadata.yaml'):
                        _remove(os.path.join(self.path, name))
                    if attempt or again.errno not in NO_SPACE:
                        break
                    room, freed = ROOM_BASE + ROOM_PER_TOPIC * len(self._connections), 0
                    while freed < room:
                        dropped = storage.drop_last_commit()
                        if not dropped:
                            break
                        freed += dropped
        except OSError:
            pass
        finally:
            storage.release()
        self._writer = None
        clock = storage.last_clock
        try:
            clock_ns: Optional[int] = None if clock is None else read_clock(clock)
        except CdrError:
            clock_ns = None
        kept = [stats for stats in storage.files if stats.count]
        messages = sum(storage.on_disk.values())
        self.failure = WriteFailure(
            reason_of(exc), messages, storage.size(),
            min((stats.first_ns for stats in kept), default=0),
            max((stats.last_ns for stats in kept), default=0), clock_ns, metadata,
            self._written - messages)
        return self.failure

    def __enter__(self):
        """Use as a context manager."""
        return self

    def __exit__(self, *exc):
        """Close on leaving the ``with`` block."""
        self.close()


def _write_text(path: str, text: str) -> None:
    with open(path, 'w', encoding='utf-8') as stream:
        stream.write(text)


def _remove(path: str) -> None:
    try:
        os.remove(path)
    except OSError:
        pass
