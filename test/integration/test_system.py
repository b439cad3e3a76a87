"""The ROS 2 system with real processes and real DDS: plant, reference, robots, launcher."""

import json
import os
import signal
import subprocess
import time

from conftest import CONFIG, exe, ROOT, write_params
from formation_ros import qos
from formation_ros.core.params import load_config
from formation_ros.sim import simulate
from formation_ros.trajectory import Trajectory
from geometry_msgs.msg import TwistStamped
import numpy as np

LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
SQUARE = os.path.join(CONFIG, 'square_4.yaml')


def launch(processes, install, params, out, duration, name='launcher'):
    args = ['bash', LAUNCHER, params, '--prefix', install, '--duration', str(duration)]
    if out:
        args += ['--out', str(out)]
    return processes.start(name, args)


def watch_commands(probe, count):
    """Subscribe to every robot's cmd_vel; return the list of (robot, (x, y, z)) heard."""
    heard = []
    for i in range(1, count + 1):
        probe.create_subscription(
            TwistStamped, f'/robot_{i}/cmd_vel',
            lambda msg, i=i: heard.append((i, (msg.twist.linear.x, msg.twist.linear.y,
                                               msg.twist.linear.z))), qos.COMMAND)
    return heard


def wait_exit(probe, process, timeout):
    probe.spin_until(lambda: process.poll() is not None, timeout)
    return process.poll()


def test_formation_converges_bounded_without_collision(processes, install, probe, tmp_path):
    heard = watch_commands(probe, 4)
    out = tmp_path / 'run'
    launcher = launch(processes, install, SQUARE, out, 9)
    expected = {'/formation/reference', '/clock'} | {
        f'/robot_{i}/{topic}' for i in range(1, 5) for topic in ('pose', 'neighbors', 'cmd_vel')}
    assert probe.spin_until(
        lambda: expected <= {name for name, _ in probe.get_topic_names_and_types()}, 30)
    assert wait_exit(probe, launcher, 60) == 0, processes.log('launcher')
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['final_max_error'] < 0.05
    assert metrics['min_pair_distance'] > 1e-3
    assert metrics['collisions'] == 0 and metrics['bound_violations'] == 0
    bound = load_config(SQUARE).law().u_bound
    assert len(heard) > 500
    assert max(max(abs(c) for c in u) for _, u in heard) <= bound
    assert any(max(abs(c) for c in u) > 0.5 for _, u in heard)
    for name in ('trajectories.png', 'metrics.json', 'trajectory.npz', 'params.yaml'):
        assert (out / name).exists()


def test_tracking_follows_a_circle(processes, install, probe, tmp_path):
    out = tmp_path / 'circle'
    launcher = launch(processes, install, os.path.join(CONFIG, 'circle_2d.yaml'), out, 18)
    assert wait_exit(probe, launcher, 90) == 0, processes.log('launcher')
    metrics = json.loads((out / 'metrics.json').read_text())
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.t[-1] > 8.0
    assert np.ptp(trajectory.q_od, axis=0).max() > 3.0
    assert metrics['settle_time'] is not None
    assert metrics['final_max_error'] < 0.02
    assert metrics['bound_violations'] == 0 and metrics['collisions'] == 0


def start_system(processes, install, params, robots):
    ros = ['--ros-args', '--params-file', params]
    plant = processes.start('plant', [exe(install, 'plant')] + ros)
    sim_time = ['-p', 'use_sim_time:=true']
    processes.start('reference', [exe(install, 'reference')] + ros + sim_time)
    for i in range(1, robots + 1):
        processes.start(f'robot_{i}', [exe(install, 'robot')] + ros + [
            '-r', f'__ns:=/robot_{i}', '-p', f'robot_id:={i}', '-p', 'use_sim_time:=true'])
    return plant


def test_robot_publishes_zero_when_its_plant_stops(processes, install, probe):
    heard = watch_commands(probe, 1)
    plant = start_system(processes, install, SQUARE, 4)
    moving = probe.spin_until(lambda: any(any(u) for _, u in heard), 30)
    assert moving, processes.log('robot_1')
    processes.stop(plant, signal.SIGKILL)
    stopped_at = time.monotonic()
    count = len(heard)
    assert probe.spin_until(lambda: any(not any(u) for _, u in heard[count:]), 5)
    elapsed = time.monotonic() - stopped_at
    assert elapsed < 0.5 + 0.3, elapsed
    probe.spin_until(lambda: False, 1.0)
    assert all(not any(u) for _, u in heard[-10:]), (heard[-12:], processes.log('robot_1'))
    assert processes.log('robot_1').count('publishing zero') == 1


