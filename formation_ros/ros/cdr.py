# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Read a serialized geometry_msgs/PoseArray (CDR bytes) straight into numpy.

rclpy turns a received PoseArray into one Python ``Pose``, ``Point`` and ``Quaternion`` object
per element: for a robot that senses 30 neighbours that costs a few hundred microseconds per
message, most of a robot's time in a dense formation. A subscription with ``raw=True`` hands
over the CDR bytes instead, and :func:`read_pose_array` reads the stamp, the frame and the
positions from them with a few numpy calls.

The layout (XCDR1, as every ROS 2 rmw writes it): a 4-byte encapsulation header (``00 01`` for
little endian, ``00 00`` for big endian, then two option bytes); then, aligned relative to the
end of that header, ``stamp.sec`` (int32), ``stamp.nanosec`` (uint32), ``frame_id`` (uint32
length counting the terminating NUL, the bytes, the NUL), the element count (uint32, 4-aligned)
and per element seven float64 (8-aligned): position x, y, z, orientation x, y, z, w.
"""

from dataclasses import dataclass
import struct

import numpy as np
from numpy.typing import NDArray

HEADER = 4
POSE_DOUBLES = 7
ENDIANS = {b'\x00\x01': '<', b'\x00\x00': '>'}


class CdrError(ValueError):
    """The bytes are not a serialized PoseArray (cut short, unknown encoding, bad lengths)."""


class TooManyPoses(CdrError):
    """A whole PoseArray header, but more elements than the reader accepts."""


@dataclass(frozen=True)
class PoseArrayData:
    """What a PoseArray carries for this package: stamp (ns), frame, positions (K, 3) in m."""

    stamp_ns: int
    frame_id: str
    positions: NDArray[np.float64]


def _align(offset: int, size: int) -> int:
    """Return ``offset`` moved up to a multiple of ``size`` counted from the end of the header."""
    return offset + (-(offset - HEADER)) % size


def read_pose_array(data: bytes, max_poses: int) -> PoseArrayData:
    """
    Read a serialized PoseArray; refuse one with more than ``max_poses`` elements.

    The count is checked before any element is read, so a flood of poses costs nothing. Raises
    :class:`CdrError` (a ValueError) for anything that is not a whole PoseArray. The positions
    are a copy, independent of ``data``.
    """
    view = memoryview(data)
    if len(view) < HEADER + 12:
        raise CdrError(f'{len(view)} bytes: too short for a PoseArray')
    endian = ENDIANS.get(bytes(view[:2]))
    if endian is None:
        raise CdrError(f'unknown CDR encapsulation {bytes(view[:2]).hex()}')
    sec, nanosec, length = struct.unpack_from(endian + 'iII', view, HEADER)
    start = HEADER + 12
    if length < 1 or start + length > len(view) or view[start + length - 1] != 0:
        raise CdrError('frame_id is cut short or not terminated')
    frame_id = bytes(view[start:start + length - 1]).decode('utf-8', 'replace')
    offset = _align(start + length, 4)
    if offset + 4 > len(view):
        raise CdrError('cut short before the element count')
    (count,) = struct.unpack_from(endian + 'I', view, offset)
    if count > max_poses:
        raise TooManyPoses(f'{count} poses, more than {max_poses}')
    offset = _align(offset + 4, 8) if count else offset + 4
    if offset + count * POSE_DOUBLES * 8 > len(view):
        raise CdrError(f'cut short: {count} poses do not fit in {len(view)} bytes')
    values = np.frombuffer(view, dtype=np.dtype(np.float64).newbyteorder(endian),
                           count=count * POSE_DOUBLES, offset=offset)
    positions = values.reshape(count, POSE_DOUBLES)[:, :3].astype(np.float64)
    return PoseArrayData(sec * 1_000_000_000 + nanosec, frame_id, positions)
