# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Quality of service of every formation topic, in one place.

Each profile below says in a line what it is for; why each topic has the profile it has (the
liveliness leases, best effort for states and measurements, the deep histories of the team
commands and of the recorder) and how publishers and subscribers match:
docs/ros_interface.md, "Quality of service".
"""
from formation_ros.ros.topics import QosKind
from rclpy.duration import Duration
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                       ReliabilityPolicy)

LIVELINESS_LEASE = 1.0
"""Liveliness lease offered with commands and states, s: a reader that asks for it (a user's
monitor) notices a dead peer within it; the plant notices by the commands' age, as long."""


def _profile(depth, reliability, durability, lease=None):
    """Return a keep-last profile; with a ``lease`` (s) offered, kept by the publisher."""
    if lease is None:
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                          reliability=reliability, durability=durability)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability,
                      durability=durability, liveliness=LivelinessPolicy.MANUAL_BY_TOPIC,
                      liveliness_lease_duration=Duration(seconds=lease))


COMMAND = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE, LIVELINESS_LEASE)
"""Commands offered (``cmd_vel``, ``/formation/commands``): reliable, the lease kept by them."""
COMMAND_INPUT = _profile(COMMAND.depth, ReliabilityPolicy.BEST_EFFORT, COMMAND.durability)
"""Commands heard by the plant and the world: best effort, no lease asked, so every publisher
of commands matches (reliable or best effort, with a lease or none: ``ros2 topic pub``, a
teleop, a user's node); a dead or silent commander shows in the commands' age instead."""
TEAM_CMD_VEL = _profile(COMMAND.depth, COMMAND.reliability, COMMAND.durability)
"""A team robot's own ``cmd_vel`` (only for those who listen): as COMMAND, no lease."""
REFERENCE = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
"""``/formation/reference``: reliable, transient local (a late joiner gets the latest)."""
STATE = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE, LIVELINESS_LEASE)
"""States offered (``pose``, ``neighbors``, ``/formation/states``): best effort, the lease."""
STATE_INPUT = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)
"""States heard by a robot: no lease asked, so any publisher of poses is heard."""
MEASUREMENT = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)
"""The relay's sources (motion capture) and the world's measured poses and odometry: best
effort, keep last 1, no lease."""
CLOCK = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
"""``/clock``: reliable, keep last 1 (matches rclpy's best-effort time source too)."""
DIAGNOSTICS = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
"""``/diagnostics``: reliable, keep last 10, volatile."""
MARKERS = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
"""``/formation/markers``: transient local, so RViz started later shows the latest picture."""
CHANGES_KEPT = 32
"""Changes kept for a late joiner on ``/formation/shape`` and ``/formation/status``."""
CHANGES = _profile(CHANGES_KEPT, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
"""The changes: reliable, transient local, CHANGES_KEPT deep."""
BY_KIND = {QosKind.COMMAND: COMMAND, QosKind.REFERENCE: REFERENCE, QosKind.STATE: STATE,
           QosKind.CLOCK: CLOCK, QosKind.DIAGNOSTICS: DIAGNOSTICS, QosKind.MARKERS: MARKERS,
           QosKind.CHANGES: CHANGES, QosKind.MEASUREMENT: MEASUREMENT}


def team_commands_input(robots: int) -> QoSProfile:
    """
    Return the plant's QoS for ``/formation/commands``: ``COMMAND_INPUT``, ``robots`` deep.

    One team command per robot process or fleet per state, and at most ``robots`` of them:
    a whole state's answers fit the one history they share (it is kept per topic, as the
    topic has no keys), however long the plant takes to read them.
    """
    return _profile(max(COMMAND.depth, robots), COMMAND_INPUT.reliability,
                    COMMAND_INPUT.durability)


RECORDING_DEPTH = 1000


def recording(profile: QoSProfile) -> QoSProfile:
    """
    Return ``profile`` with the recorder's deep history (same reliability and durability).

    It asks for no liveliness lease, so it matches every publisher, whatever lease it offers.
    """
    return _profile(max(profile.depth, RECORDING_DEPTH), profile.reliability,
                    profile.durability)
