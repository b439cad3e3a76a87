# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A flood of forged poses on one robot: its commands stay at about one per state."""

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.rules.answers import BURST, RATE_MARGIN
from formation_ros.core.settings.params import load_config
from formation_ros.ros import fields, qos
from geometry_msgs.msg import PoseStamped, TwistStamped
from helpers import node, SQUARE
import pytest
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg
import wire

pytestmark = pytest.mark.faults
START_UP = 90.0
FLOOD_PER_STATE = 10
FLOOD_PER_TICK = 2
STATES = 300
DELIVERY_SLACK = 5
"""Commands in flight when the counts are read, and /clock ticks the probe heard late."""


def test_a_pose_flood_is_not_passed_on_to_cmd_vel(processes, install, probe):
    config = load_config(SQUARE)
    processes.start(node(install, 'plant', SQUARE, '-p', 'plant.wait_for_robots:=false'))
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_1',
                         '-p', 'use_sim_time:=true', process='robot_1'))
    counts = {'commands': 0, 'forged': 0}
    latest = {'clock_ns': -1}
    flooding = {}

    def on_clock(msg):
        latest['clock_ns'] = fields.stamp_to_ns(msg.clock)

    def on_diagnostics(msg):
        for status in msg.status:
            if status.name == 'formation_ros/robot_1':
                flooding.update({kv.key: kv.value for kv in status.values})

    probe.create_subscription(ClockMsg, '/clock', on_clock, qos.CLOCK)
    probe.create_subscription(TwistStamped, '/robot_1/cmd_vel',
                              lambda msg: counts.__setitem__('commands', counts['commands'] + 1),
                              QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
    probe.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, qos.DIAGNOSTICS)
    forger = probe.create_publisher(PoseStamped, '/robot_1/pose', qos.STATE)
    start = config.start[0]
    period = 1.0 / config.plant.publish_rate if config.plant else 0.02

    def forge():
        """One forged pose: a copy of the present state's stamp, or a stamp a little after."""
        if latest['clock_ns'] < 0:
            return
        for _ in range(FLOOD_PER_TICK):
            k = counts['forged'] % FLOOD_PER_STATE
            offset = 0 if k % 2 else 1000 * (k + 1)
            forger.publish(wire.pose_stamped(start + 0.01 * k, latest['clock_ns'] + offset, 2))
            counts['forged'] += 1

    probe.create_timer(period * FLOOD_PER_TICK / FLOOD_PER_STATE, forge)
    assert probe.spin_until(lambda: counts['commands'] > 20, START_UP), processes.log('robot_1')
    before = dict(counts, clock_ns=latest['clock_ns'])
    period_ns = int(round(period * 1e9))
    assert probe.spin_until(lambda: latest['clock_ns'] - before['clock_ns']
                            >= STATES * period_ns, START_UP)
    states = (latest['clock_ns'] - before['clock_ns']) // period_ns
    commands = counts['commands'] - before['commands']
    forged = counts['forged'] - before['forged']
    print(f'flood: {forged} forged poses, {states} states, {commands} commands')
    assert forged >= 3 * states, (forged, states)
    bound = (1.0 + RATE_MARGIN) * (states + DELIVERY_SLACK) + BURST + DELIVERY_SLACK
    assert commands <= bound, (commands, states, forged)
    assert commands >= 0.5 * states, (commands, states)
    assert probe.spin_until(lambda: int(flooding.get('states not answered (flooding)', 0))
                            > states, 30), (flooding, forged, states)
    log = processes.log('robot_1')
    assert log.count('states arrive faster than one per 0.02 s') == 1, log
