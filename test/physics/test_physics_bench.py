# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""bench/bench_physics.py: its command line and a tiny run."""

import json
import os
import subprocess
import sys

import pytest

pytest.importorskip('mujoco')

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, 'bench', 'bench_physics.py')


def test_help_names_the_options():
    result = subprocess.run([sys.executable, SCRIPT, '--help'], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    for option in ('--sizes', '--duration', '--timestep', '--cpu', '--json'):
        assert option in result.stdout


def test_a_tiny_run_writes_its_row(tmp_path):
    out = tmp_path / 'physics.json'
    result = subprocess.run([sys.executable, SCRIPT, '--sizes', '4', '--duration', '0.2',
                             '--json', str(out)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert '| 4 | 2 | 0.2 |' in result.stdout
    (row,) = json.loads(out.read_text())['rows']
    assert row['robots'] == 4 and row['simulated_s'] == pytest.approx(0.2)
    assert row['realtime_factor'] > 0.0 and row['contacts'] == 0


def test_a_team_of_one_is_refused():
    result = subprocess.run([sys.executable, SCRIPT, '--sizes', '1'], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 2 and 'at least 2' in result.stderr
