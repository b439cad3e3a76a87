# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Read rosbag2 directories of formation runs (``rosbags``) back into a trajectory; recover cut bags.

Bags are written by the recorder (:mod:`formation_ros.ros.bag_writer`). Reading rebuilds a
:class:`formation_ros.core.runs.trajectory.Trajectory` from the recorded poses, commands and
reference samples (header stamps, i.e. simulated time).

A bag whose recorder was killed (SIGKILL, power cut) has no metadata.yaml and an MCAP without
summary or footer, its last record possibly cut short. :func:`recover_bag` reads such a file
record by record with the ``mcap`` library's record parsers, keeps every record that is whole
(chunks only if their CRC holds) and stops at the first one that runs past the end of the file;
:func:`repair_bag` writes what it recovered as a complete bag in place and keeps the damaged
files beside it.
"""

from dataclasses import dataclass, field, replace
from io import BytesIO
import os
import re
import shutil
import struct
import tempfile
from typing import Any, Dict, List, Optional, Tuple

from formation_ros.core.maths.frames import advance, FrameSample
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.model.bodies import UnicycleBodies
from formation_ros.core.model.commanded import (commanded_velocity, needs_orientation,
                                                UNKNOWN_ORIENTATION)
from formation_ros.core.runs.events import timeline_events
from formation_ros.core.runs.timeline import Mode, named_shape, Shape, TeamState, Timeline
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.declarations import CommandFrame
from formation_ros.core.settings.file_guard import read_params_file_text
from formation_ros.core.settings.params import check_shape, FormationConfig, ParamError
from formation_ros.ros import topics as names
from formation_ros.ros.bag_writer import BagError, BagWriter, PARAMS_FILE, TYPESTORE
from formation_ros.ros.fields import frame_of, points_of, position_of, stamp_to_ns
from formation_ros.ros.messages import team_state_of
from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Header, Message, Schema
from mcap.stream_reader import breakup_chunk
import numpy as np
from rosbags.rosbag2 import Reader
from rosbags.rosbag2.metadata import parse_qos


Recorded = Dict[str, List[Tuple[int, Any]]]
EVENTS = 'events'
"""The key of the run's events (``runs.events``) in the info of :func:`trajectory_from_topics`."""
MCAP_MAGIC = b'\x89MCAP0\r\n'
METADATA = 'metadata.yaml'
DAMAGED = '.damaged'
RECORD_HEAD = struct.Struct('<BQ')


def read_messages(path: str) -> Tuple[Recorded, Dict[str, int]]:
    """
    Return ({topic: [(timestamp_ns, message), ...]}, {topic: count in metadata.yaml}).

    Only a whole bag is read (metadata.yaml and complete MCAP files); anything else raises
    :class:`BagError` saying what is wrong (see :func:`read_or_recover`). Topics of types that
    the Jazzy type store does not know are counted but not read.
    """
    if not os.path.isfile(os.path.join(path, METADATA)):
        raise BagError(f'{path}: no {METADATA}, not a rosbag2 directory')
    recorded: Recorded = {}
    counts: Dict[str, int] = {}
    try:
        with Reader(path) as reader:
            for connection in reader.connections:
                counts[connection.topic] = counts.get(connection.topic, 0) + connection.msgcount
            known = [c for c in reader.connections if c.msgtype in TYPESTORE.types]
            for connection, timestamp, raw in reader.messages(known) if known else ():
                message = _decode(raw, connection.msgtype, connection.topic)
                recorded.setdefault(connection.topic, []).append((timestamp, message))
    except BagError:
        raise
    # rosbags parses untrusted files: whatever it raises means that this bag is not whole.
    except Exception as exc:
        raise BagError(f'{path}: rosbags cannot read it ({_one_line(exc)})') from None
    read = sum(len(messages) for messages in recorded.values())
    known_count = sum(connection.msgcount for connection in known)
    if read != known_count:
        raise BagError(f'{path}: {METADATA} counts {known_count} messages, its files hold {read}')
    return recorded, counts


def _one_line(exc: BaseException) -> str:
    text = ' '.join(str(exc).split())
    return f'{type(exc).__name__}: {text}' if text else type(exc).__name__


