# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The world's faults: beside another clock, killed, blown up, given hostile parameters."""

import json
import os
import re
import signal
import socket

from formation_ros.core.settings.exits import ENGINE_FAILED, REFUSED
from formation_ros.core.settings.params_file import write_params_file
from formation_ros.ros import qos
from geometry_msgs.msg import Twist, TwistStamped
from helpers import (CONFIG, launch, logged, node, project_processes, SimClock, wait_exit,
                     write_params)
import pytest

pytestmark = pytest.mark.faults
START_UP = 90.0
HOST = socket.gethostname()
TEAM = os.path.join(CONFIG, 'world_turtlebot3.yaml')
TWO_BASES = {'num_robots': 2, 'formation.vertices': [0.6, 0.0, -0.6, 0.0],
             'start.positions': [0.45, 0.1, -0.5, -0.1], 'start.headings': [2.5, -0.8]}
"""Two of world_turtlebot3.yaml's bases, near their places at other headings."""


def error_lines(log):
    return [line for line in log.splitlines() if '[ERROR]' in line]


def refused(probe, processes, name, maker, pid):
    """Wait for process ``name`` to end; assert it refused in one line naming ``maker``'s pid."""
    info = wait_exit(probe, processes, name, START_UP)
    log = processes.log(name)
    assert info is not None and info.returncode == REFUSED, log
    lines = error_lines(log)
    assert len(lines) == 1 and 'Traceback' not in log, log
    domain = os.environ['ROS_DOMAIN_ID']
    assert f'refusing to start: another {maker} is on ROS_DOMAIN_ID {domain}: ' in lines[0], log
    assert f'/{maker} on host {HOST} (process {pid}) publishes /clock' in lines[0], log


def test_a_world_or_a_plant_refuses_beside_a_running_one(processes, install, probe, tmp_path):
    plant_clock = SimClock(probe)
    plant = processes.start(node(install, 'plant', TEAM, '-p', 'plant.wait_for_robots:=false'))
    assert probe.spin_until(lambda: plant_clock.seconds > 0.2, START_UP), processes.log('plant')
    processes.start(node(install, 'world', TEAM, process='world_beside_a_plant'))
    refused(probe, processes, 'world_beside_a_plant', 'plant', plant.pid)
    assert processes.running('plant')
    processes.send_signal('plant', signal.SIGINT)
    assert wait_exit(probe, processes, 'plant', 30) is not None
    assert probe.spin_until(lambda: probe.count_publishers('/clock') == 0, 30)

    clock = SimClock(probe)
    out = f'world.output_dir:={tmp_path / "world"}'
    world = processes.start(node(install, 'world', TEAM, '-p', out))
    assert probe.spin_until(lambda: clock.seconds > 0.2 and (tmp_path / 'world' / 'world.xml')
                            .exists(), START_UP), processes.log('world')
    written = (tmp_path / 'world' / 'world.xml').stat().st_mtime_ns
    processes.start(node(install, 'world', TEAM, '-p', out, process='world_2'))
    refused(probe, processes, 'world_2', 'world', world.pid)
    assert (tmp_path / 'world' / 'world.xml').stat().st_mtime_ns == written, \
        'the refused world wrote into the output of the running one'
    processes.start(node(install, 'plant', TEAM, process='plant_2'))
    refused(probe, processes, 'plant_2', 'world', world.pid)
    assert probe.spin_until(lambda: probe.count_publishers('/clock') == 1, 30)
    assert [info.node_name for info in probe.get_publishers_info_by_topic('/clock')] == ['world']
    since = clock.seconds
    assert probe.spin_until(lambda: clock.seconds > since + 0.5, 30), processes.log('world')
    assert processes.running('world') and not error_lines(processes.log('world'))


def commands_of(probe, count, stamped=True):
    """Subscribe to robots 1..count's cmd_vel; return {robot: [(v, w), ...]} as heard."""
    heard = {i: [] for i in range(1, count + 1)}

    def store(i, msg):
        twist = msg.twist if stamped else msg
        heard[i].append((twist.linear.x, twist.angular.z))

    for i in heard:
        probe.create_subscription(TwistStamped if stamped else Twist, f'/robot_{i}/cmd_vel',
                                  lambda msg, i=i: store(i, msg), qos.COMMAND)
    return heard


def moving(heard):
    """Whether every robot has sent a command that is not zero."""
    return all(any(command != (0.0, 0.0) for command in commands) for commands in heard.values())


def world_pid(install):
    """Return the process id of the world the launcher started (from the process table)."""
    world = [line for line in project_processes(install)
             if any(arg.endswith(os.path.join('formation_ros', 'world'))
                    for arg in line.split()[1:3])]
    assert len(world) == 1, project_processes(install)
    return int(world[0].split()[0])


def test_a_world_killed_under_the_launcher_stops_the_run_and_names_the_world(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'world_turtlebot3.yaml', TWO_BASES)
    heard = commands_of(probe, 2)
    launch(processes, install, params, out=tmp_path / 'run', options=('--world',),
           per_process=2)
    assert probe.spin_until(lambda: moving(heard), START_UP), processes.log('launcher')
    os.kill(world_pid(install), signal.SIGKILL)
    info = wait_exit(probe, processes, 'launcher', 60)
    log = processes.log('launcher')
    assert info is not None and info.returncode == 1, log
    assert 'world ended on its own (signal SIGKILL); stopped the others' in log, log
    assert probe.spin_until(lambda: not project_processes(install), 30), \
        project_processes(install)
    assert all(commands[-1] == (0.0, 0.0) for commands in heard.values()), heard


