# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The team check: arrays kept as they arrive, read and compared when the node looks."""

import os
import socket

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from formation_ros.ros.team import TeamCheck


class Node:
    """Stands in for an rclpy node: the check only subscribes."""

    def create_subscription(self, *args, **kwargs):
        return None


def status(name, process, node, **team):
    """Return a formation status from ``process`` on host 'elsewhere' with team values."""
    values = [('host', 'elsewhere'), ('process', process), ('node', node)]
    values += [(f'team: {key}', value) for key, value in team.items()]
    return DiagnosticStatus(name=name, values=[KeyValue(key=k, value=v) for k, v in values])


def test_arrays_are_kept_by_the_callback_and_read_when_the_node_looks():
    check = TeamCheck(Node(), 'formation_ros/plant')
    check.store(DiagnosticArray(status=[
        status('formation_ros/robot_2', '4242', '/robot_2/robot', num_robots='5'),
        status('formation_ros/robot_3', '4242', '/robot_3/robot', num_robots='4'),
        DiagnosticStatus(name='other/driver'),
        DiagnosticStatus(name='formation_ros/robot_9', values=[
            KeyValue(key='host', value=socket.gethostname()),
            KeyValue(key='process', value=str(os.getpid())),
            KeyValue(key='team: num_robots', value='7')])]))
    assert check.heard == {} and len(check.pending) == 1
    found = check.disagreeing({'num_robots': '4'})
    assert list(found) == ['formation_ros/robot_2']
    assert 'num_robots' in found['formation_ros/robot_2']
    assert set(check.heard) == {'formation_ros/robot_2', 'formation_ros/robot_3'}
    assert not check.pending
    assert check.running('/robot_2/robot', now=check.processes['/robot_2/robot'][
        ('elsewhere', '4242')]) == [('elsewhere', '4242')]


def test_a_later_array_replaces_what_a_node_said_before():
    check = TeamCheck(Node(), 'formation_ros/plant')
    check.store(DiagnosticArray(status=[status('formation_ros/robot_2', '1', '/robot_2/robot',
                                               num_robots='5')]))
    check.store(DiagnosticArray(status=[status('formation_ros/robot_2', '1', '/robot_2/robot',
                                               num_robots='4')]))
    assert check.disagreeing({'num_robots': '4'}) == {}


def test_a_node_is_named_with_its_host_then_as_silent_once_its_announcements_lapse():
    check = TeamCheck(Node(), 'formation_ros/plant')
    check.store(DiagnosticArray(status=[status('formation_ros/robot_2', '4242',
                                               '/robot_2/robot')]))
    check.running('/robot_2/robot', 0.0)
    heard = check.processes['/robot_2/robot'][('elsewhere', '4242')]
    assert check.describe('/robot_2/robot', heard + 1.0) == \
        '/robot_2/robot on host elsewhere (process 4242)'
    assert check.describe('/robot_2/robot', heard + 7.2) == (
        '/robot_2/robot (silent on /diagnostics for 7 s; last on host elsewhere (process 4242))')
    assert check.describe('/robot_9/robot', heard) == \
        '/robot_9/robot (host unknown: it announces none on /diagnostics)'
