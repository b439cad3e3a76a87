# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Fleet processes: several robot nodes in one process, each still its own node.

Real executables over DDS: the launcher with ``--robots-per-process``, or the ``fleet``
executable started directly; outcomes from the probe, the launcher's output and the plant's
``trajectory.npz`` / ``metrics.json``.
"""

import json
import os
import signal
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.nodes.robots_link import LISTENER_LOOKS
from formation_ros.ros import qos
from formation_ros.ros.diagnostics import PERIOD
from formation_ros.ros.on_demand import LISTENERS_PERIOD
from formation_ros.tools.supervise import ProcessSpec
from geometry_msgs.msg import TwistStamped
from helpers import (exe, launch, project_processes, SimClock, SQUARE, START_UP,
                     stop_when, TWICE_REAL_TIME, wait_exit, watch_commands, write_params)
import numpy as np
from rcl_interfaces.srv import GetParameters, SetParameters
from rclpy.parameter import Parameter
from test_parameters import call
import yaml

SETTLED = 10.0
"""Simulated seconds after which the six robots track the circle (formation_sim: within 0.014 m
at 5 s, 0.002 m at 6 s; test_system's one-robot processes are held to 0.02 m at 10 s)."""


def fleet_pids(install, name_part):
    """Process ids of the running fleet processes whose command line holds ``name_part``."""
    return [int(line.split()[0]) for line in project_processes(install)
            if exe(install, 'fleet') in line and name_part in line]


def test_six_robots_in_two_fleet_processes_converge(processes, install, probe, tmp_path):
    clock = SimClock(probe)
    out = tmp_path / 'run'
    launch(processes, install, write_params(tmp_path, 'circle_2d.yaml', TWICE_REAL_TIME), out=out,
           options=('--robots-per-process', '3'))
    info = stop_when(probe, processes, lambda: clock.seconds > SETTLED)
    log = processes.log('launcher')
    assert info.returncode == 0, log
    assert '6 robots in 2 fleet processes of up to 3' in log, log
    assert '[fleet_1] ' in log and '[fleet_2] ' in log and '[robot_1] ' not in log, log
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['num_robots'] == 6 and metrics['collisions'] == 0, metrics
    assert metrics['final_max_error'] < 0.05, metrics
    assert metrics['bound_violations'] == 0, metrics
    assert project_processes(install) == []


def test_each_robot_of_a_fleet_is_its_own_node_with_its_parameters(
        processes, install, probe, tmp_path):
    own = tmp_path / 'robot_2.yaml'
    own.write_text(yaml.safe_dump({
        '/robot_2/robot': {'ros__parameters': {'control_rate': 25.0}},
        '/robot_3/robot': {'ros__parameters': {'reference.speed': 0.25}}}))
    processes.start(ProcessSpec('fleet', [exe(install, 'fleet'), '--robots', '1-3', '--ros-args',
                                          '--params-file', SQUARE, '--params-file', str(own),
                                          '-p', 'use_sim_time:=true']))
    assert probe.spin_until(
        lambda: {('robot', f'/robot_{i}') for i in (1, 2, 3)}
        <= set(probe.get_node_names_and_namespaces()), START_UP), processes.log('fleet')
    rates = {}
    for i in (1, 2, 3):
        answer = call(probe, probe.create_client(GetParameters, f'/robot_{i}/robot/'
                                                 'get_parameters'),
                      GetParameters.Request(names=['robot_id', 'control_rate']))
        assert answer.values[0].integer_value == i
        rates[i] = answer.values[1].double_value
    assert rates == {1: 50.0, 2: 25.0, 3: 50.0}
    names = [name for name, namespace in probe.get_node_names_and_namespaces()
             if namespace.startswith('/robot_')]
    assert sorted(names) == ['robot'] * 3, names
    assert len(fleet_pids(install, '--robots 1-3')) == 1

    def readers(topic):
        return [info for info in probe.get_subscriptions_info_by_topic(topic)
                if info.node_namespace.startswith('/robot_')]

    def namespaces(topic):
        return sorted(info.node_namespace for info in readers(topic))

    assert probe.spin_until(lambda: namespaces('/formation/reference') == ['/robot_1', '/robot_3']
                            and all(probe.count_publishers(f'/robot_{i}/cmd_vel') == 1
                                    for i in (1, 2, 3)), START_UP), readers('/formation/reference')
    assert namespaces('/formation/shape') == ['/robot_1', '/robot_3']
    assert readers('/clock') == [], readers('/clock')
    [pid] = fleet_pids(install, '--robots 1-3')
    arrays = []
    probe.create_subscription(DiagnosticArray, '/diagnostics', arrays.append, qos.DIAGNOSTICS)
    assert probe.spin_until(lambda: len(arrays) >= 2, 30)
    assert [[status.name for status in array.status] for array in arrays] == [
        [f'formation_ros/robot_{i}' for i in (1, 2, 3)]] * len(arrays)
    for array in arrays:
        for i, status in enumerate(array.status, 1):
            values = {pair.key: pair.value for pair in status.values}
            assert (values['process'], values['node']) == (str(pid), f'/robot_{i}/robot')
    assert [info.node_namespace for info in probe.get_publishers_info_by_topic('/diagnostics')
            if info.node_namespace.startswith('/robot_')] == ['/robot_1']
    refused = call(probe, probe.create_client(SetParameters, '/robot_2/robot/set_parameters'),
                   SetParameters.Request(parameters=[
                       Parameter('use_sim_time', value=False).to_parameter_msg()]))
    assert not refused.results[0].successful, refused.results
    assert 'fixed at start' in refused.results[0].reason, refused.results


def test_without_parameter_services_only_the_first_robot_offers_them(processes, install, probe):
    processes.start(ProcessSpec('fleet', [exe(install, 'fleet'), '--robots', '1-3', '--ros-args',
                                          '--params-file', SQUARE, '-p', 'use_sim_time:=true',
                                          '-p', 'fleet.parameter_services:=false']))
    statuses = {}
    probe.create_subscription(
        DiagnosticArray, '/diagnostics',
        lambda m: statuses.update({status.name: status for status in m.status}), qos.DIAGNOSTICS)

    def services():
        return {i: {name for name, _ in probe.get_service_names_and_types_by_node(
            'robot', f'/robot_{i}')} for i in (1, 2, 3)}

    def robot_3_seen():
        return ('/robot_3/cmd_vel' in dict(probe.get_publisher_names_and_types_by_node(
            'robot', '/robot_3')) and '/robot_3/pose' in dict(
                probe.get_subscriber_names_and_types_by_node('robot', '/robot_3')))

    # A node's services are made before its topics, and robot 2 before robot 3, and one
    # process announces its readers and writers in the order it made them: once robot 3's
    # pose reader and cmd_vel writer are seen, any service of robots 1 and 2 would be too.
    assert probe.spin_until(
        lambda: {('robot', f'/robot_{i}') for i in (1, 2, 3)}
        <= set(probe.get_node_names_and_namespaces()) and len(statuses) == 3
        and robot_3_seen(), START_UP), (services(), processes.log('fleet'))
    offered = services()
    assert {'/robot_1/robot/get_parameters',
            '/robot_1/robot/get_type_description'} <= offered[1], offered[1]
    assert not offered[2] and not offered[3], offered
    answer = call(probe, probe.create_client(GetParameters, '/robot_1/robot/get_parameters'),
                  GetParameters.Request(names=['fleet.parameter_services']))
    assert answer.values[0].bool_value is False
    assert sorted(statuses) == [f'formation_ros/robot_{i}' for i in (1, 2, 3)]
    log = processes.log('fleet')
    assert log.count('parameter and type description services and /rosout on /robot_1/robot '
                     'alone') == 1, log
    publishers = {i: dict(probe.get_publisher_names_and_types_by_node('robot', f'/robot_{i}'))
                  for i in (1, 2, 3)}
    assert '/rosout' in publishers[1] and not any('/rosout' in publishers[i] for i in (2, 3))
    assert 'robot 3/4: vertex' in log  # its log line reaches the console all the same


def test_a_fleet_whose_robots_differ_in_parameter_services_is_refused_in_one_line(
        processes, install, probe, tmp_path):
    own = tmp_path / 'robot_2.yaml'
    own.write_text(yaml.safe_dump({'/robot_2/robot': {'ros__parameters': {
        'fleet': {'parameter_services': False}}}}))
    processes.start(ProcessSpec('fleet', [exe(install, 'fleet'), '--robots', '1-3', '--ros-args',
                                          '--params-file', SQUARE, '--params-file', str(own),
                                          '-p', 'use_sim_time:=true']))
    info = wait_exit(probe, processes, 'fleet', START_UP)
    log = processes.log('fleet')
    assert info is not None and info.returncode == 2, log
    errors = [line for line in log.splitlines() if '[ERROR]' in line]
    assert len(errors) == 1 and "'fleet.parameter_services': must be the same" in errors[0], log
    assert 'Traceback' not in log


def test_killing_one_fleet_process_stops_only_its_robots(processes, install, probe, tmp_path):
    heard, _ = watch_commands(probe, 4)
    clock = SimClock(probe)
    out = tmp_path / 'run'
    launch(processes, install, SQUARE, out=out, options=('--robots-per-process', '2'))
    assert probe.spin_until(lambda: clock.seconds > 0.5 and {i for i, _ in heard} >= {1, 2, 3, 4},
                            START_UP), processes.log('launcher')
    [pid] = fleet_pids(install, '--robots 3-4')
    os.kill(pid, signal.SIGKILL)
    killed_at = clock.seconds
    counted = len(heard)

    def others_go_on():
        later = [i for i, _ in heard[counted:]]
        return clock.seconds > killed_at + 3.0 and all(later.count(i) > 50 for i in (1, 2))

    assert probe.spin_until(others_go_on, 60), processes.log('launcher')
    info = stop_when(probe, processes, lambda: True)
    log = processes.log('launcher')
    assert info.returncode == 1, log
    assert 'fleet_2 ended on its own (signal SIGKILL); the others go on' in log, log
    assert project_processes(install) == []
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    after = trajectory.t > killed_at + 1.0
    assert after.sum() > 50
    for robot in (2, 3):
        assert np.all(trajectory.q[after, robot] == trajectory.q[after, robot][0]), robot
    alive = trajectory.u[after][:, [0, 1]]
    assert np.all(np.any(alive != 0.0, axis=(0, 2))), 'robots 1, 2 were not controlled'


def test_a_team_fleet_whose_robots_differ_in_the_law_is_refused_in_one_line(
        processes, install, probe, tmp_path):
    own = tmp_path / 'robot_2.yaml'
    own.write_text(yaml.safe_dump({'/robot_2/robot': {'ros__parameters': {
        'controller': {'gain': 3.0}}}}))
    team = tmp_path / 'team.yaml'
    team.write_text(yaml.safe_dump({'/**': {'ros__parameters': {'transport': 'team'}}}))
    processes.start(ProcessSpec('fleet', [exe(install, 'fleet'), '--robots', '1-3', '--ros-args',
                                          '--params-file', SQUARE, '--params-file', str(team),
                                          '--params-file', str(own), '-p', 'use_sim_time:=true']))
    info = wait_exit(probe, processes, 'fleet', START_UP)
    log = processes.log('fleet')
    assert info is not None and info.returncode == 2, log
    errors = [line for line in log.splitlines() if '[ERROR]' in line]
    assert len(errors) == 1 and "'controller.gain': must be the same for every robot" in errors[0]
    assert 'Traceback' not in log


def test_a_team_fleet_sends_one_status_array_and_serves_any_robots_cmd_vel(
        processes, install, probe, tmp_path):
    """
    22 robots in two team fleets of 11: one DiagnosticArray per fleet and period, its robots'.

    Each status keeps its robot's name and identity; a fleet's listener looks take
    LISTENER_LOOKS < 11 robots each, so the last robot of a fleet is looked at only in turn
    and its cmd_vel, subscribed to during the run, must still carry its commands.
    """
    n, fleet = 22, 11
    assert LISTENER_LOOKS < fleet
    lattice = [float(v) for k in range(n) for v in (2.0 * (k % 6), 2.0 * (k // 6))]
    params = write_params(tmp_path, 'square_4.yaml', {
        'transport': 'team', 'num_robots': n, 'formation.vertices': lattice,
        'start.random_radius': 2.5, 'start.min_separation': 0.2})
    arrays = []
    probe.create_subscription(DiagnosticArray, '/diagnostics', lambda array: arrays.append(
        (time.monotonic(), [(status.name, status.message, status.level,
                             {pair.key: pair.value for pair in status.values})
                            for status in array.status if status.name.startswith(
                                'formation_ros/robot_')])), qos.DIAGNOSTICS)
    robots = [f'formation_ros/robot_{i}' for i in range(1, n + 1)]

    def latest():
        found = {}
        for _, statuses in arrays:
            found.update({name: (message, level) for name, message, level, _ in statuses})
        return found

    launch(processes, install, params, per_process=fleet)
    assert probe.spin_until(lambda: all(latest().get(name) == (
        'controlling', DiagnosticStatus.OK) for name in robots), START_UP), (
        latest(), processes.log('launcher'))

    heard = []
    probe.create_subscription(TwistStamped, f'/robot_{fleet}/cmd_vel', heard.append,
                              qos.TEAM_CMD_VEL)  # no lease asked, as ros2 topic echo
    subscribed = time.monotonic()
    bound = LISTENERS_PERIOD * -(-fleet // LISTENER_LOOKS)
    assert probe.spin_until(lambda: len(heard) >= 5, 30.0), latest()[robots[fleet - 1]]
    served = time.monotonic() - subscribed

    def window():
        return [statuses for at, statuses in arrays if at >= subscribed and statuses]

    assert probe.spin_until(lambda: len(window()) >= 6, 30.0), len(window())
    per_process = {}
    for statuses in window():
        processes_in = {values['process'] for _, _, _, values in statuses}
        assert len(processes_in) == 1 and len(statuses) == fleet, [s[0] for s in statuses]
        first = int(statuses[0][0].rsplit('_', 1)[1])
        assert first in (1, fleet + 1)
        assert [name for name, _, _, _ in statuses] == robots[first - 1:first - 1 + fleet]
        for name, _, _, values in statuses:
            i = name.rsplit('_', 1)[1]
            assert values['node'] == f'/robot_{i}/robot' and values['team: num_robots'] == '22'
            assert 'host' in values and 'neighbours within R_i' in values
        per_process.setdefault(processes_in.pop(), []).append(first)
    assert len(per_process) == 2 and all(len(set(firsts)) == 1
                                         for firsts in per_process.values()), per_process
    elapsed = time.monotonic() - subscribed
    assert all(len(firsts) <= elapsed / PERIOD + 1 for firsts in per_process.values()), (
        elapsed, {process: len(firsts) for process, firsts in per_process.items()})
    assert stop_when(probe, processes, lambda: True).returncode == 0, processes.log('launcher')
    print(f'cmd_vel of robot {fleet} served {served:.2f} s after subscribing (looks bound '
          f'{bound:g} s after discovery)')