def test_a_world_killed_by_hand_leaves_every_robot_still_saying_why(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'world_turtlebot3.yaml', TWO_BASES)
    heard = commands_of(probe, 2)
    sim_time = ('-p', 'use_sim_time:=true')
    processes.start(node(install, 'world', params))
    processes.start(node(install, 'relay', params, *sim_time))
    processes.start(node(install, 'reference', params, *sim_time))
    for i in (1, 2):
        processes.start(node(install, 'robot', params, '-r', f'__ns:=/robot_{i}', *sim_time,
                             process=f'robot_{i}'))
    assert probe.spin_until(lambda: moving(heard), START_UP), processes.log('world')
    processes.send_signal('world', signal.SIGKILL)
    # The relay's last neighbours come after the world's last pose; on a busy host more
    # than one watchdog period after, and the robot has already said why it stopped.
    stale = re.compile(r'no new pose(, neighbour)? for 0\.5 s: publishing zero')
    for i in (1, 2):
        log = logged(probe, processes, f'robot_{i}', 'publishing zero')
        assert stale.search(log), log
    counts = {i: len(commands) for i, commands in heard.items()}
    assert probe.spin_until(lambda: all(len(heard[i]) > counts[i] for i in heard), 10), heard
    assert all(commands[-1] == (0.0, 0.0) for commands in heard.values()), heard
    assert all(processes.running(f'robot_{i}') for i in (1, 2))
    assert all(processes.log(f'robot_{i}').count('publishing zero') == 1 for i in (1, 2))


UNSTABLE = {'command.type': 'twist', 'world.timestep': 0.05, 'world.pose_rate': 20.0,
            'world.mass': 1.0, 'world.wheel_torque': 10000.0, 'world.wheel_radius': 1.0,
            'world.floor_friction': 0.1}
"""Values within every declared range on which MuJoCo loses a base that is driven hard
(docs/physics.md: the cases found)."""


def test_a_world_whose_engine_blows_up_stops_at_once_and_writes_what_it_has(
        processes, install, probe, tmp_path):
    out = tmp_path / 'world'
    params = write_params(tmp_path, 'world_turtlebot3.yaml', {
        **TWO_BASES, **UNSTABLE, 'start.positions': [0.0, 0.0, 1.5, 0.0],
        'world.output_dir': str(out)})
    processes.start(node(install, 'world', params))
    drive = [probe.create_publisher(Twist, f'/robot_{i}/cmd_vel', qos.COMMAND) for i in (1, 2)]
    clock = SimClock(probe)

    def back_and_forth():
        forward = int(clock.seconds / 0.5) % 2 == 0
        twist = Twist()
        twist.linear.x, twist.angular.z = (0.22, 2.8) if forward else (-0.22, -2.8)
        for publisher in drive:
            publisher.publish(twist)
        return not processes.running('world')

    assert probe.spin_until(back_and_forth, START_UP), processes.log('world')
    info = processes.exit_info('world')
    log = processes.log('world')
    assert info.returncode == ENGINE_FAILED and 'Traceback' not in log, log
    lines = error_lines(log)
    assert len(lines) == 1 and 'world: the physics engine blew up: robot ' in lines[0], log
    assert 'world.timestep 0.05, world.mass 1, world.wheel_torque 10000' in lines[0], log
    stats = json.loads((out / 'world_stats.json').read_text())
    unstable = stats['unstable']
    assert unstable['robot'] in (1, 2) and f"at t = {unstable['t']:.3f} s" in lines[0], stats
    assert abs(stats['simulated_time'] - unstable['t']) <= 0.05 + 1e-9, stats
    import numpy as np
    trajectory = np.load(out / 'trajectory.npz')
    assert trajectory['t'][-1] < unstable['t'] and np.all(np.isfinite(trajectory['q']))
    assert np.max(np.abs(trajectory['q'])) < 10.0, 'an absurd pose was kept'


HOSTILE = {'timestep_zero': ('world.timestep:=0.0', "'world.timestep': must be >= 1e-05"),
           'timestep_nan': ('world.timestep:=.nan', "'world.timestep': must be a finite"),
           'mass_negative': ('world.mass:=-1.0', "'world.mass': must be > 0"),
           'pose_rate_above_steps': ('world.pose_rate:=1000.0',
                                     "'world.pose_rate': 1000 Hz is faster than the engine"),
           'friction_ice': ('world.floor_friction:=0.001', "'world.floor_friction': must be >="),
           'robots_100000': ('num_robots:=100000', "'num_robots': 100000 robots are more than "
                                                   'the physics world takes (1000')}


def test_hostile_world_values_give_one_line_and_exit_2(processes, install, probe, tmp_path):
    for name, (value, _) in HOSTILE.items():
        processes.start(node(install, 'world', TEAM, '-p', value, process=name))
    vertices = [float(k) for k in range(2 * 100000)]
    huge = tmp_path / 'huge.yaml'
    write_params_file(str(huge), {'num_robots': 100000, 'dim': 2, 'formation.vertices': vertices,
                                  'start.random_radius': 1000.0})
    processes.start(node(install, 'world', huge, process='huge_file'))
    expected = {**HOSTILE, 'huge_file': (None, 'num_robots: 100000 robots are more than the '
                                               'physics world takes')}
    for name, (_, text) in expected.items():
        info = wait_exit(probe, processes, name, START_UP)
        log = processes.log(name)
        assert info is not None and info.returncode == REFUSED, (name, log)
        assert text in log and 'Traceback' not in log, (name, log)
        assert len([line for line in log.splitlines() if line.strip()]) == 1, (name, log)
