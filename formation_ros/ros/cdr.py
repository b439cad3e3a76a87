# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The formation messages as CDR bytes: read into numpy and written from numpy, without rclpy.

rclpy turns every message it receives into Python objects and every message it publishes back
into C structures, field by field: a PoseArray costs one ``Pose``, ``Point`` and ``Quaternion``
per element, an Odometry two 36-element covariance arrays, on every message of every robot.
Subscriptions with ``raw=True`` hand over the serialized bytes, and ``Publisher.publish`` takes
bytes, so the hot topics (``pose``, ``neighbors``, ``cmd_vel``, ``/formation/reference``,
``/clock``) go through this module: the same messages on the wire, read and written with a few
``struct`` and numpy calls.

The layout (XCDR1, as every ROS 2 rmw writes it): a 4-byte encapsulation header (``00 01`` for
little endian, ``00 00`` for big endian, then two option bytes); then the fields in order, each
aligned to its own size relative to the end of that header: ``int32``/``uint32`` to 4,
``float64`` to 8; a string is a uint32 length counting the terminating NUL, the bytes and the
NUL; a sequence a uint32 count and the elements. A Header is ``stamp.sec`` (int32),
``stamp.nanosec`` (uint32), ``frame_id``. Readers take either byte order and refuse anything that
is not a whole message (:class:`CdrError`); writers write little endian with zero padding.
"""

from dataclasses import dataclass
import math
import struct
from typing import Dict, List, Optional, Sequence, Tuple

from formation_ros.core.maths.frames import frame_from_pose, FrameSample
from formation_ros.core.maths.obstacles import normal_quaternions, Told
from formation_ros.core.maths.unicycle import quaternions_from_headings
from formation_ros.core.maths.units import NS_PER_S
from formation_ros.core.rules.scan_obstacles import Scan
from formation_ros.core.rules.transport import NAME as ROBOT_NAME, robot_indices, state_rows
import numpy as np
from numpy.typing import ArrayLike, NDArray

HEADER = 4
LITTLE = b'\x00\x01\x00\x00'
POSE_DOUBLES = 7
COVARIANCE_DOUBLES = 36
ENDIANS = {b'\x00\x01': '<', b'\x00\x00': '>'}
LITTLE_DOUBLE = np.dtype('<f8')
"""A float64 as the writers write it, whatever the machine's byte order."""
FINAL_PADDING = 3
"""Bytes a writer may leave after a message's last field (its payload padded to 4)."""


class CdrError(ValueError):
    """The bytes are not a serialized message of the expected type (cut short, bad lengths)."""


class TooManyPoses(CdrError):
    """A whole PoseArray header, but more elements than the reader accepts."""


@dataclass(frozen=True)
class PoseArrayData:
    """
    What a PoseArray carries for this package: stamp (ns), frame, positions (K, 3) in m.

    orientations: (K, 4) quaternions (x, y, z, w) of the poses (the headings of unicycles).
    """

    stamp_ns: int
    frame_id: str
    positions: NDArray[np.float64]
    orientations: NDArray[np.float64]


@dataclass(frozen=True)
class PoseData:
    """A PoseStamped: stamp (ns), frame, position (3,) in m, orientation (x, y, z, w)."""

    stamp_ns: int
    frame_id: str
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]

    @property
    def finite(self) -> bool:
        """Whether every number is finite."""
        return all(map(math.isfinite, self.position + self.orientation))


@dataclass(frozen=True)
class TwistData:
    """A TwistStamped: stamp (ns), frame, linear (3,) m/s and angular (3,) rad/s velocity."""

    stamp_ns: int
    frame_id: str
    linear: Tuple[float, float, float]
    angular: Tuple[float, float, float]


