# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Benchmark of the multi-process ROS system (run on demand, not in CI).

Usage: python bench/bench_system.py [--sizes 4 10 20] [--duration 20] [--prefix INSTALL]

For each team size N it writes a parameters file (Section 5 constants, random start at about
10 robots per m^2, lattice goal 2 m apart), runs scripts/launch_formation.sh for DURATION
wall-clock seconds (one process per robot, plant, reference) and reads the plant's
plant_stats.json: how many of its 100 steps per second of simulated time it achieved, and how
much simulated time a wall-clock second gave. Needs the colcon install space (scripts/demo.sh
builds it into install/).
"""

import argparse
import json
import os
import platform
import random
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_core import lattice  # noqa: E402
from formation_ros.core.params_file import write_params_file  # noqa: E402, I100

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def params_for(n):
    """Parameters for N robots (Section 5 constants), flat dotted names."""
    radius = max(1.0, (n / (10.0 * 3.141592653589793)) ** 0.5)
    return {'num_robots': n, 'dim': 2, 'sensing_radius': 2.0, 'repulsion_radius': 1.0,
            'formation.vertices': [float(v) for v in lattice(n, 2.0).ravel()],
            'start.random_radius': float(radius), 'start.min_separation': 0.1,
            'start.seed': 1, 'duration': 20.0}


def main():
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--sizes', type=int, nargs='+', default=[4, 10, 20])
    parser.add_argument('--duration', type=float, default=20.0)
    parser.add_argument('--prefix', default=os.path.join(ROOT, 'install', 'formation_ros'))
    args = parser.parse_args()
    env = dict(os.environ, ROS_DOMAIN_ID=str(random.randint(1, 101)),
               ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    print(f'machine: {platform.machine()}, {os.cpu_count()} cores, Python '
          f'{platform.python_version()}; {args.duration:g} s wall per run, plant.rate 100 Hz\n')
    print('| N | processes | steps/s achieved (of 100) | simulated s per wall s | '
          'final max error (m) |')
    print('|---:|---:|---:|---:|---:|')
    for n in args.sizes:
        with tempfile.TemporaryDirectory() as tmp:
            params = os.path.join(tmp, 'params.yaml')
            write_params_file(params, params_for(n))
            out = os.path.join(tmp, 'run')
            subprocess.run(['bash', os.path.join(ROOT, 'scripts', 'launch_formation.sh'),
                            params, '--duration', str(args.duration), '--out', out,
                            '--prefix', args.prefix], env=env, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            with open(os.path.join(out, 'plant_stats.json')) as stream:
                stats = json.load(stream)
            with open(os.path.join(out, 'metrics.json')) as stream:
                metrics = json.load(stream)
        print(f"| {n} | {n + 2} | {stats['achieved_step_rate']:.1f} | "
              f"{stats['simulated_time'] / stats['wall_time']:.2f} | "
              f"{metrics['final_max_error']:.2g} |", flush=True)


if __name__ == '__main__':
    main()
