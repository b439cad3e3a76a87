# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""A node whose teardown hangs (as Fast DDS can, in a lock-order deadlock) still ends."""

import os
import subprocess
import sys
import textwrap

from formation_ros.ros.runner import TEARDOWN_LIMIT

CHILD = textwrap.dedent("""
    import sys
    import threading
    from formation_ros.ros import runner
    from rclpy.node import Node


    class Stuck(Node):
        def __init__(self):
            super().__init__('stuck')
            self.exit_code = 3

        def destroy_node(self):
            threading.Event().wait()


    sys.exit(runner.run(Stuck, name='stuck'))
""")


def test_a_hung_teardown_ends_the_process_with_its_exit_code_and_one_line():
    child = subprocess.run([sys.executable, '-c', CHILD], capture_output=True, text=True,
                           timeout=TEARDOWN_LIMIT + 120, env=dict(os.environ))
    assert child.returncode == 3, child.stderr
    lines = [line for line in child.stderr.splitlines() if 'DDS teardown' in line]
    assert lines == [f'stuck: the DDS teardown did not end within {TEARDOWN_LIMIT:g} s; '
                     'exiting without it'], child.stderr
    assert 'Traceback' not in child.stderr
