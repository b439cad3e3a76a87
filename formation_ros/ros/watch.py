# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
How a node knows the launcher that started it: a process id and start time in its environment.

The launcher puts both into every node's environment (:func:`watch_environment`); a node's
``formation_ros.ros.runner.LauncherWatch`` compares them with :func:`process_start` and ends
the node once that process is gone, even when it was killed with SIGKILL. An id alone is not
enough: once the launcher has ended, its id may be given to an unrelated process, which has
another start time. Only the standard library is imported (the launcher's ``--help`` needs no
more).
"""

import os
from typing import Dict, List, Optional

LAUNCHER_PID_ENV = 'FORMATION_LAUNCHER_PID'
LAUNCHER_START_ENV = 'FORMATION_LAUNCHER_START'
"""Process id and start time (clock ticks after boot, /proc/<pid>/stat) of the launcher."""


def stat_fields(pid: int) -> List[bytes]:
    """
    Return the fields of ``/proc/<pid>/stat`` from field 3 (the state) on, see proc_pid_stat(5).

    Field k is at index k - 3: the state at 0, utime and stime at 11 and 12, the start time
    at 19. The command name (field 2) is skipped whatever it holds (spaces, parentheses).
    Raises OSError where the file cannot be read (FileNotFoundError: no such process, or no
    /proc) and ValueError where it is not a stat line.
    """
    with open(f'/proc/{pid}/stat', 'rb') as stream:
        text = stream.read()
    if b')' not in text:
        raise ValueError(f'/proc/{pid}/stat is not a stat line')
    return text.rsplit(b')', 1)[1].split()


def process_start(pid: int) -> Optional[int]:
    """
    Return the start time of process ``pid`` in clock ticks after boot; None if it is gone.

    A zombie (ended, not yet reaped by its parent) counts as gone. Where there is no /proc,
    return 0 for any process that exists.
    """
    try:
        fields = stat_fields(pid)
    except FileNotFoundError:
        if os.path.isdir('/proc/self'):
            return None
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return None
        except PermissionError:
            pass
        return 0
    except (OSError, ValueError):
        return None
    if len(fields) < 20 or fields[0] in (b'Z', b'X'):
        return None
    return int(fields[19])


def watch_environment(pid: int) -> Dict[str, str]:
    """Return the variables with which the nodes watch running process ``pid``, to end with it."""
    start = process_start(pid)
    env = {LAUNCHER_PID_ENV: str(pid)}
    if start is not None:
        env[LAUNCHER_START_ENV] = str(start)
    return env
