# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Robots that take their obstacles from their own scans (``obstacles.source: scan``), over DDS.

A pillar stands between robot 1's start and its place; nobody's parameters file has it: the
plant knows no obstacle, and the robots see the pillar only in the scans of a stand-in scanner
written here, as a lab's LDS driver sends them (best effort, 5 Hz on the robot's clock, its own
frame, a return per degree from 0.12 to 3.5 m, the scan published a state after the pose it
was taken at). Robot 1 goes round the pillar, with either transport (the team's robots of one
process read their own scans); then its scanner sends scans in the driver's frame
``base_scan`` (refused, counted once) and it holds still and says why.
"""

import math

from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields
from geometry_msgs.msg import PoseStamped
from helpers import launch, logged, Statuses, stop_when, write_params
import numpy as np
import pytest
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

PILLAR, RADIUS = np.array([0.0, 0.0]), 0.3
RAYS, RANGE_MIN, RANGE_MAX = 360, 0.12, 3.5
SCAN_PERIOD_NS = 200_000_000
UNSEEN = {
    'start.positions': [-1.3, -1.1, 0.0, 1.6, -1.6, 0.0, 1.6, 0.0],
    'start.random_radius': None, 'start.min_separation': None,
    'repulsion_radius': 0.5, 'sensing_radii': [2.0, 2.0, 2.0, 2.0],
    'obstacles.clearance': 0.4, 'obstacles.source': 'scan',
}


def ranges_from(origin, heading):
    """Return the LDS's ranges from ``origin`` facing ``heading``, the pillar about: (360,) m."""
    angles = heading + np.arange(RAYS) * (2.0 * math.pi / RAYS)
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    f = np.asarray(origin, dtype=float) - PILLAR
    b = d @ f
    disc = b * b - (f @ f - RADIUS ** 2)
    hit = np.where(disc >= 0.0, -b - np.sqrt(np.maximum(disc, 0.0)), np.inf)
    hit = np.where(hit > 0.0, hit, np.inf)
    return np.where((hit >= RANGE_MIN) & (hit <= RANGE_MAX), hit, np.inf)


class StandInScanner:
    """Robot ``i``'s LDS driver: a scan every SCAN_PERIOD_NS of its poses' time, a state late."""

    def __init__(self, probe, i):
        self.frame = f'robot_{i}/base_scan'
        self.publisher = probe.create_publisher(LaserScan, f'/robot_{i}/scan',
                                                qos_profile_sensor_data)
        self.taken = None
        self.last_ns = None
        self.path = []
        probe.create_subscription(PoseStamped, f'/robot_{i}/pose', self.on_pose,
                                  qos_profile_sensor_data)

    def on_pose(self, message):
        stamp = fields.stamp_to_ns(message.header.stamp)
        p, o = message.pose.position, message.pose.orientation
        self.path.append((p.x, p.y))
        if self.taken is not None:
            self.publisher.publish(self.taken)
            self.taken = None
        if self.last_ns is not None and stamp - self.last_ns < SCAN_PERIOD_NS:
            return
        self.last_ns = stamp
        scan = LaserScan()
        scan.header.stamp = message.header.stamp
        scan.header.frame_id = self.frame
        scan.angle_min, scan.angle_increment = 0.0, 2.0 * math.pi / RAYS
        scan.angle_max = scan.angle_increment * (RAYS - 1)
        scan.scan_time = SCAN_PERIOD_NS * 1e-9
        scan.range_min, scan.range_max = RANGE_MIN, RANGE_MAX
        scan.ranges = ranges_from((p.x, p.y), 2.0 * math.atan2(o.z, o.w)).tolist()
        self.taken = scan


@pytest.mark.parametrize('transport', ['robot', 'team'])
def test_robots_go_round_a_pillar_only_their_scanners_see(processes, install, probe,
                                                          tmp_path, transport):
    params = write_params(tmp_path, 'square_4.yaml', {**UNSEEN, 'transport': transport})
    config = load_config(params, 'plant')
    assert config.obstacles is None, "the pillar is on nobody's map"
    scanners = [StandInScanner(probe, i) for i in range(1, 5)]
    statuses = Statuses(probe)
    launch(processes, install, params, out=tmp_path / 'out', per_process=4)

    def arrived():
        path = scanners[0].path
        return bool(path) and np.hypot(path[-1][0] - 1.0, path[-1][1] - 1.0) < 0.05

    def points_seen():
        status = statuses.get('formation_ros/robot_1')
        values = {} if status is None else {kv.key: kv.value for kv in status.values}
        return int(values.get('obstacle points from the scan', 0))

    seen = []
    assert probe.spin_until(lambda: seen.append(points_seen()) or arrived(), 240), \
        processes.log('launcher')[-3000:]
    assert max(seen) > 0, 'robot 1 used returns of the pillar'
    path = np.array(scanners[0].path)
    gap = np.min(np.hypot(*(path - PILLAR).T)) - RADIUS
    assert gap > 0.0, 'robot 1 went round the pillar, not through it'
    assert np.min(path[:, 0]) < -1.0 and np.max(path[:, 0]) > 0.9

    scanners[0].frame = 'base_scan'
    log = logged(probe, processes, 'launcher',
                 'ignoring scan messages with a frame other than obstacles.scan_frame (got '
                 "'base_scan', expected 'robot_1/base_scan')",
                 'its latest scan is more than 0.5 s older than the state: holding still')
    assert log.count('ignoring scan messages with a frame other') == 1
    info = stop_when(probe, processes, lambda: True)
    assert info.returncode == 0, processes.log('launcher')[-3000:]
