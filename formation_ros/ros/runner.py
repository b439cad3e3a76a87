# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Run one node as a process: rclpy start-up, spinning, and a clean stop on SIGINT or SIGTERM.

Signals are handled in Python (rclpy's own handlers would invalidate the context before the
node could log its summary): the handler only records the signal, and the spin loop, which
wakes at least every :data:`SIGNAL_LATENCY` s even when no timer fires (a sim-time timer whose
/clock stopped), ends between two callbacks. Then the node's ``finish()`` (if it has one) runs
while ROS is still up, the node is destroyed and rclpy shut down.

A node started by the launcher also watches the launcher (:class:`LauncherWatch`): the launcher
puts its process id and start time into the environment (``formation_ros.ros.watch``, its
variables), and when that process is gone, even killed with SIGKILL, the spin
loop ends the node as on SIGTERM and the process ends at once after (:func:`_exit_now`). This
works whatever started the node on the launcher's
behalf (``ros2 run`` puts a process of its own in between). A node started by hand, without
the variable, watches nothing. prctl(PR_SET_PDEATHSIG) is not used: it reaches only direct
children, fires when the thread that started the child ends rather than the process, and would
have to be set in a ``preexec_fn``, which is unsafe in a launcher whose relay threads run.
"""

import ctypes
import faulthandler
import gc
import os
import signal
import sys
import time
from typing import Any, Callable, List, Mapping, Optional, Sequence, Union

from formation_ros.core.settings.declarations import ParamError
from formation_ros.core.settings.exits import REFUSED
from formation_ros.core.settings.file_guard import (check_params_text, ParamsFileError,
                                                    read_params_file_text)
from formation_ros.ros.watch import LAUNCHER_PID_ENV, LAUNCHER_START_ENV, process_start
import rclpy
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

SIGNAL_LATENCY = 0.1
TEARDOWN_LIMIT = 5.0
"""
Seconds the destruction of the nodes and rclpy's shutdown may take once every node has finished
(its files written): they take well under a second, but Fast DDS (2.14) can hang in them for
ever, and signals are ignored by then. Seen in 2 of 360 launcher kills on a busy machine: the
participant's destruction spinning in ``DomainParticipant::set_listener`` until no discovery
callback runs, while a callback about a peer's reader or writer gone at the same moment waits
for the participant's lock, which that loop keeps taking. The process then ends without them,
with exit code 1 (:func:`_watch_teardown`).
"""


def make_executor() -> Executor:
    """Return rclpy's EventsExecutor where it exists (far less overhead per callback)."""
    if os.environ.get('FORMATION_EXECUTOR', 'events') == 'events':
        try:
            from rclpy.experimental import EventsExecutor
            return EventsExecutor()
        except ImportError:
            pass
    return SingleThreadedExecutor()


class _StopRequest:
    """Set by the SIGINT/SIGTERM handler; the spin loop checks it between callbacks."""

    signal_name: Optional[str] = None

    @classmethod
    def handler(cls, signum: int, frame: Any) -> None:
        cls.signal_name = signal.Signals(signum).name


class LauncherWatch:
    """
    Tells whether the launcher that started this node still runs.

    The launcher is known by its process id together with its start time: once it has ended,
    its id may be given to an unrelated process, which has another start time. Checks
    ``/proc`` at most every :data:`SIGNAL_LATENCY` s (a few microseconds each).
    """

    def __init__(self, pid: int, start: Optional[int]) -> None:
        """Watch process ``pid`` started at ``start`` ticks (None: its start time now)."""
        self.pid = pid
        self.start = process_start(pid) if start is None else start
        self._next_check = 0.0
        self._gone = self.start is None

    @classmethod
    def from_environment(cls, env: Mapping[str, str]) -> Optional['LauncherWatch']:
        """Return a watch of the launcher named in ``env``; None if there is none."""
        pid = env.get(LAUNCHER_PID_ENV, '')
        start = env.get(LAUNCHER_START_ENV, '')
        if not pid:
            return None
        if not pid.isdigit() or (start and not start.isdigit()):
            print(f'ignoring {LAUNCHER_PID_ENV}={pid!r} {LAUNCHER_START_ENV}={start!r} '
                  '(not numbers)', file=sys.stderr)
            return None
        return cls(int(pid), int(start) if start else None)

    def gone(self) -> bool:
        """Tell whether the launcher has ended (checked at most every SIGNAL_LATENCY s)."""
        now = time.monotonic()
        if not self._gone and now >= self._next_check:
            self._next_check = now + SIGNAL_LATENCY
            self._gone = process_start(self.pid) != self.start
        return self._gone


