"""
Fixtures of the integration tests: a colcon install space, processes ended by PID, a probe node.

The install space is built once per test run with ``python -m colcon build`` into a temporary
directory; every executable is started from it, as ``ros2 run`` would, with the test run's
ROS_DOMAIN_ID and discovery limited to this host. Every process a test starts is ended
(SIGINT, then SIGKILL to its process group) when the test ends, pass or fail.
"""

import glob
import os
import signal
import subprocess
import sys
import time

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = os.path.join(ROOT, 'config')


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
    return str(base / 'install' / 'formation_ros')


@pytest.fixture(scope='session')
def ros_env(install):
    """Environment in which the installed executables run (what sourcing the install does)."""
    env = dict(os.environ)
    site = glob.glob(os.path.join(install, 'lib', 'python3*', 'site-packages'))
    env['PYTHONPATH'] = os.pathsep.join(site + [env.get('PYTHONPATH', '')]).rstrip(os.pathsep)
    env['AMENT_PREFIX_PATH'] = install
    env['PYTHONUNBUFFERED'] = '1'
    return env


class Processes:
    """Starts processes in their own process groups and ends them all, by PID."""

    def __init__(self, env, log_dir):
        """Start processes with ``env``, their output in files under ``log_dir``."""
        self.env = env
        self.log_dir = log_dir
        self.started = []

    def start(self, name, args):
        """Start ``args`` (a list) with output to ``<log_dir>/<name>.log``; return the Popen."""
        log = open(os.path.join(self.log_dir, f'{name}.log'), 'w')
        process = subprocess.Popen(args, env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        self.started.append((name, process, log))
        return process

    def log(self, name):
        """Return what process ``name`` printed so far."""
        with open(os.path.join(self.log_dir, f'{name}.log')) as stream:
            return stream.read()

    def stop(self, process, sig=signal.SIGINT, timeout=10.0):
        """Send ``sig`` to the process group, wait, then SIGKILL; return the exit code."""
        if process.poll() is None:
            try:
                os.killpg(process.pid, sig)
            except ProcessLookupError:
                pass
            try:
                process.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait(5.0)
        return process.returncode

    def stop_all(self):
        """End every process started, then close the logs."""
        for _, process, _ in reversed(self.started):
            self.stop(process)
        for _, process, log in self.started:
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
            log.close()


@pytest.fixture
def processes(ros_env, tmp_path):
    """Give the test a :class:`Processes`; its processes are ended when the test ends."""
    group = Processes(ros_env, str(tmp_path))
    yield group
    group.stop_all()


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


def exe(install, name):
    """Path of an installed executable, as ``ros2 run formation_ros NAME`` runs it."""
    return os.path.join(install, 'lib', 'formation_ros', name)


def write_params(tmp_path, source, changes, name='params.yaml'):
    """Copy a shipped config with top-level ``ros__parameters`` entries added or replaced."""
    import yaml
    with open(os.path.join(CONFIG, source)) as stream:
        document = yaml.safe_load(stream)
    params = document['/**']['ros__parameters']
    for key, value in changes.items():
        node = params
        parts = key.split('.')
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    path = os.path.join(str(tmp_path), name)
    with open(path, 'w') as stream:
        yaml.safe_dump(document, stream)
    return path
