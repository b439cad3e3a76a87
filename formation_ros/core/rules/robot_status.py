# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
What a robot says of itself: its ``/diagnostics`` values and level, its first log line.

:func:`status_values` gives the values of a robot's status (input ages, neighbours in range,
command sizes), :func:`status_level` its level and message, :func:`startup_line` what it logs
as it starts. The keys and what they mean: docs/ros_interface.md ("Topics", ``/diagnostics``)
and docs/faults.md.
"""

from typing import Any, Dict, Mapping, Optional, Tuple

from formation_ros.core.maths.law import Command
from formation_ros.core.settings.params import FormationConfig
import numpy as np
from numpy.typing import NDArray

Float = NDArray[np.float64]


def status_values(ages_s: Mapping[str, Optional[float]], points: Optional[Float],
                  sensing_radius: float, repulsion_radius: float,
                  last: Optional[Tuple[Command, Optional[Float]]],
                  unicycle: bool) -> Dict[str, Any]:
    """
    Return a robot's status values.

    ages_s: {input: seconds since it was last heard, None if never}; points: (1 + K, dim) m,
    its own point and the K neighbours' it heard (None before it heard both); sensing_radius:
    R_i and repulsion_radius: b, m; last: its latest command ((dim,) m/s) and its published
    form ((v, w) for unicycles, u in the body frame) if it is not u.
    """
    values: Dict[str, Any] = {f'{name} message age [s]': 'never' if age is None else age
                              for name, age in ages_s.items()}
    if points is not None:
        gaps = np.linalg.norm(points[1:] - points[0], axis=1)
        values['neighbours heard'] = len(gaps)
        values['neighbours within R_i'] = int(np.count_nonzero(gaps < sensing_radius))
        values['neighbours within b'] = int(np.count_nonzero(gaps < repulsion_radius))
    if last is None:
        return values
    command, body = last
    values['max |u| component [m/s]'] = float(np.max(np.abs(command.u)))
    values['max |u_hat| component [m/s]'] = float(np.max(np.abs(command.u_hat)))
    if body is not None and unicycle:
        values['|v| [m/s]'] = abs(float(body[0]))
        values['|w| [rad/s]'] = abs(float(body[1]))
    elif body is not None:
        values['max |u| component in the body frame [m/s]'] = float(np.max(np.abs(body)))
    return values


def status_level(shared: Mapping[str, str], waiting: bool, stale: bool, flooding: bool,
                 lockstep: bool) -> Tuple[str, str]:
    """
    Return a robot's (level, message), the first that holds of these.

    shared: {topic: its publishers} of /clock and the reference with more than one (ERROR);
    waiting: it waits for its first inputs; stale: it publishes zero; flooding: it dropped
    states beyond the state rate since its last status (WARN each).
    """
    if shared:
        return 'error', (f"{', '.join(sorted(shared))}: more than one publisher (two teams on "
                         'one domain?)')
    if waiting:
        return 'warn', 'waiting for its first inputs'
    if stale:
        return 'warn', 'publishing zero: inputs stale'
    if flooding:
        return 'warn', 'flooding: states beyond the state rate dropped'
    return 'ok', 'lockstep' if lockstep else 'controlling'


def startup_line(config: FormationConfig, index: int, command_frame: str, sim_time: bool) -> str:
    """Return the line robot ``index`` (0-based) logs as it starts: its constants and modes."""
    law, body, robot = config.law(), config.body, config.robot
    assert robot is not None
    return (f'robot {index + 1}/{config.num_robots}: vertex '
            f'{np.round(config.vertices[index], 4)}, R_i = {config.sensing_radii[index]:g} m, '
            f'b = {config.repulsion_radius:g} m, bound c*M1 = {law.u_bound:.4g} m/s, '
            + (f'unicycle, hand point {body.hand_distance:g} m ahead, ' if body.is_unicycle
               else '')
            + f"commands as {'TwistStamped' if config.command.stamped else 'Twist'} in "
              f'{command_frame}, '
            + ('lockstep' if config.lockstep else f'{robot.control_rate:g} Hz')
            + (', team transport' if config.team_transport else '')
            + _obstacles_part(config)
            + (", simulated time from the states' stamps" if sim_time else ''))


def _obstacles_part(config: FormationConfig) -> str:
    """Return where a robot takes its obstacles from, for its start-up line ('': none)."""
    robot = config.robot
    assert robot is not None
    if robot.scan is not None:
        return (f', obstacles from its scan in {robot.scan.frame} (b_o = '
                f'{config.obstacle_clearance:g} m)')
    if config.obstacle_clearance is not None:
        return f', obstacles as told (b_o = {config.obstacle_clearance:g} m)'
    return ''
