# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A robot's obstacles from its own laser scan (``obstacles.source: scan``), without ROS.

Beyond the paper (docs/equations.md, "Obstacles from a scan"). :class:`ScanObstacles` admits a
scan (:meth:`ScanObstacles.refusal`: its frame, its fields, its size), keeps the latest one
and the robot's own poses of the last :data:`POSES_KEPT` states, and when the robot answers a
state gives the law its obstacle points (:meth:`ScanObstacles.obstacles`): the returns placed
in the world frame with the pose at the scan's stamp (interpolated between the two poses
about it), the ones on a neighbour's body left out, of each obstacle the nearest return within
R_i and the nearest of each of its faces, at most one a sector, each a point obstacle facing
the robot (``core.maths.scan``). The node counts what it refuses; the robot holds still while
it cannot tell its obstacles at a state (:meth:`ScanObstacles.unseen`: no scan yet, or the
latest older than ``input_timeout`` by the stamps, on the robot's clock, so that a world
running slower than real time is no reason).
"""

from collections import deque
from dataclasses import dataclass
import math
from typing import Deque, Optional, Tuple

from formation_ros.core.maths.scan import (facing_normals, full_turn, nearest_by_object,
                                           nearest_by_sector, off_neighbours, returning_rays,
                                           scan_points, scan_problem, ScanShape)
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.rules.admission import Reason
from formation_ros.core.rules.robot_intake import Refused
from formation_ros.core.settings.params import ScanSettings
import numpy as np
from numpy.typing import ArrayLike, NDArray

POSES_KEPT = 4096
"""The robot's latest poses kept to place a scan at its stamp (41 s of states at 100 Hz)."""
EDGE_NS = 100_000_000
"""How far beyond the poses kept a scan's stamp may lie and be placed with the nearest, ns."""
MAX_RAYS = 16384
"""The most rays a scan may have (an LDS has 360, a 2D lidar a few thousand)."""


@dataclass(frozen=True)
class Scan:
    """
    One ``sensor_msgs/LaserScan`` as a robot takes it.

    stamp_ns: its stamp, ns; frame_id: its frame; angle_min, angle_increment: rad;
    range_min, range_max: m; ranges: (R,) m (+inf: no return).
    """

    stamp_ns: int
    frame_id: str
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: NDArray[np.float64]


@dataclass(frozen=True)
class Placed:
    """
    A scan's returns placed in the world frame.

    stamp_ns: the scan's stamp, ns; points: (K, 2) m, in scan order; rays: (K,) their rays'
    indices, of ``total`` rays; wraps: the rays go round (the last one's neighbour is the
    first).
    """

    stamp_ns: int
    points: NDArray[np.float64]
    rays: NDArray[np.intp]
    total: int
    wraps: bool


