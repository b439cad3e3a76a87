# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Run one node as a process: rclpy start-up, spinning, and a clean stop on SIGINT or SIGTERM.

Signals are handled in Python (rclpy's own handlers would invalidate the context before the
node could log its summary): the handler only records the signal, and the spin loop, which
wakes at least every :data:`SIGNAL_LATENCY` s even when no timer fires (a sim-time timer whose
/clock stopped), ends between two callbacks. Then the node's ``finish()`` (if it has one) runs
while ROS is still up, the node is destroyed and rclpy shut down.
"""

import os
import signal
import sys
from typing import Any, Callable, List, Optional

from formation_ros.core.declarations import ParamError
import rclpy
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

SIGNAL_LATENCY = 0.1
LOCKSTEP_POLL = 0.001
"""Period, s (steady clock), of the timer with which a lockstep node looks for a new state."""


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


def _params_files(args: List[str]) -> List[str]:
    return [args[k + 1] for k, arg in enumerate(args[:-1]) if arg == '--params-file']


def _init(args: Optional[List[str]], name: str) -> bool:
    """Start rclpy; on a bad command line or parameters file say so in one line, False."""
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: B902 - rclpy raises its C layer's RCLError here
        files = _params_files(sys.argv if args is None else args)
        where = f" (parameters file: {', '.join(files)})" if files else ''
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f'{name}: cannot start: {reason}{where}', file=sys.stderr)
        return False
    return True


def run(node_class: Callable[[], Node], args: Optional[List[str]] = None,
        name: str = 'node') -> int:
    """
    Start rclpy, build the node, spin until SIGINT/SIGTERM, shut down without a traceback.

    Returns the exit code: 0, or 2 for invalid parameters (one line per bad parameter) or a
    command line rclpy cannot start from.
    """
    if not _init(args, name):
        return 2
    signal.signal(signal.SIGINT, _StopRequest.handler)
    signal.signal(signal.SIGTERM, _StopRequest.handler)
    node = executor = None
    code = 0
    try:
        node = node_class()
        executor = make_executor()
        executor.add_node(node)
        while rclpy.ok() and _StopRequest.signal_name is None:
            executor.spin_once(timeout_sec=SIGNAL_LATENCY)
    except ParamError as exc:
        logger = rclpy.logging.get_logger(name)
        for line in str(exc).splitlines():
            logger.error(f'invalid {line}')
        code = 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        if node is not None:
            finish = getattr(node, 'finish', None)
            if finish is not None:
                finish()
            node.destroy_node()
        if executor is not None:
            executor.shutdown()
        rclpy.try_shutdown()
    return code
