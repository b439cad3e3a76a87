# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The ROS 2 system with real processes and real DDS: plant, reference, robots, launcher."""

import json
import os
import signal

from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.params import load_config
from formation_ros.simulation.simulate import simulate
from helpers import (exe, launch, matched, node, plant_value, project_processes, SimClock,
                     SQUARE, start_system, Statuses, stop_when, watch_commands, write_params)
import numpy as np


def test_formation_converges_bounded_without_collision(processes, install, probe, tmp_path):
    heard, subscriptions = watch_commands(probe, 4)
    statuses = Statuses(probe)
    out = tmp_path / 'run'
    launch(processes, install, SQUARE, out=out, plots=True)
    expected = {'/formation/reference', '/clock'} | {
        f'/robot_{i}/{topic}' for i in range(1, 5) for topic in ('pose', 'neighbors', 'cmd_vel')}
    assert probe.spin_until(
        lambda: expected <= {name for name, _ in probe.get_topic_names_and_types()}, 60), \
        processes.log('launcher')
    assert probe.spin_until(lambda: matched(subscriptions), 30), processes.log('launcher')
    counted = len(heard)
    info = stop_when(probe, processes, lambda: plant_value(
        statuses, 'steps with fresh commands') >= 500 and len(heard) > counted + 500, timeout=300)
    assert info.returncode == 0, processes.log('launcher')
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['duration'] > 4.5
    assert metrics['final_max_error'] < 0.05
    assert metrics['min_pair_distance'] > 1e-3
    assert metrics['collisions'] == 0 and metrics['bound_violations'] == 0
    assert metrics['max_abs_u_component'] > 0.5
    bound = load_config(SQUARE).law().u_bound
    assert max(max(abs(c) for c in u) for _, u in heard[counted:]) <= bound
    for name in ('trajectories.png', 'metrics.json', 'trajectory.npz', 'params.yaml'):
        assert (out / name).exists()


def test_tracking_follows_a_circle(processes, install, probe, tmp_path):
    statuses = Statuses(probe)
    out = tmp_path / 'circle'
    launch(processes, install, write_params(tmp_path, 'circle_2d.yaml', {}), out=out,
           per_process=6)
    # 10 s of steps with fresh commands (100 Hz), however long starved robots make the run.
    info = stop_when(probe, processes, lambda: plant_value(
        statuses, 'steps with fresh commands') >= 1000, timeout=300)
    assert info.returncode == 0, processes.log('launcher')
    metrics = json.loads((out / 'metrics.json').read_text())
    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    assert trajectory.t[-1] > 9.5
    assert np.ptp(trajectory.q_od, axis=0).max() > 3.0
    assert metrics['settle_time'] is not None
    assert metrics['final_max_error'] < 0.02
    assert metrics['bound_violations'] == 0 and metrics['collisions'] == 0


def test_robots_on_sim_time_track_a_fast_circle_from_one_reference_sample_a_second(
        processes, install, probe, tmp_path):
    """Carried forward, a sample a second old would put q_od 0.25 m off this circle."""
    statuses = Statuses(probe)
    out = tmp_path / 'fast'
    fast = {'reference.radius': 2.0, 'reference.speed': 1.0, 'reference.rate': 1.0,
            'input_timeout': 1.5}
    launch(processes, install, write_params(tmp_path, 'circle_2d.yaml', fast), out=out,
           per_process=6)
    info = stop_when(probe, processes, lambda: plant_value(
        statuses, 'steps with fresh commands') >= 1000, timeout=300)
    assert info.returncode == 0, processes.log('launcher')
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['settle_time'] is not None
    assert metrics['final_max_error'] < 0.02, metrics
    assert metrics['bound_violations'] == 0 and metrics['collisions'] == 0


def test_robot_publishes_zero_when_its_plant_stops(processes, install, probe):
    heard, _ = watch_commands(probe, 1)
    start_system(processes, install, SQUARE, 4)
    assert probe.spin_until(lambda: any(any(u) for _, u in heard), 60), processes.log('robot_1')
    [killed] = processes.stop(['plant'], sig=signal.SIGKILL)
    assert killed.signal_name == 'SIGKILL'
    count = len(heard)
    assert probe.spin_until(lambda: any(not any(u) for _, u in heard[count:]), 30)
    first_zero = count + next(k for k, (_, u) in enumerate(heard[count:]) if not any(u))
    assert probe.spin_until(lambda: len(heard) >= first_zero + 50, 30)
    zeros = heard[first_zero:]
    assert all(not any(u) for _, u in zeros), (zeros[:12], processes.log('robot_1'))
    log = processes.log('robot_1')
    assert log.count('publishing zero') == log.count('inputs fresh again') + 1, log


