# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Fixtures of the integration tests: a colcon install space, supervised processes, a probe node.

The install space is built once per test process with ``python -m colcon build`` into a
temporary directory and byte-compiled (where ``PYTHONDONTWRITEBYTECODE`` is set, setuptools
leaves that out, and every process would compile the package again: a quarter of a second of
CPU each); every executable is started from it, as ``ros2 run`` would, with the test
process's ROS_DOMAIN_ID and discovery limited to this host. Under pytest-xdist each worker
builds its own (a few seconds; the builds write nothing into the source tree), in its own
temporary directory: its path is in every command line of the worker's processes, so
``helpers.project_processes`` never counts another worker's processes. Processes run under
:class:`formation_ros.tools.supervise.Supervisor`, each in its own process group with its
output in ``<tmp_path>/logs/<name>.log``, and are all ended when the test ends, pass or fail.
Helpers for the tests are in ``helpers.py``.
"""

import os
import signal
import subprocess
import sys
import time

from formation_ros.tools.launcher import Install
from formation_ros.tools.supervise import Supervisor
from helpers import project_processes, ROOT
import pytest

LEFT_WITHIN = 20.0
"""Seconds a test's processes may take to end after it (a node sees its launcher gone in 1 s)."""


@pytest.fixture(scope='session')
def install(tmp_path_factory):
    """Build the package with colcon; return the package's install prefix."""
    base = tmp_path_factory.mktemp('colcon')
    result = subprocess.run(
        [sys.executable, '-m', 'colcon', '--log-base', str(base / 'log'), 'build',
         '--base-paths', ROOT, '--build-base', str(base / 'build'),
         '--install-base', str(base / 'install')],
        cwd=str(base), capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr
    prefix = base / 'install' / 'formation_ros'
    compiled = subprocess.run([sys.executable, '-m', 'compileall', '-q', str(prefix / 'lib')],
                              capture_output=True, text=True, timeout=600)
    assert compiled.returncode == 0, compiled.stdout + compiled.stderr
    return str(prefix)


@pytest.fixture(scope='session')
def ros_env(install):
    """Environment in which the installed executables run (what sourcing the install does)."""
    env = Install(install).environment(os.environ)
    env.pop('FORMATION_PREFIX', None)
    return env


@pytest.fixture
def processes(ros_env, tmp_path):
    """Give the test a Supervisor with logs in tmp_path/logs; it ends them all afterwards."""
    with Supervisor(log_dir=str(tmp_path / 'logs'), env=ros_env) as supervisor:
        yield supervisor


@pytest.fixture(autouse=True)
def _no_process_left(request):
    """
    Fail a test whose processes outlive it, and kill them so that the tests after it can run.

    A node that hangs while it ends (seen once: Fast DDS deadlocked deleting a reader after
    its launcher was killed) would otherwise stay on the worker's domain and in its process
    table, and every later test that counts processes or nodes would fail too.
    """
    yield
    if 'install' not in request.fixturenames:
        return
    install = request.getfixturevalue('install')
    deadline = time.monotonic() + LEFT_WITHIN
    while project_processes(install) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = project_processes(install)
    for line in left:
        try:
            os.kill(int(line.split()[0]), signal.SIGKILL)
        except ProcessLookupError:
            pass
    assert not left, f'processes left running {LEFT_WITHIN:g} s after the test (killed):\n' + \
        '\n'.join(left)


@pytest.fixture
def probe():
    """Give the test an rclpy node of its own, on the test run's domain."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node('probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)

    def spin_until(predicate, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            executor.spin_once(timeout_sec=0.05)
        return predicate()

    node.spin_until = spin_until
    yield node
    executor.shutdown()
    node.destroy_node()
    rclpy.shutdown(context=context)
