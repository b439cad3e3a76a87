# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Test isolation: each run talks DDS on its own domain, on this host only, signals as default."""

import os
import random
import signal

from formation_ros.tools.domain import ports_busy
import pytest

_DOMAINS = random.SystemRandom().sample(range(1, 102), 101)
os.environ['ROS_DOMAIN_ID'] = str(next((d for d in _DOMAINS if not ports_busy(d)), _DOMAINS[0]))
"""A domain no participant of this host is on (another test run's plant would refuse ours)."""
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
