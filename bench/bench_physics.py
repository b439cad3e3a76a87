# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""
Benchmark of the physics engine alone: N differential-drive bases on MuJoCo (on demand).

Usage: python bench/bench_physics.py [--sizes 100] [--duration 10] [--timestep 0.002]
[--json FILE]

For each team size N it builds the world of N TurtleBot3-like bases (``world.*`` defaults, 2 ms
steps) on a square lattice 1 m apart with random headings, and drives them as a controller at
20 Hz would: every 0.05 s of simulated time each base gets a new stamped command, a random
(v, w) within its limits held for 1 s; the bases roam, meet and touch. Pinned to one core
(``--cpu``), it times :meth:`Engine.step` (MuJoCo's step and the engine's own work: wheel
odometry, contacts, the closest approach) and MuJoCo's ``mj_step`` alone on the same world, and
prints a Markdown table with the real-time factor (simulated seconds per wall second).
"""

import argparse
import datetime
import json
import math
import os
import platform
import sys
import time
from typing import Any, Dict, List, Optional, Sequence

BENCH = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(BENCH)
sys.path[:0] = [ROOT]

from formation_ros.core.settings.params import validate  # noqa: E402
import numpy as np  # noqa: E402

CONTROL_PERIOD = 0.05
"""Simulated seconds between two commands of a base (a 20 Hz controller)."""
HOLD = 1.0
"""Simulated seconds a base keeps the same (v, w)."""
SPACING = 1.0
"""Distance between neighbouring bases at the start, m."""
MAX_LINEAR = 0.22
MAX_ANGULAR = 2.84
HEADER = ('| N | timestep (ms) | simulated (s) | engine wall (s) | CPU (s) | real-time factor | '
          'steps/s | MuJoCo alone | contacts | closest (m) |\n'
          '|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|')


def build_parser() -> argparse.ArgumentParser:
    """Return the command line of the benchmark."""
    parser = argparse.ArgumentParser(
        prog='bench_physics.py', description=__doc__.split('\n\n')[0].strip())
    parser.add_argument('--sizes', type=int, nargs='+', default=[100],
                        help='team sizes N (default %(default)s)')
    parser.add_argument('--duration', type=float, default=10.0,
                        help='simulated seconds per size (default %(default)g)')
    parser.add_argument('--timestep', type=float, default=0.002,
                        help='world.timestep, s (default %(default)g)')
    parser.add_argument('--cpu', type=int,
                        help='the core to pin the benchmark to (default: the first allowed)')
    parser.add_argument('--seed', type=int, default=1, help='random headings and commands')
    parser.add_argument('--json', help='write the results as JSON to this file')
    return parser


def parse_args(argv: Optional[Sequence[str]] = None) -> argparse.Namespace:
    """Parse and check the command line (argparse exits 2 on a bad one)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not all(n >= 2 for n in args.sizes):
        parser.error('--sizes must be at least 2')
    if not (args.duration > 0.0 and args.timestep > 0.0):
        parser.error('--duration and --timestep must be > 0')
    return args


def params_for(n: int, timestep: float, seed: int) -> Dict[str, Any]:
    """Return the parameters of N bases on a lattice SPACING apart, random headings."""
    side = math.ceil(math.sqrt(n))
    lattice = [float(v) for i in range(n)
               for v in ((i % side) * SPACING, (i // side) * SPACING)]
    headings = np.random.default_rng([seed, 0]).uniform(-math.pi, math.pi, n)
    return {'num_robots': n, 'dim': 2, 'sensing_radius': 0.9, 'repulsion_radius': 0.5,
            'formation.vertices': lattice, 'start.positions': lattice,
            'start.headings': [float(h) for h in headings], 'controller.gain': 0.05,
            'body.kind': 'unicycle', 'body.hand_distance': 0.08, 'body.radius': 0.11,
            'body.max_linear': MAX_LINEAR, 'body.max_angular': MAX_ANGULAR,
            'world.timestep': timestep}


def run_size(n: int, args: argparse.Namespace) -> Dict[str, Any]:
    """Drive N bases for the duration; return the row."""
    import mujoco
    from formation_ros.physics.engine import Engine
    engine = Engine(validate(params_for(n, args.timestep, args.seed)))
    rng = np.random.default_rng([args.seed, 1])
    per_command = max(1, int(round(CONTROL_PERIOD / args.timestep)))
    per_hold = max(1, int(round(HOLD / CONTROL_PERIOD)))
    steps = int(round(args.duration / args.timestep))
    cpu_begun = time.process_time()
    command = np.zeros((n, 2))
    done = 0
    while done < steps:
        if (done // per_command) % per_hold == 0:
            command = np.stack([rng.uniform(-MAX_LINEAR, MAX_LINEAR, n),
                                rng.uniform(-MAX_ANGULAR, MAX_ANGULAR, n)], axis=1)
        engine.apply(command, np.full(n, engine.time_ns))
        chunk = min(per_command, steps - done)
        engine.step(chunk)
        done += chunk
    cpu = time.process_time() - cpu_begun
    stats = engine.stats(engine.wall)
    begun = time.perf_counter()
    mujoco.mj_step(engine.mj_model, engine.data, steps)
    alone = time.perf_counter() - begun
    return {'robots': n, 'timestep_s': args.timestep, 'simulated_s': stats.simulated_time,
            'wall_s': stats.engine_wall_time, 'cpu_s': cpu,
            'realtime_factor': stats.engine_realtime_factor,
            'steps_per_s': stats.steps / stats.engine_wall_time, 'mujoco_alone_realtime_factor':
            stats.simulated_time / alone, 'contacts': stats.contacts,
            'min_body_distance': stats.min_body_distance}


def format_row(row: Dict[str, Any]) -> str:
    """Return one Markdown table row."""
    return (f"| {row['robots']} | {1000.0 * row['timestep_s']:g} | {row['simulated_s']:.1f} | "
            f"{row['wall_s']:.2f} | {row['cpu_s']:.2f} | {row['realtime_factor']:.2f}x | "
            f"{row['steps_per_s']:.0f} | {row['mujoco_alone_realtime_factor']:.2f}x | "
            f"{row['contacts']} | {row['min_body_distance']:.3f} |")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run every size pinned to one core, print the table, write the JSON if asked."""
    args = parse_args(argv)
    cpu = min(os.sched_getaffinity(0)) if args.cpu is None else args.cpu
    os.sched_setaffinity(0, {cpu})
    import mujoco
    load = os.getloadavg()
    print(f'machine: {platform.machine()} ({platform.processor() or "?"}), {os.cpu_count()} '
          f'cores, pinned to core {cpu}; Python {platform.python_version()}, MuJoCo '
          f'{mujoco.__version__}; load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}\n')
    print(HEADER, flush=True)
    rows: List[Dict[str, Any]] = []
    for n in args.sizes:
        rows.append(run_size(n, args))
        print(format_row(rows[-1]), flush=True)
    if args.json:
        result = {'date': datetime.datetime.now(datetime.timezone.utc).isoformat(
            timespec='seconds'), 'machine': platform.machine(), 'cores': os.cpu_count(),
            'pinned_core': cpu, 'python': platform.python_version(),
            'mujoco': mujoco.__version__, 'load_before': load, 'load_after': os.getloadavg(),
            'arguments': vars(args), 'rows': rows}
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, 'w', encoding='utf-8') as stream:
            json.dump(result, stream, indent=2)
            stream.write('\n')
        print(f'\nwrote {args.json}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
