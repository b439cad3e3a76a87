# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Faults around the launcher: it is killed, Ctrl-C reaches its process group, a robot dies.

The launcher runs as a real process with real nodes; the test kills processes with signals
and judges the outcome from the process table, the launcher's output, an independent probe
node and the plant's ``trajectory.npz`` / ``metrics.json``.
"""

import json
import os
import re
import signal
import subprocess
import sys
import time

from formation_ros.core.runs.trajectory import Trajectory
from formation_ros.core.settings.declarations import Exe
from formation_ros.core.settings.params import load_config
from formation_ros.ros.runner import LauncherWatch
from formation_ros.ros.watch import process_start
from helpers import (exe, launch, project_processes, SimClock, SQUARE, START_UP, stop_when,
                     wait_exit, watch_commands)
import numpy as np
import pytest

pytestmark = pytest.mark.faults

GONE_WITHIN = 10.0
"""Generous bound on the seconds the nodes may take to end after the launcher is killed."""


def launch_with(processes, install, *options, out=None, record=None, env=None):
    """Start the launcher on the square formation until Ctrl-C with ``options``; its Popen."""
    return launch(processes, install, SQUARE, out=out, record=record, env=env, options=options)


def robot_pids(install, robot):
    """Return the process ids of robot ``robot``'s running processes from ``install``."""
    return [int(line.split()[0]) for line in project_processes(install)
            if f'__ns:=/robot_{robot} ' in line + ' ' and exe(install, 'robot') in line]


def wait_for_no_process(probe, text, since, timeout):
    """Spin ``probe`` until no command line mentions ``text``; return the seconds ``since``."""
    probe.spin_until(lambda: not project_processes(text), timeout)
    return time.monotonic() - since


def cmd_vel_publishers(probe, robot):
    """Return the ids of the publishers of ``/robot_<robot>/cmd_vel`` that the probe knows."""
    return {bytes(info.endpoint_gid)
            for info in probe.get_publishers_info_by_topic(f'/robot_{robot}/cmd_vel')}


def ros2_run_shim(folder, install):
    """
    Write a ``ros2`` command that runs nodes as its children, as ``ros2 run`` does.

    Unlike an ``exec``, the node's parent is then the shim, not the launcher. Returns the
    shim's directory, to go first on PATH.
    """
    shim = folder / 'bin' / 'ros2'
    shim.parent.mkdir()
    shim.write_text(
        '#!/usr/bin/env bash\n'
        'set -euo pipefail\n'
        f'if [[ "$1 $2" == "pkg prefix" ]]; then echo "{install}"; exit 0; fi\n'
        f'if [[ "$1" == run ]]; then "{install}/lib/$2/$3" "${{@:4}}"; exit "$?"; fi\n'
        'exit 1\n')
    shim.chmod(0o755)
    return shim.parent


def test_launcher_watch_tells_a_process_from_its_reused_id():
    sleeper = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)'])
    try:
        start = process_start(sleeper.pid)
        assert start is not None
        assert not LauncherWatch(sleeper.pid, start).gone()
        assert not LauncherWatch(sleeper.pid, None).gone()
        assert LauncherWatch(sleeper.pid, start + 1).gone()
        watch = LauncherWatch.from_environment({'FORMATION_LAUNCHER_PID': str(sleeper.pid),
                                                'FORMATION_LAUNCHER_START': str(start)})
        assert watch is not None and not watch.gone()
        sleeper.kill()
        deadline = time.monotonic() + 30.0
        while process_start(sleeper.pid) is not None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert process_start(sleeper.pid) is None, 'a zombie counts as gone'
        assert sleeper.poll() is not None
        assert process_start(sleeper.pid) is None
        watch._next_check = 0.0
        assert watch.gone()
    finally:
        sleeper.kill()
        sleeper.wait()
    assert LauncherWatch.from_environment({}) is None
    assert LauncherWatch.from_environment({'FORMATION_LAUNCHER_PID': 'x'}) is None


