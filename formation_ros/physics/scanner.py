# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A planar laser scanner on every wheeled or planar body, cast with MuJoCo's ray queries.

Beyond the paper (issue 37): a TurtleBot3's LDS in the world. Each scan of robot i is
``world.scan_rays`` rays in a horizontal plane from its pose body's position (x, y; the base's
frame, ``robot_<i>/base_scan`` with no offset), ray k at ``k * 2 pi / rays`` counter-clockwise
from the base's +x (its yaw; a base's pitch and roll are ignored: the scanner stays level).
The rays are cast by ``mujoco.mj_multiRay`` (one call per robot, all its rays from one point)
at :attr:`Scanner.height` above the floor, the middle of the bodies' footprints, which the
obstacles span too (``world.obstacle_height``); they see only the geoms of
:data:`SCANNED_GROUP` (the footprints and the obstacles: the wheels, caster and heading marks
are drawn in other groups) and never the scanning robot's own body (``bodyexclude``).

A return is the distance to the first surface hit, m, plus Gaussian noise of
``world.scan_noise`` (a generator seeded with ``(start.seed, SCAN_SEED_OFFSET)``); a ray
without a hit within ``world.scan_range_max``, or whose return (with its noise) is outside
[``scan_range_min``, ``scan_range_max``], reads ``+inf`` (REP 117's "no return"; the LDS's
blind zone below ``range_min`` is +inf too, since ``core.maths.scan`` takes only +inf as a
non-return). :func:`scan_shape` gives the fields a reader needs to turn the ranges back into
points (``core.maths.scan.scan_points``).
"""

import math
from typing import Optional

from formation_ros.core.maths.scan import ScanShape
from formation_ros.core.maths.unicycle import headings_from_quaternions
from formation_ros.core.settings.params import WorldSettings
import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

Float = NDArray[np.float64]
SCANNED_GROUP = 0
"""The visual group of the geoms a scan sees: the footprints and the obstacles."""
SCAN_SEED_OFFSET = 3
"""Scan noise comes from the generator seeded with (start.seed, this): apart from the random
start (start.seed alone), its headings (1) and the pose noise (2)."""
WXYZ_TO_XYZW = (1, 2, 3, 0)
"""MuJoCo's quaternions are (w, x, y, z), the package's (x, y, z, w)."""


def scan_shape(world: WorldSettings) -> ScanShape:
    """Return the fixed fields of the world's scans: angle_min 0, step 2 pi / rays, limits."""
    return ScanShape(angle_min=0.0, angle_increment=2.0 * math.pi / world.scan_rays,
                     range_min=world.scan_range_min, range_max=world.scan_range_max)


def steps_per_scan(world: WorldSettings) -> int:
    """Return the engine steps between two scans: 1 / (scan_rate x timestep), rounded (>= 1)."""
    if world.scan_rate <= 0.0:
        raise ValueError('no scanner: world.scan_rate is 0')
    return max(1, int(round(1.0 / (world.scan_rate * world.timestep))))


def scan_period(world: WorldSettings) -> float:
    """Return the time between two scans, s: :func:`steps_per_scan` steps (``scan_time``)."""
    return steps_per_scan(world) * world.timestep


def height_note(obstacles: int, obstacle_height: float, scan_height: float) -> Optional[str]:
    """
    Say in one line that the scans pass over the obstacles, or None.

    obstacles: how many there are; obstacle_height: ``world.obstacle_height``, m; scan_height:
    the scan plane's height above the floor, m (:attr:`Scanner.height`).
    """
    if obstacles == 0 or obstacle_height > scan_height:
        return None
    return (f'world.obstacle_height {obstacle_height:g} m is not above the scan plane at '
            f'{scan_height:g} m: the scans pass over every obstacle')


class Scanner:
    """
    The laser scanners of the bodies ``bodies`` (MuJoCo body ids, one per scanning robot).

    height: the scan plane's height above the floor, m; world: ``scan_*`` and ``seed``.
    """

    def __init__(self, model: 'mujoco.MjModel', bodies: ArrayLike, height: float,
                 world: WorldSettings) -> None:
        """Keep the model, the bodies and the rays' directions in each base's frame."""
        self.model = model
        self.bodies = np.asarray(bodies, dtype=np.intp)
        self.height = float(height)
        self.world = world
        self.shape = scan_shape(world)
        self.rays = world.scan_rays
        self.angles = self.shape.angle_min + self.shape.angle_increment * np.arange(self.rays)
        self.groups = np.zeros(mujoco.mjNGROUP, dtype=np.uint8)
        self.groups[SCANNED_GROUP] = 1
        self._noise = np.random.default_rng([world.seed, SCAN_SEED_OFFSET])
        self._geoms = np.zeros(self.rays, dtype=np.int32)
        self._distances = np.zeros(self.rays)

    def cast(self, data: 'mujoco.MjData') -> Float:
        """
        Return the true distances of every robot's rays (robots, rays), m: -1 where no hit.

        Hits beyond ``range_max`` are kept as they are (:meth:`scan` drops them).
        """
        positions = data.xpos[self.bodies]
        headings = headings_from_quaternions(data.xquat[self.bodies][:, WXYZ_TO_XYZW])
        result = np.empty((len(self.bodies), self.rays))
        directions = np.zeros((self.rays, 3))
        for row, (body, position, heading) in enumerate(zip(self.bodies, positions, headings)):
            angles = self.angles + heading
            directions[:, 0] = np.cos(angles)
            directions[:, 1] = np.sin(angles)
            origin = np.array([position[0], position[1], self.height])
            mujoco.mj_multiRay(self.model, data, origin, directions.reshape(-1), self.groups,
                               1, int(body), self._geoms, self._distances, None, self.rays,
                               self.shape.range_max)
            result[row] = self._distances
        return result

    def scan(self, data: 'mujoco.MjData') -> Float:
        """
        Return every robot's scan now (robots, rays), m: noisy returns, +inf for none.

        Noise is drawn for every ray of every scan (hit or not), so that a seed gives one
        sequence of scans whatever the bodies see.
        """
        distances = self.cast(data)
        noise = (self._noise.normal(0.0, self.world.scan_noise, distances.shape)
                 if self.world.scan_noise > 0.0 else 0.0)
        ranges = distances + noise
        valid = ((distances >= 0.0) & (ranges >= self.shape.range_min)
                 & (ranges <= self.shape.range_max))
        scanned: Float = np.where(valid, ranges, np.inf)
        return scanned