@dataclass(frozen=True)
class OdometryData:
    """
    A reference sample (nav_msgs/Odometry without its covariances).

    position (3,) m and orientation (x, y, z, w) of the pose; linear (3,) m/s and angular (3,)
    rad/s of the twist; stamp in ns.
    """

    stamp_ns: int
    frame_id: str
    child_frame_id: str
    position: Tuple[float, float, float]
    orientation: Tuple[float, float, float, float]
    linear: Tuple[float, float, float]
    angular: Tuple[float, float, float]

    @property
    def finite(self) -> bool:
        """Whether every number is finite and the quaternion is not zero."""
        values = self.position + self.orientation + self.linear + self.angular
        return (all(map(math.isfinite, values))
                and sum(v * v for v in self.orientation) > 0.0)

    @property
    def pose(self) -> PoseData:
        """Return its pose with the stamp and frame (what a robot and the relay read of it)."""
        return PoseData(self.stamp_ns, self.frame_id, self.position, self.orientation)

    def frame(self, dim: int) -> FrameSample:
        """Return the formation frame this sample carries (``maths.frames.frame_from_pose``)."""
        return frame_from_pose(self.stamp_ns / NS_PER_S, self.position, self.orientation,
                               self.linear, self.angular, dim)


def _align(offset: int, size: int) -> int:
    """Return ``offset`` moved up to a multiple of ``size`` counted from the end of the header."""
    return offset + (-(offset - HEADER)) % size


class _Reader:
    """Reads fields of one serialized message in order, checking that each one is there."""

    def __init__(self, data: bytes, what: str) -> None:
        self.view = memoryview(data)
        self.what = what
        if len(self.view) < HEADER:
            raise CdrError(f'{len(self.view)} bytes: too short for a {what}')
        endian = ENDIANS.get(bytes(self.view[:2]))
        if endian is None:
            raise CdrError(f'unknown CDR encapsulation {bytes(self.view[:2]).hex()}')
        self.endian = endian
        self.offset = HEADER

    def _take(self, fmt: str, size: int, align: int) -> Tuple:
        start = _align(self.offset, align)
        if start + size > len(self.view):
            raise CdrError(f'a {self.what} cut short at byte {len(self.view)}')
        self.offset = start + size
        return struct.unpack_from(self.endian + fmt, self.view, start)

    def string(self, name: str) -> str:
        start = self.skip_string(name)
        return bytes(self.view[start:self.offset - 1]).decode('utf-8', 'replace')

    def skip_string(self, name: str) -> int:
        """Check that a whole string is next, move past it; return where its bytes start."""
        (length,) = self._take('I', 4, 4)
        start = self.offset
        if length < 1 or start + length > len(self.view) or self.view[start + length - 1] != 0:
            raise CdrError(f'{name} is cut short or not terminated')
        self.offset = start + length
        return start

    def header(self) -> Tuple[int, str]:
        sec, nanosec = self._take('iI', 8, 4)
        return sec * NS_PER_S + nanosec, self.string('frame_id')

    def doubles(self, count: int) -> Tuple[float, ...]:
        return self._take(f'{count}d', 8 * count, 8)

    def skip_doubles(self, count: int) -> None:
        self._take('', 8 * count, 8)

    def floats(self, count: int) -> Tuple[float, ...]:
        return self._take(f'{count}f', 4 * count, 4)

    def uint32(self) -> int:
        return self._take('I', 4, 4)[0]

    def end(self) -> None:
        """Refuse bytes left over after the last field (beyond a final padding)."""
        left = len(self.view) - self.offset
        if left > FINAL_PADDING:
            raise CdrError(f'{left} bytes left over after a {self.what}: a message of '
                           'another type?')