@pytest.mark.parametrize('through', ['install', 'ros2 run'])
def test_nodes_end_when_the_launcher_is_killed(processes, install, probe, tmp_path, ros_env,
                                               through):
    clock = SimClock(probe)
    out = tmp_path / 'run'
    if through == 'install':
        launch_with(processes, install, out=out)
        watched = install
    else:
        shims = ros2_run_shim(tmp_path, install)
        with open(exe(install, 'plant')) as stream:
            python_dir = os.path.dirname(stream.readline()[2:].strip())
        env = dict(ros_env, PATH=os.pathsep.join([str(shims), python_dir, ros_env['PATH']]))
        launch_with(processes, None, out=out, env=env)
        watched = str(shims)
    assert probe.spin_until(lambda: clock.seconds > 1.0, START_UP), processes.log('launcher')
    nodes = [line for line in project_processes(install) if exe(install, '') in line]
    assert len(nodes) == 6, nodes
    if through == 'ros2 run':
        assert len(project_processes(watched)) >= 6, project_processes(watched)
    killed = time.monotonic()
    os.kill(processes.popen('launcher').pid, signal.SIGKILL)
    assert wait_exit(probe, processes, 'launcher', 30).signal_name == 'SIGKILL'
    took = wait_for_no_process(probe, install, killed, 3 * GONE_WITHIN)
    left = project_processes(install) + project_processes(watched)
    assert not left, left
    assert took < GONE_WITHIN, took
    print(f'nodes gone {took:.2f} s after kill -9 of the launcher ({through})')
    assert (out / 'trajectory.npz').exists(), 'the plant did not finish'


def test_ctrl_c_to_the_process_group_keeps_the_closing_lines(processes, install, probe,
                                                             tmp_path):
    clock = SimClock(probe)
    launch_with(processes, install, out=tmp_path / 'run', record=tmp_path / 'bag')
    assert probe.spin_until(lambda: clock.seconds > 1.0, START_UP), processes.log('launcher')
    os.killpg(processes.popen('launcher').pid, signal.SIGINT)
    info = wait_exit(probe, processes, 'launcher', 60)
    log = processes.log('launcher')
    assert info is not None and info.returncode == 0, log
    assert 'stopping (SIGINT)' in log and 'Traceback' not in log, log
    lines = log.splitlines()
    assert any(line.startswith('[plant] ') and 'plant: ' in line and ' steps (' in line
               for line in lines), log
    assert any(line.startswith('[record] ') and ' wrote ' in line and ' messages on ' in line
               for line in lines), log
    assert (tmp_path / 'run' / 'metrics.json').exists(), log
    assert project_processes(install) == []


def robots_in(line):
    """Return the robot ids a plant line names ('robot 2: ...', 'robots 1, 2 and 4: ...')."""
    match = re.search(r'\brobots? ([0-9, ]+(?:and [0-9]+)?)(?: and [0-9]+ more)?:', line)
    if match is None:
        return set()
    return {int(word) for word in re.findall(r'[0-9]+', match.group(1))}


def kill_robot_2_while_it_moves(processes, install, probe, clock, heard):
    """Wait until every robot is heard and the clock passes 0.5 s; kill -9 robot 2; its time."""
    assert probe.spin_until(lambda: clock.seconds > 0.5 and {i for i, _ in heard} >= {1, 2, 3, 4},
                            START_UP), processes.log('launcher')
    [pid] = robot_pids(install, 2)
    os.kill(pid, signal.SIGKILL)
    return clock.seconds