class ScanObstacles:
    """
    One robot's obstacle points from its scans.

    settings: ``obstacles.scan_*``; sensing_radius: R_i, m (a return at or beyond it is not
    kept); body_radius: ``body.radius``, m (a neighbour's body: with the margin, the reach of
    its returns about its position).
    """

    def __init__(self, settings: ScanSettings, sensing_radius: float,
                 body_radius: float) -> None:
        """Start with no scan and no pose."""
        self.settings = settings
        self.sensing_radius = float(sensing_radius)
        self.reach = float(body_radius) + settings.margin
        self.poses: Deque[Tuple[int, Tuple[float, ...], Tuple[float, ...]]] = deque(
            maxlen=POSES_KEPT)
        """(stamp ns, position, orientation quaternion) of the latest poses, oldest first."""
        self.scan: Optional[Scan] = None
        """The latest scan admitted (None: none yet)."""
        self.placed: Optional[Placed] = None
        """The latest scan's returns in the world frame, once placed."""
        self.kept = 0
        """Obstacle points given to the law at the last answer."""

    def shape(self, scan: Scan) -> ScanShape:
        """Return the fields of ``scan`` and the scanner's mount (``core.maths.scan``)."""
        return ScanShape(scan.angle_min, scan.angle_increment, scan.range_min, scan.range_max,
                         self.settings.mount, self.settings.mount_yaw)

    def refusal(self, scan: Scan) -> Optional[Refused]:
        """Return why ``scan`` is refused (frame, size, fields, NaN or -inf ranges), or None."""
        if scan.frame_id != self.settings.frame:
            return Refused(Reason.SCAN_FRAME,
                           f' (got {scan.frame_id!r}, expected {self.settings.frame!r})')
        if len(scan.ranges) > MAX_RAYS:
            return Refused(Reason.TOO_MANY_RAYS, f' ({len(scan.ranges)} > {MAX_RAYS})')
        problem = scan_problem(scan.ranges, self.shape(scan))
        if problem is None:
            return None
        reason = (Reason.NON_FINITE if problem.startswith(('non-finite', 'most ranges'))
                  else Reason.SCAN_FIELDS)
        return Refused(reason, f' ({problem})')

    def pose_heard(self, stamp_ns: int, position: Tuple[float, ...],
                   orientation: Tuple[float, ...]) -> None:
        """
        Keep an admitted pose of the robot: stamp ns, position (>= 2,) m, quaternion.

        A copy of the newest is not kept again, nor a pose with a non-finite number (nothing is
        placed with it); an older stamp (time went back: a plant or world started again)
        starts the poses anew.
        """
        if (self.poses and stamp_ns == self.poses[-1][0]) or not all(
                map(math.isfinite, (*position[:2], *orientation))):
            return
        if self.poses and stamp_ns < self.poses[-1][0]:
            self.poses.clear()
        self.poses.append((stamp_ns, position, orientation))

    def scan_heard(self, scan: Scan) -> None:
        """Keep an admitted scan (:meth:`refusal` said None); it is placed when first used."""
        self.scan = scan
        self.placed = None

    def unseen(self, state_ns: int, timeout_ns: int) -> Optional[str]:
        """
        Return why the robot cannot tell its obstacles at the state stamped ``state_ns``, or None.

        No scan yet, or the latest stamped more than ``timeout_ns`` (``input_timeout``) before
        the state: a robot on its scanner does not drive on an old picture. One text a reason
        (it is logged once while it lasts).
        """
        if self.scan is None:
            return 'no scan heard yet'
        if state_ns - self.scan.stamp_ns > timeout_ns:
            return f'its latest scan is more than {timeout_ns / 1e9:g} s older than the state'
        return None

    def pose_at(self, stamp_ns: int,
                tolerance_ns: int) -> Optional[Tuple[NDArray[np.float64], float]]:
        """
        Return the robot's (position (2,) m, heading rad) at ``stamp_ns``, or None.

        Between two poses kept: linear in position, along the shorter turn in heading. Beyond
        them, the nearest end, if at most ``tolerance_ns`` and :data:`EDGE_NS` away: after the
        newest, a scan stamped before its state arrives; before the oldest, a scan taken as
        the first states came. Farther: None.
        """
        if not self.poses:
            return None
        stamps = np.array([pose[0] for pose in self.poses], dtype=np.int64)
        later = int(np.searchsorted(stamps, stamp_ns, side='left'))
        if later in (0, len(stamps)):
            end = 0 if later == 0 else -1
            if abs(stamp_ns - int(stamps[end])) > min(tolerance_ns, EDGE_NS):
                return None
            return self._pose(end)
        if stamps[later] == stamp_ns:
            return self._pose(later)
        (p0, h0), (p1, h1) = self._pose(later - 1), self._pose(later)
        share = (stamp_ns - int(stamps[later - 1])) / float(stamps[later] - stamps[later - 1])
        turn = math.remainder(h1 - h0, 2.0 * math.pi)
        return p0 + share * (p1 - p0), h0 + share * turn

    def _pose(self, k: int) -> Tuple[NDArray[np.float64], float]:
        _, position, orientation = self.poses[k]
        heading = float(headings_from_quaternions(np.asarray([orientation], dtype=float))[0])
        return np.asarray(position[:2], dtype=float), heading

    def place(self, tolerance_ns: int) -> Optional[Placed]:
        """
        Return the latest scan's returns in the world frame; None if they cannot be placed.

        tolerance_ns: how far beyond the poses kept a scan may be stamped (``input_timeout``,
        at most :data:`EDGE_NS`). None without a scan, or when no pose was kept near its stamp
        (:data:`Reason.UNPLACED`). A scan placed between two poses is kept placed; one
        stamped after the newest is placed again at the next answer, once a later pose may
        hold its stamp between two.
        """
        if self.placed is not None or self.scan is None:
            return self.placed
        pose = self.pose_at(self.scan.stamp_ns, tolerance_ns)
        if pose is None:
            return None
        position, heading = pose
        shape = self.shape(self.scan)
        total = len(self.scan.ranges)
        placed = Placed(self.scan.stamp_ns,
                        scan_points(self.scan.ranges, shape, position, heading),
                        returning_rays(self.scan.ranges, shape), total, full_turn(shape, total))
        if self.scan.stamp_ns <= self.poses[-1][0]:
            self.placed = placed
        return placed

    def obstacles(self, placed: Placed, position: ArrayLike, control_point: ArrayLike,
                  neighbours: ArrayLike) -> Tuple[NDArray[np.float64], NDArray[np.float64]]:
        """
        Return the robot's obstacle points (K, 2) and their normals (K, 2) for the law.

        placed: the scan's returns (:meth:`place`); position: (>= 2,) the robot's position
        now (its scanner's body), m; control_point: (2,) the point the law acts on, m;
        neighbours: (M, >= 2), 2-D also for M = 0: the positions of the neighbours it heard,
        m. Returns on a neighbour's body (within the reach of its position) are left out; of
        the rest, the nearest within R_i of the position of each obstacle and of each of its
        faces (``obstacles.scan_join``), and of those the nearest of each sector
        (``obstacles.scan_sectors``).
        """
        others = np.asarray(neighbours, dtype=float)[:, :2]
        off = off_neighbours(placed.points, others, self.reach)
        centre = np.asarray(position, dtype=float)[:2]
        objects = nearest_by_object(placed.points[off], placed.rays[off], placed.total,
                                    placed.wraps, centre, self.sensing_radius,
                                    self.settings.join)
        kept = nearest_by_sector(objects, centre, self.sensing_radius, self.settings.sectors)
        self.kept = len(kept)
        return kept, facing_normals(kept, control_point)
