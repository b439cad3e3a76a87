# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
The node executables' entry points (``setup.py``): quiet when stopped while still loading.

``ros2 run formation_ros robot`` spends its first second loading numpy, rclpy and the node's
module, before :func:`formation_ros.ros.runner.run` handles SIGINT and SIGTERM. A Ctrl-C in
that second, or a launcher that stops a system it has just started, would print Python's
KeyboardInterrupt traceback from deep inside an import. Each entry point here first makes
SIGINT and SIGTERM end the process quietly with exit code 0, as the runner does once it spins
(nothing has started yet, so there is nothing to save), then loads its node module and runs
its ``main()``, which installs the runner's own handlers. This module loads nothing else.
"""

import importlib
import signal
from types import FrameType
from typing import Callable, Optional


def _stopped_while_loading(signum: int, frame: Optional[FrameType]) -> None:
    """End the process quietly: a stop request came before the node was built."""
    raise SystemExit(0)


def _run(module: str) -> int:
    """Load ``formation_ros.nodes.<module>`` with stop requests handled; return its main()."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _stopped_while_loading)
    node = importlib.import_module(f'formation_ros.nodes.{module}')
    code: int = node.main()
    return code


def _entry(executable: str, module: str) -> Callable[[], int]:
    """Return the entry point of ``ros2 run formation_ros <executable>``."""
    def entry() -> int:
        return _run(module)
    entry.__name__ = entry.__qualname__ = executable
    entry.__doc__ = f'``ros2 run formation_ros {executable}``.'
    return entry


robot = _entry('robot', 'robot')
fleet = _entry('fleet', 'fleet')
plant = _entry('plant', 'plant')
reference = _entry('reference', 'reference')
record = _entry('record', 'recorder')
relay = _entry('relay', 'relay')
world = _entry('world', 'world')
