# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The formation messages as CDR bytes: read into numpy and written from numpy, without rclpy.

rclpy turns every message it receives into Python objects and every message it publishes back
into C structures, field by field: a PoseArray costs one ``Pose``, ``Point`` and ``Quaternion``
per element, an Odometry two 36-element covariance arrays. In a team of robots that was most of
the CPU time of every process (docs/benchmarks.md). Subscriptions with ``raw=True`` hand over
the serialized bytes, and ``Publisher.publish`` takes bytes, so the hot topics (``pose``,
``neighbors``, ``cmd_vel``, ``/formation/reference``, ``/clock``) go through this module: the
same messages on the wire, read and written with a few ``struct`` and numpy calls.

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
from typing import List, Optional, Sequence, Tuple

from formation_ros.core.frames import frame_from_pose, FrameSample
from formation_ros.core.unicycle import quaternions_from_headings
import numpy as np
from numpy.typing import ArrayLike, NDArray

HEADER = 4
LITTLE = b'\x00\x01\x00\x00'
POSE_DOUBLES = 7
COVARIANCE_DOUBLES = 36
NS_PER_S = 1_000_000_000
ENDIANS = {b'\x00\x01': '<', b'\x00\x00': '>'}
IDENTITY = (0.0, 0.0, 0.0, 1.0)
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

    def frame(self, dim: int) -> FrameSample:
        """Return the formation frame this sample carries (``core.frames.frame_from_pose``)."""
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
        (length,) = self._take('I', 4, 4)
        start = self.offset
        if length < 1 or start + length > len(self.view) or self.view[start + length - 1] != 0:
            raise CdrError(f'{name} is cut short or not terminated')
        self.offset = start + length
        return bytes(self.view[start:start + length - 1]).decode('utf-8', 'replace')

    def header(self) -> Tuple[int, str]:
        sec, nanosec = self._take('iI', 8, 4)
        return sec * NS_PER_S + nanosec, self.string('frame_id')

    def doubles(self, count: int) -> Tuple[float, ...]:
        return self._take(f'{count}d', 8 * count, 8)

    def skip_doubles(self, count: int) -> None:
        self._take('', 8 * count, 8)

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


def encode_pose_stamped(stamp_ns: int, frame_id: str, position: ArrayLike,
                        orientation: Sequence[float] = IDENTITY) -> bytes:
    """Return a serialized PoseStamped: ``position`` ((dim,) m, z = 0 in 2D) and a quaternion."""
    return _with_doubles(encode_header(stamp_ns, frame_id),
                         _xyz(position) + [float(v) for v in orientation])


def encode_twist_stamped(stamp_ns: int, frame_id: str, linear: ArrayLike,
                         angular: ArrayLike = (0.0, 0.0, 0.0)) -> bytes:
    """Return a serialized TwistStamped: ``linear`` ((dim,) m/s) and ``angular`` (rad/s)."""
    return _with_doubles(encode_header(stamp_ns, frame_id), _xyz(linear) + _xyz(angular))


def encode_twist(linear: ArrayLike, angular: ArrayLike = (0.0, 0.0, 0.0)) -> bytes:
    """Return a serialized Twist (no header): ``linear`` ((dim,) m/s) and ``angular`` (rad/s)."""
    return _with_doubles(LITTLE, _xyz(linear) + _xyz(angular))


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


def encode_clock(stamp_ns: int) -> bytes:
    """Return a serialized rosgraph_msgs/Clock at ``stamp_ns`` (>= 0)."""
    return LITTLE + struct.pack('<iI', stamp_ns // NS_PER_S, stamp_ns % NS_PER_S)


Encoded = Tuple[List[bytes], List[bytes]]


class StateEncoder:
    """
    The plant's state messages of all robots at once: poses and range-sensor readings as bytes.

    Every robot's pose is 7 float64 (x, y, z, quaternion: identity, the heading of a unicycle,
    or an orientation given) in one (N, 7) array; a PoseStamped is a fixed prefix and that row,
    a PoseArray a prefix with its count and the rows of the robots it lists, taken with one
    numpy index for all arrays together. Used by the plant node and the relay node alike.
    """

    def __init__(self, num_robots: int, dim: int, frame_id: str) -> None:
        """Prepare the messages of ``num_robots`` robots in ``dim`` (2 or 3) dimensions."""
        self.dim = dim
        self.frame_id = frame_id
        self.rows = np.zeros((num_robots, POSE_DOUBLES))
        self.rows[:, 6] = 1.0

    def encode(self, q: NDArray[np.float64], observer: NDArray[np.intp],
               seen: NDArray[np.intp], stamp_ns: int,
               headings: Optional[NDArray[np.float64]] = None,
               orientations: Optional[NDArray[np.float64]] = None) -> Encoded:
        """
        Return (poses, arrays): robot i's serialized PoseStamped and PoseArray at ``stamp_ns``.

        q: (N, dim) positions, m; (observer, seen): every sensed pair, sorted by observer
        (``core.sensing.sensed_pairs``): robot ``observer[k]`` sees robot ``seen[k]``;
        headings: (N,) rad about +z, written as the orientations; else orientations: (N, 4)
        unit quaternions (x, y, z, w) written as they are (neither: the previous call's, at
        first identity).
        """
        self.rows[:, :self.dim] = q
        if headings is not None:
            self.rows[:, 3:] = quaternions_from_headings(headings)
        elif orientations is not None:
            self.rows[:, 3:] = orientations
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