def _decode(raw: bytes, msgtype: str, topic: str) -> Any:
    if msgtype not in TYPESTORE.types:
        raise BagError(f'{topic} has type {msgtype}, unknown to the ROS 2 Jazzy type store')
    try:
        return TYPESTORE.deserialize_cdr(raw, msgtype)
    # CDR bytes from the file: a message cut or corrupted in any way fails here.
    except Exception as exc:
        raise BagError(f'a message on {topic} is not a valid {msgtype} '
                       f'({_one_line(exc)})') from None


@dataclass
class RecoveredTopic:
    """One topic of a recovered MCAP: its channel, its schema and its messages (raw CDR)."""

    msgtype: str
    definition: str
    metadata: Dict[str, str]
    messages: List[Tuple[int, bytes]] = field(default_factory=list)


@dataclass
class Recovery:
    """
    What the MCAP files of a bag still hold, and what was dropped to get it.

    size: bytes in the files; kept: bytes up to the end of the last whole record (the rest was
    cut short); complete: every file's data section ended properly (its writer finished it).
    """

    files: List[str]
    topics: Dict[str, RecoveredTopic] = field(default_factory=dict)
    size: int = 0
    kept: int = 0
    complete: bool = True
    dropped_chunks: int = 0
    dropped_records: int = 0
    dropped_messages: int = 0
    undecodable: int = 0

    @property
    def count(self) -> int:
        """Messages recovered, on every topic."""
        return sum(len(topic.messages) for topic in self.topics.values())

    def describe(self) -> str:
        """One line: how many messages were recovered from which files, and what was dropped."""
        shown = ', '.join(os.path.basename(name) for name in self.files)
        dropped = []
        if self.size > self.kept:
            dropped.append(f'the last {self.size - self.kept} bytes (a record cut short)')
        for number, what in ((self.dropped_chunks, 'damaged chunks'),
                             (self.dropped_records, 'damaged records'),
                             (self.dropped_messages, 'messages without a usable channel')):
            if number:
                dropped.append(f'{number} {what}')
        ending = '; dropped ' + ', '.join(dropped) if dropped else ''
        if self.undecodable:
            ending += f'; {self.undecodable} of them do not decode and are left out'
        state = ('data section whole' if self.complete
                 else 'no summary or footer: writing was cut')
        return (f'recovered {self.count} messages on {len(self.topics)} topics from {shown} '
                f'({state}){ending}')


class _McapScan:
    """Walks the records of one MCAP file and adds what is whole to a :class:`Recovery`."""

    def __init__(self, recovery: Recovery) -> None:
        self.recovery = recovery
        self.schemas: Dict[int, Schema] = {}
        self.channels: Dict[int, Channel] = {}

    def run(self, path: str) -> None:
        with open(path, 'rb') as stream:
            size = os.fstat(stream.fileno()).st_size
            self.recovery.size += size
            name = os.path.basename(path)
            if size == 0:
                raise BagError(f'{name} is empty: nothing reached the file')
            if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
                raise BagError(f'{name} is not an MCAP file (no MCAP magic at its start)')
            offset = len(MCAP_MAGIC)
            first = True
            while True:
                head = stream.read(RECORD_HEAD.size)
                if len(head) < RECORD_HEAD.size:
                    self.recovery.complete = False
                    break
                opcode, length = RECORD_HEAD.unpack(head)
                if length > size - offset - RECORD_HEAD.size:
                    self.recovery.complete = False
                    break
                body = stream.read(length)
                offset += RECORD_HEAD.size + length
                if first:
                    self._check_header(name, opcode, body)
                    first = False
                    continue
                if opcode in (Opcode.DATA_END, Opcode.FOOTER):
                    offset = size
                    break
                self._record(opcode, body)
            self.recovery.kept += offset

    @staticmethod
    def _check_header(name: str, opcode: int, body: bytes) -> None:
        if opcode != Opcode.HEADER:
            raise BagError(f'{name} is not an MCAP file (its first record is not a header)')
        try:
            profile = Header.read(ReadDataStream(BytesIO(body))).profile
        # Header bytes from the file: any failure means that it is not an MCAP header.
        except Exception:
            raise BagError(f'{name} is not an MCAP file (unreadable header)') from None
        if profile != 'ros2':
            raise BagError(f'{name} is an MCAP file of profile {profile!r}, not a ROS 2 bag')

    def _record(self, opcode: int, body: bytes) -> None:
        stream = ReadDataStream(BytesIO(body))
        try:
            if opcode == Opcode.CHUNK:
                inner = breakup_chunk(Chunk.read(stream), validate_crc=True)
            elif opcode == Opcode.SCHEMA:
                inner = [Schema.read(stream)]
            elif opcode == Opcode.CHANNEL:
                inner = [Channel.read(stream)]
            elif opcode == Opcode.MESSAGE:
                inner = [Message.read(stream, len(body))]
            else:
                return
        # Record bytes from the file (CRC checked for chunks): any parse failure drops it.
        except Exception:
            if opcode == Opcode.CHUNK:
                self.recovery.dropped_chunks += 1
            else:
                self.recovery.dropped_records += 1
            return
        for record in inner:
            if isinstance(record, Schema):
                self.schemas[record.id] = record
            elif isinstance(record, Channel):
                self.channels[record.id] = record
            elif isinstance(record, Message):
                self._message(record)

    def _message(self, message: Message) -> None:
        channel = self.channels.get(message.channel_id)
        schema = self.schemas.get(channel.schema_id) if channel is not None else None
        if channel is None or schema is None or channel.message_encoding != 'cdr':
            self.recovery.dropped_messages += 1
            return
        topic = self.recovery.topics.get(channel.topic)
        if topic is None:
            topic = RecoveredTopic(schema.name, schema.data.decode('utf-8', 'replace'),
                                   dict(channel.metadata))
            self.recovery.topics[channel.topic] = topic
        elif topic.msgtype != schema.name:
            self.recovery.dropped_messages += 1
            return
        topic.messages.append((message.log_time, message.data))


