# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Process supervision, shared by the launcher and the integration tests.

Every process starts in a session and process group of its own, with stdin from /dev/null and
stdout and stderr merged into one pipe. A reader thread per process copies each line onto the
supervisor's echo stream as ``[name] line`` and/or into ``<log_dir>/<name>.log``; a waiter
thread per process records its exit the moment it happens, so the supervisor knows which
process ended first on its own and why (exit code or signal), and at that moment kills what
is left of its process group, so no child of a supervised process outlives it. Stopping sends
SIGINT to whole process groups at once, waits until one deadline, then sends SIGKILL to the
groups whose leader is still running, and returns once their last output lines are relayed.
Because every process has a session of its own, a Ctrl-C in the supervisor's terminal reaches
the supervisor alone, which stops the processes while it still relays their output.

The supervisor cannot clean up after itself if it is killed with SIGKILL: the processes then
have to notice on their own (the nodes watch the launcher, see ``formation_ros.ros.runner``).

Commands are argv lists, never shell strings, so paths may contain spaces.
"""

import dataclasses
import os
import queue
import signal
import subprocess
import threading
import time
from typing import IO, Iterable, Mapping, Optional, Sequence

KILL_WAIT = 5.0
READER_JOIN = 5.0


@dataclasses.dataclass(frozen=True)
class ProcessSpec:
    """
    A process to start.

    name: unique among the supervisor's processes; the prefix of its echoed lines and the name
    of its log file. argv: the command, a list (no shell). env: its whole environment (default:
    the supervisor's). cwd: its working directory (default: the supervisor's).
    """

    name: str
    argv: Sequence[str]
    env: Optional[Mapping[str, str]] = None
    cwd: Optional[str] = None


@dataclasses.dataclass(frozen=True)
class ExitInfo:
    """
    How one process ended.

    returncode: as :mod:`subprocess` reports it (negative: the number of the signal that ended
    it). stopped: whether the supervisor had asked it to stop before it ended; a process that
    ended with ``stopped`` false died on its own. at: ``time.monotonic()`` of the exit.
    """

    name: str
    pid: int
    returncode: int
    stopped: bool
    at: float

    @property
    def signal_name(self) -> Optional[str]:
        """Return the name of the signal that ended the process ('SIGKILL'), None if it exited."""
        return signal_name(self.returncode)

    @property
    def reason(self) -> str:
        """Say why it ended: 'exit code 3' or 'signal SIGSEGV'."""
        return describe_returncode(self.returncode)


def signal_name(returncode: int) -> Optional[str]:
    """Return the name of the signal a negative subprocess return code stands for, else None."""
    if returncode >= 0:
        return None
    try:
        return signal.Signals(-returncode).name
    except ValueError:
        return str(-returncode)


def describe_returncode(returncode: int) -> str:
    """Say what a subprocess return code means: 'exit code 3' or 'signal SIGSEGV'."""
    name = signal_name(returncode)
    return f'exit code {returncode}' if name is None else f'signal {name}'


class _Running:
    """One started process with its threads; internal to :class:`Supervisor`."""

    def __init__(self, spec: ProcessSpec, popen: 'subprocess.Popen[bytes]',
                 log: Optional[IO[str]]) -> None:
        self.spec = spec
        self.popen = popen
        self.log = log
        self.ended = threading.Event()
        self.exit: Optional[ExitInfo] = None
        self.stop_requested = False
        self.reader: Optional[threading.Thread] = None
        self.waiter: Optional[threading.Thread] = None

    def close_log(self) -> None:
        """Wait (briefly) for the last output lines, then close the log file."""
        if self.reader is not None:
            self.reader.join(READER_JOIN)
        if self.log is not None:
            self.log.close()


class Supervisor:
    """
    Starts processes in their own process groups, relays their output, and stops them.

    echo: a text stream for ``[name] line`` copies of every output line (None: no echo).
    log_dir: a directory for ``<name>.log`` files (None: no files); created if missing.
    env: the default environment of the processes (None: this process's environment).
    Use as a context manager, or call :meth:`close`, so that nothing outlives the supervisor.
    """

    def __init__(self, echo: Optional[IO[str]] = None, log_dir: Optional[str] = None,
                 env: Optional[Mapping[str, str]] = None) -> None:
        """Set up an empty supervisor; nothing is started yet."""
        self.echo = echo
        self.log_dir = log_dir
        self.env = dict(os.environ if env is None else env)
        self._echo_lock = threading.Lock()
        self._state_lock = threading.Lock()
        self._processes: dict[str, _Running] = {}
        self._exits: queue.Queue[ExitInfo] = queue.Queue()
        self._ended: list[ExitInfo] = []
        self._starts: dict[str, int] = {}
        if log_dir is not None:
            os.makedirs(log_dir, exist_ok=True)

    def __enter__(self) -> 'Supervisor':
        """Return the supervisor itself."""
        return self

    def __exit__(self, *exc_info: object) -> None:
        """Stop everything still running and close the logs."""
        self.close()

    def start(self, spec: ProcessSpec) -> 'subprocess.Popen[bytes]':
        """
        Start ``spec`` in a new session (its own process group) and return its Popen.

        A name may be started again once its previous process has ended (a respawn); its log
        file is then appended to. Raises ValueError for the name of a running process, and
        OSError when the program cannot be started.
        """
        with self._state_lock:
            old = self._processes.get(spec.name)
            if old is not None and not old.ended.is_set():
                raise ValueError(f"a process named '{spec.name}' is running already")
        if old is not None:
            old.close_log()
        log = None
        if self.log_dir is not None:
            log = open(self.log_path(spec.name), 'a', encoding='utf-8')
        try:
            popen = subprocess.Popen(
                list(spec.argv), env=dict(self.env if spec.env is None else spec.env),
                cwd=spec.cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT, start_new_session=True)
        except OSError:
            if log is not None:
                log.close()
            raise
        running = _Running(spec, popen, log)
        running.reader = threading.Thread(target=self._relay, args=(running,),
                                          name=f'relay {spec.name}', daemon=True)
        running.waiter = threading.Thread(target=self._wait, args=(running,),
                                          name=f'wait {spec.name}', daemon=True)
        with self._state_lock:
            self._processes[spec.name] = running
            self._starts[spec.name] = self._starts.get(spec.name, 0) + 1
        running.reader.start()
        running.waiter.start()
        return popen

    def restart(self, name: str) -> 'subprocess.Popen[bytes]':
        """
        Start process ``name`` again with the spec it was last started with; return its Popen.

        Raises ValueError while it is still running.
        """
        return self.start(self._get(name).spec)

    def starts(self, name: str) -> int:
        """Return how many times a process named ``name`` has been started (0: never)."""
        with self._state_lock:
            return self._starts.get(name, 0)

    def log_path(self, name: str) -> str:
        """Return the log file of process ``name``; raises ValueError without a log_dir."""
        if self.log_dir is None:
            raise ValueError('this supervisor keeps no log files (log_dir is None)')
        return os.path.join(self.log_dir, f'{name}.log')

    def log(self, name: str) -> str:
        """
        Return what process ``name`` has printed so far.

        Once the process has ended, this waits (briefly) until its last lines are in the file.
        """
        running = self._get(name)
        if running.ended.is_set() and running.reader is not None:
            running.reader.join(READER_JOIN)
        with open(self.log_path(name), encoding='utf-8', errors='replace') as stream:
            return stream.read()

    def names(self) -> list[str]:
        """Return the names of every process started, in the order they were first started."""
        with self._state_lock:
            return list(self._processes)

    def popen(self, name: str) -> 'subprocess.Popen[bytes]':
        """Return the Popen of the latest process started as ``name``."""
        return self._get(name).popen

    def running(self, name: str) -> bool:
        """Tell whether the latest process started as ``name`` is still running."""
        return not self._get(name).ended.is_set()

    def exit_info(self, name: str) -> Optional[ExitInfo]:
        """Return how the latest process started as ``name`` ended (None while it runs)."""
        return self._get(name).exit

    def wait(self, name: str, timeout: Optional[float] = None) -> Optional[ExitInfo]:
        """Wait up to ``timeout`` seconds for ``name`` to end; return its exit, None if not."""
        running = self._get(name)
        running.ended.wait(timeout)
        return running.exit

    def wait_exit(self, timeout: Optional[float] = None) -> Optional[ExitInfo]:
        """
        Return the next exit not returned before, in the order the processes ended.

        Waits up to ``timeout`` seconds (None: for ever) and returns None if nothing ended.
        """
        try:
            return self._exits.get(timeout=timeout)
        except queue.Empty:
            return None

    def exits(self) -> list[ExitInfo]:
        """Return every exit so far, in the order the processes ended."""
        with self._state_lock:
            return list(self._ended)

    def send_signal(self, name: str, sig: int) -> None:
        """Send ``sig`` to the process group of ``name`` (nothing if it has ended)."""
        running = self._get(name)
        if not running.ended.is_set():
            _signal_group(running.popen.pid, sig)

    def stop(self, names: Iterable[str], timeout: float = 10.0,
             sig: int = signal.SIGINT) -> list[ExitInfo]:
        """
        Stop the processes ``names`` together and return how each ended, in the given order.

        Sends ``sig`` to every one's process group at once, waits until ``timeout`` seconds
        from now for them to end, then sends SIGKILL to the groups of those still running.
        Returns once their last output lines have been relayed (or after a short wait).
        """
        stage = [self._get(name) for name in names]
        for running in stage:
            running.stop_requested = True
            if not running.ended.is_set():
                _signal_group(running.popen.pid, sig)
        deadline = time.monotonic() + timeout
        for running in stage:
            if not running.ended.wait(max(0.0, deadline - time.monotonic())):
                _signal_group(running.popen.pid, signal.SIGKILL)
                running.ended.wait(KILL_WAIT)
        relay_deadline = time.monotonic() + READER_JOIN
        for running in stage:
            if running.ended.is_set() and running.reader is not None:
                running.reader.join(max(0.0, relay_deadline - time.monotonic()))
        return [running.exit for running in stage if running.exit is not None]

    def stop_all(self, order: Sequence[Sequence[str]] = (), timeout: float = 10.0) -> None:
        """
        Stop every process: the stages of ``order`` one after another, then the rest together.

        Each stage is a list of names stopped together with :meth:`stop` (SIGINT, ``timeout``,
        SIGKILL); a stage starts once the previous one has ended.
        """
        listed: set[str] = set()
        for stage in order:
            self.stop(stage, timeout)
            listed.update(stage)
        rest = [name for name in reversed(self.names()) if name not in listed]
        if rest:
            self.stop(rest, timeout)

    def close(self, timeout: float = 10.0) -> None:
        """Stop every process still running, wait for their last output lines, close logs."""
        self.stop_all((), timeout)
        with self._state_lock:
            started = list(self._processes.values())
        for running in started:
            running.close_log()

    def _get(self, name: str) -> _Running:
        with self._state_lock:
            try:
                return self._processes[name]
            except KeyError:
                raise KeyError(f"no process named '{name}' was started") from None

    def _relay(self, running: _Running) -> None:
        prefix = f'[{running.spec.name}] '
        assert running.popen.stdout is not None
        with running.popen.stdout as stream:
            for raw in iter(stream.readline, b''):
                line = raw.decode('utf-8', errors='replace').rstrip('\r\n') + '\n'
                _write(running.log, line)
                with self._echo_lock:
                    if not _write(self.echo, prefix + line):
                        self.echo = None

    def _wait(self, running: _Running) -> None:
        returncode = running.popen.wait()
        # The group's id cannot be reused while members are left, and a leader just reaped
        # has not had its pid reused yet: this is the one safe moment to end the leftovers.
        _signal_group(running.popen.pid, signal.SIGKILL)
        info = ExitInfo(running.spec.name, running.popen.pid, returncode,
                        running.stop_requested, time.monotonic())
        with self._state_lock:
            running.exit = info
            self._ended.append(info)
        running.ended.set()
        self._exits.put(info)


def _signal_group(pgid: int, sig: int) -> None:
    try:
        os.killpg(pgid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def _write(stream: Optional[IO[str]], text: str) -> bool:
    """Write and flush ``text`` to ``stream`` if there is one; False if the stream failed."""
    if stream is None:
        return True
    try:
        stream.write(text)
        stream.flush()
    except (OSError, ValueError):
        return False
    return True
