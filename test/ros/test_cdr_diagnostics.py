# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A DiagnosticArray written as bytes (one per fleet): what rclpy reads from it."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from formation_ros.ros.cdr import encode_diagnostics, StatusData
from formation_ros.ros.diagnostics import diagnostics, encode_statuses, make_status
import pytest
from rclpy.serialization import deserialize_message

VALUES = {'pose message age [s]': 0.0123456789, 'neighbours heard': 3, 'host': 'hôte-1',
          'team: num_robots': '25', 'rejected states messages (bytes)': 0, 'empty': ''}


def fields(status):
    """Return the fields of a DiagnosticStatus as plain values."""
    return (status.level, status.name, status.message, status.hardware_id,
            [(pair.key, pair.value) for pair in status.values])


@pytest.mark.parametrize('count', [0, 1, 25])
def test_rclpy_reads_every_status_of_the_array_as_written(count):
    statuses = [StatusData(k % 4, f'formation_ros/robot_{k + 1}', 'x' * k, 'hw' * (k % 3),
                           [(f'key {j}' + 'é' * (j % 3), str(j * k)) for j in range(k % 5)])
                for k in range(count)]
    data = encode_diagnostics(1_700_000_123_456_789_012, statuses)
    array = deserialize_message(data, DiagnosticArray)
    assert (array.header.stamp.sec, array.header.stamp.nanosec) == (1_700_000_123, 456_789_012)
    assert array.header.frame_id == ''
    assert [fields(status) for status in array.status] == [
        (bytes([s.level]), s.name, s.message, s.hardware_id, list(s.values)) for s in statuses]


def test_a_status_as_bytes_equals_the_status_as_a_message():
    message = DiagnosticStatus(level=DiagnosticStatus.WARN, name='formation_ros/robot_3',
                               message='waiting for its first inputs', hardware_id='formation_ros')
    message.values = [KeyValue(key=key, value=f'{value:.6g}' if isinstance(value, float)
                               else str(value)) for key, value in VALUES.items()]
    alone = deserialize_message(diagnostics('formation_ros/robot_3', 'warn',
                                            'waiting for its first inputs', VALUES),
                                DiagnosticArray)
    assert [fields(status) for status in alone.status] == [fields(message)]
    written = deserialize_message(encode_statuses(
        [make_status('formation_ros/robot_3', 'warn', 'waiting for its first inputs', VALUES),
         make_status('formation_ros/robot_4', 'error', 'two teams', {})]), DiagnosticArray)
    assert len(written.status) == 2
    assert fields(written.status[0]) == fields(message)
    assert written.status[0].level == DiagnosticStatus.WARN
    assert fields(written.status[1])[:2] == (DiagnosticStatus.ERROR, 'formation_ros/robot_4')
    assert written.header.stamp.sec > 1_600_000_000