def _natural(name: str) -> List[Any]:
    """Sort key that puts ``bag_2.mcap`` before ``bag_10.mcap``."""
    return [int(part) if part.isdigit() else part for part in re.split(r'([0-9]+)', name)]


def mcap_files(path: str) -> List[str]:
    """Return the MCAP files of a bag directory (each ``*.mcap``, in order), or [path] itself."""
    if os.path.isfile(path):
        return [path]
    if not os.path.isdir(path):
        raise BagError(f'{path}: no such file or directory')
    return [os.path.join(path, name) for name in sorted(os.listdir(path), key=_natural)
            if name.endswith('.mcap') and os.path.isfile(os.path.join(path, name))]


def recover_bag(path: str) -> Recovery:
    """
    Recover the messages of a bag directory (or one MCAP file) without trusting its metadata.

    Raises :class:`BagError` if there is no MCAP file, a file is not an MCAP file of a ROS 2
    bag, or no message at all is left.
    """
    files = mcap_files(path)
    if not files:
        raise BagError('no .mcap file to recover messages from')
    recovery = Recovery(files)
    try:
        for name in files:
            _McapScan(recovery).run(name)
    except OSError as exc:
        raise BagError(f'cannot read {exc.filename}: {exc.strerror or exc}') from None
    if not recovery.count:
        shown = ', '.join(os.path.basename(name) for name in files)
        raise BagError(f'no whole message in {shown} ({recovery.kept} of {recovery.size} bytes '
                       'readable)')
    for topic in recovery.topics.values():
        topic.messages.sort(key=lambda item: item[0])
    return recovery


def decode_recovered(recovery: Recovery) -> Tuple[Recorded, Dict[str, int]]:
    """
    Deserialize the recovered messages: ({topic: [(timestamp_ns, message), ...]}, counts).

    A message that does not decode as its type (or whose type is not in the Jazzy type store)
    is left out and counted in ``recovery.undecodable``.
    """
    recorded: Recorded = {}
    for name, topic in recovery.topics.items():
        for timestamp, raw in topic.messages:
            try:
                message = _decode(raw, topic.msgtype, name)
            except BagError:
                recovery.undecodable += 1
                continue
            recorded.setdefault(name, []).append((timestamp, message))
    return recorded, {name: len(messages) for name, messages in recorded.items()}


