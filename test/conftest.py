# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Test isolation: each run talks DDS on its own domain, on this host only, signals as default.

Under pytest-xdist every worker has a domain of its own: the controlling process draws the
first domain of the run before it starts the workers (they inherit it as
``FORMATION_TEST_DOMAIN``), and worker ``gw<k>`` takes the k-th domain after it, so two
workers never hear each other's nodes.
"""

import os
import random
import signal

from formation_ros.tools.domain import ports_busy
import pytest

DOMAINS = 101
"""Domain ids 1..101 (the largest that Fast DDS's default ports allow for many participants)."""
LOOK_AHEAD = 8
"""Domains from the run's first that must be free: one per worker, at most this many workers."""


def _free_first_domain():
    """Return a first domain with LOOK_AHEAD free ones from it (another run's plant refuses)."""
    candidates = random.SystemRandom().sample(range(1, DOMAINS + 1), DOMAINS)
    for first in candidates:
        if not any(ports_busy((first - 1 + k) % DOMAINS + 1) for k in range(LOOK_AHEAD)):
            return first
    return candidates[0]


def _domain_of_this_process():
    """Return the ROS_DOMAIN_ID of this process: the run's first, or a worker's own."""
    first = os.environ.get('FORMATION_TEST_DOMAIN')
    if first is None:
        first = str(_free_first_domain())
        os.environ['FORMATION_TEST_DOMAIN'] = first
    worker = os.environ.get('PYTEST_XDIST_WORKER', '')
    index = int(worker[2:]) if worker.startswith('gw') and worker[2:].isdigit() else 0
    return (int(first) - 1 + index) % DOMAINS + 1


os.environ['ROS_DOMAIN_ID'] = str(_domain_of_this_process())
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('MPLBACKEND', 'Agg')

# A shell without job control starts background commands (`run_tests.sh &`) with SIGINT
# ignored, and an ignored signal is inherited by every process the tests start: their
# stand-in nodes would then never see Ctrl-C. The tests start from the default.
for _number in (signal.SIGINT, signal.SIGTERM):
    if signal.getsignal(_number) == signal.SIG_IGN:
        signal.signal(_number, signal.SIG_DFL if _number == signal.SIGTERM
                      else signal.default_int_handler)


def pytest_report_header(config):
    """Show the DDS domain of this run in pytest's header."""
    workers = getattr(config.option, 'numprocesses', None)
    if workers:
        return (f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} and the next ones, one per "
                'xdist worker (discovery: localhost only)')
    return f"ROS_DOMAIN_ID={os.environ['ROS_DOMAIN_ID']} (discovery: localhost only)"


def _ignored_signals():
    """Return the set of signals this process ignores (its SigIgn mask), or None without /proc."""
    try:
        with open('/proc/self/status', encoding='ascii') as stream:
            for line in stream:
                if line.startswith('SigIgn:'):
                    mask = int(line.split()[1], 16)
                    return {number for number in range(1, 65) if mask >> (number - 1) & 1}
    except OSError:
        return None
    return None


@pytest.fixture(autouse=True)
def _signals_left_as_found():
    """
    Fail a test that leaves SIGINT or SIGTERM ignored in the test process.

    Ignored signals are inherited by every process started later: a test that forgets to
    restore them makes the process tests after it fail (their children never see Ctrl-C).
    """
    before = _ignored_signals()
    yield
    after = _ignored_signals()
    if before is not None and after is not None:
        left = {signal.Signals(number).name for number in (after - before)
                if number in (signal.SIGINT, signal.SIGTERM)}
        assert not left, f'the test left {", ".join(sorted(left))} ignored in the test process'


@pytest.fixture
def launch_file(monkeypatch):
    """Give the test launch/formation.launch.py on stand-ins (test_package.load_launch_file)."""
    from test_package import load_launch_file
    return load_launch_file(monkeypatch, 'formation.launch.py')


@pytest.fixture
def lab_launch_file(monkeypatch):
    """Give the test launch/lab.launch.py on stand-ins (``test_package.load_launch_file``)."""
    from test_package import load_launch_file
    return load_launch_file(monkeypatch, 'lab.launch.py')
