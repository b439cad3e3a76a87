# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
RViz markers of the formation (``/formation/markers``, visualization_msgs/MarkerArray).

Namespaces: ``robots`` (spheres), ``sensing`` (discs in 2D, balls in 3D, radius R_i),
``repulsion`` (radius b), ``desired`` (the desired formation polygon), ``paths`` (recent paths).
Every marker is in frame 'world'; the arrays come from the plant.
"""

from formation_ros.ros.messages import ns_to_stamp, WORLD_FRAME
from geometry_msgs.msg import Point
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

ROBOT_DIAMETER = 0.2
DISC_THICKNESS = 0.01


def _point(row):
    values = [float(v) for v in row] + [0.0] * (3 - len(row))
    return Point(x=values[0], y=values[1], z=values[2])


def _marker(ns, marker_id, kind, stamp_ns, rgba):
    marker = Marker()
    marker.header.frame_id = WORLD_FRAME
    marker.header.stamp = ns_to_stamp(stamp_ns)
    marker.ns = ns
    marker.id = marker_id
    marker.type = kind
    marker.action = Marker.ADD
    marker.pose.orientation.w = 1.0
    marker.color = ColorRGBA(r=rgba[0], g=rgba[1], b=rgba[2], a=rgba[3])
    return marker


def _zone(ns, marker_id, centre, radius, dim, stamp_ns, rgba):
    kind = Marker.CYLINDER if dim == 2 else Marker.SPHERE
    marker = _marker(ns, marker_id, kind, stamp_ns, rgba)
    marker.pose.position = _point(centre)
    marker.scale.x = marker.scale.y = 2.0 * float(radius)
    marker.scale.z = DISC_THICKNESS if dim == 2 else 2.0 * float(radius)
    return marker


def formation_markers(q, sensing_radii, repulsion_radius, desired, paths, stamp_ns):
    """
    Build the MarkerArray of one moment.

    q: (N, dim) positions; sensing_radii: (N,); repulsion_radius: b; desired: (N, dim) desired
    positions; paths: (K, N, dim) recent positions, oldest first (K may be 0); stamp_ns: time.
    """
    dim = q.shape[1]
    array = MarkerArray()
    robots = _marker('robots', 0, Marker.SPHERE_LIST, stamp_ns, (0.1, 0.3, 0.9, 1.0))
    robots.scale.x = robots.scale.y = robots.scale.z = ROBOT_DIAMETER
    robots.points = [_point(row) for row in q]
    array.markers.append(robots)
    for i, (centre, radius) in enumerate(zip(q, sensing_radii)):
        array.markers.append(_zone('sensing', i, centre, radius, dim, stamp_ns,
                                   (0.2, 0.7, 0.2, 0.08)))
        array.markers.append(_zone('repulsion', i, centre, repulsion_radius, dim, stamp_ns,
                                   (0.9, 0.2, 0.1, 0.2)))
    polygon = _marker('desired', 0, Marker.LINE_STRIP, stamp_ns, (0.9, 0.1, 0.1, 0.9))
    polygon.scale.x = 0.04
    polygon.points = [_point(row) for row in desired] + [_point(desired[0])]
    array.markers.append(polygon)
    for i in range(q.shape[0] if len(paths) > 1 else 0):
        path = _marker('paths', i, Marker.LINE_STRIP, stamp_ns, (0.3, 0.3, 0.3, 0.7))
        path.scale.x = 0.02
        path.points = [_point(row) for row in paths[:, i]]
        array.markers.append(path)
    return array
