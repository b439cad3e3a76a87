# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Quality of service of every formation topic, in one place.

* Commands (``cmd_vel``): reliable, keep last 10, volatile; a lost command would leave a
  robot coasting on the previous one.
* References (``/formation/reference``): reliable, keep last 10, transient local, so a node
  that joins late still gets the latest samples (and the fixed reference is never missed).
* State (``pose``, ``neighbors``): best effort, keep last 1; at 50 to 100 Hz a stale sample is
  useless and a resent one would arrive late. In lockstep the plant resends a state that was not
  answered.
* Clock (``/clock``): reliable, keep last 1; it matches rclpy's best-effort time source and
  reliable subscribers such as a recorder.
* Diagnostics (``/diagnostics``): reliable, keep last 10, volatile, as diagnostic tools expect.
* Markers (``/formation/markers``): reliable, keep last 1, transient local, so RViz started
  later still shows the latest picture.

The recorder subscribes with the publishers' reliability and durability but a deep history
(:func:`recording`): a sample that waits a moment for a busy recorder is stored, not
overwritten by the next one.
"""

from formation_ros.ros.topics import QosKind
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy


def _profile(depth, reliability, durability):
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability,
                      durability=durability)


COMMAND = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
REFERENCE = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
STATE = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)
CLOCK = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
DIAGNOSTICS = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
MARKERS = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
BY_KIND = {QosKind.COMMAND: COMMAND, QosKind.REFERENCE: REFERENCE, QosKind.STATE: STATE,
           QosKind.CLOCK: CLOCK, QosKind.DIAGNOSTICS: DIAGNOSTICS, QosKind.MARKERS: MARKERS}


RECORDING_DEPTH = 1000


def recording(profile: QoSProfile) -> QoSProfile:
    """Return ``profile`` with the recorder's deep history (same reliability and durability)."""
    return _profile(max(profile.depth, RECORDING_DEPTH), profile.reliability,
                    profile.durability)
