# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Helpers of the integration tests: executables, parameter files, the launcher, what a probe hears.

The fixtures (install space, supervised processes, probe node) are in ``conftest.py``; test
modules import these helpers from here.
"""

import os
import signal
import subprocess

from diagnostic_msgs.msg import DiagnosticArray
from formation_ros.core.settings.params_file import load_params_file, write_params_file
from formation_ros.ros import fields, qos
from formation_ros.tools.supervise import ProcessSpec
from geometry_msgs.msg import TwistStamped
from rosgraph_msgs.msg import Clock as ClockMsg

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = os.path.join(ROOT, 'config')
SQUARE = os.path.join(CONFIG, 'square_4.yaml')
LAUNCHER = os.path.join(ROOT, 'scripts', 'launch_formation.sh')
START_UP = 90.0


def exe(install, name):
    """Path of an installed executable, as ``ros2 run formation_ros NAME`` runs it."""
    return os.path.join(install, 'lib', 'formation_ros', name)


def node(install, name, params, *extra, process=None):
    """Spec of node ``name`` of the install with ``--ros-args --params-file params extra...``."""
    return ProcessSpec(process or name,
                       [exe(install, name), '--ros-args', '--params-file', str(params), *extra])


TWICE_REAL_TIME = {'plant.realtime_factor': 2.0}
"""For a test of what the team does over simulated time, not of keeping up with the wall clock."""


def write_params(folder, source, changes, name='params.yaml'):
    """Copy a shipped config with parameters (dotted names) added or replaced; return its path."""
    values = load_params_file(os.path.join(CONFIG, source))
    values.update(changes)
    path = os.path.join(str(folder), name)
    write_params_file(path, values)
    return path


def launch(processes, install, params, out=None, record=None, duration=0, env=None,
           name='launcher', options=(), plots=False, per_process=None):
    """
    Start ``scripts/launch_formation.sh`` as process ``name``; return its Popen.

    install: passed as ``--prefix`` (None: the launcher finds the executables itself).
    duration: the launcher's ``--duration``; the default 0 runs until :func:`stop_when`.
    options: more launcher options, e.g. ``('--on-exit', 'respawn')``.
    plots: whether the report at the end draws its figures (``--no-plots`` unless a test
    looks at them: they cost seconds of CPU that other tests' nodes need).
    per_process: ``--robots-per-process``, for a test of what the robots do rather than of
    how they are spread over processes (each process costs its start-up and a participant).
    """
    args = ['bash', LAUNCHER, str(params), '--duration', str(duration), *options]
    if not plots:
        args.append('--no-plots')
    if per_process is not None:
        args += ['--robots-per-process', str(per_process)]
    if install is not None:
        args += ['--prefix', str(install)]
    if out is not None:
        args += ['--out', str(out)]
    if record is not None:
        args += ['--record', str(record)]
    return processes.start(ProcessSpec(name, args, env))


class SimClock:
    """The latest simulated time the probe heard on ``/clock``, in seconds (-1 before any)."""

    def __init__(self, probe):
        """Subscribe ``probe`` to ``/clock``."""
        self.seconds = -1.0
        self.subscription = probe.create_subscription(ClockMsg, '/clock', self._on_clock,
                                                      qos.CLOCK)

    def _on_clock(self, message):
        self.seconds = fields.stamp_to_ns(message.clock) * 1e-9


def watch_commands(probe, count):
    """
    Subscribe to the cmd_vel of robots 1..count.

    Return (heard, subscriptions): heard is the list of (robot, (x, y, z)) received.
    """
    heard = []
    subscriptions = [
        probe.create_subscription(
            TwistStamped, f'/robot_{i}/cmd_vel',
            lambda msg, i=i: heard.append((i, (msg.twist.linear.x, msg.twist.linear.y,
                                               msg.twist.linear.z))), qos.COMMAND)
        for i in range(1, count + 1)]
    return heard, subscriptions


def matched(subscriptions):
    """Whether every subscription has matched at least one publisher."""
    return all(s.get_publisher_count() > 0 for s in subscriptions)


class Statuses(dict):
    """{status name: the latest status on /diagnostics}, and how many of each were heard."""

    def __init__(self, probe):
        super().__init__()
        self.heard = {}
        probe.create_subscription(DiagnosticArray, '/diagnostics', self._store, qos.DIAGNOSTICS)

    def _store(self, message):
        for status in message.status:
            self[status.name] = status
            self.heard[status.name] = self.heard.get(status.name, 0) + 1


def plant_value(statuses, key, default=0):
    """Return value ``key`` of the plant's latest status as a number (``default`` before any)."""
    status = statuses.get('formation_ros/plant')
    values = {kv.key: kv.value for kv in status.values} if status is not None else {}
    return float(values.get(key, default))


def said_once(probe, processes, name, text, statuses, status):
    """
    Wait until process ``name`` has logged ``text``, then for two more ``status`` reports.

    A node's log reaches the test through a pipe, its diagnostics over DDS: either may come
    first. Each report is a moment at which a repeat would have been logged; return how
    many times ``text`` is in the log after them.
    """
    logged(probe, processes, name, text)
    after = statuses.heard.get(status, 0) + 2
    assert probe.spin_until(lambda: statuses.heard.get(status, 0) >= after, 30), statuses
    return processes.log(name).count(text)


def logged(probe, processes, name, *texts, timeout=30.0):
    """
    Wait until process ``name`` has logged every one of ``texts``; return its log.

    A node's log reaches the test through a pipe, its diagnostics over DDS: a test that has
    seen a node report something waits for the line too before it counts it.
    """
    assert probe.spin_until(lambda: all(text in processes.log(name) for text in texts),
                            timeout), processes.log(name)
    return processes.log(name)


def start_system(processes, install, params, robots):
    """Start plant, reference and robots 1..robots by hand (no launcher)."""
    processes.start(node(install, 'plant', params))
    processes.start(node(install, 'reference', params, '-p', 'use_sim_time:=true'))
    for i in range(1, robots + 1):
        processes.start(node(install, 'robot', params, '-r', f'__ns:=/robot_{i}',
                             '-p', f'robot_id:={i}', '-p', 'use_sim_time:=true',
                             process=f'robot_{i}'))


def wait_exit(probe, processes, name, timeout):
    """Spin ``probe`` until process ``name`` has ended (up to ``timeout`` s); return its exit."""
    probe.spin_until(lambda: not processes.running(name), timeout)
    return processes.exit_info(name)


def stop_when(probe, processes, condition, timeout=START_UP, name='launcher'):
    """
    Spin ``probe`` until ``condition()`` holds, then Ctrl-C the launcher; return its exit.

    Asserts that the condition was met while the launcher ran and that the launcher ended.
    """
    probe.spin_until(lambda: condition() or not processes.running(name), timeout)
    assert condition(), f'condition not met within {timeout} s:\n' + processes.log(name)[-4000:]
    assert processes.running(name), processes.log(name)[-4000:]
    processes.send_signal(name, signal.SIGINT)
    info = wait_exit(probe, processes, name, 60)
    assert info is not None, f'{name} did not end within 60 s after SIGINT'
    return info


def project_processes(install):
    """
    Command lines of the running processes that mention the install space.

    Each pytest-xdist worker has an install space of its own (conftest.py), so this sees only
    the processes of the worker's tests, orphans of a killed launcher included.
    """
    listing = subprocess.run(['ps', '-ww', '-eo', 'pid=,args='], capture_output=True,
                             text=True, check=True).stdout
    return [line for line in listing.splitlines() if install in line]
