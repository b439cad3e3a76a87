# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A node whose teardown hangs (as Fast DDS can, in a deadlock) still ends."""

import os
import subprocess
import sys
import textwrap

from formation_ros.ros.runner import TEARDOWN_LIMIT
import pytest

CHILD = textwrap.dedent("""
    import ctypes
    import sys
    import threading
    from formation_ros.ros import runner
    from rclpy.node import Node


    class Stuck(Node):
        def __init__(self):
            super().__init__('stuck')
            self.exit_code = 3

        def destroy_node(self):
            {hang}


    sys.exit(runner.run(Stuck, name='stuck'))
""")

HANGS = {
    # As rclpy's calls into rcl and Fast DDS do: ctypes.PyDLL keeps the GIL through the call.
    'in C, holding the GIL': 'ctypes.PyDLL(None).pause()',
    'in Python, waiting': 'threading.Event().wait()',
}


@pytest.mark.parametrize('hang', list(HANGS))
def test_a_hung_teardown_ends_the_process_with_every_threads_stack(hang):
    child = subprocess.run([sys.executable, '-c', CHILD.format(hang=HANGS[hang])],
                           capture_output=True, text=True, timeout=TEARDOWN_LIMIT + 120,
                           env=dict(os.environ))
    assert child.returncode == 1, child.stderr
    assert f'Timeout (0:00:{TEARDOWN_LIMIT:02.0f})!' in child.stderr, child.stderr
    assert ' in destroy_node\n' in child.stderr, child.stderr
    assert 'Traceback' not in child.stderr
