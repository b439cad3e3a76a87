# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The name a robot goes by, ``robot_<i>``, in one place.

No numpy here: the launcher's ``--help`` reads it. Robot i (1-based) is ``robot_<i>``: its
namespace ``/robot_<i>`` (``ros.topics``), its body frame ``robot_<i>/base_link``
(``ros.messages``), its body in the physics world (``physics.scene``), its name in a team
command (``core.rules.transport``), its status on ``/diagnostics`` and the launcher's name for its
process.
"""


def robot_name(robot_id: int) -> str:
    """Return the name of robot ``robot_id`` (1-based): ``robot_<i>``."""
    return f'robot_{robot_id}'


SCAN_FRAME = 'base_scan'
"""A robot's laser scanner frame below its name (a TurtleBot3 driver's ``base_scan``)."""


def scan_frame(robot_id: int) -> str:
    """Return the frame of robot ``robot_id``'s scans in the world: ``robot_<i>/base_scan``."""
    return f'{robot_name(robot_id)}/{SCAN_FRAME}'
