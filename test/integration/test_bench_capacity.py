# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The capacity benchmark on a tiny size against the real install: it runs and writes its JSON."""

import json
import os
import subprocess
import sys

from formation_ros.core.settings.params import load_config
from helpers import ROOT


def test_capacity_benchmark_runs_both_modes_on_two_robots(install, ros_env, tmp_path):
    out = tmp_path / 'capacity'
    result = subprocess.run(
        [sys.executable, os.path.join(ROOT, 'bench', 'bench_capacity.py'), '--sizes', '2',
         '--rates', '20', '--modes', 'process', 'fleet', '--robots-per-process', '2',
         '--measure', '1', '--prefix', str(install), '--out', str(out), '--keep'],
        capture_output=True, text=True, env=ros_env, timeout=600)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    rows = json.loads((out / 'capacity.json').read_text())['rows']
    assert [(row['mode'], row['robots'], row['processes']) for row in rows] == \
        [('process', 2, 4), ('fleet', 2, 3)]
    for row in rows:
        assert row['steps'] > 0 and row['step_rate'] > 0.0, row
        assert 0.0 < row['fresh_fraction'] <= 1.0, row
        assert row['latency_ms']['count'] > 0 and row['startup_s'] > 0.0, row
        assert row['rss_mib']['plant'] > 10.0 and 'launcher' in row['cpu_percent'], row
        assert row['reference_rate_hz'] == 10.0, row
    assert (out / 'capacity_fresh.png').exists()
    for mode in ('process', 'fleet'):
        kept = out / f'robot-{mode}-2-20'
        assert 'starting the clock' in (kept / 'launcher.txt').read_text()
        stats = json.loads((kept / 'run' / 'plant_stats.json').read_text())
        assert load_config(str(kept / 'params.yaml'), 'reference').reference_node.rate == 10.0
        assert stats['steps'] == next(row['steps'] for row in rows if row['mode'] == mode)
