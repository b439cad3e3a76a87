# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A dead peer is noticed through DDS liveliness and reported in ``/diagnostics``.

The plant, the reference node and four robots run as real processes; kill -9 of a robot must
show in the plant's status (``robots with lost cmd_vel``), kill -9 of the plant in the robots'
(``plant (pose publisher)``), well before DDS would drop the dead participant (about 20 s).
The probe hears ``/diagnostics`` like any monitoring tool.
"""

import signal
import time

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.ros import qos
from formation_ros.ros.diagnostics import PERIOD
from helpers import node, SQUARE, START_UP
import pytest

pytestmark = pytest.mark.faults

NOTICE_WITHIN = 10.0
"""Generous bound (s) on kill -> status: lease 1 s + diagnostics period 1 s + a busy machine."""


def values_of(status):
    """Return the key-value pairs of a DiagnosticStatus as a dict."""
    return {pair.key: pair.value for pair in status.values}


def test_dead_robot_and_dead_plant_are_noticed(processes, install, probe):
    heard = []
    probe.create_subscription(
        DiagnosticArray, '/diagnostics',
        lambda m: heard.extend((time.monotonic(), s.name, values_of(s)) for s in m.status),
        qos.DIAGNOSTICS)

    def latest(name, since=0.0):
        found = [values for at, who, values in heard if who == name and at >= since]
        return found[-1] if found else {}

    processes.start(node(install, 'plant', SQUARE))
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    for i in range(1, 5):
        processes.start(node(install, 'robot', SQUARE, '-r', f'__ns:=/robot_{i}', '-p',
                             f'robot_id:={i}', '-p', 'use_sim_time:=true',
                             process=f'robot_{i}'))
    assert probe.spin_until(
        lambda: latest('formation_ros/plant').get('robots with alive cmd_vel') == '1, 2, 3, 4'
        and latest('formation_ros/robot_2').get('plant (pose publisher)') == 'alive',
        START_UP), processes.log('plant')
    assert latest('formation_ros/plant')['robots with lost cmd_vel'] == 'none'

    processes.send_signal('robot_1', signal.SIGKILL)
    killed = time.monotonic()
    assert probe.spin_until(
        lambda: latest('formation_ros/plant', killed).get('robots with lost cmd_vel') == '1',
        NOTICE_WITHIN), latest('formation_ros/plant')
    robot_noticed = next(at for at, who, values in heard if at >= killed
                         and who == 'formation_ros/plant'
                         and values.get('robots with lost cmd_vel') == '1') - killed
    assert latest('formation_ros/plant', killed)['robots with alive cmd_vel'] == '2, 3, 4'

    processes.send_signal('plant', signal.SIGKILL)
    killed = time.monotonic()
    assert probe.spin_until(
        lambda: all(latest(f'formation_ros/robot_{i}', killed).get('plant (pose publisher)')
                    == 'lost' for i in range(2, 5)),
        NOTICE_WITHIN), latest('formation_ros/robot_2')
    plant_noticed = max(next(at for at, who, values in heard if at >= killed
                             and who == f'formation_ros/robot_{i}'
                             and values.get('plant (pose publisher)') == 'lost')
                        for i in range(2, 5)) - killed
    print(f'noticed in /diagnostics: robot killed {robot_noticed:.2f} s, plant killed '
          f'{plant_noticed:.2f} s (lease {qos.LIVELINESS_LEASE:g} s, period {PERIOD:g} s)')
    assert latest('formation_ros/robot_2', killed)['plant liveliness lost'] == '1'
