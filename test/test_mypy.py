# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Static types: mypy checks formation_ros/core and formation_ros/physics (mypy.ini)."""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_mypy_core():
    command = [sys.executable, '-m', 'mypy', '--config-file', 'mypy.ini', 'formation_ros/core',
               'formation_ros/physics']
    result = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=600)
    output = result.stdout + result.stderr
    assert result.returncode == 0, f'{" ".join(command[1:])} (exit {result.returncode}):\n{output}'
    assert 'Success' in result.stdout, output
