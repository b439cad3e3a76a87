# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
A lockstep plant that waits for a robot names it, and goes on when the robot answers again.

Robot 3's process is stopped (SIGSTOP) mid-run: the plant, which steps only once every robot
has answered, must say within NAME_AFTER s of wall time which robot it waits for, show it on
/diagnostics, hold its clock, and carry on when the process continues (SIGCONT).
"""

import re
import signal

from formation_ros.core.rules.lockstep import NAME_AFTER, REPEAT_EVERY, WAITED, WAITING_FOR
from helpers import SimClock, start_system, START_UP, Statuses, write_params
import pytest

pytestmark = pytest.mark.faults

STOPPED = 8.0
"""How long robot 3's process stays stopped, s (wall clock), as the plant's status shows it."""
WAITING = 'lockstep: waiting for robot 3 (robot_3), no answer for '


def plant_values(statuses):
    """Return the key-value pairs of the plant's latest status ({} before any)."""
    status = statuses.get('formation_ros/plant')
    return {kv.key: kv.value for kv in status.values} if status is not None else {}


def test_a_stopped_robot_is_named_and_the_run_goes_on_when_it_continues(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {
        'plant.lockstep': True, 'plant.realtime_factor': 1.0})
    clock, statuses = SimClock(probe), Statuses(probe)
    start_system(processes, install, params, 4)
    assert probe.spin_until(lambda: clock.seconds >= 0.5, START_UP), processes.log('plant')
    processes.send_signal('robot_3', signal.SIGSTOP)
    try:
        assert probe.spin_until(lambda: WAITING in processes.log('plant'), 60), \
            processes.log('plant')[-3000:]
        stopped_at = clock.seconds
        assert probe.spin_until(
            lambda: float(plant_values(statuses).get(WAITED, 0.0)) >= STOPPED, 60), \
            plant_values(statuses)
        values = plant_values(statuses)
        assert values[WAITING_FOR] == '3', values
        assert statuses['formation_ros/plant'].message.startswith(
            'lockstep: waiting for robots 3 for '), statuses['formation_ros/plant'].message
        assert clock.seconds == stopped_at, 'the clock held while robot 3 was silent'
    finally:
        processes.send_signal('robot_3', signal.SIGCONT)
    assert probe.spin_until(lambda: clock.seconds >= stopped_at + 0.5
                            and 'lockstep: every robot answered after' in processes.log('plant'),
                            60), processes.log('plant')[-3000:]
    log = processes.log('plant')
    waited = [float(x) for x in re.findall(re.escape(WAITING) + r'([0-9.]+) s', log)]
    assert waited and waited[0] >= NAME_AFTER, log[-3000:]
    assert all(later - first >= REPEAT_EVERY for first, later in zip(waited, waited[1:])), \
        waited
    answered = re.search(r'every robot answered after ([0-9.]+) s', log)
    assert answered is not None and float(answered.group(1)) >= STOPPED, log[-3000:]
    assert probe.spin_until(lambda: WAITED not in plant_values(statuses), 30), \
        plant_values(statuses)
    assert all(processes.running(name) for name in ('plant', 'robot_1', 'robot_3'))
