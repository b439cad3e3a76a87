# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
RViz markers of the formation (``/formation/markers``, visualization_msgs/MarkerArray).

Namespaces: ``robots`` (spheres), ``sensing`` (discs in 2D, balls in 3D, radius R_i: a sphere
list per distinct radius), ``repulsion`` (radius b, one sphere list), ``desired`` (the desired
formation polygon), ``paths`` (recent paths, one line list), ``obstacles`` (the map's real
obstacles: a cylinder per circle, a box and two end cylinders per wall, a sphere per sphere).
Every marker is in the world frame; the arrays come from the plant. The number of markers does
not grow with the team (a list marker per kind, not a marker per robot).
"""

from collections import deque
import math

from formation_ros.ros.messages import ns_to_stamp, WORLD_FRAME
from geometry_msgs.msg import Point
import numpy as np
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

ROBOT_DIAMETER = 0.2
DISC_THICKNESS = 0.01
HEADING_LENGTH = 0.3
"""Length of the line that shows a unicycle's heading in RViz, m."""
PILLAR_HEIGHT = {2: DISC_THICKNESS, 3: 20.0}
"""How tall circles and walls are drawn, m: flat in 2D; in 3D (unbounded in z) this tall,
about z = 0."""
OBSTACLE_RGBA = (0.45, 0.35, 0.25, 0.9)


def _point(row):
    values = [float(v) for v in row] + [0.0] * (3 - len(row))
    return Point(x=values[0], y=values[1], z=values[2])


def _marker(ns, marker_id, kind, stamp_ns, rgba, frame_id=WORLD_FRAME):
    marker = Marker()
    marker.header.frame_id = frame_id
    marker.header.stamp = ns_to_stamp(stamp_ns)
    marker.ns = ns
    marker.id = marker_id
    marker.type = kind
    marker.action = Marker.ADD
    marker.pose.orientation.w = 1.0
    marker.color = ColorRGBA(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])
    return marker


def _zones(ns, first_id, centres, radii, dim, stamp_ns, rgba, frame_id):
    """
    One SPHERE_LIST per distinct radius (scale.z is the disc thickness in 2D).

    A marker per robot costs a Python message each; a list marker costs one per radius. RViz
    draws the points of a sphere list as camera-facing spheres of diameter scale.x, so a 2D zone
    is a disc only when seen from above.
    """
    markers = []
    for k, radius in enumerate(np.unique(radii)):
        marker = _marker(ns, first_id + k, Marker.SPHERE_LIST, stamp_ns, rgba, frame_id)
        marker.scale.x = marker.scale.y = 2.0 * float(radius)
        marker.scale.z = DISC_THICKNESS if dim == 2 else 2.0 * float(radius)
        marker.points = [_point(centre) for centre in centres[radii == radius]]
        markers.append(marker)
    return markers


class Paths:
    """
    The recent positions of every robot as marker points, oldest first.

    Each position is made into a ``Point`` once, when it is added, so a marker of paths K long
    costs N points per update rather than K * N.
    """

    def __init__(self, num_robots: int, length: int) -> None:
        """Keep the last ``length`` positions of ``num_robots`` robots."""
        self.points = [deque(maxlen=length) for _ in range(num_robots)]

    def append(self, q) -> None:
        """Add the positions ``q`` ((N, dim), m) of one moment."""
        for path, row in zip(self.points, q):
            path.append(_point(row))

    def __len__(self) -> int:
        """Return the number of moments kept."""
        return len(self.points[0]) if self.points else 0


