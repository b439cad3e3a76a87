# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Benchmark of the vectorised law and of the fixed-step simulator (run on demand, not in CI).

Usage: python bench/bench_core.py [--sizes 10 100 1000 5000] [--duration 20] [--dt 0.01]

For each team size N (2D) it times one call of ``team_command`` (median of repeats) and a whole
``simulate`` run of DURATION seconds with zero-order hold at DT, and prints a Markdown table with
the real-time factor (simulated seconds per wall second) and the cost per robot-step.
"""

import argparse
import math
import os
import platform
import statistics
import time

from formation_ros.core.maths.law import team_command
from formation_ros.core.settings.params import validate
from formation_ros.simulation.simulate import simulate
import numpy as np


def lattice(n, spacing):
    """Square lattice of n points, ``spacing`` apart, centred on the origin: (n, 2)."""
    side = math.ceil(math.sqrt(n))
    grid = np.array([(i % side, i // side) for i in range(n)], dtype=float) * spacing
    return grid - grid.mean(axis=0)


def params_for(n, duration=20.0):
    """
    Parameters of N robots, flat dotted names: Section 5 constants, lattice goal 2 m apart.

    The start is random in a disc holding about 10 robots per m^2 (at least 1 m across), at
    least 0.1 m apart. Every benchmark uses these.
    """
    return {
        'num_robots': n, 'dim': 2, 'sensing_radius': 2.0, 'repulsion_radius': 1.0,
        'formation.vertices': [float(v) for v in lattice(n, 2.0).ravel()],
        'start.random_radius': float(max(1.0, math.sqrt(n / (10.0 * math.pi)))),
        'start.min_separation': 0.1, 'start.seed': 1, 'duration': float(duration),
    }


def config_for(n, duration):
    """Return the validated configuration of :func:`params_for`."""
    return validate(params_for(n, duration))


def time_law(config, repeats):
    law = config.law()
    samples = []
    for _ in range(repeats):
        start = time.perf_counter()
        team_command(config.start, config.vertices, config.sensing_radii, law)
        samples.append(time.perf_counter() - start)
    return statistics.median(samples)


def main():
    """Run the benchmark and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--sizes', type=int, nargs='+', default=[10, 100, 1000, 5000])
    parser.add_argument('--duration', type=float, default=20.0)
    parser.add_argument('--dt', type=float, default=0.01)
    args = parser.parse_args()
    print(f'machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, '
          f'Python {platform.python_version()}, numpy {np.__version__}')
    print(f'{args.duration:g} s simulated with --dt {args.dt:g} '
          f'({int(round(args.duration / args.dt))} steps)\n')
    print('| N | law step (ms) | us per robot-step | 20 s run (s) | real-time factor |')
    print('|---:|---:|---:|---:|---:|')
    rows = []
    for n in args.sizes:
        config = config_for(n, args.duration)
        step = time_law(config, repeats=max(5, min(200, 20000 // n)))
        start = time.perf_counter()
        simulate(config, args.duration, dt=args.dt, sample_dt=args.duration)
        run = time.perf_counter() - start
        rows.append((n, step))
        print(f'| {n} | {1e3 * step:.3f} | {1e6 * step / n:.2f} | {run:.2f} | '
              f'{args.duration / run:.1f}x |', flush=True)
    if len(rows) > 1:
        (n0, t0), (n1, t1) = rows[-2], rows[-1]
        exponent = math.log(t1 / t0) / math.log(n1 / n0)
        n_log_n = math.log(n1 * math.log(n1) / (n0 * math.log(n0))) / math.log(n1 / n0)
        print(f'\ngrowth of the law step between N = {n0} and {n1}: N^{exponent:.2f} '
              f'(N log N would be N^{n_log_n:.2f})')


if __name__ == '__main__':
    main()