def read_or_recover(path: str) -> Tuple[Recorded, Dict[str, int], Optional[str]]:
    """
    Read a whole bag, else recover what its MCAP files hold.

    Returns (recorded, counts, note): note is None for a whole bag, else one line that says why
    the bag was recovered and how many messages were. Raises :class:`BagError` (one line,
    both reasons) when neither works.
    """
    if os.path.isdir(path) and os.path.isfile(os.path.join(path, METADATA)):
        try:
            recorded, counts = read_messages(path)
            return recorded, counts, None
        except BagError as exc:
            why = f'{exc}; '
    elif os.path.isdir(path):
        why = f'{path}: no {METADATA} (the bag was not finished: recorder killed or running); '
    else:
        why = f'{path}: '
    try:
        recovery = recover_bag(path)
    except BagError as exc:
        raise BagError(f'{why}nothing to recover: {exc}') from None
    recorded, counts = decode_recovered(recovery)
    if not recorded:
        raise BagError(f'{why}nothing to recover: none of the {recovery.count} messages '
                       'decodes')
    return recorded, counts, f'{why}{recovery.describe()}'


def _whole(path: str) -> bool:
    """Whether rosbags reads every message that metadata.yaml counts."""
    try:
        with Reader(path) as reader:
            expected = sum(connection.msgcount for connection in reader.connections)
            return sum(1 for _ in reader.messages()) == expected
    # Untrusted files: whatever rosbags raises means that this bag is not whole.
    except Exception:
        return False


def _aside(name: str) -> str:
    target, number = name + DAMAGED, 1
    while os.path.exists(target):
        target, number = f'{name}{DAMAGED}.{number}', number + 1
    os.rename(name, target)
    return target


def _qos_profiles(metadata: Dict[str, str]) -> List[Any]:
    try:
        return parse_qos(metadata.get('offered_qos_profiles', ''))
    # Channel metadata from the file: unreadable QoS leaves the profiles out.
    except Exception:
        return []


def repair_bag(path: str) -> str:
    """
    Make a cut or damaged bag directory whole again, in place; return one line saying so.

    The recovered messages are written as a new MCAP and metadata.yaml (a complete rosbag2
    directory that rosbags and ``ros2 bag info`` read); the damaged MCAP files and
    metadata.yaml are kept beside them with the suffix ``.damaged``. A whole bag is left as
    it is. Raises :class:`BagError` if nothing can be recovered.
    """
    if not os.path.isdir(path):
        raise BagError('not a bag directory' if os.path.exists(path) else 'no such directory')
    path = os.path.abspath(path)
    if os.path.isfile(os.path.join(path, METADATA)) and _whole(path):
        return f'{path} is whole; nothing to repair'
    recovery = recover_bag(path)
    skipped = []
    work = tempfile.mkdtemp(prefix=f'.{os.path.basename(path)}.repair-',
                            dir=os.path.dirname(path))
    try:
        fresh = os.path.join(work, os.path.basename(path))
        with BagWriter(fresh) as bag:
            for name, topic in recovery.topics.items():
                digest = topic.metadata.get('topic_type_hash', '')
                if not digest and topic.msgtype in TYPESTORE.types:
                    digest = TYPESTORE.hash_rihs01(topic.msgtype)
                if not digest:
                    skipped.append(name)
                    continue
                bag.add_topic(name, topic.msgtype, _qos_profiles(topic.metadata),
                              (topic.definition, digest))
            merged = sorted((timestamp, name, raw) for name, topic in recovery.topics.items()
                            if name not in skipped for timestamp, raw in topic.messages)
            for timestamp, name, raw in merged:
                bag.write(name, timestamp, raw)
        kept = [_aside(name) for name in recovery.files]
        if os.path.exists(os.path.join(path, METADATA)):
            kept.append(_aside(os.path.join(path, METADATA)))
        for name in os.listdir(fresh):
            os.rename(os.path.join(fresh, name), os.path.join(path, name))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    written = sum(bag.counts.values())
    note = f'; left out {", ".join(skipped)} (no type hash)' if skipped else ''
    return (f'repaired {path}: {written} messages on {len(recovery.topics) - len(skipped)} '
            f'topics in a new MCAP and {METADATA}; the damaged files are kept as '
            f'{", ".join(os.path.basename(name) for name in kept)}{note}')


def bag_params_text(path: str, recorded: Recorded) -> Optional[str]:
    """
    Return the parameters YAML stored with a bag (topic, else params.yaml), or None.

    params.yaml is read within the limits of :mod:`formation_ros.core.settings.file_guard` (raises
    its ParamsFileError).
    """
    if recorded.get(names.PARAMS):
        return recorded[names.PARAMS][-1][1].data
    file_path = os.path.join(path, PARAMS_FILE)
    if os.path.isfile(file_path):
        return read_params_file_text(file_path)
    return None


