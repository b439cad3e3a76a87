# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Status of each node on ``/diagnostics``: one time base, one key style.

Every node publishes one DiagnosticStatus named ``formation_ros/<node>`` once a second
(:data:`PERIOD`, steady clock). Header stamps are system (wall-clock) time in every node,
whichever clock the node itself runs on, so statuses from nodes with and without
``use_sim_time`` can be compared. Keys are lower-case words with the unit in brackets
(``simulated time [s]``, ``stale command steps``); counts have no unit.

A process holding many robot nodes (a fleet) publishes one DiagnosticArray a period with one
status per robot (:func:`make_status` of each, then :func:`encode_statuses`). Every array is
written as CDR bytes (``ros.cdr``).
"""

import time
from typing import Any, Mapping, Sequence

from diagnostic_msgs.msg import DiagnosticStatus
from formation_ros.ros.cdr import encode_diagnostics, StatusData

PERIOD = 1.0
LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN,
          'error': DiagnosticStatus.ERROR}
HARDWARE_ID = 'formation_ros'


def format_value(value: Any) -> str:
    """Floats with 6 significant digits, everything else with ``str``."""
    return f'{value:.6g}' if isinstance(value, float) else str(value)


def diagnostics(name: str, level: str, message: str, values: Mapping[str, Any]) -> bytes:
    """
    Return a serialized DiagnosticArray with one status, stamped with the system time now.

    name: e.g. 'formation_ros/plant'; level: 'ok', 'warn' or 'error'; values: {key: value}.
    """
    return encode_statuses([make_status(name, level, message, values)])


def make_status(name: str, level: str, message: str, values: Mapping[str, Any]) -> StatusData:
    """Return one status for :func:`encode_statuses`: values formatted by format_value."""
    return StatusData(LEVELS[level][0], name, message, HARDWARE_ID,
                      [(key, format_value(value)) for key, value in values.items()])


def encode_statuses(statuses: Sequence[StatusData]) -> bytes:
    """Return a serialized DiagnosticArray of ``statuses``, stamped with the system time now."""
    return encode_diagnostics(time.time_ns(), statuses)