def read_pose_array(data: bytes, max_poses: int) -> PoseArrayData:
    """
    Read a serialized PoseArray; refuse one with more than ``max_poses`` elements.

    The count is checked before any element is read, so a flood of poses costs nothing. Raises
    :class:`CdrError` (a ValueError) for anything that is not a whole PoseArray. The positions
    are a copy, independent of ``data``.
    """
    reader = _Reader(data, 'PoseArray')
    stamp_ns, frame_id = reader.header()
    count = reader.uint32()
    if count > max_poses:
        raise TooManyPoses(f'{count} poses, more than {max_poses}')
    offset = _align(reader.offset, 8) if count else reader.offset
    if offset + count * POSE_DOUBLES * 8 > len(reader.view):
        raise CdrError(f'cut short: {count} poses do not fit in {len(reader.view)} bytes')
    values = np.frombuffer(reader.view, dtype=np.dtype(np.float64).newbyteorder(reader.endian),
                           count=count * POSE_DOUBLES, offset=offset)
    poses = values.reshape(count, POSE_DOUBLES)
    return PoseArrayData(stamp_ns, frame_id, poses[:, :3].astype(np.float64),
                         poses[:, 3:].astype(np.float64))


def read_pose_stamped(data: bytes, exact: bool = False) -> PoseData:
    """
    Read a serialized geometry_msgs/PoseStamped; :class:`CdrError` if it is not one.

    exact: also refuse bytes left over after it (a longer message, e.g. an Odometry, would
    otherwise read as a PoseStamped of whatever its first fields hold).
    """
    reader = _Reader(data, 'PoseStamped')
    stamp_ns, frame_id = reader.header()
    values = reader.doubles(POSE_DOUBLES)
    if exact:
        reader.end()
    return PoseData(stamp_ns, frame_id, values[:3], values[3:])


def read_twist_stamped(data: bytes) -> TwistData:
    """Read a serialized geometry_msgs/TwistStamped; :class:`CdrError` if it is not one."""
    reader = _Reader(data, 'TwistStamped')
    stamp_ns, frame_id = reader.header()
    values = reader.doubles(6)
    return TwistData(stamp_ns, frame_id, values[:3], values[3:])


def read_twist(data: bytes) -> TwistData:
    """Read a serialized geometry_msgs/Twist (stamp 0, frame ''); CdrError if it is not one."""
    reader = _Reader(data, 'Twist')
    values = reader.doubles(6)
    return TwistData(0, '', values[:3], values[3:])


def read_odometry(data: bytes, exact: bool = False) -> OdometryData:
    """
    Read a serialized nav_msgs/Odometry (its covariances skipped); CdrError if not one.

    exact: also refuse bytes left over after it (see :func:`read_pose_stamped`).
    """
    reader = _Reader(data, 'Odometry')
    stamp_ns, frame_id = reader.header()
    child = reader.string('child_frame_id')
    pose = reader.doubles(POSE_DOUBLES)
    reader.skip_doubles(COVARIANCE_DOUBLES)
    twist = reader.doubles(6)
    reader.skip_doubles(COVARIANCE_DOUBLES)
    if exact:
        reader.end()
    return OdometryData(stamp_ns, frame_id, child, pose[:3], pose[3:], twist[:3], twist[3:])


class TooManyRays(CdrError):
    """A whole LaserScan header, but more rays than the reader accepts."""


def read_laser_scan(data: bytes, max_rays: int) -> Scan:
    """
    Read a serialized sensor_msgs/LaserScan; refuse one with more than ``max_rays`` rays.

    The count is checked before the ranges are read (:class:`TooManyRays`); the intensities
    are checked to be whole and skipped. Raises :class:`CdrError` for anything that is not a
    whole LaserScan. The ranges are a float64 copy, independent of ``data``.
    """
    reader = _Reader(data, 'LaserScan')
    stamp_ns, frame_id = reader.header()
    angle_min, _, increment, _, _, range_min, range_max = reader.floats(7)
    count = reader.uint32()
    if count > max_rays:
        raise TooManyRays(f'{count} rays')
    if reader.offset + 4 * count > len(reader.view):
        raise CdrError(f'cut short: {count} ranges do not fit in {len(reader.view)} bytes')
    ranges = np.frombuffer(reader.view, dtype=np.dtype(np.float32).newbyteorder(reader.endian),
                           count=count, offset=reader.offset).astype(np.float64)
    reader.offset += 4 * count
    intensities = reader.uint32()
    if intensities > max_rays or reader.offset + 4 * intensities > len(reader.view):
        raise CdrError(f'{intensities} intensities do not fit in {len(reader.view)} bytes')
    reader.offset += 4 * intensities
    reader.end()
    return Scan(stamp_ns, frame_id, angle_min, increment, range_min, range_max, ranges)