def lockstep_matches_simulation(processes, install, probe, tmp_path, source, changes=(),
                                until=1.5, one_fleet=True):
    """
    Run ``source`` (with ``changes``) in lockstep to ``until`` s; assert it is formation_sim's.

    one_fleet: the robots in one fleet process (else one process each, the launcher's default).
    Returns (the plant's trajectory, the parameters file).
    """
    params = write_params(tmp_path, source, {'plant.lockstep': True,
                                             'plant.realtime_factor': 200.0, **dict(changes)})
    config = load_config(params)
    clock = SimClock(probe)
    out = tmp_path / 'lockstep'
    launch(processes, install, params, out=out,
           per_process=config.num_robots if one_fleet else None)
    info = stop_when(probe, processes, lambda: clock.seconds >= until)
    assert info.returncode == 0, processes.log('launcher')
    plant = Trajectory.load(str(out / 'trajectory.npz'))
    assert len(plant.t) >= 100 * until  # 0.01 s steps: a sample per step before it
    assert np.allclose(np.diff(plant.t), 0.01)
    sim = simulate(config, duration=plant.t[-1], dt=0.01, sample_dt=0.01)
    assert len(sim.t) == len(plant.t)
    assert np.max(np.abs(sim.q - plant.q)) < 1e-9
    assert np.max(np.abs(sim.u - plant.u)) < 1e-9
    return plant, params


def test_lockstep_equals_formation_sim_fixed_reference(processes, install, probe, tmp_path):
    lockstep_matches_simulation(processes, install, probe, tmp_path, 'square_4.yaml',
                                one_fleet=False)


def test_lockstep_equals_formation_sim_moving_reference(processes, install, probe, tmp_path):
    lockstep_matches_simulation(processes, install, probe, tmp_path, 'circle_2d.yaml')


def test_launcher_stops_everything_on_sigint(processes, install, probe):
    heard, _ = watch_commands(probe, 4)
    launch(processes, install, SQUARE)
    info = stop_when(probe, processes,
                     lambda: {i for i, _ in heard} == {1, 2, 3, 4}
                     and len(project_processes(install)) >= 6)
    assert info.returncode == 0, processes.log('launcher')
    assert project_processes(install) == []
    log = processes.log('launcher')
    assert 'Traceback' not in log and 'stopping (SIGINT)' in log
    assert all(f'[robot_{i}]' in log for i in range(1, 5)) and '[plant]' in log


def test_launcher_takes_paths_with_spaces(processes, install, probe, tmp_path):
    folder = tmp_path / 'a folder with spaces'
    folder.mkdir()
    params = write_params(folder, 'square_4.yaml', {}, 'my params.yaml')
    prefix = folder / 'install link'
    prefix.symlink_to(install)
    out, bag = folder / 'run dir', folder / 'bag dir'
    clock = SimClock(probe)
    launch(processes, prefix, params, out=out, record=bag)
    info = stop_when(probe, processes, lambda: clock.seconds >= 1.0)
    assert info.returncode == 0, processes.log('launcher')
    with open(params) as stream:
        assert (out / 'params.yaml').read_text() == stream.read()
    assert (bag / 'metadata.yaml').exists()
    assert (out / 'trajectory.npz').exists() and (out / 'plant_stats.json').exists()
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['source'] == 'rosbag2' and metrics['duration'] > 0.5


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
        processes.start(node(install, name, params, *extra, process=f'{name}_{k}'))
        info = processes.wait(f'{name}_{k}', 60)
        log = processes.log(f'{name}_{k}')
        assert info is not None and info.returncode == 2, log
        assert f"parameter '{parameter}'" in log and 'Traceback' not in log, log


def test_launcher_rejects_bad_parameters_before_starting(processes, install, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {'repulsion_radius': 5.0})
    launch(processes, install, params, out=tmp_path / 'run', duration=5)
    info = processes.wait('launcher', 60)
    assert info is not None and info.returncode == 2, processes.log('launcher')
    assert "parameter 'repulsion_radius'" in processes.log('launcher')
    assert project_processes(install) == []
    assert not (tmp_path / 'run').exists()


def test_launcher_uses_ros2_run_where_ros2_knows_the_package(processes, install, probe,
                                                             tmp_path, ros_env):
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
    with open(exe(install, 'plant')) as stream:
        python_dir = os.path.dirname(stream.readline()[2:].strip())
    env = dict(ros_env, PATH=os.pathsep.join([str(shim.parent), python_dir, ros_env['PATH']]))
    clock = SimClock(probe)
    launch(processes, None, SQUARE, out=tmp_path / 'run', env=env)
    info = stop_when(probe, processes, lambda: clock.seconds >= 1.0)
    assert info.returncode == 0, processes.log('launcher')
    used = calls.read_text()
    for name in ('plant', 'reference', 'robot', 'formation_report'):
        assert f'run formation_ros {name}' in used, used
    assert 'formation_sim' not in used
    assert '(ros2 run)' in processes.log('launcher')
    assert (tmp_path / 'run' / 'metrics.json').exists()
