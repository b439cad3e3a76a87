# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A dead peer is noticed and reported in ``/diagnostics``.

The plant, the reference node and four robots run as real processes; kill -9 of a robot must
show in the plant's status by its commands' age (``robots with lost cmd_vel``: none for the
lease, 1 s), well before DDS would drop the dead participant (about 20 s); kill -9 of the
plant in the robots' status through their watchdog (``publishing zero: inputs stale``). The
probe hears ``/diagnostics`` like any monitoring tool.
"""

import signal
import time

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.ros import qos
from formation_ros.ros.diagnostics import PERIOD
from helpers import SQUARE, start_system, START_UP
import pytest

pytestmark = pytest.mark.faults

NOTICE_WITHIN = 10.0
"""Generous bound (s) on kill -> status: lease 1 s + diagnostics period 1 s + a busy machine."""


def values_of(status):
    """Return the key-value pairs of a DiagnosticStatus as a dict."""
    return {pair.key: pair.value for pair in status.values}


STALE = 'publishing zero: inputs stale'


def test_dead_robot_and_dead_plant_are_noticed(processes, install, probe):
    heard = []
    probe.create_subscription(
        DiagnosticArray, '/diagnostics',
        lambda m: heard.extend((time.monotonic(), s.name, s.message, values_of(s))
                               for s in m.status),
        qos.DIAGNOSTICS)

    def latest(name, since=0.0):
        found = [values for at, who, _, values in heard if who == name and at >= since]
        return found[-1] if found else {}

    def status_of(name, since=0.0):
        found = [message for at, who, message, _ in heard if who == name and at >= since]
        return found[-1] if found else None

    def first(name, since, condition):
        return next(at for at, who, message, values in heard
                    if who == name and at >= since and condition(message, values))

    start_system(processes, install, SQUARE, 4)
    assert probe.spin_until(
        lambda: latest('formation_ros/plant').get('robots with alive cmd_vel') == '1, 2, 3, 4'
        and status_of('formation_ros/robot_2') == 'controlling',
        START_UP), processes.log('plant')
    assert latest('formation_ros/plant')['robots with lost cmd_vel'] == 'none'

    processes.send_signal('robot_1', signal.SIGKILL)
    killed = time.monotonic()
    assert probe.spin_until(
        lambda: latest('formation_ros/plant', killed).get('robots with lost cmd_vel') == '1',
        NOTICE_WITHIN), latest('formation_ros/plant')
    robot_noticed = first('formation_ros/plant', killed,
                          lambda _, values: values.get('robots with lost cmd_vel') == '1') - killed
    assert latest('formation_ros/plant', killed)['robots with alive cmd_vel'] == '2, 3, 4'

    processes.send_signal('plant', signal.SIGKILL)
    killed = time.monotonic()
    assert probe.spin_until(
        lambda: all(status_of(f'formation_ros/robot_{i}', killed) == STALE for i in range(2, 5)),
        NOTICE_WITHIN), [status_of(f'formation_ros/robot_{i}') for i in range(2, 5)]
    plant_noticed = max(first(f'formation_ros/robot_{i}', killed,
                              lambda message, _: message == STALE)
                        for i in range(2, 5)) - killed
    print(f'noticed in /diagnostics: robot killed {robot_noticed:.2f} s (lease '
          f'{qos.LIVELINESS_LEASE:g} s), plant killed {plant_noticed:.2f} s (watchdog), status '
          f'period {PERIOD:g} s')