def _string(text: str) -> bytes:
    """Return a CDR string for a 4-aligned offset: its length, bytes and NUL."""
    raw = text.encode('utf-8') + b'\x00'
    return struct.pack('<I', len(raw)) + raw


def _pad(length: int, size: int) -> bytes:
    return b'\x00' * ((-(length - HEADER)) % size)


def encode_header(stamp_ns: int, frame_id: str) -> bytes:
    """Return the encapsulation header and a Header at ``stamp_ns`` (>= 0) in ``frame_id``."""
    head = LITTLE + struct.pack('<iI', stamp_ns // NS_PER_S, stamp_ns % NS_PER_S)
    return head + _string(frame_id)


def _with_doubles(prefix: bytes, values: Sequence[float]) -> bytes:
    return prefix + _pad(len(prefix), 8) + struct.pack(f'<{len(values)}d', *values)


def _xyz(vector: ArrayLike) -> List[float]:
    values = [0.0, 0.0, 0.0]
    flat = [float(v) for v in np.asarray(vector, dtype=float).ravel()[:3]]
    values[:len(flat)] = flat
    return values


def encode_twist_stamped(stamp_ns: int, frame_id: str, linear: ArrayLike,
                         angular: ArrayLike = (0.0, 0.0, 0.0)) -> bytes:
    """Return a serialized TwistStamped: ``linear`` ((dim,) m/s) and ``angular`` (rad/s)."""
    return _with_doubles(encode_header(stamp_ns, frame_id), _xyz(linear) + _xyz(angular))


def encode_twist(linear: ArrayLike, angular: ArrayLike = (0.0, 0.0, 0.0)) -> bytes:
    """Return a serialized Twist (no header): ``linear`` ((dim,) m/s) and ``angular`` (rad/s)."""
    return _with_doubles(LITTLE, _xyz(linear) + _xyz(angular))


def encode_pose_stamped(stamp_ns: int, frame_id: str, position: ArrayLike,
                        orientation: Sequence[float]) -> bytes:
    """Return a serialized PoseStamped: ``position`` ((dim,) m), ``orientation`` (x, y, z, w)."""
    return _with_doubles(encode_header(stamp_ns, frame_id),
                         _xyz(position) + [float(v) for v in orientation])


def encode_odometry(stamp_ns: int, frame_id: str, child_frame_id: str, position: ArrayLike,
                    orientation: Sequence[float], linear: ArrayLike,
                    angular: ArrayLike) -> bytes:
    """Return a serialized nav_msgs/Odometry with zero covariances (vectors of 3 values)."""
    prefix = encode_header(stamp_ns, frame_id)
    prefix += _pad(len(prefix), 4)
    prefix += _string(child_frame_id)
    zeros = [0.0] * COVARIANCE_DOUBLES
    return _with_doubles(prefix, _xyz(position) + [float(v) for v in orientation] + zeros
                         + _xyz(linear) + _xyz(angular) + zeros)


def read_clock(data: bytes) -> int:
    """Read a serialized rosgraph_msgs/Clock; return its time in ns; CdrError if not one."""
    sec, nanosec = _Reader(data, 'Clock')._take('iI', 8, 4)
    return int(sec) * NS_PER_S + int(nanosec)


def encode_clock(stamp_ns: int) -> bytes:
    """Return a serialized rosgraph_msgs/Clock at ``stamp_ns`` (>= 0)."""
    return LITTLE + struct.pack('<iI', stamp_ns // NS_PER_S, stamp_ns % NS_PER_S)


Encoded = Tuple[List[bytes], List[bytes]]


class StateEncoder:
    """
    The plant's state messages of all robots at once: poses and range-sensor readings as bytes.

    Every robot's pose is 7 little-endian float64 (x, y, z, quaternion: identity, the heading
    of a unicycle, or an orientation given) in one (N, 7) array, whatever the byte order of
    the arrays given; a PoseStamped is a fixed prefix and that row,
    a PoseArray a prefix with its count and the rows of the robots it lists, taken with one
    numpy index for all arrays together. Used by the plant node and the relay node alike.
    """

    def __init__(self, num_robots: int, dim: int, frame_id: str) -> None:
        """Prepare the messages of ``num_robots`` robots in ``dim`` (2 or 3) dimensions."""
        self.dim = dim
        self.frame_id = frame_id
        self.rows = np.zeros((num_robots, POSE_DOUBLES), dtype=LITTLE_DOUBLE)
        self.rows[:, 6] = 1.0

    def encode(self, q: NDArray[np.float64], observer: NDArray[np.intp],
               seen: NDArray[np.intp], stamp_ns: int,
               headings: Optional[NDArray[np.float64]] = None,
               orientations: Optional[NDArray[np.float64]] = None) -> Encoded:
        """
        Return (poses, arrays): robot i's serialized PoseStamped and PoseArray at ``stamp_ns``.

        q: (N, dim) positions, m; (observer, seen): every sensed pair, sorted by observer
        (``core.maths.sensing.sensed_pairs``): robot ``observer[k]`` sees robot ``seen[k]``;
        headings: (N,) rad about +z, written as the orientations; else orientations: (N, 4)
        unit quaternions (x, y, z, w) written as they are (neither: the previous call's, at
        first identity).
        """
        self.set_rows(q, headings, orientations)
        header = encode_header(stamp_ns, self.frame_id)
        pose_prefix = header + _pad(len(header), 8)
        poses = [pose_prefix + row for row in map(bytes, self.rows)]
        count_at = len(header) + len(_pad(len(header), 4))
        counts = np.bincount(observer, minlength=len(q))
        ends = np.cumsum(counts) * POSE_DOUBLES * 8
        body = self.rows[seen].tobytes()
        array_prefix = header + _pad(len(header), 4)
        padding = _pad(count_at + 4, 8)
        arrays = []
        start = 0
        for count, end in zip(counts.tolist(), ends.tolist()):
            arrays.append(array_prefix + struct.pack('<I', count) + (padding if count else b'')
                          + body[start:end])
            start = end
        return poses, arrays

    def set_rows(self, q: NDArray[np.float64], headings: Optional[NDArray[np.float64]] = None,
                 orientations: Optional[NDArray[np.float64]] = None) -> None:
        """
        Take the poses of every robot (as :meth:`encode` takes them) without encoding.

        The rows are those of a team state (``core.rules.transport.state_rows``): robot i's at i -
        1.
        """
        if headings is not None:
            orientations = quaternions_from_headings(headings)
        self.rows[:] = state_rows(q, self.rows[:, 3:] if orientations is None else orientations)

    def team(self, stamp_ns: int) -> bytes:
        """Return the team state (``rules.transport``) of the poses last taken, at ``stamp_ns``."""
        return encode_team_states(stamp_ns, self.frame_id, self.rows)


NAME_BYTES = 16
"""The longest robot name a team command may carry (``robot_<i>`` with i < 10**9), bytes."""
TWIST_DOUBLES = 6
TRANSFORM_DOUBLES = 7


@dataclass(frozen=True)
class TeamCommandsData:
    """
    A team command message (``core.rules.transport``), as read.

    stamp_ns: the stamp of the state it answers; frame_id: its header's frame; per robot
    listed: its 0-based index (K,), linear (K, 3) m/s and angular (K, 3) rad/s.
    """

    stamp_ns: int
    frame_id: str
    indices: NDArray[np.intp]
    linear: NDArray[np.float64]
    angular: NDArray[np.float64]


def team_command_limit(num_robots: int) -> int:
    """Return the most bytes a team command message for ``num_robots`` robots may have."""
    frame = 256
    return (HEADER + 12 + frame + 4 + num_robots * (8 + NAME_BYTES)
            + 32 + num_robots * (8 * (TRANSFORM_DOUBLES + 2 * TWIST_DOUBLES)) + 16)


class TeamCommandReader:
    """
    Reads the plant's team commands (trajectory_msgs/MultiDOFJointTrajectory) from bytes.

    Untrusted input: the byte count is checked against :func:`team_command_limit`, every count
    against ``num_robots`` and the bytes left before any element is read. The names of a
    message are read once: the robots a sender lists are the same message after message, so
    their indices are kept by the bytes of the names (the last :data:`NAMES_KEPT` lists).
    """

    NAMES_KEPT = 64

    def __init__(self, num_robots: int) -> None:
        """Read messages for a team of ``num_robots`` robots."""
        self.num_robots = num_robots
        self.limit = team_command_limit(num_robots)
        self.names: Dict[bytes, NDArray[np.intp]] = {}

    def read(self, data: bytes) -> TeamCommandsData:
        """Return the message of ``data``; :class:`CdrError` for anything else."""
        if len(data) > self.limit:
            raise TooManyPoses(f'{len(data)} bytes, more than a team command for '
                               f'{self.num_robots} robots has')
        reader = _Reader(data, 'MultiDOFJointTrajectory')
        stamp_ns, frame_id = reader.header()
        names_at = _align(reader.offset, 4)
        count = reader.uint32()
        if count > self.num_robots:
            raise TooManyPoses(f'{count} robots, more than {self.num_robots}')
        if count * 5 > len(reader.view) - reader.offset:
            raise CdrError(f'cut short: {count} names do not fit')
        first = reader.offset
        for _ in range(count):
            reader.skip_string('a joint name')
        key = bytes(reader.view[names_at:reader.offset])
        indices = self.names.get(key)
        if indices is None:
            end, reader.offset = reader.offset, first
            names = [reader.string('a joint name') for _ in range(count)]
            assert reader.offset == end
            try:
                indices = robot_indices(names, self.num_robots)
            except ValueError as exc:
                raise CdrError(f'joint_names: {exc}') from None
            if len(self.names) >= self.NAMES_KEPT:
                self.names.pop(next(iter(self.names)))
            self.names[key] = indices
        if reader.uint32() != 1:
            raise CdrError('not one trajectory point')
        transforms = reader.uint32()
        if transforms > count:
            raise CdrError(f'{transforms} transforms for {count} robots')
        _skip_elements(reader, TRANSFORM_DOUBLES * transforms)
        if reader.uint32() != count:
            raise CdrError(f'not one velocity per robot ({count} robots)')
        start = _align(reader.offset, 8)
        _skip_elements(reader, TWIST_DOUBLES * count)
        twists = np.frombuffer(reader.view, dtype=np.dtype(np.float64).newbyteorder(
            reader.endian), count=count * TWIST_DOUBLES, offset=start) if count else np.zeros(0)
        accelerations = reader.uint32()
        if accelerations > count:
            raise CdrError(f'{accelerations} accelerations for {count} robots')
        _skip_elements(reader, TWIST_DOUBLES * accelerations)
        reader._take('iI', 8, 4)
        reader.end()
        rows = twists.reshape(count, TWIST_DOUBLES).astype(np.float64)
        return TeamCommandsData(stamp_ns, frame_id, indices, rows[:, :3], rows[:, 3:])


def _skip_elements(reader: _Reader, doubles: int) -> None:
    """Skip the float64 elements of a sequence (none: no alignment either), checking they fit."""
    if doubles:
        reader.skip_doubles(doubles)


def encode_names(names: Sequence[str]) -> bytes:
    """Return the CDR of a string sequence (count, strings) for a 4-aligned offset."""
    out = struct.pack('<I', len(names))
    for name in names:
        out += _pad(HEADER + len(out), 4) + _string(name)
    return out


def encode_team_commands(stamp_ns: int, frame_id: str, names: bytes,
                         linear: ArrayLike, angular: ArrayLike) -> bytes:
    """
    Return a serialized team command (``core.rules.transport``): a MultiDOFJointTrajectory.

    names: :func:`encode_names` of the robots' names; linear, angular: (K, 3) twists, row k
    robot k's.
    """
    head = encode_header(stamp_ns, frame_id)
    head += _pad(len(head), 4) + names
    head += _pad(len(head), 4)
    count = np.asarray(linear).shape[0]
    head += struct.pack('<III', 1, 0, count)
    if count:
        head += _pad(len(head), 8)
        rows = np.empty((count, TWIST_DOUBLES), dtype=LITTLE_DOUBLE)
        rows[:, :3] = linear
        rows[:, 3:] = angular
        head += rows.tobytes()
    return head + struct.pack('<IiI', 0, 0, 0)


def encode_team_states(stamp_ns: int, frame_id: str, rows: ArrayLike) -> bytes:
    """Return a serialized team state (``core.rules.transport``): a PoseArray of (N, 7) rows."""
    header = encode_header(stamp_ns, frame_id)
    head = header + _pad(len(header), 4)
    values = np.ascontiguousarray(rows, dtype=LITTLE_DOUBLE)
    head += struct.pack('<I', len(values))
    if len(values):
        head += _pad(len(head), 8)
    return head + values.tobytes()


@dataclass(frozen=True)
class StatusData:
    """One diagnostic_msgs/DiagnosticStatus: level (0 OK, 1 WARN, 2 ERROR, 3 STALE), texts."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: Sequence[Tuple[str, str]]


def encode_diagnostics(stamp_ns: int, statuses: Sequence[StatusData]) -> bytes:
    """
    Return a serialized diagnostic_msgs/DiagnosticArray stamped ``stamp_ns`` (no frame).

    A status's ``level`` is one byte; each string's length and each sequence's count that
    follows it is aligned to 4 (the header is 4 bytes long, so offsets from the start of
    ``out`` align as offsets from the end of the header do).
    """
    out = bytearray(encode_header(stamp_ns, ''))
    out += _pad(len(out), 4) + struct.pack('<I', len(statuses))
    for status in statuses:
        out.append(status.level)
        for text in (status.name, status.message, status.hardware_id):
            out += _pad(len(out), 4) + _string(text)
        out += _pad(len(out), 4) + struct.pack('<I', len(status.values))
        for key, value in status.values:
            out += _pad(len(out), 4) + _string(key)
            out += _pad(len(out), 4) + _string(value)
    return bytes(out)


def encode_obstacles(stamp_ns: int, frame_id: str, told: Told) -> List[bytes]:
    """
    Return every robot's ``obstacles`` message: a serialized PoseArray each, at ``stamp_ns``.

    told: ``core.maths.obstacles.told_obstacles`` of N robots; robot i's message lists its
    obstacles in map order, pose k the surface point (position, m) and the outward normal
    there as the x axis of its orientation (docs/ros_interface.md, "Obstacles"); none near:
    an empty PoseArray.
    """
    rows = state_rows(told.points.reshape(-1, told.points.shape[-1]),
                      normal_quaternions(told.normals.reshape(-1, told.normals.shape[-1])))
    rows = rows.reshape(told.listed.shape + (POSE_DOUBLES,))
    return [encode_team_states(stamp_ns, frame_id, rows[i][told.listed[i]])
            for i in range(len(rows))]


@dataclass(frozen=True)
class TeamObstaclesData:
    """
    A team obstacles message (``/formation/obstacles``), as read.

    stamp_ns: the stamp of the state it goes with; frame_id: its header's frame; per point
    listed: the robot it is for (0-based, (P,)), its position (P, 3) m and its orientation
    (P, 4) (x, y, z, w), the outward normal as its x axis.
    """

    stamp_ns: int
    frame_id: str
    robots: NDArray[np.intp]
    positions: NDArray[np.float64]
    orientations: NDArray[np.float64]


def encode_team_obstacles(stamp_ns: int, frame_id: str, told: Told) -> bytes:
    """
    Return the team transport's obstacles of a state: a MultiDOFJointTrajectory.

    ``joint_names[k]`` is the robot ``robot_<i>`` point k is for (a robot once per point, in
    id order, then map order), its one trajectory point's ``transforms[k]`` the surface point
    (translation) and the normal (the rotation's x axis), as robot i's ``obstacles`` pose k
    (:func:`encode_obstacles`); no velocities nor accelerations, ``time_from_start`` zero.
    """
    robots, kept = np.nonzero(told.listed)
    dim = told.points.shape[-1]
    rows = np.zeros((len(robots), TRANSFORM_DOUBLES), dtype=LITTLE_DOUBLE)
    rows[:, :dim] = told.points[robots, kept]
    rows[:, 3:] = normal_quaternions(told.normals[robots, kept])
    head = encode_header(stamp_ns, frame_id)
    head += _pad(len(head), 4) + encode_names([f'robot_{i + 1}' for i in robots.tolist()])
    head += _pad(len(head), 4)
    head += struct.pack('<II', 1, len(rows))
    if len(rows):
        head += _pad(len(head), 8) + rows.tobytes()
    return head + struct.pack('<IIiI', 0, 0, 0, 0)


def read_team_obstacles(data: bytes, num_robots: int, max_points: int) -> TeamObstaclesData:
    """
    Read a team obstacles message (:func:`encode_team_obstacles`); CdrError if not one.

    Untrusted: at most ``max_points`` points (:class:`TooManyPoses`, counted before any is
    read), each named ``robot_<i>`` with 1 <= i <= ``num_robots``, one transform per name,
    no velocities or accelerations, nothing left over.
    """
    reader = _Reader(data, 'MultiDOFJointTrajectory')
    stamp_ns, frame_id = reader.header()
    count = reader.uint32()
    if count > max_points:
        raise TooManyPoses(f'{count} points, more than {max_points}')
    if count * 5 > len(reader.view) - reader.offset:
        raise CdrError(f'cut short: {count} names do not fit')
    names = [reader.string('a joint name') for _ in range(count)]
    robots = np.empty(count, dtype=np.intp)
    for k, name in enumerate(names):
        match = ROBOT_NAME.fullmatch(name)
        if match is None or int(match.group(1)) > num_robots:
            raise CdrError(f'joint_names: {name[:40]!r} is not robot_<i> with i in '
                           f'1..{num_robots}')
        robots[k] = int(match.group(1)) - 1
    if reader.uint32() != 1:
        raise CdrError('not one trajectory point')
    if reader.uint32() != count:
        raise CdrError(f'not one transform per name ({count} names)')
    start = _align(reader.offset, 8)
    _skip_elements(reader, TRANSFORM_DOUBLES * count)
    values = (np.frombuffer(reader.view, dtype=np.dtype(np.float64).newbyteorder(reader.endian),
                            count=count * TRANSFORM_DOUBLES, offset=start)
              if count else np.zeros(0))
    if reader.uint32() != 0 or reader.uint32() != 0:
        raise CdrError('velocities or accelerations in an obstacles message')
    reader._take('iI', 8, 4)
    reader.end()
    rows = values.reshape(count, TRANSFORM_DOUBLES).astype(np.float64)
    return TeamObstaclesData(stamp_ns, frame_id, robots, rows[:, :3], rows[:, 3:])