def lockstep_matches_simulation(processes, install, probe, tmp_path, source):
    params = write_params(tmp_path, source, {'plant.lockstep': True,
                                             'plant.realtime_factor': 200.0})
    out = tmp_path / 'lockstep'
    launcher = launch(processes, install, params, out, 8)
    assert wait_exit(probe, launcher, 90) == 0, processes.log('launcher')
    plant = Trajectory.load(str(out / 'trajectory.npz'))
    assert len(plant.t) > 100
    assert np.allclose(np.diff(plant.t), 0.01)
    config = load_config(params)
    sim = simulate(config, duration=plant.t[-1], dt=0.01, sample_dt=0.01)
    assert len(sim.t) == len(plant.t)
    assert np.max(np.abs(sim.q - plant.q)) < 1e-9
    assert np.max(np.abs(sim.u - plant.u)) < 1e-9


def test_lockstep_equals_formation_sim_fixed_reference(processes, install, probe, tmp_path):
    lockstep_matches_simulation(processes, install, probe, tmp_path, 'square_4.yaml')


def test_lockstep_equals_formation_sim_moving_reference(processes, install, probe, tmp_path):
    lockstep_matches_simulation(processes, install, probe, tmp_path, 'circle_2d.yaml')


def project_processes(install):
    listing = subprocess.run(['ps', '-ww', '-eo', 'pid=,args='], capture_output=True,
                             text=True).stdout
    return [line for line in listing.splitlines() if install in line]


def test_launcher_stops_everything_on_sigint(processes, install, probe):
    heard = watch_commands(probe, 4)
    launcher = launch(processes, install, SQUARE, None, 0)
    assert probe.spin_until(lambda: {i for i, _ in heard} == {1, 2, 3, 4}, 30)
    assert len(project_processes(install)) >= 6
    os.kill(launcher.pid, signal.SIGINT)
    assert wait_exit(probe, launcher, 20) == 0, processes.log('launcher')
    assert project_processes(install) == []
    assert 'Traceback' not in processes.log('launcher')


def test_bad_parameters_stop_a_node_with_a_message(processes, install, tmp_path):
    cases = [
        ('plant', write_params(tmp_path, 'square_4.yaml', {'controller.gain': -1.0}, 'a.yaml'),
         [], 'controller.gain'),
        ('robot', SQUARE, ['-p', 'robot_id:=9'], 'robot_id'),
        ('reference', write_params(tmp_path, 'square_4.yaml', {'reference.kind': 'spiral'},
                                   'b.yaml'), [], 'reference.kind'),
        ('plant', write_params(tmp_path, 'square_4.yaml', {'controller.gain': 2}, 'c.yaml'),
         [], 'controller.gain'),
    ]
    for k, (name, params, extra, parameter) in enumerate(cases):
        process = processes.start(f'{name}_{k}', [exe(install, name), '--ros-args',
                                                  '--params-file', params] + extra)
        assert process.wait(30) == 2
        log = processes.log(f'{name}_{k}')
        assert f"parameter '{parameter}'" in log and 'Traceback' not in log, log


def test_launcher_rejects_bad_parameters_before_starting(processes, install, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {'repulsion_radius': 5.0})
    launcher = launch(processes, install, params, None, 5)
    assert launcher.wait(60) == 2
    assert "parameter 'repulsion_radius'" in processes.log('launcher')
    assert project_processes(install) == []


def test_launcher_uses_ros2_run_where_ros2_knows_the_package(processes, install, probe,
                                                             tmp_path):
    """With a `ros2` command on PATH the launcher starts every node through `ros2 run`."""
    shim = tmp_path / 'bin' / 'ros2'
    shim.parent.mkdir()
    calls = tmp_path / 'ros2_calls.txt'
    shim.write_text(
        '#!/usr/bin/env bash\n'
        f'echo "$*" >> {calls}\n'
        f'if [[ "$1 $2" == "pkg prefix" ]]; then echo {install}; exit 0; fi\n'
        f'if [[ "$1" == run ]]; then exec {install}/lib/"$2"/"$3" "${{@:4}}"; fi\n'
        'exit 1\n')
    shim.chmod(0o755)
    processes.env = dict(processes.env, PATH=f"{shim.parent}:{processes.env['PATH']}")
    launcher = processes.start('launcher', ['bash', LAUNCHER, SQUARE, '--duration', '6',
                                            '--out', str(tmp_path / 'run')])
    assert wait_exit(probe, launcher, 60) == 0, processes.log('launcher')
    used = calls.read_text()
    for name in ('plant', 'reference', 'robot', 'formation_sim', 'formation_report'):
        assert f'run formation_ros {name}' in used, used
    assert 'ros2 run' in processes.log('launcher')
    assert (tmp_path / 'run' / 'metrics.json').exists()