def _frames_at(stamps: List[int], reference_messages: List[Tuple[int, Any]],
               config: FormationConfig) -> Tuple[List[FrameSample], str]:
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


def trajectory_from_topics(recorded: Recorded,
                           config: FormationConfig) -> Tuple[Trajectory, Dict[str, str]]:
    """
    Rebuild the run from recorded messages.

    Samples are the state stamps at which every robot's pose was recorded; the command held by
    robot i at a sample is the one it sent for that state (or its latest earlier one, zero
    before its first); desired positions come from the recorded reference samples (or, if none
    were recorded, from the reference in the parameters) and the formation vertices. Returns
    (Trajectory, info). Unicycles: the headings are the poses' orientations, the commands (v,
    w) are linear.x and angular.z, and q, u are those of the hand points (``Trajectory`` with
    its body arrays). Poses in a frame other than ``world_frame`` are left out (counted in the
    info). Where a command needs an orientation (unicycles, body-frame commands of points), u
    is what the robot commanded, read at the orientation of the pose it answered
    (``core.model.commanded``: the robot's own /robot_<i>/pose at the command's stamp), NaN where
    that pose was not recorded or the command has no stamp to name it; u_held reads it at the
    pose of each sample instead (``Trajectory.with_held``).
    """
    n, dim = config.num_robots, config.dim
    unicycles = config.body.is_unicycle
    body_frame = not unicycles and config.command.frame is CommandFrame.BODY
    oriented = needs_orientation(unicycles, body_frame)
    poses: Dict[int, Dict[int, Any]] = {}
    orientations: Dict[Tuple[int, int], Tuple[float, ...]] = {}
    other_frame = 0
    for i in range(1, n + 1):
        for _, message in recorded.get(names.robot_topic(i, names.POSE), []):
            if message.header.frame_id != config.world_frame:
                other_frame += 1
                continue
            stamp = stamp_to_ns(message.header.stamp)
            poses.setdefault(stamp, {})[i - 1] = position_of(message, dim)
            o = message.pose.orientation
            if oriented:
                orientations[(i, stamp)] = (o.x, o.y, o.z, o.w)
    stamps = sorted(stamp for stamp, seen in poses.items() if len(seen) == n)
    if len(stamps) < 2:
        frames = (f' ({other_frame} poses in a frame other than world_frame '
                  f'{config.world_frame!r} left out)' if other_frame else '')
        raise BagError(f'fewer than two moments with the poses of all robots recorded{frames}')
    q = np.array([[poses[stamp][i] for i in range(n)] for stamp in stamps])
    width = 2 if unicycles else dim
    held = np.zeros((len(stamps), n, width))
    answered = np.full((len(stamps), n, 4), np.nan)
    for i in range(1, n + 1):
        commands = _commands_by_state(recorded, i, config)
        if not commands:
            continue
        known = np.array(sorted(commands))
        index = np.searchsorted(known, stamps, side='right') - 1
        values = np.array([commands[int(k)] for k in known])
        held[:, i - 1] = np.where((index >= 0)[:, None], values[np.maximum(index, 0)], 0.0)
        if oriented and config.command.stamped:
            answered[:, i - 1] = [orientations.get((i, int(known[k])), UNKNOWN_ORIENTATION)
                                  if k >= 0 else UNKNOWN_ORIENTATION for k in index.tolist()]
    frames, source = _frames_at(stamps, recorded.get(names.REFERENCE, []), config)
    shapes = recorded_shapes(recorded, config)
    states = recorded_states(recorded, config)
    vertices = [shapes.at(stamp).vertices for stamp in stamps]
    info: Dict[str, Any] = {'reference_source': source}
    if shapes.changes():
        info['shape_changes'] = len(shapes.changes())
    events = timeline_events(shapes, states)
    if events:
        info[EVENTS] = events
    if other_frame:
        info['poses_in_another_frame'] = other_frame
    t = np.array(stamps) / NS_PER_S
    guard = config.feed_forward_guard()
    if not oriented:
        return Trajectory.from_frames(t, q, held, frames, vertices, guard), info
    l_value = config.body.hand_distance
    sampled = np.array([[orientations[(i, stamp)] for i in range(1, n + 1)]
                        for stamp in stamps])
    shape = (len(stamps), n, dim)
    u = commanded_velocity(held.reshape(-1, width), answered.reshape(-1, 4), unicycles,
                           l_value, body_frame).reshape(shape)
    u_held = commanded_velocity(held.reshape(-1, width), sampled.reshape(-1, 4), unicycles,
                                l_value, body_frame).reshape(shape)
    if not unicycles:
        return (Trajectory.from_frames(t, q, u, frames, vertices, guard)
                .with_held(u_held, frames, guard), info)
    heading = headings_from_quaternions(sampled)
    points = UnicycleBodies(l_value).control_points(q, heading)
    trajectory = Trajectory.from_frames(t, points, u, frames, vertices, guard).with_held(
        u_held, frames, guard)
    return replace(trajectory, heading=heading, q_body=q, body_command=held), info