def _params_files(args: List[str]) -> List[str]:
    return [args[k + 1] for k, arg in enumerate(args[:-1]) if arg == '--params-file']


RobotsRule = Callable[[int], Optional[str]]
"""Why a process cannot take a team of that many robots (None: it can)."""


def params_file_problem(path: str, robots_rule: Optional[RobotsRule] = None) -> Optional[str]:
    """
    Return, as one line naming ``path``, what keeps it from being a parameters file; or None.

    robots_rule: the process's limit on ``num_robots``, applied to the file's before rcl
    parses it (rcl's parser takes minutes over the arrays of 100,000 robots).

    The file is checked by :mod:`formation_ros.core.settings.file_guard` (size, anchors, depth,
    array lengths, YAML syntax in this package's words), never parsed in full, and must hold a
    mapping: rcl parses it only after this, so that none of rcl's or libyaml's own messages
    reach the user for a file the guard refuses.
    """
    try:
        shape = check_params_text(read_params_file_text(path), path)
    except ParamsFileError as exc:
        return exc.summary
    if shape.root is None:
        return f'{path}: is empty'
    if shape.root != 'mapping':
        return (f'{path}: is not a ROS 2 parameters file (no mapping of node names to '
                'ros__parameters)')
    too_many = robots_rule(shape.num_robots) if robots_rule and shape.num_robots else None
    return f'{path}: num_robots: {too_many}' if too_many else None


def _init(args: Optional[List[str]], name: str, robots_rule: Optional[RobotsRule]) -> bool:
    """Start rclpy; on a bad command line or parameters file say so in one line, False."""
    for path in _params_files(sys.argv if args is None else args):
        problem = params_file_problem(path, robots_rule)
        if problem:
            print(f'{name}: parameters file {problem}', file=sys.stderr)
            return False
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: B902 - rclpy raises its C layer's RCLError here
        files = _params_files(sys.argv if args is None else args)
        where = f" (parameters file: {', '.join(files)})" if files else ''
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f'{name}: cannot start: {reason}{where}', file=sys.stderr)
        return False
    return True


def _exit_now(code: int) -> None:
    """
    End the process now, its work saved and its node gone: what a node does without launcher.

    The node's publishers and subscriptions are destroyed and rclpy is shut down before this
    (the peers are told, and stop sending to it); what is skipped is the interpreter's own
    teardown, which destroys the DDS participant and took about a second on a busy machine,
    while nobody waits for this process any more. Python's and C's output is flushed first.
    """
    _flush_output()
    os._exit(code)


def _watch_teardown() -> None:
    """
    End the process with exit code 1 unless the teardown is done within TEARDOWN_LIMIT s.

    The watchdog is faulthandler's thread, which runs without the GIL. A Python thread (a
    ``threading.Timer``) cannot be one: rclpy holds the GIL through its calls into rcl and
    Fast DDS, so a timer whose time is up waits for the GIL as long as the hang lasts (seen
    20 s after the launcher's kill: the timer's thread in ``take_gil``, the main thread still
    destroying the participant). Before it ends the process, the watchdog writes every thread's
    stack to stderr (file descriptor 2), where the hang shows; it cannot keep the process's own
    exit code. The output so far is flushed now, as it would not be then.
    """
    _flush_output()
    faulthandler.dump_traceback_later(TEARDOWN_LIMIT, exit=True, file=2)


