# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Quality of service of every formation topic, in one place.

* Commands (``cmd_vel``): reliable, keep last 10, volatile; a lost command would leave a
  robot coasting on the previous one. A liveliness lease of :data:`LIVELINESS_LEASE` (1 s),
  kept by the commands themselves (``MANUAL_BY_TOPIC``: a running robot sends one at least
  every control period, zero ones too while its inputs are stale): the plant hears within a
  second that a robot's process died or its link was cut (``formation_ros.ros.liveliness``).
  It asks for the lease kept by DDS (``AUTOMATIC``, ``COMMAND_INPUT``), which matches
  both kinds of publisher. Not ``AUTOMATIC`` on the robots' side: that lease is kept by
  messages from every participant to every other, whoever subscribes, and 40 processes
  offering one took half a core of this 2-core machine; a kept-by-topic lease costs nothing
  while commands flow and reaches only the publisher's subscribers.
* References (``/formation/reference``): reliable, keep last 10, transient local, so a node
  that joins late still gets the latest samples (and the fixed reference is never missed).
* State (``pose``, ``neighbors``): best effort, keep last 1; at 50 to 100 Hz a stale sample is
  useless and a resent one would arrive late. In lockstep the plant resends a state that was not
  answered. The plant offers the liveliness lease :data:`LIVELINESS_LEASE`, kept by the states
  (``STATE``); robots
  subscribe asking for none (``STATE_INPUT``), so they hear any publisher of poses and
  neighbours, a localisation system or range-sensor driver with the ROS default QoS too. A
  robot notices a silent plant by its watchdog instead (``input_timeout``, 0.5 s by default:
  it publishes zero and its ``/diagnostics`` says so).
* Team transport (``transport: team``): ``/formation/states`` as the states (``STATE``
  offered, ``STATE_INPUT`` asked), ``/formation/commands`` as the commands (``COMMAND``,
  the lease on both sides: the plant hears within it that a robot process or fleet died).
  The plant subscribes with a history as deep as the team is large
  (:func:`team_commands_input`): a history is kept per topic, not per publisher, and every
  robot process or fleet answers each state at once; with ``COMMAND``'s 10, the answers of
  20 fleets overwrote each other while the plant was busy stepping (16 % of them lost at
  N = 500, measured). A team robot's own ``cmd_vel``, published only for those who listen
  (``ros2 topic echo``, a recorder), is ``COMMAND`` without the lease (``TEAM_CMD_VEL``): the
  plant hears the team topic, and nothing needs to know whether a thousand such publishers
  are alive (when they offered a lease kept by DDS, they took half a core of this machine
  with no reader at all).
* Measurements (the relay's sources, ``relay.source_topic``: a motion-capture system's poses):
  best effort, keep last 1, volatile, no liveliness asked (``MEASUREMENT``). A best-effort
  subscriber matches best-effort publishers (vrpn_mocap, which uses the sensor-data QoS) and
  reliable ones (natnet_ros2, ``ros2 topic pub``) alike, and only the newest pose matters.
* Clock (``/clock``): reliable, keep last 1; it matches rclpy's best-effort time source and
  reliable subscribers such as a recorder.
* Diagnostics (``/diagnostics``): reliable, keep last 10, volatile, as diagnostic tools expect.
* Markers (``/formation/markers``): reliable, keep last 1, transient local, so RViz started
  later still shows the latest picture.
* Changes (``/formation/shape``, ``/formation/status``): reliable, keep last
  :data:`CHANGES_KEPT`, transient local: a node that joins late gets every recent change with
  the stamp it holds from (a scheduled switch is sent ahead), so it answers each state with
  the shape and mode in force at that state's stamp.

The recorder subscribes with the publishers' reliability and durability but a deep history
(:func:`recording`): a sample that waits a moment for a busy recorder is stored, not
overwritten by the next one.

Matching: a subscriber that asks for a liveliness lease only matches publishers that offer
at most that lease, and only a subscriber that asks for one is told when a publisher's lease
runs out, and a subscriber that asks for a lease kept by DDS (``AUTOMATIC``) matches
publishers whose lease is kept by DDS or by their own messages. The plant asks for the lease on
every ``cmd_vel`` (robots offer it), so a robot whose
process died or whose link was cut shows as lost within the lease; a ``cmd_vel`` publisher
with the ROS default (no lease), e.g. ``ros2 topic pub`` without ``--qos-liveliness automatic
--qos-liveliness-lease-duration 1``, does not reach the plant. The recorder and tools such as
``ros2 topic echo`` ask for no lease (infinite) and match any publisher.
"""

from formation_ros.ros.topics import QosKind
from rclpy.duration import Duration
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile,
                       ReliabilityPolicy)

LIVELINESS_LEASE = 1.0
"""Liveliness lease of commands and states, s: a dead peer is noticed within it."""


def _profile(depth, reliability, durability, lease=None,
             kept_by=LivelinessPolicy.MANUAL_BY_TOPIC):
    """Return a keep-last profile, with a ``lease`` (s) to offer or ask for, ``kept_by``."""
    if lease is None:
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                          reliability=reliability, durability=durability)
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=reliability,
                      durability=durability, liveliness=kept_by,
                      liveliness_lease_duration=Duration(seconds=lease))


COMMAND = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE, LIVELINESS_LEASE)
COMMAND_INPUT = _profile(COMMAND.depth, COMMAND.reliability, COMMAND.durability,
                         LIVELINESS_LEASE, LivelinessPolicy.AUTOMATIC)
TEAM_CMD_VEL = _profile(COMMAND.depth, COMMAND.reliability, COMMAND.durability)
REFERENCE = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
STATE = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE, LIVELINESS_LEASE)
STATE_INPUT = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)
MEASUREMENT = _profile(1, ReliabilityPolicy.BEST_EFFORT, DurabilityPolicy.VOLATILE)
CLOCK = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
DIAGNOSTICS = _profile(10, ReliabilityPolicy.RELIABLE, DurabilityPolicy.VOLATILE)
MARKERS = _profile(1, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
CHANGES_KEPT = 32
CHANGES = _profile(CHANGES_KEPT, ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL)
BY_KIND = {QosKind.COMMAND: COMMAND, QosKind.REFERENCE: REFERENCE, QosKind.STATE: STATE,
           QosKind.CLOCK: CLOCK, QosKind.DIAGNOSTICS: DIAGNOSTICS, QosKind.MARKERS: MARKERS,
           QosKind.CHANGES: CHANGES}


def team_commands_input(robots: int) -> QoSProfile:
    """
    Return the plant's QoS for ``/formation/commands``: ``COMMAND_INPUT``, ``robots`` deep.

    One team command per robot process or fleet per state, and at most ``robots`` of them:
    a whole state's answers fit the one history they share (it is kept per topic, as the
    topic has no keys), however long the plant takes to read them.
    """
    return _profile(max(COMMAND.depth, robots), COMMAND.reliability, COMMAND.durability,
                    LIVELINESS_LEASE, LivelinessPolicy.AUTOMATIC)


RECORDING_DEPTH = 1000


def recording(profile: QoSProfile) -> QoSProfile:
    """
    Return ``profile`` with the recorder's deep history (same reliability and durability).

    It asks for no liveliness lease, so it matches every publisher, whatever lease it offers.
    """
    return _profile(max(profile.depth, RECORDING_DEPTH), profile.reliability,
                    profile.durability)
