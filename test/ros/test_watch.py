# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The launcher's process id and start time, as the launcher writes and the nodes read them."""

import os
import re
import subprocess
import sys

from formation_ros.ros.runner import LauncherWatch
from formation_ros.ros.watch import (LAUNCHER_PID_ENV, LAUNCHER_START_ENV, process_start,
                                     stat_fields, watch_environment)
import pytest

STAT = re.compile(rb'^(\d+) \((.*)\) (\S) (.*)$', re.DOTALL)
"""A stat line: pid, the command name in parentheses (greedy: it may hold ')'), the state..."""


def start_by_regex(pid):
    """Field 22 of /proc/<pid>/stat, parsed independently of formation_ros.ros.watch."""
    with open(f'/proc/{pid}/stat', 'rb') as stream:
        match = STAT.match(stream.read())
    return int(match.group(4).split()[22 - 4])


@pytest.fixture
def oddly_named():
    """Give the test a sleeping child whose command name holds ') X (' and spaces."""
    code = ('import ctypes, sys, time\n'
            "ctypes.CDLL(None).prctl(15, b'a) Z (b c', 0, 0, 0)\n"
            "print('named', flush=True)\n"
            'time.sleep(60)\n')
    child = subprocess.Popen([sys.executable, '-c', code], stdout=subprocess.PIPE)
    assert child.stdout.readline() == b'named\n'
    yield child
    child.kill()
    child.wait()


@pytest.mark.skipif(not os.path.isdir('/proc/self'), reason='needs /proc')
def test_the_start_time_is_field_22_whatever_the_command_name(oddly_named):
    pid = oddly_named.pid
    with open(f'/proc/{pid}/comm', 'rb') as stream:
        assert stream.read().strip() == b'a) Z (b c'
    fields = stat_fields(pid)
    assert fields[0] in (b'S', b'R')
    assert process_start(pid) == start_by_regex(pid)
    env = watch_environment(pid)
    assert env == {LAUNCHER_PID_ENV: str(pid), LAUNCHER_START_ENV: str(start_by_regex(pid))}
    watch = LauncherWatch.from_environment(env)
    assert watch is not None and not watch.gone()
    oddly_named.kill()
    oddly_named.wait()
    assert process_start(pid) is None
    assert LauncherWatch.from_environment(env).gone()


def test_this_process_names_itself_as_the_launcher_does():
    env = watch_environment(os.getpid())
    assert env[LAUNCHER_PID_ENV] == str(os.getpid())
    if os.path.isdir('/proc/self'):
        assert env[LAUNCHER_START_ENV] == str(start_by_regex(os.getpid()))