def _flush_output() -> None:
    """Flush Python's stdout and stderr, and C's streams (what os._exit would not)."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except OSError:
            pass
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


def _exit_request(nodes: Sequence[Node]) -> Optional[int]:
    """Return the exit code a node has asked for (its ``exit_code`` attribute), None if none."""
    return next((code for code in (getattr(node, 'exit_code', None) for node in nodes)
                 if code is not None), None)


class _ExitRequests:
    """The nodes' ``exit_code`` attributes, looked at every SIGNAL_LATENCY s (not per spin)."""

    def __init__(self, nodes: Sequence[Node]) -> None:
        self.nodes = [node for node in nodes if hasattr(node, 'exit_code')]
        self._next_check = 0.0

    def due(self) -> Optional[int]:
        """Return the exit code a node has asked for, None if none (or not looked yet)."""
        now = time.monotonic()
        if not self.nodes or now < self._next_check:
            return None
        self._next_check = now + SIGNAL_LATENCY
        return _exit_request(self.nodes)


NodeFactory = Callable[[], Union[Node, Sequence[Node]]]
"""Builds the process's node, or its nodes (a fleet of robots): a node class, for one."""


def run(make_nodes: NodeFactory, args: Optional[List[str]] = None, name: str = 'node',
        robots_rule: Optional[RobotsRule] = None) -> int:
    """
    Start rclpy, build the node(s), spin until SIGINT/SIGTERM, shut down without a traceback.

    ``make_nodes`` returns one node or several, which then share one executor (and the one
    thread of this process). Everything allocated until then (modules, message classes, the
    nodes) is moved out of the garbage collector's sight (``gc.freeze``): a profile of the
    lockstep plant found a fifth of its time in full collections walking those objects. The
    spin also ends when the launcher named in the environment is gone (see
    :class:`LauncherWatch`), and when a node sets its ``exit_code`` attribute (checked every
    SIGNAL_LATENCY s): the recorder whose disk is full
    (:data:`formation_ros.core.settings.exits.RECORDING_FAILED`), a plant that finds another team
    on its domain (:data:`formation_ros.core.settings.exits.REFUSED`); the node has said why, in
    its own line. Returns the exit code: 0; 1 if a node's ``finish()`` failed (the others still
    finish), and from a process whose teardown hung (:data:`TEARDOWN_LIMIT`); 2 for invalid
    parameters (one line per bad parameter) or a command line rclpy cannot start from; a
    node's ``exit_code``. robots_rule: the process's limit on a parameters file's
    ``num_robots`` (the world's), checked before rcl parses the file.
    """
    if not _init(args, name, robots_rule):
        return REFUSED
    signal.signal(signal.SIGINT, _StopRequest.handler)
    signal.signal(signal.SIGTERM, _StopRequest.handler)
    launcher = LauncherWatch.from_environment(os.environ)
    nodes: List[Node] = []
    executor = None
    code = 0
    orphaned = False
    try:
        made = make_nodes()
        nodes = [made] if isinstance(made, Node) else list(made)
        executor = make_executor()
        for node in nodes:
            executor.add_node(node)
        requests = _ExitRequests(nodes)
        gc.collect()
        gc.freeze()
        while rclpy.ok() and _StopRequest.signal_name is None:
            requested = requests.due()
            if requested is not None:
                code = requested
                break
            executor.spin_once(timeout_sec=SIGNAL_LATENCY)
            if launcher is not None and launcher.gone():
                nodes[0].get_logger().warning(
                    f'the launcher (process {launcher.pid}) is gone; stopping')
                orphaned = True
                break
    except ParamError as exc:
        logger = rclpy.logging.get_logger(name)
        for line in str(exc).splitlines():
            logger.error(f'invalid {line}')
        code = REFUSED
    except (InvalidParameterTypeException, InvalidParameterValueException) as exc:
        if nodes:
            raise
        # A parameter rclpy declares itself as a node is made (use_sim_time).
        rclpy.logging.get_logger(name).error(f'invalid parameter: {exc}')
        code = REFUSED
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        for node in nodes:
            finish = getattr(node, 'finish', None)
            try:
                if finish is not None:
                    finish()
            except Exception as exc:  # noqa: B902 - one node's failure must not stop the rest
                node.get_logger().error(f'could not finish: {type(exc).__name__}: {exc}')
                code = 1
        requested = _exit_request(nodes)
        if requested is not None and code == 0:
            code = requested
        _watch_teardown()
        for node in nodes:
            node.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
        faulthandler.cancel_dump_traceback_later()
        if orphaned:
            _exit_now(code)
    return code
