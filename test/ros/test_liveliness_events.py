# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Liveliness: which profiles offer and ask for a lease, and what the events are read as."""

from types import SimpleNamespace

from formation_ros.ros import qos
from formation_ros.ros.liveliness import PeerLiveliness
from formation_ros.ros.topics import QosKind
from rclpy.event_handler import QoSLivelinessChangedInfo
from rclpy.qos import LivelinessPolicy


def changed(alive, not_alive, alive_change, not_alive_change):
    """Return an event with the fields of rclpy's (whose fields cannot be set from Python)."""
    assert {'alive_count', 'not_alive_count', 'alive_count_change',
            'not_alive_count_change'} <= set(dir(QoSLivelinessChangedInfo()))
    return SimpleNamespace(alive_count=alive, not_alive_count=not_alive,
                           alive_count_change=alive_change,
                           not_alive_count_change=not_alive_change)


def test_commands_and_states_offer_the_lease_and_the_recorder_asks_for_none():
    lease_ns = int(qos.LIVELINESS_LEASE * 1e9)
    for profile in (qos.COMMAND, qos.STATE):
        # the lease is kept by the messages, not by DDS messages to every participant
        assert profile.liveliness == LivelinessPolicy.MANUAL_BY_TOPIC
        assert profile.liveliness_lease_duration.nanoseconds == lease_ns
        recorded = qos.recording(profile)
        assert recorded.liveliness_lease_duration.nanoseconds == 0  # infinite: matches all
        assert (recorded.reliability, recorded.durability) == (profile.reliability,
                                                               profile.durability)
    for kind in (QosKind.REFERENCE, QosKind.CLOCK, QosKind.DIAGNOSTICS, QosKind.MARKERS):
        assert qos.BY_KIND[kind].liveliness_lease_duration.nanoseconds == 0
    # the plant asks for a lease kept by DDS: it matches publishers that keep theirs either way
    for asked in (qos.COMMAND_INPUT, qos.team_commands_input(100)):
        assert asked.liveliness == LivelinessPolicy.AUTOMATIC
        assert asked.liveliness_lease_duration.nanoseconds == lease_ns
    # a team robot's own cmd_vel is a command for those who listen, without the lease's cost
    assert qos.TEAM_CMD_VEL.liveliness_lease_duration.nanoseconds == 0
    assert (qos.TEAM_CMD_VEL.reliability, qos.TEAM_CMD_VEL.durability, qos.TEAM_CMD_VEL.depth) \
        == (qos.COMMAND.reliability, qos.COMMAND.durability, qos.COMMAND.depth)
    # robots hear any publisher of poses and neighbours: they ask for no lease
    assert qos.STATE_INPUT.liveliness_lease_duration.nanoseconds == 0
    assert (qos.STATE_INPUT.reliability, qos.STATE_INPUT.depth) == (qos.STATE.reliability,
                                                                    qos.STATE.depth)


def test_peer_liveliness_follows_the_events():
    peer = PeerLiveliness()
    assert peer.state() == 'unknown' and peer.changed_ns is None
    peer.on_event(changed(1, 0, 1, 0))
    assert (peer.state(), peer.lost, peer.alive) == ('alive', 0, 1)
    peer.on_event(changed(0, 1, -1, 1))
    assert (peer.state(), peer.lost, peer.not_alive) == ('lost', 1, 1)
    peer.on_event(changed(1, 0, 1, -1))
    assert (peer.state(), peer.lost) == ('alive', 1)
    peer.on_event(changed(0, 0, -1, 0))
    assert (peer.state(), peer.lost) == ('lost', 2)


def test_a_second_publisher_keeps_the_peer_alive():
    peer = PeerLiveliness()
    peer.on_event(changed(2, 0, 2, 0))
    peer.on_event(changed(1, 1, -1, 1))
    assert (peer.state(), peer.lost) == ('alive', 1)