def test_a_dead_robot_stays_still_while_the_others_go_on(processes, install, probe, tmp_path):
    heard, _ = watch_commands(probe, 4)
    clock = SimClock(probe)
    out = tmp_path / 'run'
    launch_with(processes, install, out=out)
    killed_at = kill_robot_2_while_it_moves(processes, install, probe, clock, heard)
    counted = len(heard)

    def others_go_on():
        later = [i for i, _ in heard[counted:]]
        return clock.seconds > killed_at + 3.0 and all(later.count(i) > 50 for i in (1, 3, 4))

    assert probe.spin_until(others_go_on, 60), processes.log('launcher')
    assert 'robot_2 ended on its own (signal SIGKILL); the others go on' in \
        processes.log('launcher')
    info = stop_when(probe, processes, lambda: True)
    log = processes.log('launcher')
    assert info.returncode == 1, log
    assert log.rstrip().endswith('exit code 1: robot_2 ended on its own (signal SIGKILL)'), log
    assert robot_pids(install, 2) == [] and project_processes(install) == []
    stale = [line for line in log.splitlines() if 'latest command' in line
             and 2 in robots_in(line)]
    assert len(stale) == 1 and stale[0].startswith('[plant] ') and \
        ' s old' in stale[0] and 'using zero' in stale[0], stale

    trajectory = Trajectory.load(str(out / 'trajectory.npz'))
    timeout = load_config(SQUARE, Exe.PLANT).plant.input_timeout
    moving = np.flatnonzero(np.any(trajectory.u[:, 1] != 0.0, axis=1))
    assert len(moving) > 0 and trajectory.t[moving[0]] < killed_at
    still_from = trajectory.t[moving[-1]] + 1e-9
    assert killed_at < still_from < killed_at + timeout + 1.0, (killed_at, still_from)
    after = trajectory.t >= still_from
    assert np.all(trajectory.q[after, 1] == trajectory.q[after, 1][0])
    assert trajectory.t[-1] > killed_at + 2.5
    others = trajectory.q[after][:, [0, 2, 3]]
    assert np.ptp(others, axis=0).max() > 1e-3, 'the other robots stopped moving too'


def test_a_respawned_robot_rejoins_the_formation(processes, install, probe, tmp_path):
    heard, subscriptions = watch_commands(probe, 4)
    clock = SimClock(probe)
    out = tmp_path / 'run'
    launch_with(processes, install, '--on-exit', 'respawn', out=out)
    assert probe.spin_until(lambda: subscriptions[1].get_publisher_count() > 0, START_UP)
    before = cmd_vel_publishers(probe, 2)
    kill_robot_2_while_it_moves(processes, install, probe, clock, heard)
    assert probe.spin_until(lambda: cmd_vel_publishers(probe, 2) - before, START_UP), \
        processes.log('launcher')
    counted = len(heard)
    assert probe.spin_until(
        lambda: sum(1 for i, u in heard[counted:] if i == 2 and any(u)) > 20, START_UP), \
        processes.log('launcher')
    resumed = clock.seconds
    info = stop_when(probe, processes, lambda: clock.seconds > resumed + 8.0)
    log = processes.log('launcher')
    assert info.returncode == 1, log
    assert log.count('robot_2 ended on its own (signal SIGKILL); starting it again '
                     '(restart 1 of 5)') == 1, log
    assert log.rstrip().endswith(
        'exit code 1: robot_2 ended on its own (signal SIGKILL, restarted once)'), log
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['final_max_error'] < 0.05, metrics
    assert metrics['collisions'] == 0


def mapped(pid, fragment):
    """Tell whether process ``pid`` has a file whose path holds ``fragment`` mapped."""
    try:
        with open(f'/proc/{pid}/maps', encoding='utf-8') as stream:
            return fragment in stream.read()
    except OSError:
        return False


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize('name', ['robot', 'plant'])
def test_a_node_stopped_while_it_still_loads_ends_quietly(install, name, sig):
    """A Ctrl-C in a node's first second (numpy loaded, rclpy not yet) exits 0, no traceback."""
    for _ in range(20):
        process = subprocess.Popen([exe(install, name), '--ros-args', '--params-file', SQUARE],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        deadline = time.monotonic() + 60.0
        while not mapped(process.pid, '_multiarray_umath'):
            assert time.monotonic() < deadline, 'numpy never loaded'
            try:
                process.wait(timeout=0.002)
            except subprocess.TimeoutExpired:
                continue
            pytest.fail(f'{name} ended before it loaded numpy')
        loading = not mapped(process.pid, '_rclpy_pybind11')
        process.send_signal(sig)
        out, _ = process.communicate(timeout=60)
        assert process.returncode == 0, out
        assert 'Traceback' not in out and 'KeyboardInterrupt' not in out, out
        if loading:
            return
    pytest.fail('the signal never came while the node was loading')