def recorded_shapes(recorded: Recorded, config: FormationConfig) -> Timeline[Shape]:
    """
    Return the shape in force at each stamp: the file's, then each recorded ``/formation/shape``.

    A recorded shape in another frame, or that the law could not hold, is left out (the robots
    refused it too).
    """
    shapes = Timeline(named_shape(config.vertices, config.shapes))
    for _, message in recorded.get(names.SHAPE, []):
        if message.header.frame_id != config.world_frame:
            continue
        flat = [float(v) for row in points_of(message, config.dim) for v in row]
        try:
            vertices = check_shape(flat, config.num_robots, config.dim, config.repulsion_radius)
        except ParamError:
            continue
        shapes.add(stamp_to_ns(message.header.stamp), named_shape(vertices, config.shapes))
    return shapes


def recorded_states(recorded: Recorded, config: FormationConfig) -> Timeline[TeamState]:
    """Return the team state in force at each stamp, from the recorded ``/formation/status``."""
    states = Timeline(TeamState.of(Mode.RUNNING, config.shape_name, config.reference()))
    for _, message in recorded.get(names.STATUS, []):
        try:
            states.add(stamp_to_ns(message.header.stamp), team_state_of(message, config.dim))
        except ValueError:
            continue
    return states


def _commands_by_state(recorded: Recorded, robot: int,
                       config: FormationConfig) -> Dict[int, Any]:
    """
    Return robot ``robot``'s recorded commands by the stamp of the state each answers.

    A TwistStamped carries that stamp; a Twist (``command.type: twist``) does not, and is taken
    to answer the robot's latest pose recorded before it (by the recorder's receive times): a
    guess, so such a command is not read at that pose's orientation
    (:func:`trajectory_from_topics`).
    Values: (dim,) linear velocities, or (v, w) for unicycles.
    """
    linear_only = not config.body.is_unicycle
    pose_log = [(received, stamp_to_ns(message.header.stamp)) for received, message in
                recorded.get(names.robot_topic(robot, names.POSE), [])]
    pose_log.sort()
    received_at = np.array([received for received, _ in pose_log], dtype=np.int64)
    commands: Dict[int, Any] = {}
    for received, message in recorded.get(names.robot_topic(robot, names.CMD_VEL), []):
        if config.command.stamped:
            stamp, twist = stamp_to_ns(message.header.stamp), message.twist
        else:
            index = int(np.searchsorted(received_at, received, side='right')) - 1
            if index < 0:
                continue
            stamp, twist = pose_log[index][1], message
        commands[stamp] = (np.array([twist.linear.x, twist.linear.y, twist.linear.z][:config.dim])
                           if linear_only else (twist.linear.x, twist.angular.z))
    return commands


def plant_status(recorded: Recorded) -> Dict[str, int]:
    """
    Return the counters of the plant's last /diagnostics status, or {}.

    Keys as in ``plant_stats.json`` (``stale_command_steps``...): the status's keys
    (``stale command steps``) with underscores.
    """
    wanted = ('collisions', 'bound_violations', 'stale_command_steps', 'bad_command_steps',
              'missing_command_steps', 'steps')
    for _, message in reversed(recorded.get(names.DIAGNOSTICS, [])):
        for status in message.status:
            if status.name == 'formation_ros/plant':
                return {key: int(kv.value) for kv in status.values
                        for key in [kv.key.replace(' ', '_')] if key in wanted}
    return {}