def formation_markers(q, sensing_radii, repulsion_radius, desired, paths, stamp_ns,
                      frame_id=WORLD_FRAME, headings=None, obstacles=None):
    """
    Build the MarkerArray of one moment.

    q: (N, dim) positions; sensing_radii: (N,); repulsion_radius: b; desired: (N, dim) desired
    positions of the shape in force; paths: the robots' recent positions (:class:`Paths`);
    stamp_ns: time; frame_id: the world frame (``world_frame``); headings: (N,) rad of
    unicycles, drawn as a line :data:`HEADING_LENGTH` long from each body (None: none);
    obstacles: the map (:func:`obstacle_markers`; None: none).
    """
    dim = q.shape[1]
    array = MarkerArray()
    robots = _marker('robots', 0, Marker.SPHERE_LIST, stamp_ns, (0.1, 0.3, 0.9, 1.0), frame_id)
    robots.scale.x = robots.scale.y = robots.scale.z = ROBOT_DIAMETER
    robots.points = [_point(row) for row in q]
    array.markers.append(robots)
    radii = np.asarray(sensing_radii, dtype=float)
    array.markers.extend(_zones('sensing', 0, q, radii, dim, stamp_ns, (0.2, 0.7, 0.2, 0.08),
                                frame_id))
    array.markers.extend(_zones('repulsion', 0, q, np.full(len(q), float(repulsion_radius)),
                                dim, stamp_ns, (0.9, 0.2, 0.1, 0.2), frame_id))
    polygon = _marker('desired', 0, Marker.LINE_STRIP, stamp_ns, (0.9, 0.1, 0.1, 0.9), frame_id)
    polygon.scale.x = 0.04
    polygon.points = [_point(row) for row in desired] + [_point(desired[0])]
    array.markers.append(polygon)
    if headings is not None:
        ahead = _marker('headings', 0, Marker.LINE_LIST, stamp_ns, (0.1, 0.6, 0.2, 1.0),
                        frame_id)
        ahead.scale.x = 0.03
        tips = q[:, :2] + HEADING_LENGTH * np.column_stack([np.cos(headings), np.sin(headings)])
        ahead.points = [point for body, tip in zip(q, tips)
                        for point in (_point(body), _point(tip))]
        array.markers.append(ahead)
    if len(paths) > 1:
        lines = _marker('paths', 0, Marker.LINE_LIST, stamp_ns, (0.3, 0.3, 0.3, 0.7), frame_id)
        lines.scale.x = 0.02
        lines.points = [point for path in paths.points
                        for segment in zip(list(path)[:-1], list(path)[1:]) for point in segment]
        array.markers.append(lines)
    if obstacles is not None:
        array.markers.extend(obstacle_markers(obstacles, stamp_ns, frame_id))
    return array


def obstacle_markers(obstacles, stamp_ns, frame_id=WORLD_FRAME):
    """
    Return the markers of a map's obstacles (``core.maths.obstacles.Obstacles``), ns ``obstacles``.

    Circles: a CYLINDER each (diameter 2 r); walls: a CUBE along the segment (its length, 2 t
    wide) and a CYLINDER of radius t at each end (the points within t of the segment); spheres:
    a SPHERE each. Circles and walls are :data:`PILLAR_HEIGHT` tall, as they are unbounded in
    3D. The real obstacles, not grown by the footprint.
    """
    height = PILLAR_HEIGHT[obstacles.dim]
    markers = []

    def add(kind, centre, size, yaw=0.0):
        marker = _marker('obstacles', len(markers), kind, stamp_ns, OBSTACLE_RGBA, frame_id)
        marker.pose.position = _point(centre)
        marker.pose.orientation.z = math.sin(yaw / 2.0)
        marker.pose.orientation.w = math.cos(yaw / 2.0)
        marker.scale.x, marker.scale.y, marker.scale.z = (float(v) for v in size)
        markers.append(marker)

    for x, y, r in obstacles.circles.tolist():
        add(Marker.CYLINDER, (x, y), (2.0 * r, 2.0 * r, height))
    for x1, y1, x2, y2, t in obstacles.walls.tolist():
        length = math.hypot(x2 - x1, y2 - y1)
        if length > 0.0:
            add(Marker.CUBE, ((x1 + x2) / 2.0, (y1 + y2) / 2.0), (length, 2.0 * t, height),
                math.atan2(y2 - y1, x2 - x1))
        for end in ((x1, y1), (x2, y2)):
            add(Marker.CYLINDER, end, (2.0 * t, 2.0 * t, height))
    for x, y, z, r in obstacles.spheres.tolist():
        add(Marker.SPHERE, (x, y, z), (2.0 * r, 2.0 * r, 2.0 * r))
    return markers
